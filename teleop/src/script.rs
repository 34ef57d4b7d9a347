//! Scripted operation for shells and automation, on the wall clock: `teleop send KEY --for S`
//! holds one key, `teleop script FILE.toml` follows a scenario file (the format sim-host reads),
//! `teleop pad --for S` follows a gamepad without a screen. All send the command and the heartbeat at 50 Hz like the interactive operator, listen to
//! the bus while they do, and end by going silent: the controller's operator watchdog then
//! stops the robot within 500 ms.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use host_can::bus::{Bus, BusError};
use protocol::{ControllerMode, EncodeError, Frame};
use teleop_core::bus_status::BusStatus;
use teleop_core::keys::Action;
use teleop_core::link::OperatorLink;
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

/// How long `send` keeps STOP before the key: two command periods, so that the controller's
/// interlock has seen the STOP before the motion arrives.
const ARM_MS: u64 = 2 * teleop_core::operator::PERIOD_MS;

/// Presses `key` (after a STOP, which the controller's interlock wants first) and keeps the command and heartbeat going for `hold`.
pub fn send(
    bus: &mut dyn Bus,
    bus_key: protocol::Key,
    key: Action,
    hold: Duration,
    stop: &AtomicBool,
) -> Result<ScriptReport, ScriptError> {
    let mut operator = Operator::with_link(OperatorLink::new(bus_key));
    // The controller starts interlocked: a motion key is sent after a STOP, as a script does.
    let motion = key;
    operator.press(0, Action::Mode(protocol::TeleopMode::Stop));
    // A latch goes out at once, before any session is joined.
    let mut pressed = matches!(motion, Action::EStop);
    if pressed {
        operator.press(0, motion);
    }
    // The motion goes ARM_MS after the session is joined, so that the STOP went out first.
    let mut joined_ms = None;
    serve(bus, hold, stop, |now_ms, heard| {
        for frame in heard {
            operator.observe(frame);
        }
        if operator.joined() && joined_ms.is_none() {
            joined_ms = Some(now_ms);
        }
        let armed = joined_ms.is_some_and(|t| now_ms >= t.saturating_add(ARM_MS));
        if !pressed && armed {
            operator.press(now_ms, motion);
            pressed = true;
        }
        operator.poll(now_ms)
    })
}

/// Follows `scenario` from now until its `duration_s`; `on_step` is told each step as it
/// starts.
pub fn run(
    bus: &mut dyn Bus,
    bus_key: protocol::Key,
    scenario: &Scenario,
    stop: &AtomicBool,
    mut on_step: impl FnMut(usize),
) -> Result<ScriptReport, ScriptError> {
    let mut teleop = ScriptedTeleop::with_link(scenario.plan(), OperatorLink::new(bus_key));
    let mut started = 0;
    let hold = Duration::from_secs_f64(scenario.duration_s);
    serve(bus, hold, stop, |now_ms, heard| {
        for frame in heard {
            teleop.observe(frame);
        }
        let now_us = now_ms.saturating_mul(1_000);
        while scenario
            .steps
            .get(started)
            .is_some_and(|s| s.plan.at_us <= now_us)
        {
            on_step(started);
            started += 1;
        }
        teleop
            .frames(now_us)
            .map(|frames| frames.into_iter().collect())
    })
}

/// Follows the gamepad `reader` for `hold` (or until `stop`); `on_action` is told each action
/// as it is taken, with the milliseconds since the start.
pub fn pad(
    bus: &mut dyn Bus,
    bus_key: protocol::Key,
    reader: &mut crate::gamepad::PadReader,
    hold: Duration,
    stop: &AtomicBool,
    mut on_action: impl FnMut(u64, &Action),
) -> Result<ScriptReport, ScriptError> {
    let mut operator = Operator::with_link(OperatorLink::new(bus_key));
    serve(bus, hold, stop, |now_ms, heard| {
        for frame in heard {
            operator.observe(frame);
        }
        for action in reader.poll(Instant::now()) {
            on_action(now_ms, &action);
            operator.press(now_ms, action);
        }
        operator.poll(now_ms)
    })
}

fn serve(
    bus: &mut dyn Bus,
    hold: Duration,
    stop: &AtomicBool,
    mut frames_due: impl FnMut(u64, &[Frame]) -> Result<Vec<Frame>, EncodeError>,
) -> Result<ScriptReport, ScriptError> {
    let start = Instant::now();
    let mut status = BusStatus::default();
    let mut report = ScriptReport {
        frames_sent: 0,
        frames_heard: 0,
        last_mode: None,
        interrupted: false,
    };
    // The frames heard since the last pass (a status heard before an E-stop must not confirm
    // it, so only new ones are handed on).
    let mut heard = Vec::new();
    loop {
        let now_ms = u64::try_from(start.elapsed().as_millis()).unwrap_or(u64::MAX);
        let due = frames_due(now_ms, &heard).map_err(ScriptError::Encode)?;
        heard.clear();
        for frame in due {
            bus.send(&frame)?;
            report.frames_sent += 1;
        }
        for _ in 0..crate::MAX_FRAMES_PER_PASS {
            let Some(frame) = bus.recv(Duration::ZERO)? else {
                break;
            };
            status.observe(now_ms, &frame);
            report.frames_heard += 1;
            heard.push(frame);
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
