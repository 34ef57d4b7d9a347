//! Real time: the simulator steps on the wall clock at the control rate, takes whatever frames
//! arrived since the last cycle, and sends the nodes' feedback. No SYNC: the controller keeps
//! its own time, as on the robot. Reports the real-time factor and counts overruns (cycles that
//! ended after their deadline).

use std::time::{Duration, Instant};

use crate::output::recorder::Recorder;
use crate::session::run_stats::{RunError, RunStats};
use crate::session::simulator::Simulator;
use host_can::bus::Bus;

/// Real-time settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallOptions {
    /// Control cycles to run.
    pub cycles: u64,
    /// Length of a cycle on the wall clock.
    pub period: Duration,
}

/// Runs `options.cycles` cycles on the wall clock. `peers(cycle)` runs right after the
/// simulator has sent its feedback (see [`crate::clock::lockstep::run`]); `observe` after each
/// cycle.
pub fn run(
    sim: &mut Simulator,
    bus: &mut dyn Bus,
    recorder: &mut Recorder,
    options: WallOptions,
    mut peers: impl FnMut(u32) -> Result<(), RunError>,
    mut observe: impl FnMut(&Simulator, &RunStats) -> bool,
) -> Result<RunStats, RunError> {
    let started = Instant::now();
    let mut stats = RunStats::default();
    for n in 0..options.cycles {
        let wall_s = started.elapsed().as_secs_f64();
        while let Some(frame) = bus.recv(Duration::ZERO)? {
            stats.frames_received += 1;
            recorder.frame(wall_s, &frame)?;
            sim.receive(&frame);
        }
        sim.advance();
        stats.cycles += 1;
        if !sim.physics().is_finite() {
            return Err(RunError::Diverged {
                time_s: sim.time_s(),
            });
        }
        let outgoing = sim.frames_due()?;
        let sent_s = started.elapsed().as_secs_f64();
        bus.send_all(&outgoing)?;
        for frame in &outgoing {
            recorder.frame(sent_s, frame)?;
            stats.frames_sent += 1;
        }
        peers(sim.cycle())?;
        // No SYNC in real time: the bus (its fault layer) learns of the cycle here.
        bus.end_cycle()?;
        recorder.cycle(sim)?;
        if !observe(sim, &stats) {
            break;
        }
        let deadline = started + options.period.mul_f64((n + 1) as f64);
        let now = Instant::now();
        if now > deadline {
            stats.overruns += 1;
        } else {
            std::thread::sleep(deadline - now);
        }
    }
    stats.sim_s = sim.time_s();
    stats.set_wall(started.elapsed());
    Ok(stats)
}
