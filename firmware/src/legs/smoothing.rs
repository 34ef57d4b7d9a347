//! The report's first-order smoothing `u += rate · (target − u) · dt` (section 6.4), with `dt`
//! one tick: the blend per tick is `α = rate / tick rate`, capped at 1 so a high rate at a low
//! tick rate cannot overshoot.

use crate::time::TickRate;

/// A first-order low-pass step toward a target.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Smoother {
    alpha: f32,
}

impl Smoother {
    /// The report's leg rate, 8 /s.
    pub const LEG_RATE_PER_S: f32 = 8.0;
    /// The report's fold rate, 6 /s.
    pub const FOLD_RATE_PER_S: f32 = 6.0;

    /// A smoother with `rate_per_s` (negative or NaN counts as 0: hold).
    pub fn new(rate_per_s: f32, rate: TickRate) -> Self {
        let alpha = rate_per_s * rate.period_s();
        let alpha = if alpha.is_finite() {
            crate::math::clamp(alpha, 0.0, 1.0)
        } else {
            0.0
        };
        Self { alpha }
    }

    /// The blend per tick.
    pub fn alpha(self) -> f32 {
        self.alpha
    }

    /// One tick from `current` toward `target`.
    pub fn step(self, current: f32, target: f32) -> f32 {
        current + self.alpha * (target - current)
    }
}
