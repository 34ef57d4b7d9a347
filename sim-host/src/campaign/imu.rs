//! The IMU part of a trial's plant: bias and noise drawn within the IMU's data sheet, into the
//! fields [`ImuNoise`] has. Everything that knows the part or the noise model is in this file,
//! so a different IMU model (a chip with its own filter and drift) changes this file alone.
//!
//! # The part
//!
//! A Bosch BMI088 (data sheet BST-BMI088-DS001, typical figures, which Bosch gives as 1σ of the
//! part spread), gyro at 2000 Hz with its 230 Hz filter, accelerometer at 1600 Hz with 234 Hz:
//!
//! | figure              | gyro           | accelerometer                     |
//! |---------------------|----------------|-----------------------------------|
//! | noise density       | 0.014 °/s/√Hz  | 160 µg/√Hz (x, y), 190 µg/√Hz (z) |
//! | turn-on offset (1σ) | ±1 °/s         | ±20 mg                            |
//!
//! # What is drawn, and the interpretation of "within the data sheet"
//!
//! - bias: each axis uniform within ± the turn-on offset;
//! - white noise: standard deviation uniform from 0 to the density times the square root of
//!   the filter's noise bandwidth (a second-order Butterworth's is 1.11 × its −3 dB
//!   frequency), the larger axis's density for all three;
//! - orientation noise: the IMU node on this branch reports an orientation, which a BMI088
//!   does not compute; it is drawn up to the tilt the accelerometer's noise alone makes
//!   (accelerometer noise over g), the error of an attitude taken from the accelerometer.

use crate::campaign::draw::{Harsh, Parameter, Scale, Values};
use crate::robot::imu::ImuNoise;

const DEG: f64 = std::f64::consts::PI / 180.0;
/// Standard gravity, m/s² (the data sheet's g).
const G: f64 = 9.806_65;
/// Gyro turn-on offset, 1σ, rad/s.
const GYRO_OFFSET: f64 = DEG;
/// Accelerometer turn-on offset, 1σ, m/s².
const ACCEL_OFFSET: f64 = 20e-3 * G;

/// The IMU's drawn parameters, after [`crate::campaign::draw::BODY`]'s. Ranges in SI units
/// (rad/s, m/s², rad); the table shows them so.
pub const PARAMETERS: [Parameter; 9] = [
    bias("gyro_bias_x", GYRO_OFFSET, "rad/s"),
    bias("gyro_bias_y", GYRO_OFFSET, "rad/s"),
    bias("gyro_bias_z", GYRO_OFFSET, "rad/s"),
    bias("accel_bias_x", ACCEL_OFFSET, "m/s²"),
    bias("accel_bias_y", ACCEL_OFFSET, "m/s²"),
    bias("accel_bias_z", ACCEL_OFFSET, "m/s²"),
    // The upper ends are `gyro_noise_max()` etc. rounded (a const cannot take a square
    // root); a test holds them within 2 % of the computed figures.
    white("gyro_noise", 3.9e-3, "rad/s"),
    white("accel_noise", 0.03, "m/s²"),
    white("orientation_noise", 3.1e-3, "rad"),
];

const fn bias(name: &'static str, limit: f64, unit: &'static str) -> Parameter {
    Parameter {
        name,
        range: (-limit, limit),
        unit,
        scale: Scale::Linear,
        harsh: Harsh::BothEnds,
    }
}

const fn white(name: &'static str, max: f64, unit: &'static str) -> Parameter {
    Parameter {
        name,
        range: (0.0, max),
        unit,
        scale: Scale::Linear,
        harsh: Harsh::High,
    }
}

/// The IMU noise with the parameters `value` sets (an ideal sensor where unset), its
/// generator seeded by `seed`.
pub fn noise(value: Values<'_>, seed: u64) -> ImuNoise {
    let or_zero = |name: &str| value(name).unwrap_or(0.0);
    let axes = |prefix: &str| ["x", "y", "z"].map(|axis| or_zero(&format!("{prefix}_{axis}")));
    ImuNoise {
        gyro_std_rad_s: or_zero("gyro_noise"),
        gyro_bias_rad_s: axes("gyro_bias"),
        accel_std_m_s2: or_zero("accel_noise"),
        accel_bias_m_s2: axes("accel_bias"),
        orientation_std_rad: or_zero("orientation_noise"),
        seed,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Noise bandwidth of a second-order Butterworth low-pass over its −3 dB frequency.
    const BUTTERWORTH2_NOISE_BANDWIDTH: f64 = 1.11;

    /// Gyro white noise at the output, 1σ, rad/s.
    fn gyro_noise_max() -> f64 {
        0.014 * DEG * (BUTTERWORTH2_NOISE_BANDWIDTH * 230.0_f64).sqrt()
    }

    /// Accelerometer white noise at the output, 1σ, m/s² (the z axis's density, the larger).
    fn accel_noise_max() -> f64 {
        190e-6 * G * (BUTTERWORTH2_NOISE_BANDWIDTH * 234.0_f64).sqrt()
    }

    #[test]
    fn the_noise_ranges_are_the_data_sheets() {
        let top = |name: &str| PARAMETERS.iter().find(|p| p.name == name).unwrap().range.1;
        let close = |a: f64, b: f64| (a - b).abs() <= 0.02 * b;
        assert!(
            close(top("gyro_noise"), gyro_noise_max()),
            "{}",
            gyro_noise_max()
        );
        assert!(
            close(top("accel_noise"), accel_noise_max()),
            "{}",
            accel_noise_max()
        );
        assert!(
            close(top("orientation_noise"), accel_noise_max() / G),
            "{}",
            accel_noise_max() / G
        );
    }

    #[test]
    fn the_noise_carries_the_draws() {
        let draws = crate::campaign::draw::Draws::of(3);
        let n = noise(&|name| Some(draws.value(name)), draws.seed);
        assert_eq!(n.gyro_bias_rad_s[1], draws.value("gyro_bias_y"));
        assert_eq!(n.accel_std_m_s2, draws.value("accel_noise"));
        assert_eq!(n.seed, 3);
        assert!(n.gyro_bias_rad_s.iter().all(|b| b.abs() <= GYRO_OFFSET));
    }
}
