//! The ground's force on a foot from the hip-pitch and knee torques its drives apply
//! (`firmware::legs::kinematics::foot_force_n`), checked against torques computed here by
//! virtual work on the leg's own forward kinematics, independently of the function's Jacobian.

use firmware::legs::kinematics::{foot_force_n, leg_fk, LegGeometry, LegJoints};
use proptest::prelude::*;

const GEOMETRY: LegGeometry = LegGeometry::ROBOT;

/// The torques the hip-pitch and knee drives apply to hold the ground's force (`fx_n`, `fz_n`)
/// on the foot at rest: −(∂x/∂q · fx + ∂z/∂q · fz), by central differences of the FK.
fn holding_torques_nm(joints: &LegJoints, fx_n: f32, fz_n: f32) -> (f32, f32) {
    let step = 1e-3_f32;
    let partial = |bump: fn(&mut LegJoints, f32)| {
        let (mut plus, mut minus) = (*joints, *joints);
        bump(&mut plus, step);
        bump(&mut minus, -step);
        let (a, b) = (leg_fk(&GEOMETRY, &plus), leg_fk(&GEOMETRY, &minus));
        (
            (a.x_m - b.x_m) / (2.0 * step),
            (a.z_m - b.z_m) / (2.0 * step),
        )
    };
    let (dx1, dz1) = partial(|j, d| j.hip_pitch_rad += d);
    let (dx2, dz2) = partial(|j, d| j.knee_rad += d);
    (-(dx1 * fx_n + dz1 * fz_n), -(dx2 * fx_n + dz2 * fz_n))
}

#[test]
fn a_standing_leg_carrying_a_quarter_of_the_robot_reads_its_load() {
    // The stance 0.35 m under the hip (hip pitch, knee, ankle as the posture solves them).
    let joints = LegJoints {
        hip_abduction_rad: 0.0,
        hip_pitch_rad: 0.457,
        knee_rad: -0.952,
        ankle_rad: 0.495,
    };
    let (hip_nm, knee_nm) = holding_torques_nm(&joints, 0.0, 100.0);
    let force = foot_force_n(&GEOMETRY, &joints, hip_nm, knee_nm);
    assert!(
        force.is_some_and(|f| (f.fz_n - 100.0).abs() < 0.5 && f.fx_n.abs() < 0.5),
        "{force:?}"
    );
}

#[test]
fn a_straight_leg_has_no_answer() {
    let straight = LegJoints::default();
    assert_eq!(foot_force_n(&GEOMETRY, &straight, 1.0, 1.0), None);
    let bent = LegJoints {
        knee_rad: -0.9,
        ..LegJoints::default()
    };
    assert_eq!(foot_force_n(&GEOMETRY, &bent, f32::NAN, 1.0), None);
}

proptest! {
    #[test]
    fn the_force_that_made_the_torques_comes_back(
        hip_pitch_rad in -0.8_f32..0.8,
        knee_rad in -1.8_f32..-0.5,
        ankle_rad in -0.6_f32..0.6,
        fx_n in -80.0_f32..80.0,
        fz_n in 0.0_f32..250.0,
    ) {
        let joints = LegJoints { hip_abduction_rad: 0.0, hip_pitch_rad, knee_rad, ankle_rad };
        let (hip_nm, knee_nm) = holding_torques_nm(&joints, fx_n, fz_n);
        let solved = foot_force_n(&GEOMETRY, &joints, hip_nm, knee_nm);
        prop_assert!(solved.is_some());
        let force = solved.unwrap_or_default();
        let (fx, fz) = (force.fx_n, force.fz_n);
        // The finite differences carry ~1e-6 relative error; bent knees condition the solve.
        prop_assert!((fx - fx_n).abs() < 1.0 && (fz - fz_n).abs() < 1.0,
            "({fx}, {fz}) for ({fx_n}, {fz_n})");
    }
}
