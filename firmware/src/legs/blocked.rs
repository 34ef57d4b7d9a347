//! A trot that meets what it cannot step over: the leading feet, stopped by a riser, land
//! behind where their swing was sent.
//!
//! # Why
//!
//! The trot lifts its feet 4 cm. Walked into a taller step, the front feet hit the riser on
//! every swing and the robot marks time against it for as long as the operator holds the key
//! (in the simulator, 25 s against a 6 cm and a 10 cm step alike). Nothing in the trot sees it:
//! the gait runs open loop on its phase.
//!
//! # How
//!
//! Blind, from the drives' encoders: when a front foot of a forward trot is
//! [`BlockedConfig::at_swing`] of the way through its swing, where its measured joints put it
//! is compared with where its target is, along the walking direction. Measured in the
//! simulator at 70 % of the swing, the campaign's robots as built (heavy legs, drives rated
//! low, transport delay, the chip's offsets): on flat ground, over 200 robots and 3,200
//! swings, the foot is 0.4 cm behind at the median, 1.4 cm at the 99th percentile and 3.7 cm
//! at worst; against a 9–11 cm riser, over 30 robots, a blocked foot is 2.5–7.6 cm behind.
//! Later in the swing a robot pitched nose down lands its front feet early on flat ground,
//! and they are up to 8 cm behind at touchdown: that is not a riser. A riser also pushes the
//! robot back, so that the next swing of the same foot often goes free, and often only one
//! front foot meets it. So each front leg keeps its own count, up one for a swing behind by
//! more than [`BlockedConfig::lag_m`] and down one for a free swing, and
//! [`BlockedConfig::count`] of it stops the trot; a foot more than
//! [`BlockedConfig::at_once_m`] behind stops it at once. Over the same swings this rule
//! stops none of the 200 flat-ground trots and all 30 at the riser. The controller then
//! stands and reports [`protocol::FaultFlags::LEG_BLOCKED`] until the operator asks for
//! something else.
//!
//! A robot can also settle where its leading feet reach the riser only just: robot 3 of the
//! tests (with a form of the estimator since set aside), against a 10.8 cm step, marked time
//! there for 15 s, each front foot 1.4–2.1 cm behind on every swing, under the count's
//! threshold. So a foot behind by more than [`BlockedConfig::held_lag_m`] on
//! [`BlockedConfig::held_swings`] swings in a row stops the trot too: on flat ground (robots
//! 0–99, 20 s each way at full stride, straight), no foot was behind by that much on more than
//! one forward swing in a row, nor on more than three backward (robot 94, already rolling
//! over). Not measured at lower speed or turning, where the lag is scaled up.
//!
//! Walking backward the back feet lead and are watched the same way, except that a single
//! swing counts at once from [`BlockedConfig::backward_at_once_m`]. Measured at 70 % of the
//! swing over 16 campaign robots (384 swings of 12 s of `K` on flat ground), a back foot is
//! 0.3 cm behind at the median, 1.8 cm at the 99th percentile and 2.8 cm at worst; against a
//! riser behind the robot, 1.5–4.7 cm, and the swings that meet it alternate with free ones,
//! so the count alone let 7 of 16 trots into a 6 cm riser fall before it reached two. (The
//! swing's share runs backward with the phase: [`crate::legs::gait::Trot::swing_share`]
//! counts it from lift-off in both directions.)

use protocol::Leg;

use crate::control::fsm::Direction;
use crate::legs::kinematics::{leg_fk, LegGeometry, LegJoints};

/// Tunables of the blocked-swing watch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlockedConfig {
    /// How far through its swing a leading foot is measured (0…1).
    pub at_swing: f32,
    /// How far behind its target a leading foot may be there, m.
    pub lag_m: f32,
    /// A foot this far behind there stops the trot at once, m: a riser that pushes the robot
    /// back lets every other swing go free, and a count rises slowly.
    pub at_once_m: f32,
    /// The count of one leg (up one per blocked swing, down one per free swing) that stops
    /// the trot (0: never).
    pub count: u8,
    /// The lowest stride share (0…1: the leg's fore–aft stride as a share of the full one —
    /// the speed scale walking straight, less for the inner legs of a turn) the watch runs
    /// at; a lag is divided by the share, which it is proportional to, before it is compared
    /// with the thresholds.
    /// Measured at 50 % and 30 %: none of 100 flat-ground trots stopped, 16 and 14 of 16
    /// trots into a 9–11 cm riser did (the other two had not reached it in 28 s); at 20 %
    /// none reached it.
    pub min_scale: f32,
    /// Walking backward, a back foot this far behind its target stops the trot at once, m.
    /// Against a riser behind, a foot that meets it is 1.5–4.7 cm behind, and a count of two
    /// came too late for 7 of 16 trots; on flat ground 16 robots' worst was 2.8 cm, and of the
    /// campaign's 500 `K` runs 3 stop short (safe aborts) and one is stopped already tipping;
    /// at 4 cm, 7 of 16 riser trots fell.
    pub backward_at_once_m: f32,
    /// Swings of each leading leg that do not stop the trot at once after the counts start
    /// afresh (a trot starting, or turning back); they count as any other. The start rocks the
    /// torso up to 6°, and one swing so far behind stopped 4 of 200 robots trotting backward
    /// on flat ground, 0.8 s into the trot; a riser met at once still stops it by the count.
    /// (The count of swings saturates at 255.)
    pub settle_swings: u8,
    /// A foot behind by more than this on every one of [`BlockedConfig::held_swings`] swings
    /// in a row stops the trot, m: a robot can settle where its feet reach the riser only
    /// just, and mark time there for good with each swing short of the count's threshold.
    pub held_lag_m: f32,
    /// See [`BlockedConfig::held_lag_m`] (0: never).
    pub held_swings: u8,
}

impl BlockedConfig {
    /// The robot: at 70 % of the swing, 2.5 cm and a count of two (a second at the trot's
    /// 1 Hz at the soonest), and at once from 5 cm (flat ground's worst is 3.7 cm), from a
    /// quarter of full speed up.
    pub const ROBOT: Self = Self {
        at_swing: 0.7,
        lag_m: 0.025,
        at_once_m: 0.05,
        count: 2,
        min_scale: 0.25,
        backward_at_once_m: 0.035,
        settle_swings: 1,
        held_lag_m: 0.012,
        held_swings: 4,
    };
}

/// Each leg's count of blocked swings, in [`Leg`]'s index order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BlockedSwings {
    legs: [LegSwings; 4],
}

/// One leading leg's swings since the counts started.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
struct LegSwings {
    /// Up one per blocked swing, down one per free swing.
    count: u8,
    /// Swings measured, saturating.
    swings: u8,
    /// Swings in a row behind by more than [`BlockedConfig::held_lag_m`], saturating.
    held: u8,
}

impl LegSwings {
    const NEW: Self = Self {
        count: 0,
        swings: 0,
        held: 0,
    };
}

impl BlockedSwings {
    /// Nothing counted.
    pub const fn new() -> Self {
        Self {
            legs: [LegSwings::NEW; 4],
        }
    }

    /// Starts counting again (a new trot).
    pub fn reset(&mut self) {
        *self = Self::new();
    }

    /// `leg`'s foot was measured `lag_m` behind its target along the walking direction at
    /// [`BlockedConfig::at_swing`]; whether the trot is now blocked.
    pub fn swing_measured(
        &mut self,
        config: &BlockedConfig,
        leg: Leg,
        lag_m: f32,
        direction: Direction,
    ) -> bool {
        let at_once_m = match direction {
            Direction::Forward => config.at_once_m,
            Direction::Backward => config.backward_at_once_m,
        };
        let Some(this) = self.legs.get_mut(leg as usize) else {
            return false;
        };
        this.swings = this.swings.saturating_add(1);
        let settled = this.swings > config.settle_swings;
        this.held = if lag_m > config.held_lag_m {
            this.held.saturating_add(1)
        } else {
            0
        };
        this.count = if settled && lag_m > at_once_m {
            config.count
        } else if lag_m > config.lag_m {
            this.count.saturating_add(1)
        } else {
            this.count.saturating_sub(1)
        };
        (config.held_swings > 0 && this.held >= config.held_swings)
            || (config.count > 0 && this.count >= config.count)
    }

    /// `leg`'s count.
    pub fn count(&self, leg: Leg) -> u8 {
        self.legs.get(leg as usize).map_or(0, |this| this.count)
    }
}

/// How far the foot at `measured` is behind the foot at `target`, m, along `sign` (+1 forward,
/// −1 backward); non-finite joints give 0 (not blocked).
pub fn lag_m(geometry: &LegGeometry, target: &LegJoints, measured: &LegJoints, sign: f32) -> f32 {
    let lag = sign * (leg_fk(geometry, target).x_m - leg_fk(geometry, measured).x_m);
    if lag.is_finite() {
        lag
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The robot's watch, judging from the first swing.
    const JUDGING: BlockedConfig = BlockedConfig {
        settle_swings: 0,
        ..BlockedConfig::ROBOT
    };

    #[test]
    fn each_leg_counts_its_own_blocked_swings_and_a_free_one_counts_down() {
        let config = JUDGING;
        let mut swings = BlockedSwings::new();
        // Only the left front foot meets the riser; the right one swings free.
        let mut stopped = false;
        for lag in [0.03, 0.005, 0.03, 0.004, 0.03, 0.04] {
            assert!(!stopped);
            stopped = swings.swing_measured(&config, Leg::Fl, lag, Direction::Forward);
            assert!(!swings.swing_measured(&config, Leg::Fr, 0.004, Direction::Forward));
        }
        assert!(stopped, "up, down, up, down, up, up: a count of two");
        assert_eq!(swings.count(Leg::Fr), 0);
        swings.reset();
        assert_eq!(swings.count(Leg::Fl), 0);
        assert!(
            swings.swing_measured(&config, Leg::Fr, 0.051, Direction::Forward),
            "far behind: at once"
        );
        let never = BlockedConfig {
            count: 0,
            held_swings: 0,
            ..config
        };
        assert!((0_u32..10).all(|_| !swings.swing_measured(
            &never,
            Leg::Fl,
            0.1,
            Direction::Forward
        )));
    }

    #[test]
    fn walking_backward_one_swing_past_its_own_threshold_stops_at_once() {
        let config = JUDGING;
        let mut swings = BlockedSwings::new();
        let between = 0.5 * (config.backward_at_once_m + config.lag_m);
        assert!(!swings.swing_measured(&config, Leg::Bl, between, Direction::Backward));
        swings.reset();
        let past = config.backward_at_once_m + 0.001;
        assert!(
            past < config.at_once_m,
            "the backward threshold is the lower one"
        );
        assert!(!swings.swing_measured(&config, Leg::Bl, past, Direction::Forward));
        swings.reset();
        assert!(swings.swing_measured(&config, Leg::Bl, past, Direction::Backward));
    }

    #[test]
    fn the_first_swings_of_each_leg_after_a_start_stop_only_by_the_count() {
        let config = BlockedConfig::ROBOT;
        assert!(config.settle_swings > 0 && config.count > 1);
        let far = config.at_once_m + 0.01;
        let mut swings = BlockedSwings::new();
        assert!(!swings.swing_measured(&config, Leg::Fl, far, Direction::Forward));
        assert_eq!(swings.count(Leg::Fl), 1, "a settling swing counts");
        // Free swings take the count back to 0 and see the settling through.
        for _ in 0..config.settle_swings {
            assert!(!swings.swing_measured(&config, Leg::Fl, 0.0, Direction::Forward));
        }
        assert_eq!(swings.count(Leg::Fl), 0);
        assert!(
            swings.swing_measured(&config, Leg::Fl, far, Direction::Forward),
            "settled: at once"
        );
        swings.reset();
        assert!(!swings.swing_measured(&config, Leg::Fr, far, Direction::Forward));
        assert!(
            swings.swing_measured(&config, Leg::Fr, far, Direction::Forward),
            "behind twice from the start: stopped on the second swing"
        );
    }

    #[test]
    fn a_foot_held_a_little_behind_swing_after_swing_stops_the_trot() {
        let config = JUDGING;
        let mut swings = BlockedSwings::new();
        let little = 0.5 * (config.held_lag_m + config.lag_m);
        assert!(little < config.lag_m, "under the count's threshold");
        for _ in 1..config.held_swings {
            assert!(!swings.swing_measured(&config, Leg::Fl, little, Direction::Forward));
        }
        assert!(!swings.swing_measured(&config, Leg::Fl, 0.0, Direction::Forward));
        for _ in 1..config.held_swings {
            assert!(!swings.swing_measured(&config, Leg::Fl, little, Direction::Forward));
        }
        assert!(
            swings.swing_measured(&config, Leg::Fl, little, Direction::Forward),
            "held behind {} swings in a row",
            config.held_swings
        );
    }

    #[test]
    fn the_lag_is_along_the_walking_direction() {
        let geometry = LegGeometry::ROBOT;
        let at = |hip_deg: f32| LegJoints {
            hip_abduction_rad: 0.0,
            hip_pitch_rad: hip_deg.to_radians(),
            knee_rad: -0.8,
            ankle_rad: 0.2,
        };
        // The foot swung forward less than asked: behind walking forward, ahead walking back.
        let (target, measured) = (at(20.0), at(10.0));
        let lag = lag_m(&geometry, &target, &measured, 1.0);
        assert!(lag > 0.03, "{lag}");
        assert_eq!(lag_m(&geometry, &target, &measured, -1.0), -lag);
        let broken = LegJoints {
            knee_rad: f32::NAN,
            ..measured
        };
        assert_eq!(lag_m(&geometry, &target, &broken, 1.0), 0.0);
    }
}
