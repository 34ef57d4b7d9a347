//! Lockstep: the simulator is the clock. Each cycle it sends the nodes' feedback and then SYNC,
//! waits for the controller's wheel command (the frame a controller sends every cycle, after its
//! leg targets), then steps. Deterministic, and as fast as the two sides can go.
//!
//! A command that does not arrive within the reply timeout counts as a missed cycle; the drives
//! then act on their previous commands (and time out after 100 ms, as real drives do).

use std::time::{Duration, Instant};

use protocol::MessageId;

use crate::output::recorder::Recorder;
use crate::session::run_stats::{RunError, RunStats};
use crate::session::simulator::Simulator;
use host_can::bus::Bus;

/// Lockstep settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LockstepOptions {
    /// Control cycles to run.
    pub cycles: u64,
    /// How long to wait for the controller's command each cycle.
    pub reply_timeout: Duration,
    /// Run at most this many times real time (`None`: as fast as possible). Still lockstep and
    /// deterministic; paced so that people and outside tools (cansend, canplayer) see the
    /// simulation at a speed they can act in.
    pub max_speed: Option<f64>,
}

/// Runs `options.cycles` cycles after joining the controller's session. `peers(cycle)` runs after the simulator has sent its frames
/// and before it waits: nodes sharing this thread (the in-process controller, a scripted
/// teleop) do their work there; over SocketCAN it is a no-op. `observe` sees the simulator after
/// each cycle (progress, stop conditions); returning `false` ends the run early.
pub fn run(
    sim: &mut Simulator,
    bus: &mut dyn Bus,
    recorder: &mut Recorder,
    options: LockstepOptions,
    mut peers: impl FnMut(u32) -> Result<(), RunError>,
    mut observe: impl FnMut(&Simulator, &RunStats) -> bool,
) -> Result<RunStats, RunError> {
    let mut started = Instant::now();
    let mut stats = RunStats::default();
    // Cycles spent waiting to join count against the same budget, so a run without a
    // controller ends (with no cycles run) after as many reply timeouts.
    let mut joining = 0_u64;
    while stats.cycles < options.cycles && joining < options.cycles {
        let advanced = cycle(
            sim,
            bus,
            recorder,
            &mut stats,
            options.reply_timeout,
            &mut peers,
        )?;
        if !advanced {
            joining += 1;
            // The run's wall time counts from the session's first cycle, not the wait for it.
            started = Instant::now();
            continue;
        }
        recorder.cycle(sim)?;
        if !observe(sim, &stats) {
            break;
        }
        if let Some(speed) = options.max_speed.filter(|s| *s > 0.0) {
            let due = started + Duration::from_secs_f64(sim.time_s() / speed);
            if let Some(wait) = due.checked_duration_since(Instant::now()) {
                std::thread::sleep(wait);
            }
        }
    }
    stats.sim_s = sim.time_s();
    stats.set_wall(started.elapsed());
    Ok(stats)
}

/// One lockstep cycle: feedback and SYNC out, `peers(cycle)`, the controller's commands in
/// (waiting up to `reply_timeout` for its WheelCommand), one physics step. Counts into `stats`;
/// the caller records the telemetry row. Returns whether the physics stepped: until the
/// simulator's nodes have joined the controller's session (heard its announcement) they send
/// nothing and time stands still.
pub fn cycle(
    sim: &mut Simulator,
    bus: &mut dyn Bus,
    recorder: &mut Recorder,
    stats: &mut RunStats,
    reply_timeout: Duration,
    peers: &mut impl FnMut(u32) -> Result<(), RunError>,
) -> Result<bool, RunError> {
    let time_s = sim.time_s();
    let joined = sim.joined();
    // Feedback first, then SYNC: a controller in another process computes the tick when
    // SYNC arrives, with this cycle's feedback already in hand.
    let mut outgoing = sim.frames_due()?;
    if let Some(sync) = sim.sync_frame()? {
        // SYNC has its slot in the schedule, which no node fills: there is room.
        let pushed = outgoing.push(sync);
        debug_assert!(pushed.is_ok(), "the schedule has a slot for SYNC");
    }
    // In one call: a controller in another process wakes once for the cycle, not per frame.
    bus.send_all(&outgoing)?;
    for frame in &outgoing {
        recorder.frame(time_s, frame)?;
        stats.frames_sent += 1;
    }
    peers(sim.cycle())?;
    // What has arrived is taken first; the clock is read only when the command is still to
    // come (never in-process, where the controller has already answered).
    let mut deadline = None;
    let mut commanded = false;
    loop {
        let mut received = bus.recv(Duration::ZERO)?;
        if received.is_none() && !commanded {
            let until = *deadline.get_or_insert_with(|| Instant::now() + reply_timeout);
            received = bus.recv(until.saturating_duration_since(Instant::now()))?;
        }
        match received {
            Some(frame) => {
                stats.frames_received += 1;
                recorder.frame(time_s, &frame)?;
                sim.receive(&frame);
                commanded |= frame.id() == MessageId::WheelCommand.raw();
                if !joined && sim.joined() {
                    // Joined: the first SYNC goes out next cycle; no command comes before.
                    break;
                }
            }
            None => break,
        }
    }
    if !joined {
        // No SYNC goes out before the join, so end the cycle here: a bus that delays frames
        // by cycles must still deliver the announcement.
        bus.end_cycle()?;
        return Ok(false);
    }
    if !commanded {
        stats.missed_cycles += 1;
    }
    sim.advance();
    stats.cycles += 1;
    if !sim.physics().is_finite() {
        return Err(RunError::Diverged {
            time_s: sim.time_s(),
        });
    }
    Ok(true)
}
