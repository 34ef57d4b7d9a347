//! Gait phase as a wrapping integer: one full cycle is 2^32 counts.
//!
//! An ever-growing float time `t` loses resolution with uptime (an `f32` holding 36 000 s has
//! 4 ms steps), so the gait would change character after hours. Here the phase advances by an
//! exact rational step per tick — a whole part plus a Bresenham remainder — so the phase after
//! `n` ticks is exactly `floor(n · f / rate · 2^32) mod 2^32`, whatever `n`.

use crate::time::TickRate;

/// Counts per cycle: the phase is a `u32`, so one cycle is its full range.
const COUNTS_PER_CYCLE: u64 = 1 << 32;

/// How far the phase moves per tick: `whole + numerator / denominator` counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PhaseStep {
    whole: u32,
    numerator: u32,
    denominator: u32,
}

impl PhaseStep {
    /// The step for a cycle of `frequency_millihz` millihertz at `rate`. `None` if the frequency is
    /// zero or not below the tick rate (the phase would alias).
    pub const fn new(frequency_millihz: u32, rate: TickRate) -> Option<Self> {
        let denominator = rate.hz() as u64 * 1000;
        if frequency_millihz == 0 || frequency_millihz as u64 >= denominator {
            return None;
        }
        let counts = frequency_millihz as u64 * COUNTS_PER_CYCLE;
        let whole = counts / denominator;
        let numerator = counts % denominator;
        if whole > u32::MAX as u64 || denominator > u32::MAX as u64 {
            return None;
        }
        Some(Self {
            whole: whole as u32,
            numerator: numerator as u32,
            denominator: denominator as u32,
        })
    }
}

/// A phase in `[0, 1)` cycle, stored as `count / 2^32`, plus the fractional remainder of the
/// steps so far.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Phase {
    count: u32,
    remainder: u32,
}

impl Phase {
    /// A phase at `count / 2^32` of a cycle.
    pub const fn from_count(count: u32) -> Self {
        Self {
            count,
            remainder: 0,
        }
    }

    /// The raw phase, `count / 2^32` of a cycle.
    pub const fn count(self) -> u32 {
        self.count
    }

    /// Advances by one tick's step.
    pub fn advance(&mut self, step: PhaseStep) {
        self.count = self.count.wrapping_add(step.whole);
        // remainder < denominator ≤ u32::MAX / 2 + numerator < denominator: no overflow in u64.
        let remainder = self.remainder as u64 + step.numerator as u64;
        if remainder >= step.denominator as u64 {
            self.count = self.count.wrapping_add(1);
            self.remainder = (remainder - step.denominator as u64) as u32;
        } else {
            self.remainder = remainder as u32;
        }
    }

    /// The phase `ticks` steps after the start, computed directly — equal to calling
    /// [`Phase::advance`] `ticks` times from [`Phase::default`].
    pub const fn after(step: PhaseStep, ticks: u64) -> Self {
        // ticks · (whole · den + num) / den, in u128 so 10 years at 10 kHz cannot overflow.
        let per_tick = step.whole as u128 * step.denominator as u128 + step.numerator as u128;
        let total = ticks as u128 * per_tick;
        let den = step.denominator as u128;
        Self {
            count: ((total / den) % COUNTS_PER_CYCLE as u128) as u32,
            remainder: (total % den) as u32,
        }
    }

    /// This phase shifted by `offset_count / 2^32` of a cycle.
    pub const fn shifted(self, offset_count: u32) -> Self {
        Self {
            count: self.count.wrapping_add(offset_count),
            remainder: self.remainder,
        }
    }

    /// This phase mirrored (`1 − phase`): the same cycle run backward in time.
    pub const fn reversed(self) -> Self {
        Self {
            count: self.count.wrapping_neg(),
            remainder: 0,
        }
    }

    /// The phase as a fraction of the cycle, `0 ≤ f < 1`, resolution 2^-24.
    pub fn fraction(self) -> f32 {
        (self.count >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// The phase as an angle, `0 ≤ a < 2π` rad.
    pub fn radians(self) -> f32 {
        self.fraction() * core::f32::consts::TAU
    }
}

/// Half a cycle: the offset between the two diagonal pairs of a trot.
pub const HALF_CYCLE: u32 = 1 << 31;
