//! A joint-space move of the legs from one pose to another over a whole number of ticks, with a
//! smoothstep profile: every joint starts and ends at rest, and the fastest peaks at 1.5 times
//! its mean rate. The controlled stop and the moves between legs and wheels are made of these.

use protocol::Joints;

use crate::time::{Tick, TickRate};

/// A move from `from` to `to`, starting at `start`, over `ticks`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ramp {
    from: Joints<f32>,
    to: Joints<f32>,
    start: Tick,
    ticks: u32,
}

impl Ramp {
    /// From `from` to `to` starting at `start`, no joint faster than `peak_rate_rad_s`.
    pub fn new(
        from: Joints<f32>,
        to: Joints<f32>,
        start: Tick,
        peak_rate_rad_s: f32,
        rate: TickRate,
    ) -> Self {
        Self::over(
            from,
            to,
            start,
            ramp_ticks(&from, &to, peak_rate_rad_s, rate),
        )
    }

    /// From `from` to `to` starting at `start`, over `ticks` (0: at once).
    pub const fn over(from: Joints<f32>, to: Joints<f32>, start: Tick, ticks: u32) -> Self {
        Self {
            from,
            to,
            start,
            ticks,
        }
    }

    /// Where it starts.
    pub fn from(&self) -> &Joints<f32> {
        &self.from
    }

    /// How far along it is at `now`, 0…1 (in time, before the smoothstep).
    pub fn progress(&self, now: Tick) -> f32 {
        let elapsed = now.since(self.start);
        if elapsed >= self.ticks {
            1.0
        } else {
            elapsed as f32 / self.ticks as f32
        }
    }

    /// The pose at `now`, and whether the ramp is over.
    pub fn at(&self, now: Tick) -> (Joints<f32>, bool) {
        self.at_warped(now, 0.0)
    }

    /// As [`Ramp::at`], with time warped so that the middle of the move goes `1 − slow` times
    /// as fast as an even pace and its ends `1 + 2 slow` times (`slow` within 0…1; 0: no warp):
    /// for a move whose middle is where it pushes hardest.
    pub fn at_warped(&self, now: Tick, slow: f32) -> (Joints<f32>, bool) {
        if now.since(self.start) >= self.ticks {
            return (self.to, true);
        }
        let c = crate::math::clamp(slow, 0.0, 1.0);
        let d = self.progress(now) - 0.5;
        let s = 0.5 + d * (1.0 - c) + 4.0 * c * d * d * d;
        let blend = crate::math::smoothstep(s);
        let mut pose = self.from;
        for (joint, goal) in pose.iter_mut().zip(self.to.iter()) {
            *joint += blend * (goal - *joint);
        }
        (pose, false)
    }
}

/// Ticks for a smoothstep ramp from `from` to `to` whose fastest joint peaks at
/// `peak_rate_rad_s` (a non-finite or non-positive rate, or a non-finite pose, gives 0: jump).
pub fn ramp_ticks(
    from: &Joints<f32>,
    to: &Joints<f32>,
    peak_rate_rad_s: f32,
    rate: TickRate,
) -> u32 {
    let largest = from
        .iter()
        .zip(to.iter())
        .map(|(a, b)| (b - a).abs())
        .fold(0.0_f32, f32::max);
    // Smoothstep peaks at 1.5 × the mean rate.
    let seconds = 1.5 * largest / peak_rate_rad_s;
    let ticks = seconds * rate.hz() as f32;
    if !(ticks.is_finite() && ticks > 0.0) {
        return 0;
    }
    // Rounded up (the cast truncates, and saturates past u32::MAX).
    let whole = ticks as u32;
    if (whole as f32) < ticks {
        whole.saturating_add(1)
    } else {
        whole
    }
}
