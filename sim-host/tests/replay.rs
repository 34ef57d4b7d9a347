//! Replays of a recorded session, closed loop: the firmware and the emulated drives on the
//! in-process bus in lockstep, a session with two E-stops recorded from a listener as
//! `candump -L` text (the run's `bus.log` format) and read back, then replayed from outside as
//! `canplayer` would — all of it at its recorded pace, seeded random slices, and seeded random
//! pairs of consecutive frames — against the same controller held at STOP, then latched, then
//! restarted (a new session).
//!
//! What must hold: nothing releases, nothing moves (torso ≤ 2 cm horizontally), the controller's
//! state is what it was, and every replayed frame except the E-stop latches (which always act)
//! is refused and counted by the nodes that consume it: the firmware for what it consumes
//! (feedback, SYNC, operator commands, heartbeats, releases), each drive for what it consumes
//! (its commands, the controller's status and announcement, releases).
//!
//! `cargo test -p sim-host --test replay -- --nocapture` prints the figures.

use std::time::Duration;

use firmware::control::fsm::State;
use host_can::candump::{read_log, CandumpWriter, LoggedFrame};
use host_can::fault_plan::Faults;
use host_can::inproc_bus::InprocEndpoint;
use host_can::Bus;
use protocol::{
    AnyMessage, EStop, EStopAction, Epoch, Frame, MessageId, NodeId, RejectCause, Session,
    TeleopMode, TEST_KEY,
};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use sim_host::faults::rig::{Rig, RIG_EPOCH};
use sim_host::robot::model::DEFAULT_MODEL;
use teleop_core::scripted::PlanStep;

fn latch() -> Frame {
    AnyMessage::EStop(EStop::latch(NodeId::Tool))
        .encode(&Session::unjoined(TEST_KEY), 0)
        .unwrap()
}

fn is_latch(frame: &Frame) -> bool {
    frame.id() == MessageId::EStop.raw()
        && protocol::decode_frame(frame.id(), frame.data()).is_ok_and(
            |d| matches!(d.message, AnyMessage::EStop(e) if e.action == EStopAction::Latch),
        )
}

/// How many refusals one replayed frame must bring: (by the firmware, by the drives).
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

/// A recorded session: STOP, W (the robot folds and drives), a latch at 3 s, its release at
/// 4 s, STOP then W again (the interlock), a second latch at 5.5 s, its release at 6.5 s, STOP
/// from 6.6 s. Returns the rig, still running, and the log as read back from its text.
fn record() -> (Rig, Vec<LoggedFrame>) {
    let plan = vec![
        PlanStep::at(0.0, TeleopMode::Stop),
        PlanStep::at(0.2, TeleopMode::WheelForward),
        PlanStep::at(7.7, TeleopMode::Stop),
        PlanStep::at(8.0, TeleopMode::WheelForward),
        PlanStep::at(15.7, TeleopMode::Stop),
    ];
    let clean = Faults::default();
    let mut rig = Rig::new(DEFAULT_MODEL.as_ref(), plan, &clean, &clean).unwrap();
    let mut tap = rig.tap();
    let mut log = CandumpWriter::new(Vec::new(), "vcan0").unwrap();
    // The fold from standing takes about 4 s: each latch comes while driving, each release
    // after the stop has set the robot down.
    let mut events = [(5.0, true), (7.5, false), (13.0, true), (15.5, false)].into_iter();
    let mut next = events.next();
    while rig.time_s() < 16.5 {
        if let Some((_, latching)) = next.filter(|(at_s, _)| rig.time_s() >= *at_s) {
            let frame = if latching {
                latch()
            } else {
                rig.release_frame(NodeId::Tool).unwrap()
            };
            rig.tool_send(&frame).unwrap();
            next = events.next();
        }
        rig.step().unwrap();
        drain(&mut tap, rig.time_s(), &mut log);
    }
    let text = String::from_utf8(log.finish().unwrap()).unwrap();
    let frames = read_log(&text).unwrap();
    let released = rig
        .records()
        .iter()
        .filter(|r| r.time_us > 15_600_000)
        .all(|r| r.state != Some(State::EStop));
    assert!(released, "the recorded session ends released");
    let latches = frames.iter().filter(|f| is_latch(&f.frame)).count();
    assert!(latches >= 2, "the log holds the two latches");
    (rig, frames)
}

fn drain(tap: &mut InprocEndpoint, time_s: f64, log: &mut CandumpWriter<Vec<u8>>) {
    while let Some(frame) = tap.recv(Duration::ZERO).unwrap() {
        log.write(&LoggedFrame { time_s, frame }).unwrap();
    }
}

/// What the nodes refused so far: (firmware, drives).
fn refused(rig: &Rig) -> (u64, u64) {
    let firmware = RejectCause::ALL
        .iter()
        .map(|cause| rig.firmware_rejected(*cause))
        .sum();
    (firmware, rig.sim().hardware().rejected())
}

fn torso_xy(rig: &Rig) -> [f64; 2] {
    let pos = rig.sim().physics().torso().pos_m;
    [pos[0], pos[1]]
}

/// Replays `frames` into `rig`, those logged in one cycle together in one cycle, then runs
/// 0.2 s more. Checks the contract; returns the frames replayed. A replayed latch may latch
/// the robot (latches always act); the robot is then released with a fresh release, so that the
/// next replay finds it as this one did.
fn replay(rig: &mut Rig, frames: &[LoggedFrame], what: &str) -> usize {
    let before = refused(rig);
    let state = rig.records().last().and_then(|r| r.state);
    let at = torso_xy(rig);
    let expected = frames
        .iter()
        .map(|f| consumers(&f.frame))
        .fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    let mut latched = state == Some(State::EStop);
    let mut index = 0;
    while index < frames.len() {
        let cycle_s = frames[index].time_s;
        while index < frames.len() && frames[index].time_s == cycle_s {
            rig.tool_send(&frames[index].frame).unwrap();
            index += 1;
        }
        rig.step().unwrap();
        latched = check_still(rig, state, latched, at, what);
    }
    let until = rig.time_s() + 0.2;
    rig.run_until(until).unwrap();
    check_still(rig, state, latched, at, what);
    let after = refused(rig);
    let counted = (after.0 - before.0, after.1 - before.1);
    assert_eq!(
        counted,
        expected,
        "{what}: {} frames, refusals (firmware, drives)",
        frames.len()
    );
    if latched && state != Some(State::EStop) {
        rig.tool_send(&rig.release_frame(NodeId::Tool).unwrap())
            .unwrap();
        let until = rig.time_s() + 0.3;
        rig.run_until(until).unwrap();
        assert_eq!(
            rig.records().last().unwrap().state,
            state,
            "{what}: re-armed"
        );
    }
    frames.len()
}

/// Whether the robot is latched now. It must be where it was, in the state it was, or latched
/// (by a replayed latch) and then stay latched.
fn check_still(rig: &Rig, state: Option<State>, latched: bool, at: [f64; 2], what: &str) -> bool {
    let now = torso_xy(rig);
    let moved_m = (now[0] - at[0]).hypot(now[1] - at[1]);
    let record = rig.records().last().unwrap();
    let time_s = rig.time_s();
    assert!(
        moved_m <= 0.02,
        "{what}: moved {moved_m:.3} m at {time_s:.3} s"
    );
    if latched {
        assert_eq!(
            record.state,
            Some(State::EStop),
            "{what}: released at {time_s:.3} s"
        );
    } else {
        assert!(
            record.state == state || record.state == Some(State::EStop),
            "{what}: {:?} at {time_s:.3} s, was {state:?}",
            record.state
        );
    }
    record.state == Some(State::EStop)
}

/// The whole log, then 20 seeded slices and 200 seeded pairs of consecutive frames.
fn replay_every_way(rig: &mut Rig, frames: &[LoggedFrame], target: &str, seed: u64) {
    let mut rng = SmallRng::seed_from_u64(seed);
    let all = replay(rig, frames, &format!("{target}: the whole log"));
    let mut sliced = 0;
    for n in 0..20 {
        let start = rng.random_range(0..frames.len());
        let len = rng.random_range(1..=400).min(frames.len() - start);
        sliced += replay(
            rig,
            &frames[start..start + len],
            &format!("{target}: slice {n} ({start}..+{len})"),
        );
    }
    for n in 0..200 {
        let start = rng.random_range(0..frames.len() - 1);
        // A pair goes out in one cycle, as two frames back to back.
        let pair: Vec<LoggedFrame> = frames[start..start + 2]
            .iter()
            .map(|f| LoggedFrame {
                time_s: 0.0,
                frame: f.frame,
            })
            .collect();
        replay(rig, &pair, &format!("{target}: pair {n} at {start}"));
    }
    println!(
        "MEASURED replay against {target}: the whole log ({all} frames), 20 slices ({sliced} \
         frames), 200 pairs: nothing released, nothing moved, every frame but the latches refused \
         and counted"
    );
}

#[test]
fn a_recorded_session_replayed_any_way_releases_nothing_and_moves_nothing() {
    let (mut rig, frames) = record();
    let non_latch = frames.iter().filter(|f| !is_latch(&f.frame)).count();
    println!(
        "recorded {} frames ({non_latch} not latches) over 16.5 s",
        frames.len()
    );
    // Held at STOP, released, in the same session as the recording.
    rig.run_until(17.5).unwrap();
    assert_eq!(rig.records().last().unwrap().state, Some(State::Hold));
    replay_every_way(&mut rig, &frames, "the robot held at STOP", 1);
    // Latched, same session: the log's releases are refused as stale.
    rig.tool_send(&latch()).unwrap();
    let until = rig.time_s() + 3.0;
    rig.run_until(until).unwrap();
    assert_eq!(rig.records().last().unwrap().state, Some(State::EStop));
    replay_every_way(&mut rig, &frames, "the latched robot", 2);
    // The controller restarted: a new session, in which none of the log is authentic.
    rig.restart_firmware(Epoch::new(RIG_EPOCH.raw() + 1))
        .unwrap();
    let until = rig.time_s() + 1.0;
    rig.run_until(until).unwrap();
    replay_every_way(&mut rig, &frames, "the restarted controller", 3);
}
