//! Levelling: where the folded legs put their mass, so that the robot balances upright.
//!
//! # Why
//!
//! On its wheels the robot leans until its centre of mass is over the axle. That centre lies
//! only about 12 cm above the axle, so every centimetre it sits off the axle leans the robot
//! about 4.6°: a torso whose centre of mass is 2 cm off leans it 7.5°, and folded legs three
//! times as heavy as drawn, tucked behind the hips, 9° nose down. Tilt the robot has at rest is
//! tilt it cannot spend accelerating: W and S lean about 5° more while they speed up, and the
//! acceptance figure is 10°. A fixed trim cannot help (it moves where the law balances, not
//! where the mass is); the legs can: they carry a tenth to a quarter of the mass.
//!
//! # How
//!
//! The fold is a family of poses along one number, the shift (−1…1, [`FoldFamily`]): at 0 the
//! front legs tucked under the front of the torso and the back legs behind their hips (the
//! report's sense of the fold); toward +1 the back legs swing forward under the torso
//! (their mass moves forward), toward −1 the front legs swing back. Every pose keeps every
//! leg point at least 2 cm above flat ground with the torso within ±12° of level (the back legs
//! at +1 within 10° nose up): a foot that touches down while balancing breaks the pendulum.
//!
//! [`Levelling`] moves the shift by the balance point the balance law has found
//! ([`crate::wheels::balance::Balance::pitch_trim_rad`]): an integral loop on it, slow beside
//! the trim's own following, so it needs no model of the masses, and it holds while the trim
//! is not fresh (accelerating, turning). What it learned is kept: the next fold tucks straight
//! into it.

use protocol::{Joints, Leg};

use crate::legs::kinematics::LegJoints;
use crate::math::{deg_to_rad, toward};

/// The fold poses along the shift.
///
/// The report's fold (0, −1.0, −1.0, 0.3) rad for every leg is not one of them: its hip pitch
/// lies past the report's own ±50° limit; clamped there, it folds every foot backward and the
/// drawn robot balances 7° nose down, which leaves 3° of the tilt budget for accelerating.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FoldFamily {
    /// Front legs for a shift ≥ 0: tucked under the front of the torso.
    pub front: LegJoints,
    /// Front legs at shift −1: swung back under the torso.
    pub front_back: LegJoints,
    /// Back legs for a shift ≤ 0: tucked behind the hips.
    pub back: LegJoints,
    /// Back legs at shift [`FoldFamily::back_under_at`]: under the hips.
    pub back_under: LegJoints,
    /// Back legs at shift +1: swung forward under the torso.
    pub back_forward: LegJoints,
    /// The shift at which the back legs are at [`FoldFamily::back_under`] (in (0, 1)).
    pub back_under_at: f32,
    /// Front legs riding in the autonomous mode once it has climbed (the left leg's; the
    /// right one mirrors its abduction): as the tucked fold but with the knees at their stop
    /// and the legs spread outward (still under the torso), so that they clear the plateau's
    /// edge when the wheels roll off a step down back first. The tucked fold hangs its shanks
    /// 6.5 cm over the ground; this pose, 11 cm, with their mass where the fold has it. (Swung
    /// back under the hips they cleared 13 cm, but robots then balanced up to 11° nose down
    /// and some ran into a limit cycle on the plateau: 46 of 50 crossed instead of 49.)
    pub front_clear: LegJoints,
    /// Front legs riding in the autonomous mode on its wheels (the left leg's; the right one
    /// mirrors its abduction): swung back under the torso, knees at their stop, spread
    /// outward, so that they clear a 10° ramp's foot as the robot comes off it back first,
    /// leaning 12° uphill beyond its balance point (the tucked fold hung them 4 cm lower
    /// there, and robots whose balance point was 10° nose down ran their shanks into the
    /// slope).
    pub ride_front: LegJoints,
    /// Back legs riding in the autonomous mode: under the hips, knees at their stop, spread:
    /// they lead up a ramp, where the tucked fold's shanks, 0.45 m behind the axle, met the
    /// slope. Their mass moves forward as the front legs' moves back.
    pub ride_back: LegJoints,
}

const fn leg(hip_pitch_deg: f32, knee_deg: f32, ankle_deg: f32) -> LegJoints {
    LegJoints {
        hip_abduction_rad: 0.0,
        hip_pitch_rad: deg_to_rad(hip_pitch_deg),
        knee_rad: deg_to_rad(knee_deg),
        ankle_rad: deg_to_rad(ankle_deg),
    }
}

impl FoldFamily {
    /// The robot. Shift 0 is the fold the balance law was first tuned on (the robot as drawn
    /// balances 3.2° nose down in it); at +1 the drawn robot balances 0.6° nose up whatever its
    /// legs weigh (their mass sits over the axle), at −1 5.0° nose down.
    pub const ROBOT: Self = Self {
        front: leg(50.0, -100.0, -40.0),
        front_back: leg(0.0, -100.0, -40.0),
        back: leg(-45.0, -50.0, -20.0),
        back_under: leg(0.0, -100.0, -40.0),
        back_forward: leg(45.0, -100.0, -40.0),
        back_under_at: 0.6,
        front_clear: LegJoints {
            hip_abduction_rad: deg_to_rad(34.0),
            ..leg(50.0, -110.0, -40.0)
        },
        ride_front: LegJoints {
            hip_abduction_rad: deg_to_rad(34.0),
            ..leg(-50.0, -110.0, 0.0)
        },
        ride_back: LegJoints {
            hip_abduction_rad: deg_to_rad(34.0),
            ..leg(0.0, -110.0, -40.0)
        },
    };

    /// The pose of all four legs at `shift` (clamped to −1…1; NaN counts as 0).
    pub fn pose(&self, shift: f32) -> Joints<f32> {
        let shift = if shift.is_finite() {
            crate::math::clamp(shift, -1.0, 1.0)
        } else {
            0.0
        };
        let front = if shift < 0.0 {
            blend(&self.front, &self.front_back, -shift)
        } else {
            self.front
        };
        let under_at = crate::math::clamp(self.back_under_at, 0.01, 0.99);
        let back = if shift <= 0.0 {
            self.back
        } else if shift < under_at {
            blend(&self.back, &self.back_under, shift / under_at)
        } else {
            let along = (shift - under_at) / (1.0 - under_at);
            blend(&self.back_under, &self.back_forward, along)
        };
        let (front, back) = (front.to_array(), back.to_array());
        Joints::from_leg_fn(|leg| match leg {
            Leg::Fl | Leg::Fr => front,
            Leg::Bl | Leg::Br => back,
        })
    }
}

/// `from` moved `share` (0…1) of the way to `to`, joint by joint.
fn blend(from: &LegJoints, to: &LegJoints, share: f32) -> LegJoints {
    let mix = |a: f32, b: f32| a + share * (b - a);
    LegJoints {
        hip_abduction_rad: mix(from.hip_abduction_rad, to.hip_abduction_rad),
        hip_pitch_rad: mix(from.hip_pitch_rad, to.hip_pitch_rad),
        knee_rad: mix(from.knee_rad, to.knee_rad),
        ankle_rad: mix(from.ankle_rad, to.ankle_rad),
    }
}

/// Tunables of the levelling loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LevellingConfig {
    /// The fold poses (a reference: the configuration is copied into every node, and the
    /// MCU's stack is measured to the byte).
    pub family: &'static FoldFamily,
    /// The shift of a robot that has not balanced yet: where the drawn robot balances near
    /// upright and the spread of real robots' balance points is centred.
    pub start_shift: f32,
    /// The balance point it levels to, rad, positive nose down.
    pub target_rad: f32,
    /// Shift per second per rad of balance point off the target.
    pub gain_per_rad_s: f32,
    /// Fastest change of the shift, per second: the legs' mass moves slowly beside the
    /// balance law, which takes each new balance point as it comes.
    pub max_rate_per_s: f32,
}

impl LevellingConfig {
    /// The robot.
    pub const ROBOT: Self = Self {
        family: &FoldFamily::ROBOT,
        start_shift: 0.6,
        target_rad: 0.0,
        gain_per_rad_s: 15.0,
        max_rate_per_s: 1.0,
    };
}

/// The levelling loop's state: the shift it has learned, and the shift the legs are at.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Levelling {
    shift: f32,
    /// Where the legs are: the learned shift, or on the way to or from shift 0 around a
    /// stand-up ([`Levelling::stow`]).
    pose_shift: f32,
}

impl Levelling {
    /// At the configured start.
    pub fn new(config: &LevellingConfig) -> Self {
        let shift = if config.start_shift.is_finite() {
            crate::math::clamp(config.start_shift, -1.0, 1.0)
        } else {
            0.0
        };
        Self {
            shift,
            pose_shift: shift,
        }
    }

    /// The learned shift.
    pub fn shift(&self) -> f32 {
        self.shift
    }

    /// Whether the legs are at shift 0, where a stand-up from the wheels starts: unfolding
    /// from under the torso, the back legs reached the ground after the front ones and tipped
    /// the robot 8° nose up; from behind the hips, 6.5°.
    pub fn stowed(&self) -> bool {
        self.pose_shift == 0.0
    }

    /// One tick of `dt_s` of the legs toward shift 0 ([`Levelling::stowed`]), at the loop's
    /// fastest rate; the learned shift is kept.
    pub fn stow(&mut self, config: &LevellingConfig, dt_s: f32) {
        self.pose_shift = toward(self.pose_shift, 0.0, config.max_rate_per_s * dt_s);
    }

    /// One tick of `dt_s` of the legs back toward the learned shift after a stow.
    pub fn unstow(&mut self, config: &LevellingConfig, dt_s: f32) {
        self.pose_shift = toward(self.pose_shift, self.shift, config.max_rate_per_s * dt_s);
    }

    /// One tick of `dt_s`: the shift moves toward levelling the balance point
    /// `balance_point_rad` (positive nose down: the mass must move forward, the shift up).
    pub fn update(&mut self, config: &LevellingConfig, balance_point_rad: f32, dt_s: f32) {
        let error_rad = balance_point_rad - config.target_rad;
        let rate = crate::math::clamp(
            config.gain_per_rad_s * error_rad,
            -config.max_rate_per_s,
            config.max_rate_per_s,
        );
        let next = self.shift + rate * dt_s;
        if next.is_finite() {
            let legs_at_shift = self.pose_shift == self.shift;
            self.shift = crate::math::clamp(next, -1.0, 1.0);
            // After a stow the legs come back at the loop's rate, not in one tick.
            self.pose_shift = if legs_at_shift {
                self.shift
            } else {
                toward(self.pose_shift, self.shift, config.max_rate_per_s * dt_s)
            };
        }
    }

    /// The fold pose the legs are at.
    pub fn pose(&self, config: &LevellingConfig) -> Joints<f32> {
        config.family.pose(self.pose_shift)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shift_zero_is_the_tuned_fold_and_the_ends_are_the_family_poses() {
        let family = FoldFamily::ROBOT;
        let at = |shift: f32, leg: Leg| *family.pose(shift).leg(leg);
        assert_eq!(at(0.0, Leg::Fl), family.front.to_array());
        assert_eq!(at(0.0, Leg::Br), family.back.to_array());
        assert_eq!(at(1.0, Leg::Bl), family.back_forward.to_array());
        assert_eq!(at(-1.0, Leg::Fr), family.front_back.to_array());
        assert_eq!(
            at(family.back_under_at, Leg::Bl),
            family.back_under.to_array()
        );
        assert_eq!(at(f32::NAN, Leg::Bl), family.back.to_array());
        assert_eq!(at(7.0, Leg::Bl), family.back_forward.to_array());
    }

    #[test]
    fn the_family_is_continuous() {
        let family = FoldFamily::ROBOT;
        let mut last = family.pose(-1.0);
        for i in -999_i32..=1_000_i32 {
            let pose = family.pose(i as f32 / 1000.0);
            for (a, b) in pose.iter().zip(last.iter()) {
                assert!((a - b).abs() < 0.01, "jump at shift {}", i as f32 / 1000.0);
            }
            last = pose;
        }
    }

    #[test]
    fn a_nose_down_balance_point_moves_the_mass_forward_and_stops_at_the_end() {
        let config = LevellingConfig::ROBOT;
        let mut levelling = Levelling::new(&config);
        let start = levelling.shift();
        levelling.update(&config, deg_to_rad(5.0), 0.1);
        assert!(levelling.shift() > start);
        assert!(levelling.shift() - start <= config.max_rate_per_s * 0.1 + 1e-6);
        for _ in 0..100_u32 {
            levelling.update(&config, deg_to_rad(5.0), 0.1);
        }
        assert_eq!(levelling.shift(), 1.0);
        levelling.update(&config, f32::NAN, 0.1);
        assert_eq!(levelling.shift(), 1.0);
        for _ in 0..100_u32 {
            levelling.update(&config, deg_to_rad(-5.0), 0.1);
        }
        assert_eq!(levelling.shift(), -1.0);
    }

    #[test]
    fn a_stow_moves_the_legs_to_shift_zero_and_back_and_keeps_what_was_learned() {
        let config = LevellingConfig::ROBOT;
        let mut levelling = Levelling::new(&config);
        assert!(!levelling.stowed());
        for _ in 0..50_u32 {
            levelling.stow(&config, 0.01);
        }
        assert!(!levelling.stowed(), "at most the loop's rate");
        for _ in 0..100_u32 {
            levelling.stow(&config, 0.01);
        }
        assert!(levelling.stowed());
        assert_eq!(levelling.pose(&config), config.family.pose(0.0));
        assert_eq!(levelling.shift(), config.start_shift);
        for _ in 0..100_u32 {
            levelling.unstow(&config, 0.01);
        }
        assert_eq!(
            levelling.pose(&config),
            config.family.pose(config.start_shift)
        );
    }

    #[test]
    fn after_a_stow_the_loop_brings_the_legs_back_at_its_rate() {
        let config = LevellingConfig::ROBOT;
        let mut levelling = Levelling::new(&config);
        for _ in 0..100_u32 {
            levelling.stow(&config, 0.01);
        }
        assert!(levelling.stowed());
        levelling.update(&config, 0.0, 0.01);
        let moved = levelling.pose_shift.abs();
        assert!(
            moved <= config.max_rate_per_s * 0.01 + 1e-6,
            "the legs jumped by {moved} of the shift"
        );
        assert!(!levelling.stowed());
    }
}
