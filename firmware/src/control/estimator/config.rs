//! The attitude filter's gains and thresholds, and the robot's.

/// Gains and thresholds of the attitude filter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EstimatorConfig {
    /// Accelerometer correction after the start-up phase, rad/s per unit of error: the
    /// crossover below which the tilt follows the accelerometer.
    pub kp_per_s: f32,
    /// Bias integral after the start-up phase, 1/s² (with `kp_per_s` it sets how fast a bias
    /// is learned and its drift tracked: poles of `s² + k_p s + k_i`).
    pub ki_per_s2: f32,
    /// Accelerometer correction for a while after the first sample, rad/s: the initial
    /// alignment converges from the accelerometer within about a second.
    pub kp_start_per_s: f32,
    /// How long the start-up gain holds after the first sample, ms (no bias learning then).
    pub start_ms: u32,
    /// Time constant with which the reference `|a|` at rest follows the gravity share along
    /// "up" while the torso does not turn, s: about a second, because a 1σ chip offset along z
    /// already leaves the trust band, and a robot that folds onto its wheels at once gets no
    /// still window to measure it (with 20 s the accelerometer of such a chip was ignored
    /// through the campaign's scenarios: over 100 trials 86.6 → 89.6 %, `A` 88 → 95 %).
    pub rest_s: f32,
    /// A still window this long calibrates the gyro bias, ms.
    pub still_ms: u32,
    /// A gyro reading this far from the window's mean on any axis is not still, rad/s (five
    /// times a BMI088's noise at its 230 Hz bandwidth).
    pub still_rad_s: f32,
    /// An accelerometer reading this far from the window's mean on any axis is not still,
    /// m/s² (0.7° of tilt; four times a BMI088's noise at its bandwidth).
    pub still_m_s2: f32,
    /// `|a|` within this fraction of its value at rest: the accelerometer is fully trusted.
    pub accel_trust: f32,
    /// `|a|` this fraction or more away from its value at rest: the accelerometer is ignored.
    pub accel_distrust: f32,
    /// Turning slower than this, the accelerometer is fully trusted, rad/s.
    pub turn_trust_rad_s: f32,
    /// Turning this fast or faster, the accelerometer is ignored, rad/s.
    pub turn_distrust_rad_s: f32,
    /// A start and a still window need `|a|` within this fraction of g (a BMI088's 3σ offsets
    /// move it by up to 6 %).
    pub near_g: f32,
    /// Bound on the bias estimate, rad/s (beyond a BMI088's 3σ turn-on offset).
    pub bias_limit_rad_s: f32,
    /// Samples further apart than this restart the filter from the accelerometer, ms.
    pub max_gap_ms: u32,
    /// The IMU's height above the wheel axle, along body z, m (its lever arm on the wheels).
    pub imu_above_axle_m: f32,
    /// On the wheels, the accelerometer correction grows by this per rad/s of spin about
    /// "up" beyond [`EstimatorConfig::turn_trust_rad_s`], 1/rad (see the module docs,
    /// "Spinning").
    pub spin_kp_per_rad: f32,
    /// Time constant of the low-pass on the accelerometer's gravity share, s (40 ms, a
    /// twentieth of the crossover's: the wheels' speed and the IMU's reading do not line up
    /// sample by sample, and their difference's jitter would fail the `|a|` test).
    pub accel_filter_s: f32,
    /// The same while the legs stride, s: a stride of the trot at its nominal 1 Hz. Read
    /// sample by sample, the trot's bounce left the accelerometer outside the trust band most
    /// of the time, and the estimate drifted on the gyro by up to 10.5° in 10 s of `K`.
    pub stride_filter_s: f32,
}

impl EstimatorConfig {
    /// The robot's filter: crossover 1.2 rad/s, bias integral critically damped (a double
    /// pole at 0.6 rad/s: a bias is learned within about 6 s), start-up at 2 rad/s for 1 s,
    /// calibration over 0.4 s still. Chosen in the closed loop: a slower integral (k_i 0.032)
    /// left a 1.7σ bias half learned after 8 s, 3° of pitch error; at 0.8 rad/s (k_i 0.16) the
    /// fold, which the filter rides out mostly on the gyro, left the estimate 4–7° off the
    /// truth when the robot began to balance, decaying over seconds, and the balance law's
    /// trim, the levelling and W's start followed that error (campaign over 100 trials: 84.7 →
    /// 86.6 %, A 78 → 88 %, W 58 → 66 %). Faster still gave more in the campaign (1.6, 2.2 rad/s:
    /// 87.6, 88.3 %) but moved the fold's return: from standing 4.8 and 6.0 cm from where it
    /// began, against 3.8 cm here and a goal of 5.
    pub const ROBOT: Self = Self {
        kp_per_s: 1.2,
        ki_per_s2: 0.36,
        kp_start_per_s: 2.0,
        start_ms: 1_000,
        rest_s: 1.0,
        still_ms: 400,
        still_rad_s: 0.02,
        still_m_s2: 0.12,
        accel_trust: 0.02,
        accel_distrust: 0.04,
        near_g: 0.1,
        turn_trust_rad_s: 0.1,
        turn_distrust_rad_s: 0.3,
        bias_limit_rad_s: 0.1,
        max_gap_ms: 100,
        imu_above_axle_m: 0.15,
        spin_kp_per_rad: 2.0,
        accel_filter_s: 0.04,
        stride_filter_s: 1.0,
    };
}
