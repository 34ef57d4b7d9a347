//! Scripted operation for shells and automation, on the wall clock: `teleop send KEY --for S`
//! holds one key, `teleop script FILE.toml` follows a scenario file (the format sim-host reads).
//! Both send the command and the heartbeat at 50 Hz like the interactive operator, listen to
//! the bus while they do, and end by going silent: the controller's operator watchdog then
//! stops the robot within 500 ms.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use host_can::bus::{Bus, BusError};
use protocol::{ControllerMode, EncodeError, Frame, MessageId};
use teleop_core::bus_status::BusStatus;
use teleop_core::keys::Action;
use teleop_core::operator::Operator;
use teleop_core::scenario::Scenario;
use teleop_core::scripted::ScriptedTeleop;

/// How often the script services the bus.
const SERVICE_PERIOD: Duration = Duration::from_millis(2);

/// Why a script failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ScriptError {
    /// The bus failed.
    #[error(transparent)]
    Bus(#[from] BusError),
    /// A frame could not be encoded (a bug: values are clamped to their wire ranges).
    #[error("a teleop frame could not be encoded: {0:?}")]
    Encode(EncodeError),
}

/// What a script did and heard.
#[derive(Debug, Clone, PartialEq)]
pub struct ScriptReport {
    /// Frames sent.
    pub frames_sent: u64,
    /// Frames heard from the other nodes.
    pub frames_heard: u64,
    /// The controller's mode in its last status, `None` if it never spoke.
    pub last_mode: Option<ControllerMode>,
    /// Whether the script was interrupted (Ctrl-C).
    pub interrupted: bool,
}

/// Presses `key` and keeps the command and heartbeat going for `hold`.
pub fn send(
    bus: &mut dyn Bus,
    key: Action,
    hold: Duration,
    stop: &AtomicBool,
) -> Result<ScriptReport, ScriptError> {
    let mut operator = Operator::new();
    operator.press(0, key);
    serve(bus, hold, stop, |now_ms, controller| {
        // An E-stop is sent again until the controller reports it.
        if let Some(mode) = controller {
            operator.observe_controller(mode);
        }
        operator.poll(now_ms)
    })
}

/// Follows `scenario` from now until its `duration_s`; `on_step` is told each step as it
/// starts.
pub fn run(
    bus: &mut dyn Bus,
    scenario: &Scenario,
    stop: &AtomicBool,
    mut on_step: impl FnMut(usize),
) -> Result<ScriptReport, ScriptError> {
    let mut teleop = ScriptedTeleop::new(scenario.plan());
    let mut started = 0;
    let hold = Duration::from_secs_f64(scenario.duration_s);
    serve(bus, hold, stop, |now_ms, _| {
        let now_us = now_ms.saturating_mul(1_000);
        while scenario
            .steps
            .get(started)
            .is_some_and(|s| s.plan.at_us <= now_us)
        {
            on_step(started);
            started += 1;
        }
        teleop.frames(now_us)
    })
}

fn serve(
    bus: &mut dyn Bus,
    hold: Duration,
    stop: &AtomicBool,
    mut frames_due: impl FnMut(u64, Option<ControllerMode>) -> Result<Vec<Frame>, EncodeError>,
) -> Result<ScriptReport, ScriptError> {
    let start = Instant::now();
    let mut status = BusStatus::default();
    let mut report = ScriptReport {
        frames_sent: 0,
        frames_heard: 0,
        last_mode: None,
        interrupted: false,
    };
    // The controller's mode from a status frame heard since the last pass (not a stored one:
    // a status from before an E-stop must not confirm it).
    let mut heard = None;
    loop {
        let now_ms = u64::try_from(start.elapsed().as_millis()).unwrap_or(u64::MAX);
        for frame in frames_due(now_ms, heard.take()).map_err(ScriptError::Encode)? {
            bus.send(&frame)?;
            report.frames_sent += 1;
        }
        for _ in 0..crate::MAX_FRAMES_PER_PASS {
            let Some(frame) = bus.recv(Duration::ZERO)? else {
                break;
            };
            status.observe(now_ms, &frame);
            report.frames_heard += 1;
            if frame.id() == MessageId::ControllerStatus.raw() {
                heard = status.controller(now_ms).map(|c| c.mode).or(heard);
            }
        }
        if let Some(controller) = status.controller(now_ms) {
            report.last_mode = Some(controller.mode);
        }
        if stop.load(Ordering::Relaxed) {
            report.interrupted = true;
            return Ok(report);
        }
        if start.elapsed() >= hold {
            return Ok(report);
        }
        std::thread::sleep(SERVICE_PERIOD);
    }
}
