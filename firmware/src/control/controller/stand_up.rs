//! The stand-up's roll ahead. Unfolded from the wheels, the feet land behind their hips
//! (within the joint ranges no foot comes closer than 7 cm behind its hip at the depth of the
//! ground on the wheels) and sweep forward on the ground under the rising robot: they push it
//! back. So before the legs leave the fold the balance law rolls the robot ahead by about as
//! much, and the stand-up ends where it began.

use super::folding::half_sine_m_s;
use super::Controller;
use crate::time::Tick;

/// How far a stand-up from the wheels rolls the robot ahead first, m.
const STAND_PREROLL_M: f32 = 0.15;

/// Over how long, ms: a half-sine of speed.
const STAND_PREROLL_MS: u32 = 1_500;

impl Controller {
    /// The stand-up's speed reference, m/s: the roll ahead once it has begun, else none.
    pub(super) fn stand_preroll_m_s(&self, now: Tick) -> f32 {
        let Some(since) = self.stand_preroll else {
            return 0.0;
        };
        let t_s = now.since(since) as f32 * self.config.rate.period_s();
        half_sine_m_s(STAND_PREROLL_M, STAND_PREROLL_MS, t_s)
    }

    /// Whether the stand-up's roll ahead still runs at `now`; the first call of a stand-up
    /// (on the wheels, settled and stowed) begins it.
    pub(super) fn prerolling(&mut self, now: Tick) -> bool {
        let since = *self.stand_preroll.get_or_insert(now);
        now.since(since) < self.config.rate.ticks_from_ms(STAND_PREROLL_MS)
    }
}
