//! The firmware's control core as a CAN node in a host process: frames in through a
//! [`Bus`], the [`Node`] decides, frames out. Two clocks:
//!
//! - **lockstep**: the simulator sends each cycle's feedback and then `SYNC(tick)`; on `SYNC`
//!   the runner computes that tick and answers with its commands. Nothing else paces it.
//! - **wall**: the runner keeps its own time at the control rate, as on the MCU, taking
//!   whatever arrived since the last tick.
//!
//! On a stop request (SIGINT/SIGTERM in the binary) it sends the drives a last command — zero
//! wheel torque, legs torque-free — rather than leave them to time out.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use firmware::config::Config;
use firmware::node::service::{self, Drain};
use firmware::node::Node;
use firmware::time::{Tick, TickRate};
use host_can::port::{BusPort, Wait};
use host_can::{Bus, BusError};
use protocol::{RejectCause, Session};

use crate::state::{StateError, StateFile};

/// Most frames taken in one call of the service loop: a bound for a flooded bus, far above
/// what one control period carries (a call that reaches it is simply followed by another).
/// 4096 frames are 0.4 s of a 10,000 frames/s flood.
const RX_LIMIT: u32 = 4096;

/// Lockstep: how long one call of the service loop waits for the simulator's frames before the
/// runner looks at its stop flag and idle timeout again.
const LOCKSTEP_POLL: Duration = Duration::from_millis(50);

/// Lockstep: how often the session is announced while no SYNC comes (a simulator started after
/// the firmware joins within this, then starts its clock).
const ANNOUNCE_IDLE: Duration = Duration::from_millis(100);

/// How the runner keeps time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Clock {
    /// Compute one tick per `SYNC` frame.
    Lockstep,
    /// Compute on the wall clock at the control rate, as on the microcontroller.
    Wall,
}

/// Runner settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunnerConfig {
    /// The session this controller opens (its key and this start's epoch).
    pub session: Session,
    /// Whether an E-stop was latched when the last run ended: the node starts latched.
    pub latched: bool,
    /// Clock.
    pub clock: Clock,
    /// Control rate, Hz.
    pub control_hz: u32,
    /// Stop after this many control ticks (`None`: until asked to stop).
    pub max_ticks: Option<u64>,
    /// Lockstep: give up when no `SYNC` arrives for this long.
    pub idle_timeout: Option<Duration>,
}

/// What a run did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RunnerStats {
    /// Control ticks computed.
    pub ticks: u64,
    /// Frames received.
    pub frames_in: u64,
    /// Frames sent.
    pub frames_out: u64,
    /// Frames the firmware rejected, by cause, in [`RejectCause::ALL`] order (unknown id, wrong
    /// length, CRC, out of range, repeated, wrong sequence, rate limited).
    pub rejected: [u64; RejectCause::ALL.len()],
    /// Wall clock: ticks lost because the runner woke in a later period than the one they were
    /// due in (the tick counter then runs slow, as on the MCU, instead of catching up in a burst).
    pub overruns: u64,
}

/// Why the runner stopped with an error.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RunnerError {
    /// The control rate is not one the firmware runs at.
    #[error("the firmware cannot run at {0} Hz (1…10000 Hz)")]
    Rate(u32),
    /// The firmware rejected its configuration.
    #[error("the firmware rejected its configuration: {0:?}")]
    Config(firmware::control::controller::ConfigError),
    /// The bus failed.
    #[error(transparent)]
    Bus(#[from] BusError),
    /// Lockstep: the simulator went quiet.
    #[error("no SYNC for {0:?}: is the simulator running on this bus in lockstep mode?")]
    NoSync(Duration),
    /// The state file could not be written.
    #[error(transparent)]
    State(#[from] StateError),
}

/// Runs the firmware on `bus` until `stop` is set, `max_ticks` are done, or an error. With a
/// `state` file, a change of the E-stop latch is written to it before the next tick.
pub fn run(
    bus: &mut dyn Bus,
    config: RunnerConfig,
    stop: &AtomicBool,
    state: Option<&mut StateFile>,
) -> Result<RunnerStats, RunnerError> {
    let rate = TickRate::new(config.control_hz).ok_or(RunnerError::Rate(config.control_hz))?;
    let mut node =
        Node::new(Config::ROBOT.at_rate(rate), config.session).map_err(RunnerError::Config)?;
    if config.latched {
        node.restore_latch(Tick(0));
    }
    let mut stats = RunnerStats::default();
    let mut keeper = LatchKeeper { state };
    let result = match config.clock {
        Clock::Lockstep => lockstep(bus, &mut node, config, stop, &mut stats, &mut keeper),
        Clock::Wall => wall(bus, &mut node, rate, config, stop, &mut stats, &mut keeper),
    };
    stats.rejected = node.reject_counters().rejected.map(|n| u64::from(n.raw()));
    send_stop(bus, &mut node, &mut stats)?;
    result.map(|()| stats)
}

/// Writes the latch to the state file when it changes.
struct LatchKeeper<'a> {
    state: Option<&'a mut StateFile>,
}

impl LatchKeeper<'_> {
    fn keep(&mut self, node: &Node) -> Result<(), RunnerError> {
        match self.state.as_deref_mut() {
            Some(state) => Ok(state.record_latch(node.estop_latched())?),
            None => Ok(()),
        }
    }
}

fn done(config: &RunnerConfig, stats: &RunnerStats, stop: &AtomicBool) -> bool {
    stop.load(Ordering::Relaxed) || config.max_ticks.is_some_and(|n| stats.ticks >= n)
}

fn lockstep(
    bus: &mut dyn Bus,
    node: &mut Node,
    config: RunnerConfig,
    stop: &AtomicBool,
    stats: &mut RunnerStats,
    keeper: &mut LatchKeeper<'_>,
) -> Result<(), RunnerError> {
    // Frames before a SYNC belong to the tick it names; until the first, to tick 0.
    let mut next = Tick(0);
    let mut last_sync = Instant::now();
    let mut last_announce: Option<Instant> = None;
    while !done(&config, stats, stop) {
        // Ticking, the node announces on its schedule; waiting for SYNC, the runner does.
        let idle = stats.ticks == 0 || last_sync.elapsed() >= ANNOUNCE_IDLE;
        if idle && last_announce.is_none_or(|t| t.elapsed() >= ANNOUNCE_IDLE) {
            if let Some(frame) = node.announce_frame() {
                let mut port = BusPort::new(&mut *bus, Wait::Never);
                stats.frames_out += u64::from(service::send_all(&mut port, &[frame])?);
            }
            last_announce = Some(Instant::now());
        }
        let mut port = BusPort::batching(&mut *bus, Wait::Until(Instant::now() + LOCKSTEP_POLL));
        let received = service::receive(node, next, &mut port, Drain::ThroughSync, RX_LIMIT)?;
        stats.frames_in += u64::from(received.frames);
        keeper.keep(node)?;
        let Some(sync_tick) = received.sync_tick else {
            if let Some(limit) = config.idle_timeout {
                if last_sync.elapsed() > limit {
                    return Err(RunnerError::NoSync(limit));
                }
            }
            continue;
        };
        last_sync = Instant::now();
        let tick = Tick(sync_tick);
        let sent = service::transmit(node, tick, &mut port)?;
        port.flush()?;
        stats.frames_out += u64::from(sent.sent);
        stats.ticks += 1;
        next = tick.plus(1);
    }
    Ok(())
}

fn wall(
    bus: &mut dyn Bus,
    node: &mut Node,
    rate: TickRate,
    config: RunnerConfig,
    stop: &AtomicBool,
    stats: &mut RunnerStats,
    keeper: &mut LatchKeeper<'_>,
) -> Result<(), RunnerError> {
    let period = Duration::from_nanos(1_000_000_000 / u64::from(rate.hz()));
    let start = Instant::now();
    let mut tick = Tick(0);
    // The period the next tick is due in; period `slot` begins at `start + slot * period`.
    let mut slot: u64 = 0;
    while !done(&config, stats, stop) {
        slot = current_slot(slot, start.elapsed(), period, &mut stats.overruns);
        let mut port = BusPort::batching(&mut *bus, Wait::Never);
        let received = service::receive(node, tick, &mut port, Drain::All, RX_LIMIT)?;
        stats.frames_in += u64::from(received.frames);
        keeper.keep(node)?;
        let sent = service::transmit(node, tick, &mut port)?;
        port.flush()?;
        stats.frames_out += u64::from(sent.sent);
        stats.ticks += 1;
        tick = tick.plus(1);
        bus.end_cycle()?;
        slot += 1;
        let deadline = start + slot_start(period, slot);
        // Wait for the next tick, taking frames as they come so that they are timely.
        while Instant::now() < deadline {
            let mut port = BusPort::new(&mut *bus, Wait::Until(deadline));
            let received = service::receive(node, tick, &mut port, Drain::All, RX_LIMIT)?;
            stats.frames_in += u64::from(received.frames);
        }
    }
    Ok(())
}

/// When period `slot` begins, counted from the start: `period × slot`, exact for any `u64`
/// slot (saturating only past `Duration::MAX`). A `u32` slot count would stop the clock after
/// 2^32 periods (49.7 days at 1 kHz) and run every later tick back to back.
pub fn slot_start(period: Duration, slot: u64) -> Duration {
    let nanos = period.as_nanos().saturating_mul(u128::from(slot));
    let secs = u64::try_from(nanos / 1_000_000_000).unwrap_or(u64::MAX);
    // The remainder is below 10^9, so it fits.
    let subsec = u32::try_from(nanos % 1_000_000_000).unwrap_or(0);
    Duration::new(secs, subsec)
}

/// The period a tick due in `slot` runs in, when it starts `elapsed` after the start. As the
/// MCU's SysTick loop does, a runner that woke in a later period runs the tick in that one and
/// loses the ticks of the periods it slept through (counted in `lost`) rather than bunching
/// them up: the core measures every timeout in ticks, and a burst of ticks with no frames
/// between them would age the feedback read just before it by the length of the stall. So
/// at most one tick runs per period.
pub fn current_slot(slot: u64, elapsed: Duration, period: Duration, lost: &mut u64) -> u64 {
    let now = u64::try_from(elapsed.as_nanos() / period.as_nanos().max(1)).unwrap_or(u64::MAX);
    if now > slot {
        *lost += now - slot;
        now
    } else {
        slot
    }
}

/// Zero wheel torque and torque-free legs, in sequence with the node's commands, so that the
/// drives stop now instead of after their 100 ms timeout.
fn send_stop(bus: &mut dyn Bus, node: &mut Node, stats: &mut RunnerStats) -> Result<(), BusError> {
    let mut port = BusPort::new(bus, Wait::Never);
    stats.frames_out += u64::from(service::send_all(&mut port, &node.stop_frames())?);
    Ok(())
}
