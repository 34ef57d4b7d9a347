//! A teleop node that follows a plan (time → mode) instead of a keyboard: it sends the current
//! command and a heartbeat at 50 Hz, as the interactive teleop does. Used by `sim-host run
//! --drive` and by tests.

use protocol::{
    AnyMessage, BodyHeight, E2eCounter, EncodeError, Frame, Millis, SpeedScale, TeleopCommand,
    TeleopHeartbeat, TeleopMode,
};

/// Teleop traffic period, µs (50 Hz).
pub const PERIOD_US: u64 = 20_000;

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
}

/// The scripted operator.
#[derive(Debug, Clone)]
pub struct ScriptedTeleop {
    plan: Vec<PlanStep>,
    next_send_us: u64,
    command_counter: E2eCounter,
    heartbeat_counter: E2eCounter,
}

impl ScriptedTeleop {
    /// An operator following `plan` (sorted by time here).
    pub fn new(mut plan: Vec<PlanStep>) -> Self {
        plan.sort_by_key(|s| s.at_us);
        Self {
            plan,
            next_send_us: 0,
            command_counter: E2eCounter::default(),
            heartbeat_counter: E2eCounter::default(),
        }
    }

    /// The step in force at `now_us`.
    pub fn current(&self, now_us: u64) -> Option<&PlanStep> {
        self.plan.iter().rev().find(|s| s.at_us <= now_us)
    }

    /// The frames to send at `now_us` (none between two 50 Hz slots).
    pub fn frames(&mut self, now_us: u64) -> Result<Vec<Frame>, EncodeError> {
        if now_us < self.next_send_us {
            return Ok(Vec::new());
        }
        self.next_send_us = now_us - now_us % PERIOD_US + PERIOD_US;
        let mut frames = Vec::with_capacity(2);
        if let Some(step) = self.current(now_us).copied() {
            let command = AnyMessage::TeleopCommand(TeleopCommand {
                mode: step.mode,
                body_height: BodyHeight::saturating_from_si(step.body_height_m),
                speed_scale: SpeedScale::saturating_from_si(step.speed_scale_pct),
            });
            frames.push(command.encode(self.command_counter.advance())?);
        }
        let uptime_ms = u32::try_from(now_us / 1000).unwrap_or(u32::MAX);
        let heartbeat = AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
            uptime: Millis::from_raw(uptime_ms).unwrap_or(Millis::saturating_from_si(0.0)),
        });
        frames.push(heartbeat.encode(self.heartbeat_counter.advance())?);
        Ok(frames)
    }
}
