//! What carries the robot: its legs or its wheels. The balance law may only drive the wheels
//! while they are on the ground; a wheel torque with the wheels in the air spins them up, and
//! the stored momentum jolts the robot when they touch down.
//!
//! On flat ground the torso stands on its legs at the depth of its deepest foot (below the
//! hips, from the measured joint angles) plus the foot radius; the wheels touch once that
//! height falls to the wheels' contact height (mount depth + wheel radius).

use protocol::Joints;

use crate::legs::kinematics::{leg_fk, LegGeometry, LegJoints};

/// Where the legs put the feet, relative to the hips.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegStance {
    /// The torso-centre height the legs give on flat ground, m.
    pub height_m: f32,
    /// The torso-centre height the least extended leg gives, m: with all four feet planted,
    /// the legs that carry the most sag the most, so as the torso settles onto its wheels
    /// over its front feet this leg is the one still on the ground, and the deepest one is
    /// already lifting off.
    pub shallowest_height_m: f32,
    /// The feet's mean position forward of their hips, m (a non-finite foot counts as 0).
    pub mean_foot_x_m: f32,
}

/// Dimensions that decide which part touches the ground.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SupportGeometry {
    /// Foot sphere radius, m.
    pub foot_radius_m: f32,
    /// Torso-centre height at which the wheels touch flat ground (wheel mount depth below the
    /// hips' plane + wheel radius), m.
    pub wheel_contact_height_m: f32,
    /// The wheels count as on the ground up to this far above it, m: joint sag and servo error.
    pub margin_m: f32,
}

impl SupportGeometry {
    /// The robot: foot r 0.035 m, wheels r 0.12 m mounted 0.15 m below the hips.
    pub const ROBOT: Self = Self {
        foot_radius_m: 0.035,
        wheel_contact_height_m: 0.27,
        margin_m: 0.01,
    };

    /// The torso-centre height the legs give on flat ground, m: the deepest foot + its radius.
    /// Non-finite joint angles give 0 (the wheels are assumed to carry the robot).
    pub fn leg_height_m(&self, geometry: &LegGeometry, joints_rad: &Joints<f32>) -> f32 {
        self.stance_of(geometry, joints_rad).height_m
    }

    /// Where the measured legs put the feet, in one pass of the legs' kinematics.
    pub fn stance_of(&self, geometry: &LegGeometry, joints_rad: &Joints<f32>) -> LegStance {
        let (mut deepest_m, mut sum_x_m): (f32, f32) = (0.0, 0.0);
        let mut shallowest_m = f32::INFINITY;
        for (_, &angles_rad) in joints_rad.iter_legs() {
            let foot = leg_fk(geometry, &LegJoints::from_array(angles_rad));
            if foot.z_m.is_finite() {
                deepest_m = deepest_m.max(-foot.z_m);
                shallowest_m = shallowest_m.min(-foot.z_m);
            }
            if foot.x_m.is_finite() {
                sum_x_m += foot.x_m;
            }
        }
        let shallowest_m = if shallowest_m.is_finite() {
            shallowest_m
        } else {
            0.0
        };
        LegStance {
            height_m: deepest_m + self.foot_radius_m,
            shallowest_height_m: shallowest_m + self.foot_radius_m,
            mean_foot_x_m: 0.25 * sum_x_m,
        }
    }

    /// Whether the wheels are on the ground (the legs hold the torso no higher than the wheels'
    /// contact height + margin).
    pub fn wheels_grounded(&self, geometry: &LegGeometry, joints_rad: &Joints<f32>) -> bool {
        self.grounds_wheels(&self.stance_of(geometry, joints_rad))
    }

    /// Whether legs in `stance` leave the wheels on the ground.
    pub fn grounds_wheels(&self, stance: &LegStance) -> bool {
        stance.height_m <= self.wheel_contact_height_m + self.margin_m
    }

    /// Whether four planted feet in `stance` have let the torso down onto its wheels: the
    /// least extended leg, the one carrying, is at the wheels' contact height.
    pub fn lowered_onto_wheels(&self, stance: &LegStance) -> bool {
        stance.shallowest_height_m <= self.wheel_contact_height_m + self.margin_m
    }
}
