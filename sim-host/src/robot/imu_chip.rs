//! The torso IMU's chip: a Bosch BMI088 as its data sheet describes it, between MuJoCo's ideal
//! gyro and accelerometer and the IMU node.
//!
//! # The part and its figures
//!
//! Bosch Sensortec BMI088 data sheet (BST-BMI088-DS001), typical values (Bosch gives typical
//! figures as 1σ of the part spread). The robot runs the gyro at ±1000 °/s, ODR 2000 Hz with
//! its 230 Hz filter, and the accelerometer at ±6 g, ODR 1600 Hz in OSR2 mode (234 Hz):
//!
//! | figure                          | gyro                      | accelerometer                     |
//! |---------------------------------|---------------------------|-----------------------------------|
//! | range, resolution               | ±1000 °/s, 32.768 LSB/(°/s) | ±6 g, 5460 LSB/g                 |
//! | noise density                   | 0.014 °/s/√Hz             | 160 µg/√Hz (x, y), 190 µg/√Hz (z) |
//! | turn-on offset (1σ)             | ±1 °/s                    | ±20 mg                            |
//! | offset temperature coefficient  | 0.015 °/s/K               | 0.2 mg/K                          |
//! | output data rate / −3 dB        | 2000 Hz / 230 Hz          | 1600 Hz / 234 Hz                  |
//!
//! # The model
//!
//! Each sensor samples at its ODR. A sample is the truth (linearly interpolated between the
//! simulator's readings), plus the bias, plus white noise of variance `n² · ODR / 2` (a flat
//! one-sided density `n` up to Nyquist); it passes a second-order Butterworth low-pass at the
//! −3 dB bandwidth (the chip's digital filter: group delay √2 / (2π f_c), 0.98 ms for the gyro,
//! 0.96 ms for the accelerometer), is clamped to the range and rounded to the LSB. The node reads
//! the newest sample, so a reading is also up to one ODR period old.
//!
//! The bias is drawn per run from the turn-on spread (normal, 1σ as above) and then walks. The
//! data sheet gives no in-run bias instability; the walk is the offset's temperature
//! coefficient over a die temperature that wanders 1 K per √hour (gyro 4.4e-6 rad/s/√s,
//! accelerometer 3.3e-5 m/s²/√s) — an assumption, stated as one.
//!
//! Everything is drawn from one generator seeded per run, so a run repeats exactly.

use crate::robot::noise::gaussian;
use rand::rngs::SmallRng;
use rand::SeedableRng;

const DEG: f64 = std::f64::consts::PI / 180.0;
/// Standard gravity, m/s² (the data sheet's g).
const G: f64 = 9.806_65;

/// One sensor (three axes) of an IMU chip, SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorSpec {
    /// One count of the output register.
    pub lsb: f64,
    /// The largest output magnitude (the register's 32767 counts).
    pub full_scale: f64,
    /// White-noise density per axis, per √Hz (one-sided).
    pub noise_density: [f64; 3],
    /// Spread of the turn-on offset, 1σ per axis.
    pub offset_sigma: f64,
    /// Random walk of the offset, per √s.
    pub drift_per_sqrt_s: f64,
    /// Output data rate, Hz.
    pub odr_hz: f64,
    /// −3 dB bandwidth of the chip's filter, Hz.
    pub bandwidth_hz: f64,
}

impl SensorSpec {
    /// The filter's group delay at low frequency, s (second-order Butterworth).
    pub fn group_delay_s(&self) -> f64 {
        std::f64::consts::SQRT_2 / (2.0 * std::f64::consts::PI * self.bandwidth_hz)
    }
}

/// A named IMU part: its gyro and accelerometer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChipSpec {
    /// Maker and part number.
    pub part: &'static str,
    /// Angular rate, rad/s.
    pub gyro: SensorSpec,
    /// Specific force, m/s².
    pub accel: SensorSpec,
}

impl ChipSpec {
    /// Bosch BMI088 at ±1000 °/s, 2000 Hz / 230 Hz and ±6 g, 1600 Hz OSR2 (see the module).
    pub const BMI088: Self = Self {
        part: "Bosch BMI088",
        gyro: SensorSpec {
            lsb: DEG / 32.768,
            full_scale: 32_767.0 * DEG / 32.768,
            noise_density: [0.014 * DEG; 3],
            offset_sigma: DEG,
            drift_per_sqrt_s: 0.015 * DEG / 60.0,
            odr_hz: 2000.0,
            bandwidth_hz: 230.0,
        },
        accel: SensorSpec {
            lsb: G / 5460.0,
            full_scale: 32_767.0 * G / 5460.0,
            noise_density: [160e-6 * G, 160e-6 * G, 190e-6 * G],
            offset_sigma: 20e-3 * G,
            drift_per_sqrt_s: 0.2e-3 * G / 60.0,
            odr_hz: 1600.0,
            bandwidth_hz: 234.0,
        },
    };
}

/// Second-order Butterworth low-pass (bilinear transform, pre-warped), direct form II
/// transposed.
#[derive(Debug, Clone, Copy, PartialEq)]
struct LowPass {
    b0: f64,
    a1: f64,
    a2: f64,
    z1: f64,
    z2: f64,
}

impl LowPass {
    fn new(cutoff_hz: f64, rate_hz: f64) -> Self {
        let k = (std::f64::consts::PI * cutoff_hz / rate_hz).tan();
        let norm = 1.0 / (1.0 + std::f64::consts::SQRT_2 * k + k * k);
        Self {
            b0: k * k * norm,
            a1: 2.0 * (k * k - 1.0) * norm,
            a2: (1.0 - std::f64::consts::SQRT_2 * k + k * k) * norm,
            z1: 0.0,
            z2: 0.0,
        }
    }

    /// Settles the filter on a constant input `x` (so the first outputs carry no transient).
    fn settle(&mut self, x: f64) {
        let (b1, b2) = (2.0 * self.b0, self.b0);
        self.z2 = (b2 - self.a2) * x;
        self.z1 = (b1 - self.a1) * x + self.z2;
    }

    fn step(&mut self, x: f64) -> f64 {
        let (b1, b2) = (2.0 * self.b0, self.b0);
        let y = self.b0 * x + self.z1;
        self.z1 = b1 * x - self.a1 * y + self.z2;
        self.z2 = b2 * x - self.a2 * y;
        y
    }
}

/// One sensor of the chip as it runs.
#[derive(Debug, Clone)]
struct Channel {
    spec: SensorSpec,
    bias: [f64; 3],
    filters: [LowPass; 3],
    output: [f64; 3],
    /// Time of the next sample, s.
    next_s: f64,
}

impl Channel {
    fn new(spec: SensorSpec, rng: &mut SmallRng) -> Self {
        let bias = [0; 3].map(|_| gaussian(rng, spec.offset_sigma));
        Self {
            spec,
            bias,
            filters: [LowPass::new(spec.bandwidth_hz, spec.odr_hz); 3],
            output: [0.0; 3],
            next_s: 0.0,
        }
    }

    /// Starts sampling at `t_s` on a steady `truth`.
    fn start(&mut self, t_s: f64, truth: [f64; 3]) {
        for (axis, filter) in self.filters.iter_mut().enumerate() {
            filter.settle(truth[axis] + self.bias[axis]);
        }
        self.output = self.quantised(std::array::from_fn(|axis| truth[axis] + self.bias[axis]));
        self.next_s = t_s;
    }

    /// Takes every sample due up to `t_s`, the truth moving linearly from `from` (at `t0_s`) to
    /// `to` (at `t_s`).
    fn advance(&mut self, rng: &mut SmallRng, t0_s: f64, from: [f64; 3], t_s: f64, to: [f64; 3]) {
        let period = 1.0 / self.spec.odr_hz;
        while self.next_s <= t_s {
            let span = t_s - t0_s;
            let f = if span > 0.0 {
                ((self.next_s - t0_s) / span).clamp(0.0, 1.0)
            } else {
                1.0
            };
            let truth: [f64; 3] =
                std::array::from_fn(|axis| from[axis] + f * (to[axis] - from[axis]));
            let filtered = self.sample(rng, truth);
            self.output = self.quantised(filtered);
            self.next_s += period;
        }
    }

    /// One filtered sample of `truth` (before the register), and the bias's step.
    fn sample(&mut self, rng: &mut SmallRng, truth: [f64; 3]) -> [f64; 3] {
        let rate = self.spec.odr_hz;
        let filtered = std::array::from_fn(|axis| {
            let white = gaussian(rng, self.spec.noise_density[axis] * (0.5 * rate).sqrt());
            self.filters[axis].step(truth[axis] + self.bias[axis] + white)
        });
        let walk = self.spec.drift_per_sqrt_s / rate.sqrt();
        for bias in &mut self.bias {
            *bias += gaussian(rng, walk);
        }
        filtered
    }

    /// The register's value: clamped to the range, rounded to the LSB.
    fn quantised(&self, value: [f64; 3]) -> [f64; 3] {
        let (lsb, full) = (self.spec.lsb, self.spec.full_scale);
        value.map(|v| ((v.clamp(-full, full) / lsb).round() * lsb).clamp(-full, full))
    }
}

/// A running chip: both sensors with their biases and filters.
#[derive(Debug, Clone)]
pub struct ImuChip {
    rng: SmallRng,
    gyro: Channel,
    accel: Channel,
    /// The last truth handed in: time (s), rate, specific force.
    last: Option<(f64, [f64; 3], [f64; 3])>,
}

impl ImuChip {
    /// A chip of `spec` whose biases and noise come from `seed`.
    pub fn new(spec: ChipSpec, seed: u64) -> Self {
        let mut rng = SmallRng::seed_from_u64(seed);
        let gyro = Channel::new(spec.gyro, &mut rng);
        let accel = Channel::new(spec.accel, &mut rng);
        Self {
            rng,
            gyro,
            accel,
            last: None,
        }
    }

    /// The present biases (turn-on offset plus walk): gyro rad/s, accelerometer m/s².
    pub fn bias(&self) -> ([f64; 3], [f64; 3]) {
        (self.gyro.bias, self.accel.bias)
    }

    /// Runs the chip up to `t_s` with the true rate (rad/s) and specific force (m/s²) there;
    /// returns the newest output of each sensor.
    pub fn read(&mut self, t_s: f64, rate: [f64; 3], force: [f64; 3]) -> ([f64; 3], [f64; 3]) {
        match self.last {
            None => {
                self.gyro.start(t_s, rate);
                self.accel.start(t_s, force);
            }
            Some((t0_s, rate0, force0)) => {
                self.gyro.advance(&mut self.rng, t0_s, rate0, t_s, rate);
                self.accel.advance(&mut self.rng, t0_s, force0, t_s, force);
            }
        }
        self.last = Some((t_s, rate, force));
        (self.gyro.output, self.accel.output)
    }
}

#[cfg(test)]
mod tests;
