//! Each foot's load from what its drives report: the crawl frees a foot by the loads its
//! sway leaves on the feet, not by the sway's commanded length.

use protocol::{Joints, Leg};

use super::frame::PerLeg;
use crate::legs::kinematics::{LegGeometry, LegJoints};

/// Each foot's load along its leg frame's z (vertical with the body level), N, from its leg's
/// measured angles and the torques its hip and knee drives report; a pull counts as none, and
/// a leg too nearly straight for its torques to tell is `None`.
pub fn foot_loads_n(
    geometry: &LegGeometry,
    measured_rad: &Joints<f32>,
    effort_nm: &Joints<f32>,
) -> PerLeg<Option<f32>> {
    let load = |leg: Leg| {
        let joints = LegJoints::from_array(*measured_rad.leg(leg));
        let [_, hip_pitch_nm, knee_nm, _] = *effort_nm.leg(leg);
        crate::legs::kinematics::foot_force_n(geometry, &joints, hip_pitch_nm, knee_nm)
            .map(|force| force.fz_n.max(0.0))
    };
    PerLeg::from_fn(load)
}

/// What the four feet carry together, N ([`foot_loads_n`] summed; a leg too nearly straight
/// to tell counts none), or NaN when a drive's torque cannot be read (non-finite): unknown
/// torques are not no load.
pub fn legs_load_n(
    geometry: &LegGeometry,
    measured_rad: &Joints<f32>,
    effort_nm: &Joints<f32>,
) -> f32 {
    let readable = Leg::ALL
        .iter()
        .all(|&leg| effort_nm.leg(leg).iter().all(|nm| nm.is_finite()));
    if !readable {
        return f32::NAN;
    }
    let loads = foot_loads_n(geometry, measured_rad, effort_nm);
    Leg::ALL
        .iter()
        .map(|&leg| loads.get(leg).unwrap_or(0.0))
        .sum()
}
