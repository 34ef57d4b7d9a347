//! Differential drive: a wheel-speed PI loop that produces torque, saturated, with anti-windup.
//!
//! The balance law ([`crate::wheels::balance`]) owns the common mode (both wheels together: it
//! must, since driving the wheels is how an inverted pendulum keeps its balance). This loop owns the
//! differential mode — half the speed difference of the wheels, which turns the robot — and
//! [`mix`] combines the two into per-wheel torques.

/// Gains and limits of a PI speed loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpeedLoopGains {
    /// Proportional gain, N·m per rad/s.
    pub kp_nm_per_rad_s: f32,
    /// Integral gain, N·m per rad.
    pub ki_nm_per_rad: f32,
    /// Output limit, N·m (symmetric).
    pub limit_nm: f32,
}

impl SpeedLoopGains {
    /// Turn loop of the robot (wheel inertia ≈ 0.018 kg·m² each, robot yaw inertia ≈ 2 kg·m²
    /// seen through r/track): a 2–3 rad/s bandwidth with a quarter of the wheel torque.
    pub const TURN: Self = Self {
        kp_nm_per_rad_s: 8.0,
        ki_nm_per_rad: 25.0,
        limit_nm: 24.0,
    };
}

/// A PI speed loop. Anti-windup by conditional integration: the integral stops growing while
/// the output is saturated in the direction the error pushes, and it is itself bounded so that
/// it alone can never exceed the output limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpeedLoop {
    gains: SpeedLoopGains,
    integral_nm: f32,
}

impl SpeedLoop {
    /// A loop at rest.
    pub const fn new(gains: SpeedLoopGains) -> Self {
        Self {
            gains,
            integral_nm: 0.0,
        }
    }

    /// Forgets the integral (on mode changes).
    pub fn reset(&mut self) {
        self.integral_nm = 0.0;
    }

    /// The integral term, N·m.
    pub fn integral_nm(&self) -> f32 {
        self.integral_nm
    }

    /// One tick of `dt_s`: torque for a speed `error_rad_s` (target − measured). Non-finite
    /// error gives zero torque and leaves the integral untouched.
    pub fn update(&mut self, error_rad_s: f32, dt_s: f32) -> f32 {
        if !error_rad_s.is_finite() {
            return 0.0;
        }
        let limit = self.gains.limit_nm;
        let proportional = self.gains.kp_nm_per_rad_s * error_rad_s;
        let unclamped = proportional + self.integral_nm;
        let pushing_further =
            (unclamped >= limit && error_rad_s > 0.0) || (unclamped <= -limit && error_rad_s < 0.0);
        if !pushing_further {
            let integral = self.integral_nm + self.gains.ki_nm_per_rad * error_rad_s * dt_s;
            self.integral_nm = crate::math::clamp(integral, -limit, limit);
        }
        crate::math::clamp(proportional + self.integral_nm, -limit, limit)
    }
}

/// Per-wheel torques `(left, right)` from the common torque (total of both wheels) and the
/// differential torque (added to the left wheel, taken from the right), each clamped to
/// `limit_nm`. Non-finite inputs count as zero.
pub fn mix(common_nm: f32, differential_nm: f32, limit_nm: f32) -> (f32, f32) {
    let finite = |value: f32| if value.is_finite() { value } else { 0.0 };
    let (common, differential) = (finite(common_nm), finite(differential_nm));
    let limit = finite(limit_nm).abs();
    (
        crate::math::clamp(0.5 * common + differential, -limit, limit),
        crate::math::clamp(0.5 * common - differential, -limit, limit),
    )
}
