//! Joint ranges of a leg, from the report's section 5.1 (hip1 ±35°, hip2 ±50°, knee −110…+15°,
//! ankle ±40°), in the model's joint convention (see [`crate::legs::kinematics`]).

use crate::math::deg_to_rad;

/// One joint's allowed range, `min_rad ≤ max_rad`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointRange {
    /// Lower end, rad.
    pub min_rad: f32,
    /// Upper end, rad.
    pub max_rad: f32,
}

impl JointRange {
    /// The range `min_deg…max_deg`, given in degrees.
    pub const fn from_degrees(min_deg: f32, max_deg: f32) -> Self {
        Self {
            min_rad: deg_to_rad(min_deg),
            max_rad: deg_to_rad(max_deg),
        }
    }

    /// Whether `angle_rad` lies in the range (NaN does not).
    pub fn contains(self, angle_rad: f32) -> bool {
        angle_rad >= self.min_rad && angle_rad <= self.max_rad
    }

    /// `angle_rad` clamped into the range; NaN becomes `fallback_rad`, itself clamped.
    pub fn clamp(self, angle_rad: f32, fallback_rad: f32) -> f32 {
        let value = if angle_rad.is_finite() {
            angle_rad
        } else {
            fallback_rad
        };
        crate::math::clamp(value, self.min_rad, self.max_rad)
    }
}

/// The four joints of a leg, in wire order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Joint {
    /// `hip1_*`: abduction about the forward axis.
    HipAbduction,
    /// `hip2_*`: hip pitch, the report's q1 (offset by π/2, see [`crate::legs::kinematics`]).
    HipPitch,
    /// `knee_*`: the report's q2.
    Knee,
    /// `ankle_*`: the report's q3.
    Ankle,
}

impl Joint {
    /// All four, in wire order.
    pub const ALL: [Joint; 4] = [
        Joint::HipAbduction,
        Joint::HipPitch,
        Joint::Knee,
        Joint::Ankle,
    ];
}

/// Ranges of the four joints of one leg (all four legs share them).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointLimits {
    /// Per joint, in [`Joint::ALL`] order.
    pub ranges: [JointRange; 4],
}

impl JointLimits {
    /// The report's ranges: hip1 ±35°, hip2 ±50°, knee −110…+15°, ankle ±40°.
    pub const REPORT: Self = Self {
        ranges: [
            JointRange::from_degrees(-35.0, 35.0),
            JointRange::from_degrees(-50.0, 50.0),
            JointRange::from_degrees(-110.0, 15.0),
            JointRange::from_degrees(-40.0, 40.0),
        ],
    };

    /// The range of `joint`.
    pub fn range(&self, joint: Joint) -> JointRange {
        match joint {
            Joint::HipAbduction => self.ranges[0],
            Joint::HipPitch => self.ranges[1],
            Joint::Knee => self.ranges[2],
            Joint::Ankle => self.ranges[3],
        }
    }
}
