//! Forward and inverse kinematics of one leg: hip abduction, then the report's planar 3-R chain
//! (section 3) in the sagittal plane.
//!
//! # Frames and conventions
//!
//! The leg frame sits on the hip: x forward, y left, z up. Hip abduction turns the sagittal plane
//! about x; inside that plane the report's equations hold unchanged:
//!
//! ```text
//! x = l1 cos q1 + l2 cos(q1+q2) + l3 cos(q1+q2+q3)        θ = q1 + q2 + q3
//! z = l1 sin q1 + l2 sin(q1+q2) + l3 sin(q1+q2+q3)
//! ```
//!
//! with angles measured from +x toward +z. The robot's joints read zero with the leg hanging
//! straight down and turn positive when they swing the foot forward (the pitch joints' axis is
//! −y in the model), so the model's joint angles are
//! `hip_pitch = q1 + π/2`, `knee = q2`, `ankle = q3`.
//!
//! # Branches
//!
//! The law of cosines gives two knee solutions (section 3.4). [`KneeBranch::Up`] takes
//! `q2 = +arccos(…)`, the report's own numeric example; [`KneeBranch::Down`] takes
//! `q2 = −arccos(…)`, the one this robot's knee range (−110°…+15°) mostly allows.
//!
//! # Errors
//!
//! A pose outside the annulus the two inner links reach (`|cos q2| > 1`) is
//! [`IkError::Unreachable`]; a solution outside the joint ranges is [`IkError::JointLimit`];
//! non-finite input is [`IkError::NonFinite`]. No function here returns NaN.

use core::f32::consts::FRAC_PI_2;

use crate::limits::{Joint, JointLimits};
use crate::math::{acos, atan2, clamp, cos, sin, sqrt, wrap_pi};

/// Link lengths of the sagittal chain, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegGeometry {
    /// Hip → knee.
    pub l1_m: f32,
    /// Knee → ankle.
    pub l2_m: f32,
    /// Ankle → foot centre.
    pub l3_m: f32,
}

impl LegGeometry {
    /// The robot's links (report section 5.1).
    pub const ROBOT: Self = Self {
        l1_m: 0.14,
        l2_m: 0.13,
        l3_m: 0.11,
    };
    /// The links of the report's numeric example (section 4).
    pub const REPORT_EXAMPLE: Self = Self {
        l1_m: 0.20,
        l2_m: 0.25,
        l3_m: 0.15,
    };
}

/// Tolerance on `|cos q2|` beyond 1 that still counts as reachable: f32 rounding at the
/// workspace boundary (a fully stretched leg) lands a few ulp outside.
const COS_TOLERANCE: f32 = 1e-5;

/// How far past a joint limit a solution may land from rounding and still count as on it, rad.
/// Near a straight knee `q2 = arccos(c)` amplifies the f32 rounding of `c` by `1 / sin q2`
/// (2e-5 rad at q2 = 0.01 rad), so the tolerance is 2e-4 rad (0.01°).
const LIMIT_TOLERANCE_RAD: f32 = 2e-4;

/// Which of the two knee solutions to take.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KneeBranch {
    /// `q2 ≥ 0`: the report's example solution.
    Up,
    /// `q2 ≤ 0`.
    Down,
}

/// Why a pose has no valid joint solution.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum IkError {
    /// The wrist is out of the two inner links' reach: `cos_q2` is what the law of cosines gave.
    Unreachable {
        /// `(r² − l1² − l2²) / (2 l1 l2)`, beyond ±1.
        cos_q2: f32,
    },
    /// The solution needs a joint past its range.
    JointLimit {
        /// The first joint out of range, in wire order.
        joint: Joint,
        /// The angle it would need, rad (model convention).
        angle_rad: f32,
    },
    /// The target held NaN or infinity.
    NonFinite,
}

/// A foot pose in the sagittal plane: the report's (x, z, φ).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanarPose {
    /// Forward, m.
    pub x_m: f32,
    /// Up, m (negative below the hip).
    pub z_m: f32,
    /// Foot pitch φ = q1 + q2 + q3, rad from +x toward +z.
    pub pitch_rad: f32,
}

/// The report's planar joint angles (q1 from +x).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanarAngles {
    /// Hip pitch from +x, rad.
    pub q1_rad: f32,
    /// Knee, relative to the thigh, rad.
    pub q2_rad: f32,
    /// Ankle, relative to the shin, rad.
    pub q3_rad: f32,
}

/// The report's forward kinematics (section 3.2).
pub fn planar_fk(geometry: &LegGeometry, angles: &PlanarAngles) -> PlanarPose {
    let a1 = angles.q1_rad;
    let a2 = a1 + angles.q2_rad;
    let a3 = a2 + angles.q3_rad;
    PlanarPose {
        x_m: geometry.l1_m * cos(a1) + geometry.l2_m * cos(a2) + geometry.l3_m * cos(a3),
        z_m: geometry.l1_m * sin(a1) + geometry.l2_m * sin(a2) + geometry.l3_m * sin(a3),
        pitch_rad: a3,
    }
}

/// The report's inverse kinematics (section 3.3), without joint limits; `q1` and `q3` are
/// wrapped into −π…π.
pub fn planar_ik(
    geometry: &LegGeometry,
    pose: &PlanarPose,
    branch: KneeBranch,
) -> Result<PlanarAngles, IkError> {
    if !(pose.x_m.is_finite() && pose.z_m.is_finite() && pose.pitch_rad.is_finite()) {
        return Err(IkError::NonFinite);
    }
    let (l1, l2, l3) = (geometry.l1_m, geometry.l2_m, geometry.l3_m);
    let x_w = pose.x_m - l3 * cos(pose.pitch_rad);
    let z_w = pose.z_m - l3 * sin(pose.pitch_rad);
    let r_squared = x_w * x_w + z_w * z_w;
    let cos_q2 = (r_squared - l1 * l1 - l2 * l2) / (2.0 * l1 * l2);
    if !cos_q2.is_finite() {
        return Err(IkError::NonFinite);
    }
    if cos_q2.abs() > 1.0 + COS_TOLERANCE {
        return Err(IkError::Unreachable { cos_q2 });
    }
    let cos_q2 = clamp(cos_q2, -1.0, 1.0);
    let knee = acos(cos_q2);
    let q2 = match branch {
        KneeBranch::Up => knee,
        KneeBranch::Down => -knee,
    };
    let sin_q2 = match branch {
        KneeBranch::Up => sqrt(1.0 - cos_q2 * cos_q2),
        KneeBranch::Down => -sqrt(1.0 - cos_q2 * cos_q2),
    };
    let k1 = l1 + l2 * cos_q2;
    let k2 = l2 * sin_q2;
    let q1 = wrap_pi(atan2(z_w, x_w) - atan2(k2, k1));
    let q3 = wrap_pi(pose.pitch_rad - q1 - q2);
    let angles = PlanarAngles {
        q1_rad: q1,
        q2_rad: q2,
        q3_rad: q3,
    };
    if q1.is_finite() && q2.is_finite() && q3.is_finite() {
        Ok(angles)
    } else {
        Err(IkError::NonFinite)
    }
}

/// Joint angles of one leg in the model's convention (zero = hanging straight down), wire order.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LegJoints {
    /// `hip1_*`, abduction about +x, rad.
    pub hip_abduction_rad: f32,
    /// `hip2_*`, rad.
    pub hip_pitch_rad: f32,
    /// `knee_*`, rad.
    pub knee_rad: f32,
    /// `ankle_*`, rad.
    pub ankle_rad: f32,
}

impl LegJoints {
    /// In wire order.
    pub const fn to_array(self) -> [f32; 4] {
        [
            self.hip_abduction_rad,
            self.hip_pitch_rad,
            self.knee_rad,
            self.ankle_rad,
        ]
    }

    /// From wire order.
    pub const fn from_array(angles_rad: [f32; 4]) -> Self {
        let [hip_abduction_rad, hip_pitch_rad, knee_rad, ankle_rad] = angles_rad;
        Self {
            hip_abduction_rad,
            hip_pitch_rad,
            knee_rad,
            ankle_rad,
        }
    }

    /// The first joint outside `limits`, with its angle.
    pub fn first_violation(&self, limits: &JointLimits) -> Option<(Joint, f32)> {
        Joint::ALL
            .into_iter()
            .zip(self.to_array())
            .find(|&(joint, angle)| !limits.range(joint).contains(angle))
    }
}

/// A foot target in the leg frame (x forward, y left, z up, origin at the hip) with the foot
/// pitch φ measured inside the abducted sagittal plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FootTarget {
    /// Forward, m.
    pub x_m: f32,
    /// Left, m.
    pub y_m: f32,
    /// Up, m (negative below the hip).
    pub z_m: f32,
    /// Foot pitch φ, rad, as in [`PlanarPose`].
    pub pitch_rad: f32,
}

/// Forward kinematics of the whole leg, model convention in, leg frame out.
pub fn leg_fk(geometry: &LegGeometry, joints: &LegJoints) -> FootTarget {
    let planar = planar_fk(
        geometry,
        &PlanarAngles {
            q1_rad: joints.hip_pitch_rad - FRAC_PI_2,
            q2_rad: joints.knee_rad,
            q3_rad: joints.ankle_rad,
        },
    );
    let (sin_abd, cos_abd) = (sin(joints.hip_abduction_rad), cos(joints.hip_abduction_rad));
    FootTarget {
        x_m: planar.x_m,
        y_m: -planar.z_m * sin_abd,
        z_m: planar.z_m * cos_abd,
        pitch_rad: planar.pitch_rad,
    }
}

/// Inverse kinematics of the whole leg with joint limits. The foot must be below the hip
/// (`z < 0` after abduction); the abduction angle is the one that puts the foot in the
/// abducted sagittal plane with the foot downward.
pub fn leg_ik(
    geometry: &LegGeometry,
    limits: &JointLimits,
    target: &FootTarget,
    branch: KneeBranch,
) -> Result<LegJoints, IkError> {
    if !(target.x_m.is_finite()
        && target.y_m.is_finite()
        && target.z_m.is_finite()
        && target.pitch_rad.is_finite())
    {
        return Err(IkError::NonFinite);
    }
    let abduction = atan2(target.y_m, -target.z_m);
    let planar_z = -sqrt(target.y_m * target.y_m + target.z_m * target.z_m);
    let planar = planar_ik(
        geometry,
        &PlanarPose {
            x_m: target.x_m,
            z_m: planar_z,
            pitch_rad: target.pitch_rad,
        },
        branch,
    )?;
    let solved = LegJoints {
        hip_abduction_rad: abduction,
        hip_pitch_rad: wrap_pi(planar.q1_rad + FRAC_PI_2),
        knee_rad: planar.q2_rad,
        ankle_rad: planar.q3_rad,
    };
    // A pose on a joint's limit solves to within rounding of it, on either side: snap those.
    let mut snapped = solved.to_array();
    for (angle, joint) in snapped.iter_mut().zip(Joint::ALL) {
        let range = limits.range(joint);
        if *angle >= range.min_rad - LIMIT_TOLERANCE_RAD
            && *angle <= range.max_rad + LIMIT_TOLERANCE_RAD
        {
            *angle = clamp(*angle, range.min_rad, range.max_rad);
        }
    }
    let joints = LegJoints::from_array(snapped);
    match joints.first_violation(limits) {
        Some((joint, angle_rad)) => Err(IkError::JointLimit { joint, angle_rad }),
        None => Ok(joints),
    }
}

/// The ground's force on a foot, in the leg's sagittal plane (x forward, z up along the leg
/// frame: vertical while the body is level and the hip not abducted), N.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FootForce {
    /// Forward, N.
    pub fx_n: f32,
    /// Up, N.
    pub fz_n: f32,
}

/// Below this `|det J|` (m²) of the hip and knee rows the leg is too nearly straight for its
/// torques to tell the force: about 0.374 m deep under the hip (0.021 m² at the 0.35 m stance,
/// 0.010 at 0.37 m). A crawl's leg extended past it read ten times its load.
const STRAIGHT_LEG_DET_M2: f32 = 0.005;

/// The ground's force on the foot from the hip-pitch and knee torques the drives apply, at
/// rest and with the foot a point (`τ = −Jᵀ F`). `None` where the two rows do not determine it
/// (a nearly straight leg) or for non-finite input.
pub fn foot_force_n(
    geometry: &LegGeometry,
    joints: &LegJoints,
    hip_pitch_nm: f32,
    knee_nm: f32,
) -> Option<FootForce> {
    let angles = PlanarAngles {
        q1_rad: joints.hip_pitch_rad - FRAC_PI_2,
        q2_rad: joints.knee_rad,
        q3_rad: joints.ankle_rad,
    };
    let foot = planar_fk(geometry, &angles);
    let knee_angle = angles.q1_rad + angles.q2_rad;
    // d(x, z)/dq1 = (−z, x); d(x, z)/dq2 is the same for the chain below the knee.
    let (below_x, below_z) = (
        geometry.l2_m * cos(knee_angle) + geometry.l3_m * cos(foot.pitch_rad),
        geometry.l2_m * sin(knee_angle) + geometry.l3_m * sin(foot.pitch_rad),
    );
    let (a, b) = (-foot.z_m, foot.x_m);
    let (c, d) = (-below_z, below_x);
    let det = a * d - b * c;
    if !(det.is_finite() && det.abs() > STRAIGHT_LEG_DET_M2) {
        return None;
    }
    let (t1, t2) = (-hip_pitch_nm, -knee_nm);
    let force = FootForce {
        fx_n: (d * t1 - b * t2) / det,
        fz_n: (a * t2 - c * t1) / det,
    };
    (force.fx_n.is_finite() && force.fz_n.is_finite()).then_some(force)
}
