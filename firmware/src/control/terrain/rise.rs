//! The ground behind a trot, as the rangefinder sees it: whether it rises ahead of the back
//! feet (a riser or a slope up that the trot cannot take).
//!
//! Walking, the rangefinder's spot lies about 0.85 m behind the axle, 0.6 m behind the back
//! feet. Its height is taken over the line through the feet that stand (the controller's
//! part, from the encoders), averaged over one stride, and compared with the averages of the
//! last 3.2 s: ground that stands [`RiseConfig::rise_m`] higher for a second has risen. Not
//! against zero: each robot's stance puts the spot's height a few centimetres either way on
//! flat ground. So a riser already nearer than the spot when the watch starts (the trot's
//! first 4 s, 0.3–0.4 m) is never seen to rise, and only the feet find it
//! ([`crate::legs::blocked`]). Measured in docs/obstacles.md.

use crate::legs::hips::HipLayout;

/// Rangings averaged for one height: one stride of the 1 Hz trot at the part's 50 Hz (over
/// half a stride the averages swung by ±3 cm with the stride).
pub const RISE_WINDOW: usize = 50;

/// Rangings a walk takes before its averages count, 3 s at the part's 50 Hz: as the trot
/// starts, its stride and the body's sway settle (robot 50 stopped on flat ground 5 s into
/// its trot with 1 s).
pub const SETTLE_RANGINGS: usize = 150;

/// Rangings in a row that must read the ground risen, a second: the body sways over two
/// strides by up to 4 cm of the spot's height (robot 25), which a riser's plateau does not
/// undo.
pub const RISEN_RANGINGS: usize = 50;

/// Averages kept to compare the present one with: one every [`HISTORY_EVERY`] rangings.
pub const HISTORY: usize = 16;

/// Rangings between two kept averages: with [`HISTORY`], the last 3.2 s.
pub const HISTORY_EVERY: usize = 10;

/// Heights are clamped to this either way, m: a riser the trot cannot take is 5–30 cm.
const HEIGHT_LIMIT_M: f32 = 0.3;

/// Rangings before the watch judges: the settling and one full window.
const READY: usize = SETTLE_RANGINGS + RISE_WINDOW;

/// A whole number of windows and of the history's turns, 16 s: past [`READY`] the count
/// wraps by it, so that a trot of any length keeps every index it gives running unbroken.
const COUNT_PERIOD: usize = 800;

/// Tunables of the watch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RiseConfig {
    /// The present average this far above the lowest of the last 3.2 s is ground that
    /// rises, m.
    pub rise_m: f32,
    /// Where the hips are on the torso: the feet that give the ground's line.
    pub hips: HipLayout,
}

impl RiseConfig {
    /// The robot: the steps are 5–7 cm; flat ground's sway stays under it once
    /// [`RISEN_RANGINGS`] ask it to last.
    pub const ROBOT: Self = Self {
        rise_m: 0.035,
        hips: HipLayout::ROBOT,
    };
}

/// The watch: the last [`RISE_WINDOW`] heights and the averages of the last 3.2 s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RiseWatch {
    heights_m: [f32; RISE_WINDOW],
    averages_m: [f32; HISTORY],
    count: usize,
    /// Rangings in a row that have read the ground risen.
    risen: usize,
    /// Whether the ground has risen since the last reset: what the watch saw is kept while
    /// the robot stands (see [`RiseWatch::latched`]).
    latched: bool,
}

impl Default for RiseWatch {
    fn default() -> Self {
        Self {
            heights_m: [0.0; RISE_WINDOW],
            averages_m: [f32::INFINITY; HISTORY],
            count: 0,
            risen: 0,
            latched: false,
        }
    }
}

impl RiseWatch {
    /// Whether the watch has taken no height since it was made or reset.
    pub fn fresh(&self) -> bool {
        self.count == 0
    }

    /// Forgets every height (in place: the watch is large for the control step's stack).
    pub fn reset(&mut self) {
        self.heights_m.fill(0.0);
        self.averages_m.fill(f32::INFINITY);
        self.count = 0;
        self.risen = 0;
        self.latched = false;
    }

    /// Whether the ground has risen since the last reset. The controller keeps such a watch
    /// through the stop it caused: walked back again, the robot still has the riser behind it
    /// and stops again at its next ranging, instead of walking its feet onto the riser while
    /// a fresh watch settles.
    pub fn latched(&self) -> bool {
        self.latched
    }

    /// Takes one height of the ground where the spot meets it, m (any fixed origin: the
    /// watch compares heights only with each other); whether the ground has risen. A
    /// non-finite height is skipped.
    ///
    /// The ground rises where the present average has stood [`RiseConfig::rise_m`] above
    /// the lowest average of the last 3.2 s for [`RISEN_RANGINGS`]: a riser's face lifts the
    /// spot 5–7 cm while the robot backs 0.15 m (the beam's grade), under 1.5 s at the trot's
    /// pace, and the plateau keeps it there.
    pub fn update(&mut self, config: &RiseConfig, height_m: f32) -> bool {
        if !height_m.is_finite() {
            return false;
        }
        // A stray long or short ranging (the beam past an edge, a foot in it) moves one
        // stride's average by at most a fiftieth of this.
        let height_m = crate::math::clamp(height_m, -HEIGHT_LIMIT_M, HEIGHT_LIMIT_M);
        if let Some(slot) = self.heights_m.get_mut(self.count % RISE_WINDOW) {
            *slot = height_m;
        }
        self.count = self.count.saturating_add(1);
        if self.count >= READY + COUNT_PERIOD {
            self.count -= COUNT_PERIOD;
        }
        if self.count < READY {
            return false;
        }
        let average_m = self.heights_m.iter().sum::<f32>() / RISE_WINDOW as f32;
        let lowest_m = self
            .averages_m
            .iter()
            .copied()
            .fold(f32::INFINITY, f32::min);
        if self.count % HISTORY_EVERY == 0 {
            let kept = (self.count / HISTORY_EVERY) % HISTORY;
            if let Some(slot) = self.averages_m.get_mut(kept) {
                *slot = average_m;
            }
        }
        self.risen = if average_m - lowest_m > config.rise_m {
            self.risen.saturating_add(1)
        } else {
            0
        };
        // Once risen, the count stays: a latched watch walked on judges at once.
        self.latched |= self.risen >= RISEN_RANGINGS;
        self.risen >= RISEN_RANGINGS
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::default_numeric_fallback)]

    use super::*;

    const CONFIG: RiseConfig = RiseConfig::ROBOT;

    /// A trot's bob on flat ground: ±4 cm around `base_m` over one stride ([`RISE_WINDOW`]).
    fn bobbing(n: usize, base_m: f32) -> impl Iterator<Item = f32> {
        swaying(n, base_m, 0.04, RISE_WINDOW)
    }

    /// `base_m` ± `amplitude_m`, a square wave of `period` rangings.
    fn swaying(
        n: usize,
        base_m: f32,
        amplitude_m: f32,
        period: usize,
    ) -> impl Iterator<Item = f32> {
        (0..n).map(move |i| {
            let up = (i % period) * 2 < period;
            base_m + if up { amplitude_m } else { -amplitude_m }
        })
    }

    #[test]
    fn flat_ground_bobbing_by_four_centimetres_never_rises() {
        let mut watch = RiseWatch::default();
        // The level is what the robot sees, however far from zero.
        assert!(bobbing(2_000, 0.07).all(|h| !watch.update(&CONFIG, h)));
    }

    #[test]
    fn a_sway_over_two_strides_rises_only_if_it_lasts() {
        // ±2 cm over two strides: the averages swing by nearly 4 cm, past the threshold, but
        // never for a whole second.
        let mut watch = RiseWatch::default();
        assert!(swaying(3_000, 0.0, 0.02, 2 * RISE_WINDOW).all(|h| !watch.update(&CONFIG, h)));
        // Over four strides the same sway stays up long enough, and counts.
        let mut watch = RiseWatch::default();
        assert!(swaying(3_000, 0.0, 0.03, 8 * RISE_WINDOW).any(|h| watch.update(&CONFIG, h)));
    }

    #[test]
    fn a_riser_met_while_the_trot_settles_is_its_level() {
        // The spot climbs a riser 1.5 s into the settling: the watch starts on the
        // plateau, and the plateau does not rise (without the settling it would).
        let mut watch = RiseWatch::default();
        let riser = bobbing(75, 0.0).chain(bobbing(2_000, 0.1));
        assert!(riser.into_iter().all(|h| !watch.update(&CONFIG, h)));
    }

    #[test]
    fn a_riser_five_centimetres_up_rises_within_two_strides_of_the_spot_reaching_it() {
        let mut watch = RiseWatch::default();
        for h in bobbing(200, -0.03) {
            assert!(!watch.update(&CONFIG, h));
        }
        let rose_after = bobbing(200, 0.02).position(|h| watch.update(&CONFIG, h));
        let within = RISE_WINDOW + RISEN_RANGINGS;
        assert!(rose_after.is_some_and(|n| n <= within), "{rose_after:?}");
    }

    #[test]
    fn a_slow_rise_is_no_riser_however_far_it_goes() {
        let mut watch = RiseWatch::default();
        // 0.8 cm a second (the spot on a 5° slope at the trot's 0.1 m/s): 16 cm in 20 s.
        let rising = bobbing(1_000, 0.0)
            .enumerate()
            .map(|(i, h)| h + 0.00016 * i as f32);
        assert!(rising.into_iter().all(|h| !watch.update(&CONFIG, h)));
    }

    #[test]
    fn the_count_wraps_by_whole_windows_and_history_turns() {
        assert_eq!(COUNT_PERIOD % RISE_WINDOW, 0);
        assert_eq!(COUNT_PERIOD % (HISTORY * HISTORY_EVERY), 0);
        let mut watch = RiseWatch::default();
        // Ten minutes of trot on flat ground, then a riser: seen as on the first minute.
        assert!(bobbing(30_000, 0.0).all(|h| !watch.update(&CONFIG, h)));
        assert!(watch.count < READY + COUNT_PERIOD);
        let rose_after = bobbing(200, 0.05).position(|h| watch.update(&CONFIG, h));
        let within = RISE_WINDOW + RISEN_RANGINGS;
        assert!(rose_after.is_some_and(|n| n <= within), "{rose_after:?}");
    }

    #[test]
    fn a_non_finite_height_is_skipped_and_a_reset_forgets_what_was_seen() {
        let mut watch = RiseWatch::default();
        assert!(!watch.update(&CONFIG, f32::NAN));
        assert!(watch.fresh());
        for h in bobbing(2 * READY, 0.0) {
            assert!(!watch.update(&CONFIG, h));
        }
        // Without a reset, ground 10 cm higher rises and latches.
        let mut kept = watch;
        assert!(bobbing(READY, 0.1).any(|h| kept.update(&CONFIG, h)));
        assert!(kept.latched());
        // After one, it is where the robot now is: no rise.
        watch.reset();
        assert!(watch.fresh() && !watch.latched());
        assert!(bobbing(2 * READY, 0.1).all(|h| !watch.update(&CONFIG, h)));
    }

    #[test]
    fn a_latched_watch_walked_on_rises_again_at_once() {
        let mut watch = RiseWatch::default();
        for h in bobbing(2 * READY, 0.0) {
            watch.update(&CONFIG, h);
        }
        let rose_after = bobbing(READY, 0.06).position(|h| watch.update(&CONFIG, h));
        assert!(rose_after.is_some() && watch.latched());
        // Walked back on toward the riser: the same heights, still risen.
        let again = bobbing(READY, 0.06).position(|h| watch.update(&CONFIG, h));
        assert_eq!(again, Some(0));
    }
}
