//! What a drive measures of its own joint: the angle its encoder counts, the velocity it
//! derives from those counts, and the torque it infers from its phase current — not MuJoCo's
//! exact state.
//!
//! # The parts
//!
//! - **Leg joints**: a 14-bit magnetic encoder (AS5047P class, 16,384 counts per turn) on the
//!   motor, behind the actuator class's 9.1 : 1 reduction ([`Rating::LEG_JOINT`](crate::robot::rating::Rating::LEG_JOINT)):
//!   149,094 counts per joint turn, 4.2e-5 rad per count (finer than the wire's 1e-4 rad).
//! - **Wheels**: the same encoder on the wheel axle (a hub motor turns with its wheel):
//!   16,384 counts per turn, 3.8e-4 rad per count.
//! - **Velocity**: the count difference between two consecutive samples of the drive's
//!   encoder over the time between them, as a drive without an observer computes it. The
//!   drive samples when it reports and when it closes its loop, at most once per simulated
//!   instant (once a control cycle here): one count in 4 ms is 0.0105 rad/s on a leg joint and
//!   0.096 rad/s (1.2 cm/s of ground speed) on a wheel, and the value lags the true speed by
//!   half a cycle.
//! - **Effort**: the torque the motor applied times (1 + gain error), the error the drive's
//!   torque constant and current sense leave: drawn once per joint, uniform within
//!   ±[`DriveSensing::effort_gain_error`] (5 % by default, the spread of a motor's torque
//!   constant over temperature and parts).
//!
//! [`DriveSensing::IDEAL`] keeps the exact values, for debugging a controller.

use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};

/// How the drives measure their joints.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DriveSensing {
    /// Counts per joint turn of a leg joint's encoder; `None`: the exact angle.
    pub leg_counts_per_turn: Option<f64>,
    /// Counts per turn of a wheel's encoder; `None`: the exact angle.
    pub wheel_counts_per_turn: Option<f64>,
    /// Largest relative error of a reported effort (each joint's drawn uniformly within ±).
    pub effort_gain_error: f64,
    /// Seed of the drawn gain errors.
    pub seed: u64,
}

/// Counts per turn of the AS5047P class's 14-bit output.
const ENCODER_COUNTS_PER_TURN: f64 = 16_384.0;
/// The leg actuator class's reduction, output turns per motor turn inverted.
const LEG_REDUCTION: f64 = 9.1;

impl DriveSensing {
    /// The parts named in the module's documentation.
    pub const REAL: Self = Self {
        leg_counts_per_turn: Some(ENCODER_COUNTS_PER_TURN * LEG_REDUCTION),
        wheel_counts_per_turn: Some(ENCODER_COUNTS_PER_TURN),
        effort_gain_error: 0.05,
        seed: 1,
    };

    /// Exact angles, velocities and efforts.
    pub const IDEAL: Self = Self {
        leg_counts_per_turn: None,
        wheel_counts_per_turn: None,
        effort_gain_error: 0.0,
        seed: 1,
    };

    /// The effort gains of `n` joints, drawn from this sensing's seed and `stream` (one stream
    /// per drive, so that the drives' errors differ).
    pub fn effort_gains<const N: usize>(&self, stream: u64) -> [f64; N] {
        let mut rng = SmallRng::seed_from_u64(self.seed ^ stream.wrapping_mul(0x9E37_79B9));
        let error = self.effort_gain_error.abs();
        std::array::from_fn(|_| {
            if error > 0.0 {
                1.0 + rng.random_range(-error..=error)
            } else {
                1.0
            }
        })
    }
}

/// One joint's encoder and the velocity its drive derives from it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Encoder {
    /// Radians per count; `None`: exact.
    count_rad: Option<f64>,
    /// The last sample's time (s) and count, and the measured angle and velocity.
    last: Option<(f64, i64)>,
    angle_rad: f64,
    velocity_rad_s: f64,
}

impl Encoder {
    /// An encoder of `counts_per_turn` (`None`: exact) that has not sampled yet.
    pub fn new(counts_per_turn: Option<f64>) -> Self {
        Self {
            count_rad: counts_per_turn
                .filter(|counts| counts.is_finite() && *counts > 0.0)
                .map(|counts| std::f64::consts::TAU / counts),
            last: None,
            angle_rad: 0.0,
            velocity_rad_s: 0.0,
        }
    }

    /// Samples the joint at `angle_rad` at simulated time `time_s` (true velocity
    /// `velocity_rad_s`, used by an exact encoder and for the very first sample). A second
    /// sample at the same time changes nothing, so every user of the drive's measurement may
    /// ask for it first.
    pub fn sample(&mut self, angle_rad: f64, velocity_rad_s: f64, time_s: f64) {
        let Some(count_rad) = self.count_rad else {
            self.angle_rad = angle_rad;
            self.velocity_rad_s = velocity_rad_s;
            return;
        };
        let count = (angle_rad / count_rad).floor() as i64;
        match self.last {
            Some((last_s, _)) if time_s == last_s => return,
            Some((last_s, last_count)) if time_s > last_s => {
                self.velocity_rad_s = (count - last_count) as f64 * count_rad / (time_s - last_s);
            }
            _ => self.velocity_rad_s = velocity_rad_s,
        }
        self.angle_rad = count as f64 * count_rad;
        self.last = Some((time_s, count));
    }

    /// The angle of the last sample's count, rad.
    pub fn angle_rad(&self) -> f64 {
        self.angle_rad
    }

    /// The velocity from the last two samples' counts, rad/s.
    pub fn velocity_rad_s(&self) -> f64 {
        self.velocity_rad_s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_count_difference_gives_the_mean_speed_in_whole_counts() {
        let mut encoder = Encoder::new(Some(16_384.0));
        let count_rad = std::f64::consts::TAU / 16_384.0;
        encoder.sample(0.1, 0.0, 0.0);
        // 0.5 rad/s for 4 ms is 2 mrad: 5.2 counts, seen as 5 or 6.
        encoder.sample(0.1 + 0.002, 0.5, 0.004);
        let velocity = encoder.velocity_rad_s();
        encoder.sample(0.2, 9.0, 0.004);
        assert_eq!(
            encoder.velocity_rad_s(),
            velocity,
            "a second sample at one time"
        );
        let counts = encoder.velocity_rad_s() * 0.004 / count_rad;
        assert!((counts - counts.round()).abs() < 1e-9, "{counts}");
        assert!((5.0..=6.0).contains(&counts.round()), "{counts}");
        assert!((encoder.angle_rad() - 0.102).abs() <= count_rad);
    }

    #[test]
    fn an_exact_encoder_reports_the_truth_and_gains_stay_in_their_bound() {
        let mut encoder = Encoder::new(None);
        encoder.sample(0.123_456, 1.5, 0.0);
        assert_eq!(
            (encoder.angle_rad(), encoder.velocity_rad_s()),
            (0.123_456, 1.5)
        );
        let gains: [f64; 16] = DriveSensing::REAL.effort_gains(3);
        assert!(gains.iter().all(|g| (0.95..=1.05).contains(g)));
        assert!(gains.iter().any(|g| (g - 1.0).abs() > 1e-3), "{gains:?}");
        assert_eq!(DriveSensing::IDEAL.effort_gains::<4>(3), [1.0; 4]);
    }
}
