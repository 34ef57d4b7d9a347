//! The latest feedback from the drives and the IMU, in SI units, with a watchdog per source.
//! The IMU sends rate and specific force; the attitude is the [`AttitudeEstimator`]'s.

use protocol::{Imu, Joints, Leg, LegFeedback, Range, RangeStatus, WheelFeedback};

use crate::attitude::Attitude;
use crate::control::estimator::{AttitudeEstimator, EstimatorConfig, Motion};
use crate::control::safety::Watchdog;
use crate::time::Tick;

/// The newest samples and how fresh they are.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sensors {
    /// Joint positions, rad.
    pub joint_position_rad: Joints<f32>,
    /// Joint velocities, rad/s.
    pub joint_velocity_rad_s: Joints<f32>,
    /// Joint torques the drives report, N·m (what a climb weighs its feet's loads with).
    pub joint_effort_nm: Joints<f32>,
    /// Wheel joint rates (left, right), relative to the body, rad/s.
    pub wheel_rate_rad_s: [f32; 2],
    /// Torso attitude (the estimator's; level before the first IMU sample).
    pub attitude: Attitude,
    /// Body rates about x, y, z with the estimated gyro bias removed, rad/s.
    pub angular_rate_rad_s: [f32; 3],
    estimator: AttitudeEstimator,
    /// The IMU sample received this tick, for [`Sensors::estimate`] (as it came: 12 bytes, not
    /// the 24 of its values in SI units).
    imu_sample: Option<(Tick, Imu)>,
    /// The rangefinder's ranging received this tick: its distance, m (`None`: no return).
    range_sample: Option<Option<f32>>,
    legs: [Watchdog; 4],
    wheels: Watchdog,
    imu: Watchdog,
}

impl Sensors {
    /// Nothing received yet; watchdogs of `feedback_ticks` (drives) and `imu_ticks`; the IMU's
    /// samples go through `estimator`.
    pub const fn new(feedback_ticks: u32, imu_ticks: u32, estimator: AttitudeEstimator) -> Self {
        Self {
            joint_position_rad: Joints::splat(0.0),
            joint_velocity_rad_s: Joints::splat(0.0),
            joint_effort_nm: Joints::splat(0.0),
            wheel_rate_rad_s: [0.0; 2],
            attitude: Attitude {
                pitch_rad: 0.0,
                roll_rad: 0.0,
            },
            angular_rate_rad_s: [0.0; 3],
            estimator,
            imu_sample: None,
            range_sample: None,
            legs: [Watchdog::new(feedback_ticks); 4],
            wheels: Watchdog::new(feedback_ticks),
            imu: Watchdog::new(imu_ticks),
        }
    }

    /// Stores one leg's feedback.
    pub fn record_leg(&mut self, now: Tick, leg: Leg, feedback: &LegFeedback) {
        *self.joint_position_rad.leg_mut(leg) = feedback.position.map(|p| p.si());
        *self.joint_velocity_rad_s.leg_mut(leg) = feedback.velocity.map(|v| v.si());
        *self.joint_effort_nm.leg_mut(leg) = feedback.effort.map(|e| e.si());
        if let Some(watchdog) = self.legs.get_mut(leg_index(leg)) {
            watchdog.feed(now);
        }
    }

    /// Stores the wheel feedback.
    pub fn record_wheels(&mut self, now: Tick, feedback: &WheelFeedback) {
        self.wheel_rate_rad_s = feedback.velocity.map(|v| v.si());
        self.wheels.feed(now);
    }

    /// Keeps an IMU sample for this tick's [`Sensors::estimate`] and feeds the IMU watchdog.
    /// An all-zero sample (what an IMU that is not initialised or broken sends: no rate and
    /// no specific force, which a robot on the ground always feels) is no sample.
    pub fn record_imu(&mut self, now: Tick, imu: &Imu) {
        let zero = imu.angular_rate.iter().all(|w| w.raw() == 0)
            && imu.acceleration.iter().all(|a| a.raw() == 0);
        if !zero {
            self.imu_sample = Some((now, *imu));
            self.imu.feed(now);
        }
    }

    /// Keeps a ranging for this tick's [`Sensors::take_range`].
    pub fn record_range(&mut self, range: &Range) {
        self.range_sample = Some(match range.status {
            RangeStatus::Valid => Some(range.distance.si()),
            RangeStatus::SignalFail => None,
        });
    }

    /// The ranging received this tick, if any: `Some(Some(m))` a distance, `Some(None)` no
    /// return within the part's range.
    pub fn take_range(&mut self) -> Option<Option<f32>> {
        self.range_sample.take()
    }

    /// Runs this tick's IMU sample, if any, through the attitude estimator (configured as
    /// `config`) with the torso's `motion`, and returns its specific force's magnitude, m/s²
    /// (`None`: no sample this tick). Not inlined: the filter's temporaries then do not add to
    /// the control step's frame (56 bytes of peak stack on the MCU).
    #[inline(never)]
    pub fn estimate(&mut self, config: &EstimatorConfig, motion: Motion) -> Option<f32> {
        let (tick, imu) = self.imu_sample.take()?;
        let gyro = imu.angular_rate.map(|w| w.si());
        let accel = imu.acceleration.map(|a| a.si());
        if self.estimator.update(config, tick, gyro, accel, motion) {
            self.attitude = self.estimator.attitude();
            self.angular_rate_rad_s = self.estimator.rate_rad_s();
        }
        let [x, y, z] = accel;
        Some(crate::math::sqrt(x * x + y * y + z * z))
    }

    /// Whether there is an attitude to act on: the IMU talks and its estimator has started
    /// (until then [`Sensors::attitude`] is level, a placeholder).
    pub fn attitude_known(&self, now: Tick) -> bool {
        !self.imu.expired(now) && self.estimator.started()
    }

    /// The attitude estimator (its bias estimate, whether it has calibrated).
    pub fn estimator(&self) -> &AttitudeEstimator {
        &self.estimator
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
    use crate::time::TickRate;
    use protocol::{Acceleration, AngularRate};

    #[test]
    fn an_all_zero_imu_sample_feeds_no_watchdog_and_a_level_one_does() {
        let estimator = AttitudeEstimator::new(&EstimatorConfig::ROBOT, TickRate::SIM_250_HZ);
        let mut sensors = Sensors::new(10, 10, estimator);
        let zero = Imu {
            angular_rate: [AngularRate::saturating_from_si(0.0); 3],
            acceleration: [Acceleration::saturating_from_si(0.0); 3],
        };
        for t in 0..20 {
            sensors.record_imu(Tick(t), &zero);
            sensors.estimate(&EstimatorConfig::ROBOT, Motion::default());
        }
        assert!(sensors.imu_stale(Tick(20)), "zeros are no IMU");
        // Level and at rest: gravity felt.
        let level = Imu {
            acceleration: [0.0, 0.0, 9.81].map(Acceleration::saturating_from_si),
            ..zero
        };
        assert!(!sensors.attitude_known(Tick(20)));
        sensors.record_imu(Tick(20), &level);
        sensors.estimate(&EstimatorConfig::ROBOT, Motion::default());
        assert!(!sensors.imu_stale(Tick(21)));
        assert!(sensors.attitude_known(Tick(21)));
        assert_eq!(sensors.attitude.tilt_rad(), 0.0);
    }
}
