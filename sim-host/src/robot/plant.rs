//! What the emulated hardware is made of, for a run: the IMU's noise, the drives' ratings and
//! how the body differs from the model.
//! The tested default is [`Plant::default`]; the ideal parts stay for debugging a controller.

use crate::robot::imu::ImuNoise;
use crate::robot::rating::Rating;
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
    /// What the IMU adds to the truth.
    pub imu_noise: ImuNoise,
    /// What the drives can deliver.
    pub drives: DriveRatings,
    /// How this robot's body differs from the model's.
    pub variation: Variation,
}

impl Default for Plant {
    /// The tested default. The ideal drives until every acceptance scenario has been run on
    /// [`DriveRatings::RATED`]: the report's fold needed 74 N·m at the hips and ran the robot
    /// away; the fold in place, W and the stand-up into a trot now each pass a single run on
    /// rated drives.
    fn default() -> Self {
        Self {
            imu_noise: ImuNoise::default(),
            drives: DriveRatings::IDEAL,
            variation: Variation::NOMINAL,
        }
    }
}
