//! Torso attitude estimated from the IMU's gyro and accelerometer: a Mahony complementary
//! filter in its gravity-vector form, with gyro-bias estimation.
//!
//! # Why
//!
//! The IMU sends what its chip measures — angular rate and specific force — not an
//! orientation. Integrating the gyro alone drifts with its bias (a BMI088's turn-on offset is
//! ±1 °/s, 1σ: a degree of tilt every second); the accelerometer alone points along gravity
//! only while the torso does not accelerate. The filter integrates the gyro and pulls the
//! result toward the accelerometer's "up" slowly (crossover [`EstimatorConfig::kp_per_s`]),
//! so the tilt has the gyro's bandwidth without its drift. The balance law's pitch therefore
//! carries no filter lag: its high frequencies are the gyro's.
//!
//! # State
//!
//! Only the direction of "up" in the body frame, `v` (a unit vector; world z seen from the
//! torso), and the gyro bias `b`. Yaw is neither observable from gravity nor needed, so the
//! filter keeps no quaternion. Each sample of rate `ω` and specific force `a` over `dt`:
//!
//! ```text
//! ω' = ω − b                             the rate, bias removed (what the balance law gets)
//! g  ← lowpass(a − a_own(v, ω', motion)) gravity's share of the specific force
//! e  = w · (g/|g| × v)                   correction axis, weighted by how far to trust g
//! b ← b − k_i e dt                       bias: the part of the correction that persists
//! v ← normalise(v + (v × (ω' + k_p e)) dt)   v̇ = −ω × v
//! ```
//!
//! Pitch and roll follow from `v = (−sin θ, sin φ cos θ, cos φ cos θ)` (Z-Y-X Euler).
//!
//! # Accelerations
//!
//! A wheeled pendulum accelerates its axle under the torso to balance, and its torso turns
//! about that axle: both lean the accelerometer's "up" in step with the pitch, which a
//! complementary filter would follow. The controller therefore tells the filter the
//! [`Motion`] it knows: on the wheels, the axle's acceleration along the ground (the change of
//! the wheels' ground speed) and that the torso turns about the axle, the IMU
//! [`EstimatorConfig::imu_above_axle_m`] above it. `a_own` is that acceleration at the IMU
//! (tangential and centripetal terms from `ω'` and its change). What remains is weighted:
//! `w` is 1 while `|g|` is within [`EstimatorConfig::accel_trust`] of what the accelerometer
//! reads at rest (its offsets move that by a few per cent: tracked within about a second while
//! the torso does not turn, from the share along "up", which a sideways push does not move)
//! and falls to 0 at [`EstimatorConfig::accel_distrust`] (impacts, a trot's bounce), and it
//! falls likewise while the torso turns faster than
//! [`EstimatorConfig::turn_trust_rad_s`] (on the wheels, only its tilting counts: see
//! "Spinning"). An acceleration nobody told the filter and that
//! keeps `|a|` near g (a push on the legs) leans the estimate toward `atan(a/g)` with the
//! crossover's time constant.
//!
//! # Spinning
//!
//! What the filter converges to at rest carries the chip's accelerometer offset, an error fixed
//! to the body (the balance law's learned trim takes up its pitch share), and the share of the
//! gyro bias not yet learned. A spin in place on the wheels would turn that error with the
//! body if the gyro carried the estimate alone: a roll error of 3° becomes a pitch error of 3°
//! after a quarter turn, which the balance law rolls 15 cm to hold (measured in the campaign's
//! `A`). So on the wheels the spin about "up" does not count as turning for `w` (its
//! accelerations are in `a_own`), and `k_p` grows by [`EstimatorConfig::spin_kp_per_rad`] per
//! rad/s of spin beyond [`EstimatorConfig::turn_trust_rad_s`] (so that nothing changes while
//! the robot does not spin): at the on-the-spot turn's 2 rad/s the crossover is 5.0 rad/s,
//! fast against the turn, so the estimate stays where the accelerometer puts it, error and
//! all, as the trim expects.
//!
//! # Striding
//!
//! A trot bounces the torso at its step rate: read sample by sample, `|g|` sits outside the
//! trust band most of a stride, and the estimate coasts on the gyro (its pitch 10.5° off the
//! truth after 10 s of `K` on some of the campaign's robots). While the legs stride
//! ([`Motion::striding`]) gravity is therefore low-passed over
//! [`EstimatorConfig::stride_filter_s`], a stride: the bounce is cut to about a twelfth, and
//! what remains points along gravity as long as the torso, on average, does not accelerate.
//! The turn test reads the rate low-passed alike, so the stride's rocking does not count as
//! turning. The price: a tilt that goes on while the legs stride (a slow topple, a slope) is
//! pulled toward where gravity was a stride ago (8.5° behind after 2 s of a 0.3 rad/s topple,
//! the gyro carrying the rest). Two cures were measured and set aside: the estimate's "up"
//! averaged alike and compared with the average put the stride's lag inside the correction
//! loop (a damping ratio of about 0.3 instead of 1), and the average turned with the gyro
//! drifts by the gyro's unlearned bias; neither measured better in the campaign.
//!
//! # Start-up
//!
//! The first sample that feels about 1 g and shows no fast turn sets `v` from the
//! accelerometer (initial alignment),
//! and for [`EstimatorConfig::start_ms`] the filter runs with the fast
//! [`EstimatorConfig::kp_start_per_s`] and no bias integral, so that it converges from the
//! accelerometer within about a second, before or while the controller arms. The first time
//! the torso is still for [`EstimatorConfig::still_ms`] (every reading within
//! [`EstimatorConfig::still_rad_s`] and [`EstimatorConfig::still_m_s2`] of the window's mean:
//! a robot standing after power-up), the mean gyro reading there becomes the bias, the mean
//! specific force resets `v` (coarse alignment) and its magnitude the reference at rest. A
//! robot that folds onto its wheels at once is never that still, so the controller does not
//! wait for it: the integral learns the bias instead (an uncorrected bias `b` tilts the
//! estimate by `b / k_p`: 1.25° for a 1σ BMI088, decaying as the integral learns it). A gap in
//! the samples longer than [`EstimatorConfig::max_gap_ms`] restarts from the accelerometer
//! (keeping the bias).
//!
//! What no estimator removes: the accelerometer's own offset tilts "up" (20 mg, a BMI088's
//! 1σ, is 1.1°). On the wheels that becomes a static pitch error, which the balance law turns
//! into a position offset of 5 cm per degree (its pitch gain over its position gain, 2.97 m per
//! radian).

mod config;
mod vector;

pub use config::EstimatorConfig;

use crate::attitude::Attitude;
use crate::math::{atan2, clamp, sqrt};
use crate::time::{Tick, TickRate};
use vector::{cross, dot, normalise, scale, zip3};

/// Standard gravity, m/s².
pub const GRAVITY_M_S2: f32 = 9.806_65;

/// What the controller knows of the torso's own acceleration, so that the accelerometer's
/// reading can be freed of it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Motion {
    /// The wheels carry the robot: the torso turns about the wheel axle.
    pub on_wheels: bool,
    /// The axle's acceleration along the ground, forward, m/s² (from the wheels' speed).
    pub ground_accel_m_s2: f32,
    /// The legs stride in a periodic gait: the torso bounces and rocks about a steady
    /// attitude, so the accelerometer is read as its average over a stride.
    pub striding: bool,
}

/// The running filter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AttitudeEstimator {
    period_s: f32,
    still_ticks: u32,
    max_gap_ticks: u32,
    /// Up in the body frame (unit); `None` before the first usable sample.
    up: Option<[f32; 3]>,
    bias_rad_s: [f32; 3],
    /// Whether a still window has calibrated the bias (it does once).
    calibrated: bool,
    /// Gyro and accelerometer sums and the sample count of the still window under way.
    still_gyro: [f32; 3],
    still_accel: [f32; 3],
    still_count: u32,
    /// Ticks since the first sample, up to the start-up phase's length.
    started_ticks: u32,
    start_ticks: u32,
    /// The specific force with the torso's own acceleration taken out, low-passed, m/s².
    gravity: [f32; 3],
    /// The rate low-passed over a stride while the legs stride, rad/s: how far the torso
    /// turns, its stride's rocking averaged out.
    stride_rate_rad_s: [f32; 3],
    /// The specific force the accelerometer reads at rest, m/s²: g until a still window
    /// measures it (a chip's offsets move it by up to a few per cent).
    rest_m_s2: f32,
    last: Tick,
    attitude: Attitude,
    rate_rad_s: [f32; 3],
}

impl AttitudeEstimator {
    /// A filter with no sample yet, for samples arriving at `rate`, configured as `config`
    /// (which [`AttitudeEstimator::update`] is given again: the filter keeps no copy).
    pub fn new(config: &EstimatorConfig, rate: TickRate) -> Self {
        Self {
            period_s: rate.period_s(),
            still_ticks: rate.ticks_from_ms(config.still_ms).max(1),
            max_gap_ticks: rate.ticks_from_ms(config.max_gap_ms).max(1),
            up: None,
            bias_rad_s: [0.0; 3],
            calibrated: false,
            still_gyro: [0.0; 3],
            still_accel: [0.0; 3],
            still_count: 0,
            started_ticks: 0,
            start_ticks: rate.ticks_from_ms(config.start_ms),
            rest_m_s2: GRAVITY_M_S2,
            gravity: [0.0, 0.0, GRAVITY_M_S2],
            stride_rate_rad_s: [0.0; 3],
            last: Tick(0),
            attitude: Attitude::default(),
            rate_rad_s: [0.0; 3],
        }
    }

    /// The latest pitch and roll (level before the first sample).
    pub fn attitude(&self) -> Attitude {
        self.attitude
    }

    /// The latest body rate with the bias estimate removed, rad/s.
    pub fn rate_rad_s(&self) -> [f32; 3] {
        self.rate_rad_s
    }

    /// The gyro bias estimate, rad/s.
    pub fn bias_rad_s(&self) -> [f32; 3] {
        self.bias_rad_s
    }

    /// Whether the filter has an attitude (a usable sample arrived).
    pub fn started(&self) -> bool {
        self.up.is_some()
    }

    /// Whether a still window has calibrated the gyro bias.
    pub fn calibrated(&self) -> bool {
        self.calibrated
    }

    /// Takes one sample at `now`: body rate (rad/s) and specific force (m/s²), with what the
    /// controller knows of the torso's own `motion`. Returns whether it was used: a
    /// non-finite sample, a first sample whose specific force is not near g, or a second
    /// sample in the same tick is ignored.
    pub fn update(
        &mut self,
        config: &EstimatorConfig,
        now: Tick,
        gyro_rad_s: [f32; 3],
        accel_m_s2: [f32; 3],
        motion: Motion,
    ) -> bool {
        let finite = gyro_rad_s.iter().chain(&accel_m_s2).all(|x| x.is_finite());
        if !finite {
            return false;
        }
        let ticks = now.since(self.last);
        let up = match self.up {
            Some(up) if ticks <= self.max_gap_ticks => up,
            _ => return self.try_start(config, now, gyro_rad_s, accel_m_s2),
        };
        if ticks == 0 {
            return false;
        }
        if !self.calibrated {
            if let Some(still_up) = self.calibrate(config, gyro_rad_s, accel_m_s2) {
                let rate = zip3(gyro_rad_s, self.bias_rad_s, |w, b| w - b);
                self.finish(now, still_up, rate);
                return true;
            }
        }
        let dt_s = ticks as f32 * self.period_s;
        let rate = zip3(gyro_rad_s, self.bias_rad_s, |w, b| w - b);
        self.started_ticks = self
            .started_ticks
            .saturating_add(ticks)
            .min(self.start_ticks);
        let error = self.correction(config, up, rate, accel_m_s2, dt_s, motion);
        let (kp, ki) = if self.started_ticks < self.start_ticks {
            (config.kp_start_per_s, 0.0)
        } else {
            (config.kp_per_s, config.ki_per_s2)
        };
        let kp = if motion.on_wheels {
            let spin_rad_s = dot(rate, up).abs() - config.turn_trust_rad_s;
            kp + config.spin_kp_per_rad * spin_rad_s.max(0.0)
        } else {
            kp
        };
        let (step, limit) = (ki * dt_s, config.bias_limit_rad_s);
        self.bias_rad_s = zip3(self.bias_rad_s, error, |b, e| {
            clamp(b - step * e, -limit, limit)
        });
        let corrected = zip3(rate, error, |w, e| w + kp * e);
        let moved = zip3(up, cross(up, corrected), |v, d| v + d * dt_s);
        self.finish(now, normalise(moved).unwrap_or(up), rate);
        true
    }

    /// The correction axis `e`: the accelerometer's gravity share (the torso's own acceleration
    /// taken out, low-passed) crossed with `up`, weighted by how far it can be trusted.
    fn correction(
        &mut self,
        config: &EstimatorConfig,
        up: [f32; 3],
        rate: [f32; 3],
        accel_m_s2: [f32; 3],
        dt_s: f32,
        motion: Motion,
    ) -> [f32; 3] {
        let own = self.own_acceleration(config, up, rate, dt_s, motion);
        let filter_s = if motion.striding {
            config.stride_filter_s
        } else {
            config.accel_filter_s
        };
        let k = (dt_s / filter_s).min(1.0);
        let gravity = zip3(
            self.gravity,
            zip3(accel_m_s2, own, |a, o| a - o),
            |lp, x| lp + k * (x - lp),
        );
        self.gravity = gravity;
        let norm = sqrt(dot(gravity, gravity));
        // On the wheels a spin about "up" tilts nothing and its acceleration at the IMU is in
        // `own`: only the tilting part of the rate makes the accelerometer less trustworthy.
        let turning = if motion.on_wheels {
            cross(rate, up)
        } else {
            rate
        };
        // A stride's rocking turns the torso back and forth about where it stays: only a turn
        // that lasts over a stride counts.
        self.stride_rate_rad_s = if motion.striding {
            zip3(self.stride_rate_rad_s, turning, |lp, x| lp + k * (x - lp))
        } else {
            turning
        };
        let turn = turn_weight(config, self.stride_rate_rad_s);
        self.track_rest(config, dot(gravity, up), dt_s, turn >= 1.0);
        let weight = self.accel_weight(config, norm) * turn;
        if weight > 0.0 {
            scale(cross(scale(gravity, 1.0 / norm), up), weight)
        } else {
            [0.0; 3]
        }
    }

    /// The specific force of the torso's own acceleration at the IMU, body frame, m/s²: the
    /// axle's along the ground, and on the wheels the turn about the axle (tangential
    /// `α × r` and centripetal `ω × (ω × r)`, `r` the IMU's height above the axle along body
    /// z; `α` from the change of the rate since the last sample).
    fn own_acceleration(
        &self,
        config: &EstimatorConfig,
        up: [f32; 3],
        rate: [f32; 3],
        dt_s: f32,
        motion: Motion,
    ) -> [f32; 3] {
        let [ux, uy, uz] = up;
        // The ground's forward direction in the body frame: body x with its vertical part out.
        let level = sqrt((1.0 - ux * ux).max(0.0));
        let forward = if level > 0.1 {
            scale([1.0 - ux * ux, -ux * uy, -ux * uz], 1.0 / level)
        } else {
            [0.0; 3]
        };
        let mut own = scale(forward, motion.ground_accel_m_s2);
        if motion.on_wheels {
            let h = config.imu_above_axle_m;
            let alpha = zip3(rate, self.rate_rad_s, |w, w0| (w - w0) / dt_s);
            let ([wx, wy, wz], [ax, ay, _]) = (rate, alpha);
            let turn = [
                h * (ay + wx * wz),
                h * (wy * wz - ax),
                -h * (wx * wx + wy * wy),
            ];
            own = zip3(own, turn, |a, b| a + b);
        }
        own
    }

    /// Follows what the accelerometer reads at rest while the torso does not turn: its
    /// gravity share along "up", `along_m_s2`, where it is near g. A chip's offsets move it by
    /// a few per cent, as much as the trust band, and a torso that folds onto its wheels at
    /// once is never still long enough to measure it; a push or an untold acceleration leans
    /// the specific force sideways, which moves its magnitude but not its share along "up".
    fn track_rest(&mut self, config: &EstimatorConfig, along_m_s2: f32, dt_s: f32, quiet: bool) {
        if quiet && near_g(config, along_m_s2) {
            let k = (dt_s / config.rest_s).min(1.0);
            self.rest_m_s2 += k * (along_m_s2 - self.rest_m_s2);
        }
    }

    /// (Re)start: up is where the accelerometer points, from a sample that feels about 1 g and
    /// shows no fast turn (not one of a fall).
    fn try_start(
        &mut self,
        config: &EstimatorConfig,
        now: Tick,
        gyro_rad_s: [f32; 3],
        accel_m_s2: [f32; 3],
    ) -> bool {
        let norm = sqrt(dot(accel_m_s2, accel_m_s2));
        if !(near_g(config, norm) && turn_weight(config, gyro_rad_s) > 0.0) {
            return false;
        }
        self.start(now, scale(accel_m_s2, 1.0 / norm), gyro_rad_s);
        true
    }

    fn start(&mut self, now: Tick, up: [f32; 3], gyro_rad_s: [f32; 3]) {
        self.restart_window();
        self.gravity = scale(up, self.rest_m_s2);
        let rate = zip3(gyro_rad_s, self.bias_rad_s, |w, b| w - b);
        self.stride_rate_rad_s = rate;
        self.finish(now, up, rate);
    }

    fn finish(&mut self, now: Tick, up: [f32; 3], rate_rad_s: [f32; 3]) {
        self.up = Some(up);
        self.last = now;
        self.rate_rad_s = rate_rad_s;
        self.attitude = attitude_of(up);
    }

    fn restart_window(&mut self) {
        self.still_gyro = [0.0; 3];
        self.still_accel = [0.0; 3];
        self.still_count = 0;
    }

    /// One sample of the start-up calibration. Over a still window the torso does not turn, so
    /// the mean gyro reading is the bias and the mean specific force points up: when the window
    /// completes, the bias is set and the new "up" returned. Any motion restarts the window.
    fn calibrate(
        &mut self,
        config: &EstimatorConfig,
        gyro_rad_s: [f32; 3],
        accel_m_s2: [f32; 3],
    ) -> Option<[f32; 3]> {
        // Stillness: every reading stays near the window's mean so far (a steady turn keeps
        // the gyro steady but turns the accelerometer, so both are checked).
        // |sum / n − x| ≤ limit, as |sum − n x| ≤ n limit: no division per sample.
        let n = self.still_count as f32;
        let (turn, push) = (config.still_rad_s, config.still_m_s2);
        let near = |sum: [f32; 3], x: [f32; 3], limit: f32| {
            zip3(sum, x, |s, x| s - n * x)
                .iter()
                .all(|d| d.abs() <= n * limit)
        };
        let still = near_g(config, sqrt(dot(accel_m_s2, accel_m_s2)))
            && near(self.still_gyro, gyro_rad_s, turn)
            && near(self.still_accel, accel_m_s2, push);
        if !still {
            self.restart_window();
            return None;
        }
        self.still_gyro = zip3(self.still_gyro, gyro_rad_s, |s, w| s + w);
        self.still_accel = zip3(self.still_accel, accel_m_s2, |s, a| s + a);
        self.still_count = self.still_count.saturating_add(1);
        if self.still_count < self.still_ticks {
            return None;
        }
        let n = self.still_count as f32;
        self.bias_rad_s = self.still_gyro.map(|s| s / n);
        self.calibrated = true;
        let mean = scale(self.still_accel, 1.0 / n);
        self.rest_m_s2 = sqrt(dot(mean, mean));
        normalise(mean)
    }

    /// How far the accelerometer is trusted at specific force `norm`, 0…1: by how far `norm`
    /// is from what it reads at rest.
    fn accel_weight(&self, config: &EstimatorConfig, norm: f32) -> f32 {
        let deviation = (norm / self.rest_m_s2 - 1.0).abs();
        let (trust, distrust) = (config.accel_trust, config.accel_distrust);
        if deviation <= trust {
            1.0
        } else if deviation < distrust {
            (distrust - deviation) / (distrust - trust)
        } else {
            // Beyond the band, and NaN.
            0.0
        }
    }
}

/// How far the accelerometer is trusted while the torso turns at `gyro_rad_s`, 0…1: a turning
/// torso feels the tangential and centripetal accelerations of its turn (a balancing robot
/// pitches hardest when it brakes or starts).
fn turn_weight(config: &EstimatorConfig, gyro_rad_s: [f32; 3]) -> f32 {
    let rate = sqrt(dot(gyro_rad_s, gyro_rad_s));
    let (trust, distrust) = (config.turn_trust_rad_s, config.turn_distrust_rad_s);
    clamp((distrust - rate) / (distrust - trust), 0.0, 1.0)
}

/// Whether specific force `norm` is within [`EstimatorConfig::near_g`] of g: what a still
/// torso with any chip's offsets reads.
fn near_g(config: &EstimatorConfig, norm: f32) -> bool {
    (norm / GRAVITY_M_S2 - 1.0).abs() <= config.near_g
}

/// Pitch and roll of the body whose "up" is `up` (unit). Pitch as `atan2`, not `asin`: the
/// kinematics already link `atan2` into the image, and it needs no clamp.
fn attitude_of(up: [f32; 3]) -> Attitude {
    let [x, y, z] = up;
    Attitude {
        pitch_rad: atan2(-x, sqrt(y * y + z * z)),
        roll_rad: atan2(y, z),
    }
}

#[cfg(test)]
mod tests;
