//! The operator's speed and yaw rate ([`protocol::TeleopMode::Drive`] and
//! [`protocol::TeleopMode::Walk`], and the yaw rate that steers `W`, `S`, `L` and `K`), within
//! the limits the controller owns: the wire carries ±2 m/s and ±3 rad/s, the robot takes less.
//!
//! On the wheels a yaw rate ω is a difference of the wheels' ground speeds, `v_right − v_left
//! = ω · track`, which the turn loop ([`crate::wheels::wheel`]) holds while the balance law
//! holds their mean. On the legs it is a stride per leg along its hip's path
//! ([`crate::legs::gait::Trot::strides`]).

/// Limits and dimensions of steering.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SteeringConfig {
    /// Distance between the wheels' contact points, m.
    pub wheel_track_m: f32,
    /// Largest yaw rate on the wheels, rad/s.
    pub wheel_yaw_limit_rad_s: f32,
    /// Largest yaw rate of a trot, rad/s.
    pub trot_yaw_limit_rad_s: f32,
}

impl SteeringConfig {
    /// The robot: wheels 0.46 m apart; the yaw-rate limits the operator is told of
    /// ([`protocol::motion_limits`]): 1 rad/s on the wheels (a curve of 0.48 m radius at full
    /// speed, within the turn loop's quarter of the wheel torque), 0.4 rad/s on the legs (the
    /// front and back feet stride 0.6 of the full stride sideways at a turn on the spot).
    pub const ROBOT: Self = Self {
        wheel_track_m: 0.46,
        wheel_yaw_limit_rad_s: protocol::motion_limits::DRIVE_LIMITS.yaw_rate_rad_s,
        trot_yaw_limit_rad_s: protocol::motion_limits::WALK_LIMITS.yaw_rate_rad_s,
    };

    /// The yaw rate the wheels take for `requested_rad_s` (0 for a non-finite one).
    pub fn wheel_yaw_rad_s(&self, requested_rad_s: f32) -> f32 {
        within(requested_rad_s, self.wheel_yaw_limit_rad_s)
    }

    /// The yaw rate a trot takes for `requested_rad_s` (0 for a non-finite one).
    pub fn trot_yaw_rad_s(&self, requested_rad_s: f32) -> f32 {
        within(requested_rad_s, self.trot_yaw_limit_rad_s)
    }

    /// Half the wheels' rate difference, left minus right, rad/s, that turns the robot at
    /// `yaw_rate_rad_s` on wheels of `wheel_radius_m` (the turn loop's reference).
    pub fn differential_rate_rad_s(&self, yaw_rate_rad_s: f32, wheel_radius_m: f32) -> f32 {
        if wheel_radius_m > 0.0 {
            -yaw_rate_rad_s * self.wheel_track_m / (2.0 * wheel_radius_m)
        } else {
            0.0
        }
    }
}

/// `value` within ±`limit` (0 for a non-finite value).
pub fn within(value: f32, limit: f32) -> f32 {
    if value.is_finite() {
        crate::math::clamp(value, -limit, limit)
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn turning_left_speeds_the_right_wheel_and_the_limits_hold() {
        let steering = SteeringConfig::ROBOT;
        // 0.3 rad/s: the right wheel 0.138 m/s faster than the left, 0.575 rad/s each way.
        let differential = steering.differential_rate_rad_s(0.3, 0.12);
        assert!((differential + 0.575).abs() < 1e-3, "{differential}");
        assert_eq!(steering.wheel_yaw_rad_s(5.0), 1.0);
        assert_eq!(steering.trot_yaw_rad_s(-5.0), -0.4);
        assert_eq!(steering.wheel_yaw_rad_s(f32::NAN), 0.0);
    }

    /// The speeds the operator is told of are the robot's: W's full speed on the wheels, the
    /// trot's full stride on the legs.
    #[test]
    fn the_operators_speed_limits_are_the_robots() {
        let config = crate::config::Config::ROBOT;
        let wheels_m_s = config.wheel_speed_rad_s * config.balance.wheel_radius_m;
        let drive = protocol::motion_limits::DRIVE_LIMITS.speed_m_s;
        assert!((wheels_m_s - drive).abs() < 1e-5, "{wheels_m_s} vs {drive}");
        let trot = crate::legs::gait::Trot::new(config.trot, config.rate);
        let full_m_s = trot.and_then(|t| t.full_speed_m_s()).unwrap_or(0.0);
        let walk = protocol::motion_limits::WALK_LIMITS.speed_m_s;
        assert!((full_m_s - walk).abs() < 0.001, "{full_m_s} vs {walk}");
    }
}
