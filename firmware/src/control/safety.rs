//! The safety supervisor's parts: watchdogs in ticks, the last clamp every output passes, and
//! the deadline of the E-stop's controlled stop.

use protocol::{Joints, Leg};

use crate::limits::{Joint, JointLimits};
use crate::time::Tick;

/// An E-stop latch leaves the controller this long for its controlled stop (IEC 60204-1 stop
/// category 1, see [`crate::control::stop`]), ms: the drives start a timer of the same length on
/// the latch frame and cut their torque when it ends whatever they hear, so the controller
/// disables every drive itself at this deadline at the latest.
pub const SS1_DEADLINE_MS: u32 = 2_000;

/// Trips when nothing has fed it for `timeout_ticks`. A watchdog never fed counts as expired.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Watchdog {
    timeout_ticks: u32,
    last_fed: Option<Tick>,
}

impl Watchdog {
    /// A watchdog that has never been fed.
    pub const fn new(timeout_ticks: u32) -> Self {
        Self {
            timeout_ticks,
            last_fed: None,
        }
    }

    /// Records a sign of life at `now`.
    pub fn feed(&mut self, now: Tick) {
        self.last_fed = Some(now);
    }

    /// Whether it was ever fed.
    pub fn ever_fed(&self) -> bool {
        self.last_fed.is_some()
    }

    /// Ticks since the last feed (`None` if never fed).
    pub fn age_ticks(&self, now: Tick) -> Option<u32> {
        self.last_fed.map(|fed| now.since(fed))
    }

    /// Whether more than `timeout_ticks` have passed since the last feed, or it was never fed.
    pub fn expired(&self, now: Tick) -> bool {
        match self.age_ticks(now) {
            Some(age) => age > self.timeout_ticks,
            None => true,
        }
    }
}

/// Clamps the 16 leg targets into `limits`. A non-finite target is replaced by
/// `fallback` (the last safe target of that joint, itself clamped). Returns whether any value
/// was non-finite.
pub fn clamp_leg_targets(
    limits: &JointLimits,
    targets_rad: &mut Joints<f32>,
    fallback_rad: &Joints<f32>,
) -> bool {
    let mut replaced = false;
    for leg in Leg::ALL {
        let leg_targets = targets_rad.leg_mut(leg);
        let leg_fallbacks = fallback_rad.leg(leg);
        for ((target, fallback), joint) in leg_targets.iter_mut().zip(leg_fallbacks).zip(Joint::ALL)
        {
            replaced |= !target.is_finite();
            let fallback = if fallback.is_finite() { *fallback } else { 0.0 };
            *target = limits.range(joint).clamp(*target, fallback);
        }
    }
    replaced
}

/// Clamps wheel torques into ±`limit_nm`; non-finite torques become zero. Returns whether any
/// value was non-finite.
pub fn clamp_wheel_torques(limit_nm: f32, torques_nm: &mut [f32; 2]) -> bool {
    let limit = if limit_nm.is_finite() {
        limit_nm.abs()
    } else {
        0.0
    };
    let mut replaced = false;
    for torque in torques_nm.iter_mut() {
        if torque.is_finite() {
            *torque = crate::math::clamp(*torque, -limit, limit);
        } else {
            *torque = 0.0;
            replaced = true;
        }
    }
    replaced
}
