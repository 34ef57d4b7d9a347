//! The limits the robot's controller holds the operator's ground speed and yaw rate to in its
//! `Drive` and `Walk` modes ([`crate::TeleopMode`]): what an operator's full stick should ask
//! for. The wire carries more (±2 m/s, ±3 rad/s) and the controller clamps; these are the
//! contract between the two ends, and the controller's configuration is tested against them.

/// A mode's largest ground speed and yaw rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionLimits {
    /// Ground speed, m/s, either way.
    pub speed_m_s: f32,
    /// Yaw rate, rad/s, either way.
    pub yaw_rate_rad_s: f32,
}

/// On the wheels: `W`'s full speed (4 rad/s on 0.12 m wheels) and 1 rad/s.
pub const DRIVE_LIMITS: MotionLimits = MotionLimits {
    speed_m_s: 0.48,
    yaw_rate_rad_s: 1.0,
};

/// On the legs: the trot's full stride (8 cm in 55 % of a 1 s cycle) and 0.4 rad/s.
pub const WALK_LIMITS: MotionLimits = MotionLimits {
    speed_m_s: 0.145,
    yaw_rate_rad_s: 0.4,
};
