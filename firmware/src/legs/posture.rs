//! The stance that carries the body at a commanded height, and how the foot pitch is chosen
//! for the IK. (The fold for the wheels is [`crate::legs::levelling`]'s.)
//!
//! # Body height
//!
//! The report's elevator range (−0.10…+0.12 m) arrives on the wire as an offset from the
//! nominal stance; here it becomes the depth of the feet below the hips. With the report's
//! joint ranges the hips (±50°) only let the feet stand under the hips between 0.287 m and
//! 0.38 m below them (a straight leg), so the offset is clamped into the band
//! `[depth_min_m, depth_max_m]` where the stance has IK solutions, and a trot further to
//! `trot_depth_min_m` so that the swing arc stays in reach.
//! [`Posture::body_height_range_m`] says what the legs can realise.
//!
//! # Foot pitch
//!
//! The leg has three sagittal joints for a 2-D foot position, so the foot pitch φ is a free
//! choice. It is scheduled linearly in the foot position, fitted to the middle of the window
//! of φ in which all joints stay in range over the gait's workspace:
//! `φ = φ0 + dφ/dx · x + dφ/dd · (depth − d_ref)`. The fit (φ0 = −119°, 80°/m, 600°/m about
//! 0.33 m, found by a grid search) keeps every joint 1.9° inside its range for a stance
//! 0.30…0.37 m deep and for the default trot (8 cm stride centred 3 cm ahead of the hip, 4 cm
//! clearance) on a stance line 0.35…0.37 m deep; the test
//! `every_gait_pose_solves_across_the_body_height_band_and_speed_scales` holds it to that.

use crate::legs::kinematics::{leg_ik, FootTarget, IkError, KneeBranch, LegGeometry, LegJoints};
use crate::limits::JointLimits;
use crate::math::deg_to_rad;

/// Poses and the foot-pitch schedule.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Posture {
    /// Feet below the hips at zero body-height offset, m.
    pub depth_nominal_m: f32,
    /// Shallowest stance the legs realise, m.
    pub depth_min_m: f32,
    /// Deepest stance the legs realise, m.
    pub depth_max_m: f32,
    /// Shallowest stance line of the trot, m: the swing arc rises above it and must stay in
    /// reach.
    pub trot_depth_min_m: f32,
    /// φ0 of the schedule, rad.
    pub pitch_base_rad: f32,
    /// dφ/dx, rad per m of forward foot position.
    pub pitch_per_x_rad_m: f32,
    /// dφ/d(depth), rad per m.
    pub pitch_per_depth_rad_m: f32,
    /// Depth where φ = φ0 at x = 0, m.
    pub pitch_reference_depth_m: f32,
    /// Knee solution to use.
    pub branch: KneeBranch,
}

impl Posture {
    /// Defaults for the robot's links and the report's joint ranges.
    pub const ROBOT: Self = Self {
        depth_nominal_m: 0.35,
        depth_min_m: 0.30,
        depth_max_m: 0.37,
        trot_depth_min_m: 0.35,
        pitch_base_rad: deg_to_rad(-119.0),
        pitch_per_x_rad_m: deg_to_rad(80.0),
        pitch_per_depth_rad_m: deg_to_rad(600.0),
        pitch_reference_depth_m: 0.33,
        branch: KneeBranch::Down,
    };

    /// Stance depth for a body-height offset (m, positive = taller), clamped into the band the
    /// legs realise; NaN gives the nominal depth.
    pub fn depth_for(&self, body_height_offset_m: f32) -> f32 {
        let depth = self.depth_nominal_m + body_height_offset_m;
        if depth.is_finite() {
            crate::math::clamp(depth, self.depth_min_m, self.depth_max_m)
        } else {
            self.depth_nominal_m
        }
    }

    /// Stance-line depth of the trot for a body-height offset: [`Posture::depth_for`], raised
    /// to at least `trot_depth_min_m`.
    pub fn trot_depth_for(&self, body_height_offset_m: f32) -> f32 {
        self.depth_for(body_height_offset_m)
            .max(self.trot_depth_min_m)
    }

    /// The body-height offsets the legs realise, `(lowest, highest)`, m.
    pub fn body_height_range_m(&self) -> (f32, f32) {
        (
            self.depth_min_m - self.depth_nominal_m,
            self.depth_max_m - self.depth_nominal_m,
        )
    }

    /// The scheduled foot pitch for a foot at `x_m` forward and `depth_m` below the hip.
    pub fn foot_pitch_rad(&self, x_m: f32, depth_m: f32) -> f32 {
        self.pitch_base_rad
            + self.pitch_per_x_rad_m * x_m
            + self.pitch_per_depth_rad_m * (depth_m - self.pitch_reference_depth_m)
    }

    /// Joint angles that put the foot at `(x_m, −depth_m)` with the scheduled pitch.
    pub fn foot_ik(
        &self,
        geometry: &LegGeometry,
        limits: &JointLimits,
        x_m: f32,
        depth_m: f32,
    ) -> Result<LegJoints, IkError> {
        self.foot_ik_at(geometry, limits, x_m, 0.0, depth_m)
    }

    /// Joint angles that put the foot at `(x_m, y_m, −depth_m)` with the scheduled pitch (the
    /// abduction takes `y_m`; the pitch is scheduled on the vertical depth, which differs from
    /// the depth within the abducted plane by under a millimetre at a trot's few centimetres
    /// sideways).
    pub fn foot_ik_at(
        &self,
        geometry: &LegGeometry,
        limits: &JointLimits,
        x_m: f32,
        y_m: f32,
        depth_m: f32,
    ) -> Result<LegJoints, IkError> {
        leg_ik(
            geometry,
            limits,
            &FootTarget {
                x_m,
                y_m,
                z_m: -depth_m,
                pitch_rad: self.foot_pitch_rad(x_m, depth_m),
            },
            self.branch,
        )
    }

    /// The stance: feet under the hips at `depth_m`.
    pub fn stance(
        &self,
        geometry: &LegGeometry,
        limits: &JointLimits,
        depth_m: f32,
    ) -> Result<LegJoints, IkError> {
        self.foot_ik(geometry, limits, 0.0, depth_m)
    }
}
