//! The IK and FK of one leg: the report's worked example, both branches, the accuracy budget
//! over the whole reachable workspace, and the errors.

use firmware::legs::kinematics::{
    leg_fk, leg_ik, planar_fk, planar_ik, FootTarget, IkError, KneeBranch, LegGeometry, LegJoints,
    PlanarAngles, PlanarPose,
};
use firmware::limits::{Joint, JointLimits};
use proptest::prelude::*;

const LIMITS: JointLimits = JointLimits::REPORT;

fn report_pose() -> PlanarPose {
    PlanarPose {
        x_m: 0.25,
        z_m: -0.45,
        pitch_rad: (-20.0f32).to_radians(),
    }
}

/// The exact solution of the report's example (section 4: l = 0.20/0.25/0.15 m, x = 0.25 m,
/// z = −0.45 m, φ = −20°), evaluated in f64 by the report's own formulas.
fn exact_example() -> [f64; 3] {
    let (l1, l2, l3) = (0.20f64, 0.25f64, 0.15f64);
    let (x, z, phi) = (0.25f64, -0.45f64, (-20f64).to_radians());
    let (xw, zw) = (x - l3 * phi.cos(), z - l3 * phi.sin());
    let c = (xw * xw + zw * zw - l1 * l1 - l2 * l2) / (2.0 * l1 * l2);
    let q2 = c.acos();
    let q1 = zw.atan2(xw) - (l2 * q2.sin()).atan2(l1 + l2 * c);
    [q1, q2, phi - q1 - q2]
}

/// The report's printed answer.
const REPORT_ANGLES: [f64; 3] = [-1.762_618_849_6, 0.817_966_848_2, 0.595_586_151_0];

#[test]
fn reproduces_the_reports_numeric_example() {
    let angles = planar_ik(&LegGeometry::REPORT_EXAMPLE, &report_pose(), KneeBranch::Up).unwrap();
    let ours = [angles.q1_rad, angles.q2_rad, angles.q3_rad];
    for (q, exact) in ours.iter().zip(exact_example()) {
        assert!(
            (*q as f64 - exact).abs() < 1e-4,
            "{ours:?} vs exact {:?}",
            exact_example()
        );
    }
    // The report's printed angles carry arithmetic slips (r² = 0.1708884 where its own x_w,
    // z_w give 0.1708503; arccos(0.6838838) printed as 0.8179668 instead of 0.8177236), so they
    // sit within 2e-3 rad of the exact solution, not 1e-4 …
    for (q, printed) in ours.iter().zip(REPORT_ANGLES) {
        assert!(
            (*q as f64 - printed).abs() < 2e-3,
            "{ours:?} vs report {REPORT_ANGLES:?}"
        );
    }
    // … and their FK misses the report's own target by 0.7 mm, while ours hits it.
    let miss = |q: [f32; 3]| {
        let pose = planar_fk(
            &LegGeometry::REPORT_EXAMPLE,
            &PlanarAngles {
                q1_rad: q[0],
                q2_rad: q[1],
                q3_rad: q[2],
            },
        );
        ((pose.x_m - 0.25).powi(2) + (pose.z_m + 0.45).powi(2)).sqrt()
    };
    assert!(miss(ours) < 1e-5, "ours misses by {} m", miss(ours));
    let printed = REPORT_ANGLES.map(|q| q as f32);
    assert!(
        miss(printed) > 0.5e-3,
        "the report's angles miss by {} m",
        miss(printed)
    );
    let back = planar_fk(&LegGeometry::REPORT_EXAMPLE, &angles);
    assert!((back.pitch_rad - report_pose().pitch_rad).abs() < 1e-5);
}

#[test]
fn the_other_branch_reaches_the_same_pose_with_the_knee_mirrored() {
    let geometry = LegGeometry::REPORT_EXAMPLE;
    let down = planar_ik(&geometry, &report_pose(), KneeBranch::Down).unwrap();
    assert!((down.q2_rad as f64 + exact_example()[1]).abs() < 1e-4);
    let back = planar_fk(&geometry, &down);
    assert!((back.x_m - 0.25).abs() < 1e-5 && (back.z_m + 0.45).abs() < 1e-5);
}

#[test]
fn an_unreachable_pose_is_a_typed_error_not_nan() {
    let far = PlanarPose {
        x_m: 1.0,
        z_m: -1.0,
        pitch_rad: 0.0,
    };
    match planar_ik(&LegGeometry::ROBOT, &far, KneeBranch::Down) {
        Err(IkError::Unreachable { cos_q2 }) => assert!(cos_q2 > 1.0),
        other => panic!("expected Unreachable, got {other:?}"),
    }
    // Too close: the wrist inside the inner annulus.
    let near = PlanarPose {
        x_m: 0.11,
        z_m: 0.0,
        pitch_rad: 0.0,
    };
    assert!(matches!(
        planar_ik(&LegGeometry::ROBOT, &near, KneeBranch::Down),
        Err(IkError::Unreachable { cos_q2 }) if cos_q2 < -1.0
    ));
}

#[test]
fn a_pose_past_a_joint_limit_names_the_joint() {
    // Foot far in front of the hip: needs the hip pitch past +50°.
    let target = FootTarget {
        x_m: 0.30,
        y_m: 0.0,
        z_m: -0.15,
        pitch_rad: -0.3,
    };
    match leg_ik(&LegGeometry::ROBOT, &LIMITS, &target, KneeBranch::Down) {
        Err(IkError::JointLimit { joint, angle_rad }) => {
            assert!(
                !LIMITS.range(joint).contains(angle_rad),
                "{joint:?} {angle_rad}"
            )
        }
        other => panic!("expected JointLimit, got {other:?}"),
    }
    // Foot to the side beyond ±35° of abduction.
    let sideways = FootTarget {
        x_m: 0.0,
        y_m: 0.30,
        z_m: -0.20,
        pitch_rad: -1.8,
    };
    assert!(matches!(
        leg_ik(&LegGeometry::ROBOT, &LIMITS, &sideways, KneeBranch::Down),
        Err(IkError::JointLimit {
            joint: Joint::HipAbduction,
            ..
        })
    ));
}

#[test]
fn non_finite_targets_are_rejected() {
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let target = FootTarget {
            x_m: bad,
            y_m: 0.0,
            z_m: -0.3,
            pitch_rad: -1.6,
        };
        assert_eq!(
            leg_ik(&LegGeometry::ROBOT, &LIMITS, &target, KneeBranch::Down),
            Err(IkError::NonFinite)
        );
    }
}

fn in_range(joint: Joint) -> std::ops::RangeInclusive<f32> {
    let range = LIMITS.range(joint);
    range.min_rad..=range.max_rad
}

fn joints_in_limits() -> impl Strategy<Value = LegJoints> {
    (
        in_range(Joint::HipAbduction),
        in_range(Joint::HipPitch),
        in_range(Joint::Knee),
        in_range(Joint::Ankle),
    )
        .prop_map(|(a, h, k, n)| LegJoints::from_array([a, h, k, n]))
}

fn position_error_m(a: &FootTarget, b: &FootTarget) -> f32 {
    ((a.x_m - b.x_m).powi(2) + (a.y_m - b.y_m).powi(2) + (a.z_m - b.z_m).powi(2)).sqrt()
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 20_000,
        max_global_rejects: 100_000,
        ..ProptestConfig::default()
    })]

    /// The accuracy budget: every pose the leg reaches within its limits comes back through
    /// FK(IK(p)) within 0.5 mm and 0.1°.
    #[test]
    fn fk_of_ik_is_within_half_a_millimetre_and_a_tenth_of_a_degree(joints in joints_in_limits()) {
        let geometry = LegGeometry::ROBOT;
        let target = leg_fk(&geometry, &joints);
        prop_assume!(target.z_m < -0.02); // the foot below the hip: the leg's workspace
        let branch = if joints.knee_rad >= 0.0 { KneeBranch::Up } else { KneeBranch::Down };
        let solved = leg_ik(&geometry, &LIMITS, &target, branch);
        let solved = match solved {
            Ok(solved) => solved,
            // A knee within a hair of zero may land on the other branch's side.
            Err(IkError::JointLimit { .. }) if joints.knee_rad.abs() < 1e-3 => return Ok(()),
            Err(error) => panic!("{joints:?} → {target:?}: {error:?}"),
        };
        let back = leg_fk(&geometry, &solved);
        let position = position_error_m(&target, &back);
        let pitch = (target.pitch_rad - back.pitch_rad).abs();
        let pitch = pitch.min((pitch - std::f32::consts::TAU).abs());
        prop_assert!(position <= 0.5e-3, "position error {position} m at {joints:?}");
        prop_assert!(pitch <= 0.1f32.to_radians(), "pitch error {pitch} rad at {joints:?}");
    }

    /// Any target at all — reachable or not, inside the limits or not — gives either finite
    /// in-limit joints or a typed error.
    #[test]
    fn ik_never_returns_nan_or_out_of_limit_joints(
        x in -1.0f32..1.0, y in -1.0f32..1.0, z in -1.0f32..1.0, pitch in -7.0f32..7.0,
        up in any::<bool>(),
    ) {
        let target = FootTarget { x_m: x, y_m: y, z_m: z, pitch_rad: pitch };
        let branch = if up { KneeBranch::Up } else { KneeBranch::Down };
        if let Ok(joints) = leg_ik(&LegGeometry::ROBOT, &LIMITS, &target, branch) {
            for (joint, angle) in Joint::ALL.into_iter().zip(joints.to_array()) {
                prop_assert!(angle.is_finite() && LIMITS.range(joint).contains(angle));
            }
        }
    }

    /// The report's planar IK on its own example geometry, over its whole reachable annulus.
    #[test]
    fn planar_round_trip_on_the_report_geometry(
        q1 in -3.1f32..3.1, q2 in -3.0f32..3.0, q3 in -3.1f32..3.1,
    ) {
        prop_assume!(q2.abs() > 1e-3);
        let geometry = LegGeometry::REPORT_EXAMPLE;
        let pose = planar_fk(&geometry, &PlanarAngles { q1_rad: q1, q2_rad: q2, q3_rad: q3 });
        let branch = if q2 > 0.0 { KneeBranch::Up } else { KneeBranch::Down };
        let solved = planar_ik(&geometry, &pose, branch).unwrap();
        let back = planar_fk(&geometry, &solved);
        let error = ((pose.x_m - back.x_m).powi(2) + (pose.z_m - back.z_m).powi(2)).sqrt();
        prop_assert!(error <= 0.5e-3, "error {error} m");
    }
}
