//! What the emulated hardware is made of, for a run: the IMU's chip and extra noise, the
//! drives' ratings and sensing, the bus's transport delay, and how the body differs from the
//! model. The tested default is [`Plant::default`]; the ideal parts stay for debugging a
//! controller.

use host_can::fault_plan::Faults;

use crate::robot::imu::{ImuModel, ImuNoise};
use crate::robot::imu_chip::ChipSpec;
use crate::robot::rangefinder::{RangeModel, RangeSpec};
use crate::robot::rating::Rating;
use crate::robot::sensing::DriveSensing;
use crate::robot::variation::Variation;

/// The ratings the drives enforce.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DriveRatings {
    /// Each leg joint's motor.
    pub leg_joint: Rating,
    /// Each wheel's motor.
    pub wheel: Rating,
}

impl DriveRatings {
    /// Real parts: [`Rating::LEG_JOINT`], [`Rating::WHEEL`].
    pub const RATED: Self = Self {
        leg_joint: Rating::LEG_JOINT,
        wheel: Rating::WHEEL,
    };

    /// Legs without a torque limit (the report's position servos) and wheels with a flat 30
    /// N·m (the controller's own limit): the plant before the drives had ratings.
    pub const IDEAL: Self = Self {
        leg_joint: Rating::UNLIMITED,
        wheel: Rating::FLAT_WHEEL,
    };
}

/// The parts of one run's emulated hardware.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plant {
    /// The IMU's chip (or a perfect one).
    pub imu: ImuModel,
    /// Extra noise and bias on the IMU, and the seed of its chip.
    pub imu_noise: ImuNoise,
    /// The rangefinder's part (or a perfect one).
    pub rangefinder: RangeModel,
    /// What the drives can deliver.
    pub drives: DriveRatings,
    /// How the drives measure their joints.
    pub sensing: DriveSensing,
    /// Control cycles each frame between the simulator's nodes and the controller is held
    /// back, each way: the CAN loop's transport delay (lockstep has none of its own; a real
    /// loop has a sample, a transfer and a command transfer).
    pub transport_delay_cycles: u32,
    /// How this robot's body differs from the model's.
    pub variation: Variation,
}

impl Plant {
    /// `faults` on the simulator's connection with this plant's transport delay added to
    /// both directions (SYNC stays undelayed, as every fault leaves it).
    pub fn link_faults(&self, faults: &Faults) -> Faults {
        let mut faults = faults.clone();
        for plan in [&mut faults.tx, &mut faults.rx] {
            plan.delay_cycles = plan
                .delay_cycles
                .saturating_add(self.transport_delay_cycles);
        }
        faults
    }
}

impl Default for Plant {
    /// The tested default: the IMU is a real chip ([`ChipSpec::BMI088`]), the part drawn with
    /// seed 1 — the same chip as `sim-host run`'s default `--seed 1` (see `docs/simulator.md`
    /// for what other draws do to the acceptance figures) — and rated drives
    /// ([`DriveRatings::RATED`]) that measure with real encoders ([`DriveSensing::REAL`]), a
    /// VL53L1X rangefinder ([`RangeSpec::VL53L1X`], the part drawn with seed 1), on a
    /// bus that holds every frame back a cycle each way (a real CAN loop's transport delay).
    fn default() -> Self {
        Self {
            imu: ImuModel::Chip(ChipSpec::BMI088),
            imu_noise: ImuNoise {
                seed: 1,
                ..ImuNoise::default()
            },
            rangefinder: RangeModel::Part {
                spec: RangeSpec::VL53L1X,
                seed: 1,
            },
            drives: DriveRatings::RATED,
            sensing: DriveSensing::REAL,
            transport_delay_cycles: 1,
            variation: Variation::NOMINAL,
        }
    }
}
