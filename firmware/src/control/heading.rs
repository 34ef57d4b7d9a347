//! Heading hold for the trot: the robot walks straight when the operator does not steer.
//!
//! # Why
//!
//! A trot that strides the same on both sides still turns: robots as built walk circles on
//! flat ground (feet slipping unevenly, a centre of mass off to a side, unequal drives), some
//! by a quarter turn in half a minute. An operator corrects it by hand; a robot
//! meant to reach a step squarely, or to walk a course by itself, must hold its heading.
//!
//! # How
//!
//! The gyro's yaw rate, with its bias removed, integrates to the heading turned since the
//! operator last steered; low-passed over half a stride (the trot swings the body's heading
//! back and forth each stride, which is no turn to correct), a PI law on it asks the trot
//! for a yaw rate ([`crate::legs::gait::Trot::strides`] turns by it), within
//! [`HeadingConfig::max_rad_s`]. The operator steering takes over and the held heading
//! restarts where they leave off; a trot at no speed is not held (a correction would lift
//! feet that stay down there). docs/firmware.md has the measurements.
//!
//! The hold needs the gyro's bias about the vertical, which gravity does not show: it is held
//! only once the estimator has measured the bias standing still
//! ([`crate::control::estimator::AttitudeEstimator::calibrated`]). Before that, a bias of a
//! BMI088's 1σ (1°/s) would turn the robot 24° in 24 s by itself, as much as many robots turn
//! unheld; the trot then runs as the operator asks.

/// Tunables.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeadingConfig {
    /// Yaw rate asked per rad of heading turned, 1/s.
    pub kp_per_s: f32,
    /// Integral gain, 1/s²: the trot answers a yaw-rate request only in part (its feet slip),
    /// so a steady turn needs a steady correction.
    pub ki_per_s2: f32,
    /// Largest yaw rate the hold asks for, rad/s (its integral is held within it too).
    pub max_rad_s: f32,
    /// An operator's yaw rate past this is steering, rad/s.
    pub steering_rad_s: f32,
    /// Time constant of the low-pass on the heading, s: the trot swings the body's heading
    /// back and forth each stride, which is no turn to correct.
    pub smoothing_s: f32,
}

impl HeadingConfig {
    /// The robot.
    pub const ROBOT: Self = Self {
        kp_per_s: 0.5,
        ki_per_s2: 0.1,
        max_rad_s: 0.25,
        steering_rad_s: 0.01,
        smoothing_s: 0.5,
    };

    /// No hold: the trot turns as the operator asks.
    pub const OFF: Self = Self {
        kp_per_s: 0.0,
        ki_per_s2: 0.0,
        max_rad_s: 0.0,
        steering_rad_s: 0.01,
        smoothing_s: 0.5,
    };
}

/// The hold's state.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct HeadingHold {
    /// Heading turned since the hold began, rad, positive to the left.
    turned_rad: f32,
    /// The integral term, rad/s.
    integral_rad_s: f32,
    /// The heading turned, low-passed, rad.
    smoothed_rad: f32,
}

impl HeadingHold {
    /// Forgets the held heading: the next hold starts from where the robot then points.
    pub fn reset(&mut self) {
        *self = Self::default();
    }

    /// Heading turned since the hold began, rad, positive to the left.
    pub fn turned_rad(&self) -> f32 {
        self.turned_rad
    }

    /// One tick of `dt_s` while the trot runs: the yaw rate the trot takes, rad/s — the
    /// operator's `operator_rad_s` when they steer or when `held` is false (the hold then
    /// restarts), else the hold's correction for `measured_rad_s`, the body's rate about the
    /// vertical with the gyro bias removed (positive turning left).
    pub fn yaw_rate_rad_s(
        &mut self,
        config: &HeadingConfig,
        held: bool,
        operator_rad_s: f32,
        measured_rad_s: f32,
        dt_s: f32,
    ) -> f32 {
        // A non-finite request counts as steering: the operator's value goes on unchanged.
        let quiet = operator_rad_s.abs() <= config.steering_rad_s;
        if !held || !quiet || !measured_rad_s.is_finite() {
            self.reset();
            return operator_rad_s;
        }
        let limit = config.max_rad_s;
        self.turned_rad += measured_rad_s * dt_s;
        let share = if config.smoothing_s > dt_s {
            dt_s / config.smoothing_s
        } else {
            1.0
        };
        self.smoothed_rad += (self.turned_rad - self.smoothed_rad) * share;
        self.integral_rad_s = crate::math::clamp(
            self.integral_rad_s + config.ki_per_s2 * self.smoothed_rad * dt_s,
            -limit,
            limit,
        );
        crate::math::clamp(
            -config.kp_per_s * self.smoothed_rad - self.integral_rad_s,
            -limit,
            limit,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT_S: f32 = 0.004;

    /// A robot whose trot turns `drift_rad_s` by itself and answers a yaw-rate request by
    /// `authority` of it, held for `seconds`: the heading it ends at, rad.
    fn walk(config: &HeadingConfig, drift_rad_s: f32, authority: f32, seconds: f32) -> f32 {
        let mut hold = HeadingHold::default();
        let (mut heading, mut asked) = (0.0_f32, 0.0_f32);
        for _ in 0..(seconds / DT_S) as u32 {
            let rate = drift_rad_s + authority * asked;
            heading += rate * DT_S;
            asked = hold.yaw_rate_rad_s(config, true, 0.0, rate, DT_S);
        }
        heading
    }

    #[test]
    fn a_robot_that_walks_a_circle_walks_straight_held() {
        let config = HeadingConfig::ROBOT;
        // 150° in 24 s unheld, answering half of what it is asked.
        let drift = 150_f32.to_radians() / 24.0;
        let held = walk(&config, drift, 0.5, 24.0);
        assert!(
            held.abs() < 5_f32.to_radians(),
            "held at {}°",
            held.to_degrees()
        );
        let unheld = walk(&HeadingConfig::OFF, drift, 0.5, 24.0);
        assert!((unheld.to_degrees() - 150.0).abs() < 0.5);
    }

    #[test]
    fn the_operator_steering_takes_over_and_the_hold_restarts_after() {
        let config = HeadingConfig::ROBOT;
        let mut hold = HeadingHold::default();
        for _ in 0..100_u32 {
            hold.yaw_rate_rad_s(&config, true, 0.0, 0.1, DT_S);
        }
        assert!(hold.turned_rad() > 0.03);
        assert_eq!(hold.yaw_rate_rad_s(&config, true, 0.2, 0.1, DT_S), 0.2);
        assert_eq!(hold.turned_rad(), 0.0);
        // Not held (the bias unknown): the operator's rate, and nothing learned.
        assert_eq!(hold.yaw_rate_rad_s(&config, false, 0.0, 0.1, DT_S), 0.0);
        assert_eq!(hold, HeadingHold::default());
    }

    #[test]
    fn the_correction_stays_within_its_limit_and_a_bad_rate_is_ignored() {
        let config = HeadingConfig::ROBOT;
        let mut hold = HeadingHold::default();
        for _ in 0..10_000_u32 {
            let asked = hold.yaw_rate_rad_s(&config, true, 0.0, 1.0, DT_S);
            assert!(asked.abs() <= config.max_rad_s);
        }
        assert_eq!(hold.yaw_rate_rad_s(&config, true, 0.0, f32::NAN, DT_S), 0.0);
        assert_eq!(hold, HeadingHold::default());
    }
}
