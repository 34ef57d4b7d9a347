//! The latest feedback from the drives and the IMU, in SI units, with a watchdog per source.

use protocol::{Imu, Joints, Leg, LegFeedback, WheelFeedback};

use crate::attitude::Attitude;
use crate::control::safety::Watchdog;
use crate::time::Tick;

/// The newest samples and how fresh they are.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sensors {
    /// Joint positions, rad.
    pub joint_position_rad: Joints<f32>,
    /// Joint velocities, rad/s.
    pub joint_velocity_rad_s: Joints<f32>,
    /// Wheel joint rates (left, right), relative to the body, rad/s.
    pub wheel_rate_rad_s: [f32; 2],
    /// Torso attitude.
    pub attitude: Attitude,
    /// Body rates about x, y, z, rad/s.
    pub angular_rate_rad_s: [f32; 3],
    legs: [Watchdog; 4],
    wheels: Watchdog,
    imu: Watchdog,
}

impl Sensors {
    /// Nothing received yet; watchdogs of `feedback_ticks` (drives) and `imu_ticks`.
    pub const fn new(feedback_ticks: u32, imu_ticks: u32) -> Self {
        Self {
            joint_position_rad: Joints::splat(0.0),
            joint_velocity_rad_s: Joints::splat(0.0),
            wheel_rate_rad_s: [0.0; 2],
            attitude: Attitude {
                pitch_rad: 0.0,
                roll_rad: 0.0,
            },
            angular_rate_rad_s: [0.0; 3],
            legs: [Watchdog::new(feedback_ticks); 4],
            wheels: Watchdog::new(feedback_ticks),
            imu: Watchdog::new(imu_ticks),
        }
    }

    /// Stores one leg's feedback.
    pub fn record_leg(&mut self, now: Tick, leg: Leg, feedback: &LegFeedback) {
        *self.joint_position_rad.leg_mut(leg) = feedback.position.map(|p| p.si());
        *self.joint_velocity_rad_s.leg_mut(leg) = feedback.velocity.map(|v| v.si());
        if let Some(watchdog) = self.legs.get_mut(leg_index(leg)) {
            watchdog.feed(now);
        }
    }

    /// Stores the wheel feedback.
    pub fn record_wheels(&mut self, now: Tick, feedback: &WheelFeedback) {
        self.wheel_rate_rad_s = feedback.velocity.map(|v| v.si());
        self.wheels.feed(now);
    }

    /// Stores an IMU sample. An all-zero sample (what an IMU that is not initialised or broken
    /// sends: no rotation, no rate, and no specific force, which a robot on the ground always
    /// feels) does not count as a sample; neither does a quaternion that gives no attitude.
    pub fn record_imu(&mut self, now: Tick, imu: &Imu) {
        let zero = imu.orientation.iter().all(|c| c.raw() == 0)
            && imu.angular_rate.iter().all(|w| w.raw() == 0)
            && imu.acceleration.iter().all(|a| a.raw() == 0);
        let attitude = Attitude::from_quaternion(imu.quaternion(crate::math::sqrt));
        if !zero && attitude.tilt_rad().is_finite() {
            self.attitude = attitude;
            self.angular_rate_rad_s = imu.angular_rate.map(|w| w.si());
            self.imu.feed(now);
        }
    }

    /// Whether every leg and the wheels have reported at least once.
    pub fn drives_ever_reported(&self) -> bool {
        self.legs.iter().all(Watchdog::ever_fed) && self.wheels.ever_fed()
    }

    /// Whether any leg or the wheels went silent.
    pub fn drives_stale(&self, now: Tick) -> bool {
        self.legs.iter().any(|w| w.expired(now)) || self.wheels.expired(now)
    }

    /// Whether the IMU went silent.
    pub fn imu_stale(&self, now: Tick) -> bool {
        self.imu.expired(now)
    }

    /// Mean wheel joint rate, rad/s.
    pub fn mean_wheel_rate_rad_s(&self) -> f32 {
        let [left, right] = self.wheel_rate_rad_s;
        0.5 * (left + right)
    }

    /// Half the wheel rate difference, left minus right, rad/s.
    pub fn differential_wheel_rate_rad_s(&self) -> f32 {
        let [left, right] = self.wheel_rate_rad_s;
        0.5 * (left - right)
    }
}

/// Position of `leg` in wire order.
pub const fn leg_index(leg: Leg) -> usize {
    match leg {
        Leg::Fl => 0,
        Leg::Fr => 1,
        Leg::Bl => 2,
        Leg::Br => 3,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use protocol::{Acceleration, AngularRate, QuatComponent};

    #[test]
    fn an_all_zero_imu_sample_feeds_no_watchdog_and_a_level_one_does() {
        let mut sensors = Sensors::new(10, 10);
        let zero = Imu {
            orientation: [QuatComponent::saturating_from_si(0.0); 3],
            angular_rate: [AngularRate::saturating_from_si(0.0); 3],
            acceleration: [Acceleration::saturating_from_si(0.0); 3],
        };
        for t in 0..20 {
            sensors.record_imu(Tick(t), &zero);
        }
        assert!(sensors.imu_stale(Tick(20)), "zeros are no IMU");
        // Level and at rest: the same quaternion, with gravity felt.
        let level = Imu {
            acceleration: [0.0, 0.0, 9.81].map(Acceleration::saturating_from_si),
            ..zero
        };
        sensors.record_imu(Tick(20), &level);
        assert!(!sensors.imu_stale(Tick(21)));
        assert_eq!(sensors.attitude.tilt_rad(), 0.0);
    }
}
