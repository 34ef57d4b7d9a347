//! A teleop node that follows a plan (time → mode) instead of a keyboard: it sends the current
//! command and a heartbeat at 50 Hz, as the interactive teleop does. Used by `sim-host run
//! --drive` and by tests.
//!
//! The controller starts interlocked (no motion until a STOP, then a motion). A script arms it
//! on its own once, at its start: it sends STOP until the controller's status shows the
//! interlock released, then follows its plan — so scenario files need no STOP of their own.
//! It does not re-arm a controller that restarts or releases an E-stop later in the run: that
//! takes a STOP step in the plan, as it takes an operator's X.

use protocol::{
    AnyMessage, BodyHeight, EncodeError, FaultFlags, Frame, GroundSpeed, Millis, SpeedScale,
    TeleopCommand, TeleopHeartbeat, TeleopMode, YawRate, TEST_KEY,
};

use crate::link::OperatorLink;

/// Teleop traffic period, µs (50 Hz).
pub const PERIOD_US: u64 = 20_000;
/// The heartbeat goes out half a period after the command (as the interactive operator's).
pub const HEARTBEAT_OFFSET_US: u64 = crate::operator::HEARTBEAT_OFFSET_MS * 1000;

/// One step of a plan: from `at_us` on, command `mode`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanStep {
    /// Simulation time the step starts, µs.
    pub at_us: u64,
    /// The mode to command.
    pub mode: TeleopMode,
    /// Body-height offset, m (−0.10…+0.12).
    pub body_height_m: f32,
    /// Speed scale, % (0…100).
    pub speed_scale_pct: f32,
    /// Ground speed for `drive` and `walk`, m/s.
    pub speed_m_s: f32,
    /// Yaw rate, rad/s, + left: steers W, S, L, K, `drive` and `walk`.
    pub yaw_rate_rad_s: f32,
}

impl PlanStep {
    /// `mode` from `at_s` seconds on (rounded to the microsecond), at the neutral body height
    /// and full speed: the step of the report's keys.
    pub fn at(at_s: f64, mode: TeleopMode) -> Self {
        Self {
            at_us: (at_s * 1e6).round() as u64,
            mode,
            body_height_m: 0.0,
            speed_scale_pct: 100.0,
            speed_m_s: 0.0,
            yaw_rate_rad_s: 0.0,
        }
    }

    /// This step at `speed_scale_pct` of the mode's preset speed.
    pub fn with_speed_scale(self, speed_scale_pct: f32) -> Self {
        Self {
            speed_scale_pct,
            ..self
        }
    }

    /// This step with a ground speed and a yaw rate.
    pub fn with_velocity(self, speed_m_s: f32, yaw_rate_rad_s: f32) -> Self {
        Self {
            speed_m_s,
            yaw_rate_rad_s,
            ..self
        }
    }
}

/// The frames the operator sends at one moment: the command and the heartbeat at most, held
/// without the heap (a lockstep cycle allocates nothing).
pub type TeleopFrames = heapless::Vec<Frame, 2>;

/// The scripted operator.
#[derive(Debug, Clone)]
pub struct ScriptedTeleop {
    plan: Vec<PlanStep>,
    next_send_us: u64,
    next_heartbeat_us: u64,
    link: OperatorLink,
    /// Whether a STOP of the arming phase went out.
    stop_sent: bool,
    /// Whether the controller has been seen armed after that STOP: the plan is followed.
    armed: bool,
}

impl ScriptedTeleop {
    /// An operator following `plan` (sorted by time here), with the simulation's test key.
    pub fn new(plan: Vec<PlanStep>) -> Self {
        Self::with_link(plan, OperatorLink::new(TEST_KEY))
    }

    /// As [`ScriptedTeleop::new`], on `link`.
    pub fn with_link(mut plan: Vec<PlanStep>, link: OperatorLink) -> Self {
        plan.sort_by_key(|s| s.at_us);
        Self {
            plan,
            next_send_us: 0,
            next_heartbeat_us: HEARTBEAT_OFFSET_US,
            link,
            stop_sent: false,
            armed: false,
        }
    }

    /// Takes a frame heard on the bus: the controller's announcement and status.
    pub fn observe(&mut self, frame: &Frame) {
        if let Some(AnyMessage::ControllerStatus(status)) = self.link.observe(frame) {
            if self.stop_sent && !status.faults.contains(FaultFlags::AWAITING_STOP) {
                self.armed = true;
            }
        }
    }

    /// Whether the script has armed the controller and follows its plan.
    pub fn armed(&self) -> bool {
        self.armed
    }

    /// The step in force at `now_us`.
    pub fn current(&self, now_us: u64) -> Option<&PlanStep> {
        self.plan.iter().rev().find(|s| s.at_us <= now_us)
    }

    /// The frames to send at `now_us`: the command in its 50 Hz slots, the heartbeat in slots
    /// half a period later (as the interactive operator sends them).
    pub fn frames(&mut self, now_us: u64) -> Result<TeleopFrames, EncodeError> {
        let mut frames = TeleopFrames::new();
        if now_us >= self.next_send_us {
            self.next_send_us = now_us - now_us % PERIOD_US + PERIOD_US;
            if let Some(command) = self.command(now_us)? {
                let pushed = frames.push(command);
                debug_assert!(pushed.is_ok(), "room for the command and the heartbeat");
            }
        }
        if now_us >= self.next_heartbeat_us {
            // The next time after now at the heartbeat's phase of the period.
            let ahead = (HEARTBEAT_OFFSET_US + PERIOD_US - now_us % PERIOD_US) % PERIOD_US;
            self.next_heartbeat_us = now_us + if ahead == 0 { PERIOD_US } else { ahead };
            let uptime_ms = u32::try_from(now_us / 1000).unwrap_or(u32::MAX);
            let heartbeat = AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
                uptime: Millis::from_raw(uptime_ms).unwrap_or(Millis::saturating_from_si(0.0)),
            });
            if let Some(heartbeat) = self.link.seal(&heartbeat)? {
                let pushed = frames.push(heartbeat);
                debug_assert!(pushed.is_ok(), "room for the command and the heartbeat");
            }
        }
        Ok(frames)
    }

    /// The command of the plan's step in force at `now_us` (STOP until armed).
    fn command(&mut self, now_us: u64) -> Result<Option<Frame>, EncodeError> {
        let mut sent = None;
        if let Some(step) = self.current(now_us).copied() {
            let mode = if self.armed {
                step.mode
            } else {
                TeleopMode::Stop
            };
            let command = AnyMessage::TeleopCommand(TeleopCommand {
                mode,
                body_height: BodyHeight::saturating_from_si(step.body_height_m),
                speed_scale: SpeedScale::saturating_from_si(step.speed_scale_pct),
                speed: GroundSpeed::saturating_from_si(step.speed_m_s),
                yaw_rate: YawRate::saturating_from_si(step.yaw_rate_rad_s),
            });
            if let Some(frame) = self.link.seal(&command)? {
                self.stop_sent |= mode == TeleopMode::Stop;
                sent = Some(frame);
            }
        }
        Ok(sent)
    }
}
