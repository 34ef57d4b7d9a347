//! The IMU part of a trial's plant: which Bosch BMI088 the robot carries. Everything that
//! knows the part is in this file and in the simulator's chip model
//! ([`crate::robot::imu_chip`]), so a different IMU changes this file alone.
//!
//! # What is drawn, and the interpretation of "within the data sheet"
//!
//! The trial does not draw noise figures of its own: it gives the chip model a seed (drawn
//! from the trial's stream), and the model draws the part from the data sheet
//! (BST-BMI088-DS001, typical figures, which Bosch gives as 1σ of the part spread), as it does
//! for `sim-host run --seed`:
//!
//! - turn-on offset: normal per axis, 1σ = 1 °/s (gyro) and 20 mg (accelerometer), then its
//!   walk (the offset's temperature coefficient over a wandering die temperature);
//! - white noise at the data sheet's density (0.014 °/s/√Hz; 160 µg/√Hz in x and y, 190 in
//!   z) through the chip's 230 / 234 Hz filters, the range, the LSB, the output rate and the
//!   filter's delay: the part's, the same for every chip.
//!
//! So the noise is the data sheet's and the offsets are the data sheet's spread. The six
//! turn-on offsets are reported as parameters ([`PARAMETERS`]: the chip's own draw, read back
//! from the model) so that the table can say how far out in the spread a failing robot's chip
//! was; their `u` is that place, Φ(offset / σ).
//!
//! The sweep (one parameter at a time) cannot pick a chip by one offset; it keeps the default
//! chip and moves one axis's offset to the end of its range with the IMU's extra bias, added
//! before the chip as the chip adds its own ([`set_offset`]).

use crate::campaign::draw::{Harsh, Parameter, Scale};
use crate::robot::imu::ImuModel;
use crate::robot::imu_chip::{ChipSpec, ImuChip};
use crate::robot::plant::Plant;

/// The part.
pub const SPEC: ChipSpec = ChipSpec::BMI088;

/// The chip's turn-on offsets, gyro x y z (rad/s) then accelerometer x y z (m/s²), each over
/// ±2σ of the data sheet's spread (the sweep's ends; the draw is the chip's, normal).
pub const PARAMETERS: [Parameter; 6] = [
    offset("gyro_offset_x", SPEC.gyro.offset_sigma, "rad/s"),
    offset("gyro_offset_y", SPEC.gyro.offset_sigma, "rad/s"),
    offset("gyro_offset_z", SPEC.gyro.offset_sigma, "rad/s"),
    offset("accel_offset_x", SPEC.accel.offset_sigma, "m/s²"),
    offset("accel_offset_y", SPEC.accel.offset_sigma, "m/s²"),
    offset("accel_offset_z", SPEC.accel.offset_sigma, "m/s²"),
];

const fn offset(name: &'static str, sigma: f64, unit: &'static str) -> Parameter {
    Parameter {
        name,
        range: (-2.0 * sigma, 2.0 * sigma),
        unit,
        scale: Scale::Chip,
        harsh: Harsh::BothEnds,
    }
}

/// The chip of `seed`'s turn-on offsets in [`PARAMETERS`] order: per offset, its place in the
/// spread (Φ(offset / σ)) and its value.
pub fn offsets(seed: u64) -> [(f64, f64); 6] {
    let (gyro, accel) = ImuChip::new(SPEC, seed).bias();
    let sigma = |i: usize| {
        if i < 3 {
            SPEC.gyro.offset_sigma
        } else {
            SPEC.accel.offset_sigma
        }
    };
    std::array::from_fn(|i| {
        let value = if i < 3 { gyro[i] } else { accel[i - 3] };
        (normal_cdf(value / sigma(i)), value)
    })
}

/// Puts the chip of `seed` into `plant`; the rest of the IMU (its mounting, the extra noise
/// and bias, off by default) stays the plant's.
pub fn fit_chip(plant: &mut Plant, seed: u64) {
    plant.imu = ImuModel::Chip(SPEC);
    plant.imu_noise.seed = seed;
}

/// Moves `plant`'s chip's turn-on offset `name` (one of [`PARAMETERS`]) to `value`: the extra
/// bias on that axis makes up the difference to the chip's own. Returns whether `name` is an
/// offset.
pub fn set_offset(plant: &mut Plant, name: &str, value: f64) -> bool {
    let Some(index) = PARAMETERS.iter().position(|p| p.name == name) else {
        return false;
    };
    plant.imu = ImuModel::Chip(SPEC);
    let own = offsets(plant.imu_noise.seed)[index].1;
    let noise = &mut plant.imu_noise;
    let axis = if index < 3 {
        &mut noise.gyro_bias_rad_s[index]
    } else {
        &mut noise.accel_bias_m_s2[index - 3]
    };
    *axis = value - own;
    true
}

/// The standard normal distribution function, Φ(z) = erfc(−z/√2) / 2, with erfc's Chebyshev
/// fit (Numerical Recipes' `erfcc`, fractional error below 1.2e-7): a place in a spread, for
/// the table's bins.
fn normal_cdf(z: f64) -> f64 {
    let x = -z / std::f64::consts::SQRT_2;
    let a = x.abs();
    let t = 1.0 / (1.0 + 0.5 * a);
    let poly = [
        -1.265_512_23,
        1.000_023_68,
        0.374_091_96,
        0.096_784_18,
        -0.186_288_06,
        0.278_868_07,
        -1.135_203_98,
        1.488_515_87,
        -0.822_152_23,
        0.170_872_77,
    ]
    .iter()
    .rev()
    .fold(0.0, |acc, c| c + t * acc);
    let erfc = t * (-a * a + poly).exp();
    0.5 * if x >= 0.0 { erfc } else { 2.0 - erfc }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::draw::Draws;

    #[test]
    fn the_normal_distribution_function_has_its_known_values() {
        for (z, phi) in [
            (0.0, 0.5),
            (1.0, 0.841_344_746),
            (-1.0, 0.158_655_254),
            (2.0, 0.977_249_868),
            (-3.0, 0.001_349_898),
        ] {
            assert!(
                (normal_cdf(z) - phi).abs() < 1e-6,
                "Φ({z}) = {}",
                normal_cdf(z)
            );
        }
    }

    #[test]
    fn the_offsets_are_the_chips_own_and_spread_as_the_data_sheet_says() {
        let draws = Draws::of(3);
        let plant = draws.plant(crate::robot::plant::DriveRatings::RATED);
        let chip = ImuChip::new(SPEC, plant.imu_noise.seed);
        assert_eq!(chip.bias().1[0], draws.value("accel_offset_x"));
        assert_eq!(plant.imu_noise.gyro_bias_rad_s, [0.0; 3]);
        // Over 400 chips, about 68 % of the offsets lie within 1σ (u within 0.16…0.84).
        let within: usize = (0..400)
            .flat_map(offsets)
            .filter(|(u, _)| (0.158..=0.842).contains(u))
            .count();
        let share = within as f64 / 2400.0;
        assert!((0.64..=0.72).contains(&share), "{share}");
    }

    #[test]
    fn the_sweep_moves_one_offset_of_the_default_chip() {
        let mut plant = Plant::default();
        assert!(set_offset(&mut plant, "accel_offset_x", 0.4));
        let own = offsets(plant.imu_noise.seed)[3].1;
        assert!((plant.imu_noise.accel_bias_m_s2[0] + own - 0.4).abs() < 1e-12);
        assert_eq!(plant.imu_noise.accel_bias_m_s2[1], 0.0);
        assert!(!set_offset(&mut plant, "mass", 1.0));
    }
}
