//! What the operator asked for. Mode requests are edges: a command acts when its mode differs
//! from the previous command's, so a teleop that keeps repeating `W` after a fault reset does
//! not restart the motion by itself — the operator has to press a key. Body height, speed
//! scale, speed and yaw rate are levels and apply on every command.
//!
//! On top of the edges sits the **restart interlock** (IEC 60204-1, no unexpected start-up):
//! after the controller starts, after an E-stop release and after the operator was lost, no
//! request but STOP acts until a STOP has arrived; then the next new request acts. A teleop
//! that was holding `W` through a controller restart therefore moves nothing until its
//! operator presses `X` and then `W`.

use protocol::{TeleopCommand, TeleopMode};

use crate::control::safety::Watchdog;
use crate::time::Tick;

/// The operator's latest wishes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Teleop {
    last_mode: Option<TeleopMode>,
    /// Body-height offset from the nominal stance, m (−0.10…+0.12 on the wire).
    pub body_height_m: f32,
    /// Speed scale, 0…1.
    pub speed_scale: f32,
    /// Ground speed for `Drive` and `Walk`, m/s, as sent (the controller applies its limits).
    pub speed_m_s: f32,
    /// Yaw rate, rad/s, + turning left, as sent (the controller applies its limits).
    pub yaw_rate_rad_s: f32,
    watchdog: Watchdog,
    alive: bool,
    interlocked: bool,
}

impl Teleop {
    /// No operator yet: full speed scale, nominal height, watchdog of `timeout_ticks`, and
    /// the interlock engaged.
    pub const fn new(timeout_ticks: u32) -> Self {
        Self {
            last_mode: None,
            body_height_m: 0.0,
            speed_scale: 1.0,
            speed_m_s: 0.0,
            yaw_rate_rad_s: 0.0,
            watchdog: Watchdog::new(timeout_ticks),
            alive: false,
            interlocked: true,
        }
    }

    /// Records a command; returns the mode if it is a new request the interlock lets through: a
    /// new STOP, or the STOP that releases the interlock; anything else only once released. A
    /// STOP repeated by an idle operator is not a new request (it resets no fault).
    pub fn command(&mut self, now: Tick, command: &TeleopCommand) -> Option<TeleopMode> {
        self.watchdog.feed(now);
        self.alive = true;
        self.body_height_m = command.body_height.si();
        self.speed_scale = crate::math::clamp(command.speed_scale.si() * 0.01, 0.0, 1.0);
        self.speed_m_s = command.speed.si();
        self.yaw_rate_rad_s = command.yaw_rate.si();
        let new = self.last_mode != Some(command.mode);
        self.last_mode = Some(command.mode);
        if command.mode == TeleopMode::Stop {
            let released = core::mem::replace(&mut self.interlocked, false);
            return (new || released).then_some(command.mode);
        }
        (new && !self.interlocked).then_some(command.mode)
    }

    /// Engages the interlock: nothing but STOP acts until a STOP arrives.
    pub fn interlock(&mut self) {
        self.interlocked = true;
    }

    /// Whether the interlock holds motion back until a STOP.
    pub fn interlocked(&self) -> bool {
        self.interlocked
    }

    /// Records a heartbeat.
    pub fn heartbeat(&mut self, now: Tick) {
        self.watchdog.feed(now);
        self.alive = true;
    }

    /// Whether the operator is silent at `now`.
    pub fn stale(&self, now: Tick) -> bool {
        self.watchdog.expired(now)
    }

    /// `true` exactly once when a live operator falls silent; engages the interlock.
    pub fn just_lost(&mut self, now: Tick) -> bool {
        if self.alive && self.stale(now) {
            self.alive = false;
            self.interlocked = true;
            true
        } else {
            false
        }
    }
}

#[cfg(test)]
mod tests {
    use protocol::{BodyHeight, SpeedScale};

    use super::*;

    fn command(mode: TeleopMode, speed_pct: u8) -> TeleopCommand {
        TeleopCommand {
            mode,
            body_height: BodyHeight::saturating_from_si(0.05),
            speed_scale: SpeedScale::from_raw(speed_pct)
                .unwrap_or(SpeedScale::saturating_from_si(0.0)),
            speed: Default::default(),
            yaw_rate: Default::default(),
        }
    }

    #[test]
    fn levels_apply_with_every_command_and_the_speed_is_a_fraction_of_the_full_speed() {
        let mut teleop = Teleop::new(100);
        assert_eq!(
            teleop.command(Tick(0), &command(TeleopMode::Stop, 50)),
            Some(TeleopMode::Stop)
        );
        assert!(
            (teleop.speed_scale - 0.5).abs() < 1e-6,
            "{}",
            teleop.speed_scale
        );
        assert!((teleop.body_height_m - 0.05).abs() < 1e-3);
        teleop.command(Tick(1), &command(TeleopMode::Stop, 100));
        assert!((teleop.speed_scale - 1.0).abs() < 1e-6);
        teleop.command(Tick(2), &command(TeleopMode::Stop, 0));
        assert_eq!(teleop.speed_scale, 0.0);
    }
}
