//! What the operator asked for. Mode requests are edges: a command acts when its mode differs
//! from the previous command's, so a teleop that keeps repeating `W` after an E-stop clear, a
//! fault reset or a lost heartbeat does not restart the motion by itself — the operator has to
//! press a key. Body height and speed scale are levels and apply on every command.

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
    watchdog: Watchdog,
    alive: bool,
}

impl Teleop {
    /// No operator yet: full speed scale, nominal height, watchdog of `timeout_ticks`.
    pub const fn new(timeout_ticks: u32) -> Self {
        Self {
            last_mode: None,
            body_height_m: 0.0,
            speed_scale: 1.0,
            watchdog: Watchdog::new(timeout_ticks),
            alive: false,
        }
    }

    /// Records a command; returns the mode if it is a new request.
    pub fn command(&mut self, now: Tick, command: &TeleopCommand) -> Option<TeleopMode> {
        self.watchdog.feed(now);
        self.alive = true;
        self.body_height_m = command.body_height.si();
        self.speed_scale = crate::math::clamp(command.speed_scale.si() * 0.01, 0.0, 1.0);
        let new = self.last_mode != Some(command.mode);
        self.last_mode = Some(command.mode);
        new.then_some(command.mode)
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

    /// `true` exactly once when a live operator falls silent.
    pub fn just_lost(&mut self, now: Tick) -> bool {
        if self.alive && self.stale(now) {
            self.alive = false;
            true
        } else {
            false
        }
    }

    /// Ticks since the operator was last heard (`None` if never).
    pub fn age_ticks(&self, now: Tick) -> Option<u32> {
        self.watchdog.age_ticks(now)
    }
}
