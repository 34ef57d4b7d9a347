//! `canplayer` (can-utils) replaying recorded sessions onto a kernel vcan, into the firmware and
//! the simulator running as two processes: a recorded operator's frames into the controller
//! restarted in a new session, and a whole recorded bus — every node's frames, E-stop latches
//! and releases included — into the same controller held at STOP and latched: the whole log,
//! then seeded random slices and pairs of consecutive frames of it, played back to back from
//! one file. Nothing releases, nothing moves, and the nodes refuse and count every replayed
//! frame but the latches.
//!
//! The tests run one at a time: a recording replayed on the wall clock must land in a lockstep
//! run paced to real time, which a second closed loop beside it (in an emulated VM) would slow.

use std::fmt::Write as _;
use std::ops::Range;
use std::path::Path;
use std::time::Duration;

use hil_tests::{
    announced_session, candump, cansend, firmware_with_state, one_at_a_time, out_dir, read_candump,
    read_telemetry, start_sim, Process, Vcan,
};
use protocol::{
    classic_latch, decode_frame, AnyMessage, ControllerMode, ControllerStatus, EStop, EStopAction,
    Frame, MessageId, NodeId, RejectCause, SessionTime,
};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};

/// The firmware (keeping its state in `state`) and the simulator in lockstep, paced to at most
/// real time (`--pace 1`), so that frames replayed at their recorded wall-clock times land at
/// about the same simulated times as when they were recorded.
fn lockstep_pair(
    bus: &Vcan,
    state: &std::path::Path,
    out: &std::path::Path,
    duration_s: &str,
    extra: &[&str],
) -> (Process, Process) {
    let fw = firmware_with_state(bus, state);
    let mut args = vec!["--duration-s", duration_s, "--pace", "1"];
    args.extend_from_slice(extra);
    let sim = start_sim(bus.name(), out, &args);
    (fw, sim)
}

#[test]
fn canplayer_replaying_a_recorded_teleop_session_into_the_restarted_controller_moves_nothing() {
    let _alone = one_at_a_time();
    // Record: a scripted operator folds and drives forward; candump records the bus.
    let first = Vcan::new();
    let log = out_dir("session").with_extension("log");
    let dump = candump(&first, &log);
    std::thread::sleep(Duration::from_millis(200));
    let out1 = out_dir("session-run");
    let state = first.state_file();
    let (fw, sim) = lockstep_pair(
        &first,
        &state,
        &out1,
        "8",
        &["--drive", "0:fold", "--drive", "3:W"],
    );
    assert!(sim.wait(Duration::from_secs(600)).success());
    let _ = fw.terminate();
    std::thread::sleep(Duration::from_millis(100));
    let _ = dump.terminate();

    // Keep only the operator's frames (teleop command and heartbeat).
    let text = std::fs::read_to_string(&log).unwrap();
    let teleop: Vec<&str> = text
        .lines()
        .filter(|l| l.contains(" 200##") || l.contains(" 201##"))
        .collect();
    assert!(
        teleop.len() > 300,
        "only {} teleop frames recorded",
        teleop.len()
    );
    let session = out_dir("teleop-only").with_extension("log");
    std::fs::write(&session, teleop.join("\n") + "\n").unwrap();

    // Replay on a fresh bus into the same controller restarted (its state file gives it the
    // next session epoch), with a fresh simulator and nobody else driving: the recording
    // belongs to the earlier session, so every replayed command and heartbeat fails its
    // authentication, is counted, and moves nothing.
    let second = Vcan::new();
    let log2 = out_dir("replay").with_extension("log");
    let dump = candump(&second, &log2);
    let out2 = out_dir("replay-run");
    let (fw, sim) = lockstep_pair(&second, &state, &out2, "8", &[]);
    std::thread::sleep(Duration::from_millis(300));
    let mapping = format!("{}={}", second.name(), first.name());
    let player = Process::start("canplayer", &["-I", &session.to_string_lossy(), &mapping]);
    assert!(player.wait(Duration::from_secs(120)).success());
    assert!(sim.wait(Duration::from_secs(600)).success());
    let _ = fw.terminate();
    std::thread::sleep(Duration::from_millis(100));
    let _ = dump.terminate();

    let moved = |dir: &std::path::Path| {
        let text = std::fs::read_to_string(dir.join("telemetry.csv")).unwrap();
        let last = text.lines().last().unwrap().to_owned();
        last.split(',').nth(1).unwrap().parse::<f64>().unwrap()
    };
    let (recorded, replayed) = (moved(&out1), moved(&out2));
    let frames = read_candump(&log2);
    let epochs = [
        announced_session(&read_candump(&log)),
        announced_session(&frames),
    ]
    .map(|s| s.and_then(|s| s.epoch()).map(|e| e.raw()));
    let refused = frames
        .iter()
        .rev()
        .find_map(
            |(_, f)| match decode_frame(f.id(), f.data()).map(|d| d.message) {
                Ok(AnyMessage::RejectCounters(c)) => Some(c.get(RejectCause::Unauthentic).raw()),
                _ => None,
            },
        )
        .unwrap_or(0);
    let modes: std::collections::BTreeSet<String> = read_telemetry(&out2.join("telemetry.csv"))
        .into_iter()
        .map(|(.., mode)| mode)
        .collect();
    println!(
        "recorded session (epoch {:?}): {recorded:.3} m forward; replayed {} frames into epoch          {:?}: {replayed:.3} m, {refused} refused as unauthentic, modes {modes:?}",
        epochs[0],
        teleop.len(),
        epochs[1]
    );
    assert!(recorded > 0.5, "the recorded session drove {recorded:.3} m");
    assert!(
        epochs[1] > epochs[0],
        "the restarted controller opened epoch {:?} after {:?}",
        epochs[1],
        epochs[0]
    );
    assert!(
        !modes.contains("WheelForward") && !modes.contains("Folding"),
        "the replay moved the robot: {modes:?}"
    );
    assert!(replayed.abs() < 0.05, "replayed run moved {replayed:.3} m");
    // The controller reports its counters while the simulator runs: most of the replay.
    assert!(
        usize::from(refused) * 2 >= teleop.len(),
        "{refused} of {} replayed frames refused",
        teleop.len()
    );
}

/// The controller's lockstep control period, s (the simulator's SYNC at 250 Hz): a status's
/// tick times this is the simulated time it was sent at.
const PERIOD_S: f64 = 0.004;

/// Simulated seconds of the recorded session: the operator's STOP goes at 7 s.
const RECORD_S: f64 = 8.5;

/// Polls the `candump` log at `path` every 200 ms (a long log is costly to read in the VM)
/// until `seen` gives a value for its frames, at most `timeout`.
fn wait_on_log<T>(
    path: &Path,
    timeout: Duration,
    what: &str,
    seen: impl Fn(&[(f64, Frame)]) -> Option<T>,
) -> T {
    let started = std::time::Instant::now();
    while started.elapsed() < timeout {
        std::thread::sleep(Duration::from_millis(200));
        if let Some(value) = seen(&read_candump(path)) {
            return value;
        }
    }
    panic!("{what}: not seen within {timeout:?}");
}

fn message(frame: &Frame) -> Option<AnyMessage> {
    decode_frame(frame.id(), frame.data())
        .ok()
        .map(|d| d.message)
}

fn is_latch(frame: &Frame) -> bool {
    matches!(message(frame), Some(AnyMessage::EStop(e)) if e.action == EStopAction::Latch)
}

/// The controller's statuses in `frames` sent after tick `after`: replayed statuses carry the
/// older ticks of the recording, so these are the controller's own.
fn statuses_after(frames: &[(f64, Frame)], after: u32) -> Vec<ControllerStatus> {
    frames
        .iter()
        .filter_map(|(_, f)| match message(f) {
            Some(AnyMessage::ControllerStatus(s)) if s.tick.raw() > after => Some(s),
            _ => None,
        })
        .collect()
}

/// The controller's latest status (the greatest tick: a replayed one is older).
fn latest_status(frames: &[(f64, Frame)]) -> Option<ControllerStatus> {
    statuses_after(frames, 0)
        .into_iter()
        .max_by_key(|s| s.tick.raw())
}

/// A release as a keyholder's tool composes it: in the session of the latest announcement,
/// with the token of the latest status (what `cargo xtask frame release` does).
fn fresh_release(frames: &[(f64, Frame)]) -> Frame {
    let announce = frames
        .iter()
        .filter_map(|(_, f)| match message(f) {
            Some(AnyMessage::Announce(a)) => Some(a),
            _ => None,
        })
        .max_by_key(|a| (a.epoch.raw(), a.time.ms()))
        .expect("the controller announced its session");
    let token = latest_status(frames).expect("a status").release_token;
    let session = announced_session(frames)
        .expect("a session")
        .at(SessionTime::from_ms(announce.time.ms()));
    AnyMessage::EStop(EStop::release(NodeId::Tool, token))
        .encode(&session, announce.time.ms())
        .expect("a release encodes")
}

/// How many refusals one replayed frame must bring: (by the firmware, by the drives): each
/// node that consumes its identifier refuses it once (a latch always acts).
fn consumers(frame: &Frame) -> (u64, u64) {
    if is_latch(frame) {
        return (0, 0);
    }
    match MessageId::from_raw(frame.id()) {
        Some(MessageId::EStop) => (1, 5),
        Some(MessageId::LegTargets) => (0, 4),
        Some(MessageId::WheelCommand) => (0, 1),
        Some(MessageId::Announce | MessageId::ControllerStatus) => (0, 5),
        Some(
            MessageId::Sync
            | MessageId::LegFeedback(_)
            | MessageId::WheelFeedback
            | MessageId::Imu
            | MessageId::Range
            | MessageId::TeleopCommand
            | MessageId::TeleopHeartbeat
            | MessageId::DriveStatus(_),
        ) => (1, 0),
        _ => (0, 0),
    }
}

/// Every refusal counter on the bus as last reported: the controller's per cause, then each
/// drive's (its `DriveStatus`). Read when no replay runs, the latest reports are the nodes'
/// own.
fn counters(frames: &[(f64, Frame)]) -> Vec<u16> {
    let mut firmware = [0_u16; RejectCause::ALL.len()];
    let mut drives = std::collections::BTreeMap::new();
    for (_, frame) in frames {
        match message(frame) {
            Some(AnyMessage::RejectCounters(c)) => {
                for (slot, cause) in firmware.iter_mut().zip(RejectCause::ALL) {
                    *slot = c.get(cause).raw();
                }
            }
            Some(AnyMessage::DriveStatus(_, s)) => {
                drives.insert(frame.id(), s.rejected.raw());
            }
            _ => {}
        }
    }
    assert_eq!(drives.len(), 5, "every drive reported");
    firmware.into_iter().chain(drives.into_values()).collect()
}

/// Refusals between two readings of [`counters`]: (firmware, drives); the counts wrap at 2^16.
fn refused_between(before: &[u16], after: &[u16]) -> (u64, u64) {
    let delta: Vec<u64> = before
        .iter()
        .zip(after)
        .map(|(b, a)| u64::from(a.wrapping_sub(*b)))
        .collect();
    let (firmware, drives) = delta.split_at(RejectCause::ALL.len());
    (firmware.iter().sum(), drives.iter().sum())
}

/// The torso's position in the simulator's telemetry: `(time s, [x, y] m)`.
fn torso_xy(out: &Path) -> Vec<(f64, [f64; 2])> {
    let text = std::fs::read_to_string(out.join("telemetry.csv")).expect("telemetry");
    text.lines()
        .skip(1)
        .filter_map(|line| {
            let mut cells = line.split(',').map(|c| c.parse::<f64>().ok());
            Some((cells.next()??, [cells.next()??, cells.next()??]))
        })
        .collect()
}

/// A run of the robot on its own vcan with candump recording it.
struct Bench {
    bus: Vcan,
    log: std::path::PathBuf,
}

impl Bench {
    fn frames(&self) -> Vec<(f64, Frame)> {
        read_candump(&self.log)
    }

    /// Waits until the controller's own status (after `after`) satisfies `holds`; its tick.
    fn wait_status(
        &self,
        after: u32,
        what: &str,
        holds: impl Fn(&ControllerStatus) -> bool,
    ) -> u32 {
        wait_on_log(&self.log, Duration::from_secs(300), what, |frames| {
            statuses_after(frames, after)
                .into_iter()
                .find(|s| holds(s))
                .map(|s| s.tick.raw())
        })
    }

    /// Waits until `seconds` of simulated time have passed since `tick`; the tick then.
    fn wait_s(&self, tick: u32, seconds: f64) -> u32 {
        let until = tick + (seconds / PERIOD_S) as u32;
        self.wait_status(until, "simulated time", |_| true)
    }

    /// Replays the candump text at `recording` with `canplayer` (its own timing, onto the bus
    /// it was recorded on), waits until the nodes have reported their counters again, and
    /// checks what the replay brought (see [`check_replay`]) against the robot found in `from`.
    fn replay(&self, recording: &Path, what: &str, from: ControllerMode) -> Replayed {
        let frames = read_candump(recording);
        let before = counters(&self.frames());
        let start = latest_status(&self.frames()).expect("a status").tick.raw();
        let player = Process::start("canplayer", &["-I", &recording.to_string_lossy()]);
        assert!(
            player.wait(Duration::from_secs(300)).success(),
            "{what}: canplayer failed"
        );
        // A second after the last replayed frame, the latest reports are the nodes' own.
        let end = latest_status(&self.frames()).expect("a status").tick.raw();
        self.wait_status(end + 250, what, |_| true);
        let log = self.frames();
        let replayed = Replayed {
            frames: frames.len(),
            playing_s: frames.last().map_or(0.0, |last| last.0 - frames[0].0),
            refused: refused_between(&before, &counters(&log)),
            expected: expected_refusals(&frames),
            statuses: statuses_after(&log, start),
            ticks: (start, end),
        };
        check_replay(what, &replayed, from);
        replayed
    }

    /// Re-arms the robot if `replayed` left it latched (a replayed latch always acts, by
    /// design): a fresh release, then half a second for the nodes to report their counters, so
    /// that the next replay finds it held at STOP again.
    fn rearm(&self, replayed: &Replayed) {
        if replayed
            .statuses
            .last()
            .is_some_and(|s| s.mode == ControllerMode::EStop)
        {
            cansend(&self.bus, &fresh_release(&self.frames()));
            let rearmed = self.wait_status(replayed.ticks.1, "re-armed", |s| {
                s.mode == ControllerMode::Stop
            });
            self.wait_s(rearmed, 0.5);
        }
    }
}

/// What a replay brought.
struct Replayed {
    /// Frames replayed.
    frames: usize,
    /// How long they took to play at their recorded timing, s.
    playing_s: f64,
    /// Refusals counted while it ran: (firmware, drives).
    refused: (u64, u64),
    /// Refusals its frames must bring: (firmware, drives).
    expected: (u64, u64),
    /// The controller's statuses from its start.
    statuses: Vec<ControllerStatus>,
    /// The controller's ticks when it started and when its last frame had gone.
    ticks: (u32, u32),
}

impl Replayed {
    /// The index of the first status that says EStop, if any.
    fn latched_at(&self) -> Option<usize> {
        self.statuses
            .iter()
            .position(|s| s.mode == ControllerMode::EStop)
    }
}

/// How far the torso moved horizontally, m, between `ticks` (simulated time).
fn moved_m(out: &Path, ticks: (u32, u32)) -> f64 {
    let (from_s, to_s) = (f64::from(ticks.0) * PERIOD_S, f64::from(ticks.1) * PERIOD_S);
    let track: Vec<[f64; 2]> = torso_xy(out)
        .into_iter()
        .filter(|(t, _)| (from_s..=to_s).contains(t))
        .map(|(_, xy)| xy)
        .collect();
    let first = track.first().copied().expect("telemetry over the replay");
    track
        .iter()
        .map(|p| (p[0] - first[0]).hypot(p[1] - first[1]))
        .fold(0.0, f64::max)
}

/// The refusals `recording` must bring when replayed: (firmware, drives).
fn expected_refusals(recording: &[(f64, Frame)]) -> (u64, u64) {
    recording
        .iter()
        .map(|(_, f)| consumers(f))
        .fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
}

/// Checks one replay: every frame but the latches refused and counted, and — from the first
/// status that says EStop on — never released.
fn check_replay(what: &str, replayed: &Replayed, from: ControllerMode) {
    let (refused, expected) = (replayed.refused, replayed.expected);
    let modes: Vec<ControllerMode> = replayed.statuses.iter().map(|s| s.mode).collect();
    assert_eq!(
        refused, expected,
        "{what}: refusals (firmware, drives) of {} frames",
        replayed.frames
    );
    assert!(
        modes
            .iter()
            .all(|m| *m == from || *m == ControllerMode::EStop),
        "{what}: the controller left {from:?}: {modes:?}"
    );
    if let Some(at) = replayed.latched_at() {
        assert!(
            modes[at..].iter().all(|m| *m == ControllerMode::EStop),
            "{what}: released by the replay"
        );
    }
}

/// Seeded random slices of the recording replayed together: this many slices …
const SLICES: usize = 5;
/// … of 100 to this many frames …
const SLICE_MAX: usize = 400;
/// … and this many pairs of consecutive frames, besides the pairs on either side of every
/// E-stop frame.
const PAIRS: usize = 50;
/// Silence between two pieces as `canplayer` plays them, s (10 control periods).
const GAP_S: f64 = 0.04;

/// The pieces of a recording of `len` frames to replay (`is_estop`, `is_latch`: whether frame
/// `i` is an E-stop frame, a latch): seeded random slices and pairs of consecutive frames and
/// the pairs on either side of every E-stop frame. A replayed latch latches a robot held at
/// STOP, so the pieces holding one go last and the others find the robot as it was.
fn pieces(
    len: usize,
    is_estop: impl Fn(usize) -> bool,
    is_latch: impl Fn(usize) -> bool,
    seed: u64,
) -> Vec<Range<usize>> {
    let mut rng = SmallRng::seed_from_u64(seed);
    let mut pieces: Vec<Range<usize>> = (0..SLICES)
        .map(|_| {
            let start = rng.random_range(0..len - SLICE_MAX);
            start..start + rng.random_range(100..=SLICE_MAX)
        })
        .collect();
    pieces.extend((0..PAIRS).map(|_| {
        let start = rng.random_range(0..len - 1);
        start..start + 2
    }));
    pieces.extend(
        (1..len - 1)
            .filter(|i| is_estop(*i))
            .flat_map(|i| [i - 1..i + 1, i..i + 2]),
    );
    pieces.sort_by_key(|piece| piece.clone().any(&is_latch));
    pieces
}

/// Writes pieces of the recording (`text`, its `candump -L` lines) to `path` as one input of
/// `canplayer`: each piece at its recorded timing (a pair as two consecutive frames), the
/// next [`GAP_S`] after its last frame. Returns a description of what it holds.
fn compose(text: &str, seed: u64, path: &Path) -> String {
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    let recording = host_can::candump::read_log(text).expect("the recording reads back");
    assert_eq!(recording.len(), lines.len(), "one frame per line");
    let micros = |time_s: f64| (time_s * 1e6).round() as u64;
    let frame = |i: usize| &recording[i].frame;
    let is_latch_at = |i: usize| is_latch(frame(i));
    let is_estop_at = |i: usize| frame(i).id() == MessageId::EStop.raw();
    let chosen = pieces(recording.len(), is_estop_at, is_latch_at, seed);
    let mut out = String::new();
    let mut at = micros(recording[0].time_s);
    for piece in &chosen {
        let first = micros(recording[piece.start].time_s);
        for i in piece.clone() {
            let time = at + micros(recording[i].time_s).saturating_sub(first);
            let (_, rest) = lines[i].split_once(')').expect("a candump line");
            writeln!(out, "({}.{:06}){rest}", time / 1_000_000, time % 1_000_000).unwrap();
        }
        at += micros(recording[piece.end - 1].time_s).saturating_sub(first) + micros(GAP_S);
    }
    std::fs::write(path, out).unwrap();
    let slices: usize = chosen.iter().filter(|p| p.len() > 2).map(Range::len).sum();
    let latches = chosen
        .iter()
        .filter(|&p| p.clone().any(is_latch_at))
        .count();
    format!(
        "{} slices ({slices} frames) and {} pairs (seed {seed}; {latches} pieces with the latch)",
        chosen.iter().filter(|p| p.len() > 2).count(),
        chosen.iter().filter(|p| p.len() <= 2).count(),
    )
}

#[test]
fn canplayer_replaying_a_session_with_e_stops_whole_in_slices_and_in_pairs_into_the_same_controller_releases_and_moves_nothing(
) {
    let _alone = one_at_a_time();
    let bus = Vcan::new();
    let log = out_dir("whole-dump").with_extension("log");
    let dump = candump(&bus, &log);
    std::thread::sleep(Duration::from_millis(200));
    let out = out_dir("whole-run");
    let bench = Bench { bus, log };
    let state = bench.bus.state_file();
    // The session: W (the robot folds and drives), an E-stop from a shell, its release, then
    // STOP from 7 s (the operator's W is held through the release: the interlock holds it).
    // The simulator runs until interrupted after the last replay.
    let (fw, sim) = lockstep_pair(
        &bench.bus,
        &state,
        &out,
        "120",
        &["--drive", "0:W", "--drive", "7:X"],
    );
    let driving = bench.wait_status(0, "driving", |s| s.mode == ControllerMode::WheelForward);
    bench.wait_s(driving, 0.5);
    cansend(&bench.bus, &classic_latch(NodeId::Tool, 0).unwrap());
    let latched = bench.wait_status(driving, "latched", |s| s.mode == ControllerMode::EStop);
    bench.wait_s(latched, 2.5);
    cansend(&bench.bus, &fresh_release(&bench.frames()));
    let released = bench.wait_status(latched, "released", |s| s.mode != ControllerMode::EStop);
    let held = bench.wait_status(
        released.max((RECORD_S / PERIOD_S) as u32),
        "held at STOP",
        |s| s.mode == ControllerMode::Stop,
    );

    // The recording: the whole bus so far; and from it, for each target, one input of
    // seeded random slices and pairs of consecutive frames played back to back.
    let text = std::fs::read_to_string(&bench.log).unwrap();
    let complete = text.rfind('\n').map_or("", |end| &text[..=end]);
    let recording_path = out_dir("whole-recording").with_extension("log");
    std::fs::write(&recording_path, complete).unwrap();
    let recording = read_candump(&recording_path);
    let latches = recording.iter().filter(|(_, f)| is_latch(f)).count();
    let releases = recording
        .iter()
        .filter(|(_, f)| f.id() == MessageId::EStop.raw() && !is_latch(f))
        .count();
    println!(
        "recorded {} frames over {:.1} s: {latches} latch, {releases} release; held at STOP from \
         tick {held}",
        recording.len(),
        recording.last().unwrap().0 - recording[0].0
    );
    assert!(
        latches >= 1 && releases >= 1,
        "the session has its E-stop and release"
    );
    let [at_stop, at_estop] = [1, 2].map(|seed| {
        let path = out_dir(&format!("pieces-{seed}")).with_extension("log");
        let holds = compose(complete, seed, &path);
        (path, holds)
    });
    let whole = (recording_path.clone(), "the whole log".to_owned());

    // Held at STOP, then latched (2.5 s after a fresh latch: the controlled stop is over):
    // each time the whole log, then slices and pairs.
    let mut replays = Vec::new();
    for (path, holds) in [whole.clone(), at_stop] {
        let what = format!("held at STOP, {holds}");
        let replayed = bench.replay(&path, &what, ControllerMode::Stop);
        bench.rearm(&replayed);
        replays.push((what, replayed));
    }
    cansend(&bench.bus, &classic_latch(NodeId::Tool, 0).unwrap());
    let now = latest_status(&bench.frames()).unwrap().tick.raw();
    let latched = bench.wait_status(now, "latched again", |s| s.mode == ControllerMode::EStop);
    bench.wait_s(latched, 2.5);
    for (path, holds) in [whole, at_estop] {
        let what = format!("latched, {holds}");
        let replayed = bench.replay(&path, &what, ControllerMode::EStop);
        replays.push((what, replayed));
    }

    let (status, _) = sim.interrupt();
    assert!(status.is_some_and(|s| s.success()), "the simulator failed");
    let _ = fw.terminate();
    let _ = dump.terminate();
    // While each replay ran, the torso stayed where it was (a replayed latch latches a robot
    // held at STOP: its controlled stop is part of the window).
    let moved: Vec<f64> = replays
        .iter()
        .map(|(_, r)| moved_m(&out, r.ticks))
        .collect();
    for ((what, replayed), moved) in replays.iter().zip(&moved) {
        println!(
            "MEASURED vcan canplayer, {what}: {} frames over {:.1} s; refused (firmware, drives) \
             {:?}, expected {:?}; latched by the replay at status {:?} of {}, never released; \
             the torso moved {moved:.3} m",
            replayed.frames,
            replayed.playing_s,
            replayed.refused,
            replayed.expected,
            replayed.latched_at(),
            replayed.statuses.len(),
        );
    }
    for ((what, _), moved) in replays.iter().zip(moved) {
        assert!(
            moved <= 0.02,
            "{what}: the replay moved the robot {moved:.3} m"
        );
    }
}
