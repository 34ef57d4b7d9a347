//! Why `firmware::math` uses what it uses: measures `micromath`'s errors against exact values
//! and the IK's worst round-trip error over a dense grid of the leg's workspace. Run with
//! `--nocapture` to see the figures quoted in the module docs.

use firmware::legs::kinematics::{leg_fk, leg_ik, KneeBranch, LegGeometry, LegJoints};
use firmware::limits::{Joint, JointLimits};
use micromath::F32Ext;

struct Errors {
    sqrt_relative: f64,
    sin_cos: f64,
    acos_rad: f64,
    atan2_rad: f64,
}

fn measure(
    sqrt: impl Fn(f32) -> f32,
    sin: impl Fn(f32) -> f32,
    cos: impl Fn(f32) -> f32,
    acos: impl Fn(f32) -> f32,
    atan2: impl Fn(f32, f32) -> f32,
) -> Errors {
    let mut e = Errors {
        sqrt_relative: 0.0,
        sin_cos: 0.0,
        acos_rad: 0.0,
        atan2_rad: 0.0,
    };
    for i in 1..200_000 {
        let x = i as f32 * 3e-5;
        let exact = (x as f64).sqrt();
        e.sqrt_relative = e
            .sqrt_relative
            .max(((sqrt(x) as f64 - exact) / exact).abs());
        let t = -std::f32::consts::PI + i as f32 * (std::f32::consts::TAU / 200_000.0);
        e.sin_cos = e
            .sin_cos
            .max((sin(t) as f64 - (t as f64).sin()).abs())
            .max((cos(t) as f64 - (t as f64).cos()).abs());
        let c = -1.0 + i as f32 * 1e-5;
        e.acos_rad = e.acos_rad.max((acos(c) as f64 - (c as f64).acos()).abs());
        let (y, x) = ((t as f64).sin() as f32 * 0.3, (t as f64).cos() as f32 * 0.2);
        e.atan2_rad = e
            .atan2_rad
            .max((atan2(y, x) as f64 - (y as f64).atan2(x as f64)).abs());
    }
    e
}

#[test]
fn micromath_misses_the_ik_budget_and_the_chosen_functions_meet_it() {
    let micromath = measure(
        F32Ext::sqrt,
        F32Ext::sin,
        F32Ext::cos,
        F32Ext::acos,
        F32Ext::atan2,
    );
    let chosen = measure(
        firmware::math::sqrt,
        firmware::math::sin,
        firmware::math::cos,
        firmware::math::acos,
        firmware::math::atan2,
    );
    println!(
        "micromath: sqrt {:.2e} relative, sin/cos {:.2e}, acos {:.2e} rad, atan2 {:.2e} rad",
        micromath.sqrt_relative, micromath.sin_cos, micromath.acos_rad, micromath.atan2_rad
    );
    println!(
        "chosen:    sqrt {:.2e} relative, sin/cos {:.2e}, acos {:.2e} rad, atan2 {:.2e} rad",
        chosen.sqrt_relative, chosen.sin_cos, chosen.acos_rad, chosen.atan2_rad
    );
    // 0.1° = 1.7e-3 rad: micromath's acos and atan2 alone would spend the whole angle budget.
    assert!(micromath.acos_rad > 1.7e-3 && micromath.atan2_rad > 1.7e-3);
    assert!(micromath.sqrt_relative > 0.01);
    assert!(chosen.sqrt_relative < 1e-6 && chosen.sin_cos < 1e-6);
    assert!(chosen.acos_rad < 1e-6 && chosen.atan2_rad < 1e-6);
}

#[test]
fn worst_round_trip_error_over_a_dense_grid_of_the_workspace() {
    let limits = JointLimits::REPORT;
    let geometry = LegGeometry::ROBOT;
    let steps = 24;
    let span = |joint: Joint, i: usize| {
        let range = limits.range(joint);
        range.min_rad + (range.max_rad - range.min_rad) * i as f32 / steps as f32
    };
    let (mut worst_m, mut worst_rad, mut solved) = (0.0f32, 0.0f32, 0);
    for a in 0..=steps {
        for h in 0..=steps {
            for k in 0..=steps {
                for n in 0..=steps {
                    let joints = LegJoints::from_array([
                        span(Joint::HipAbduction, a),
                        span(Joint::HipPitch, h),
                        span(Joint::Knee, k),
                        span(Joint::Ankle, n),
                    ]);
                    let target = leg_fk(&geometry, &joints);
                    if target.z_m > -0.02 || joints.knee_rad.abs() < 1e-3 {
                        continue;
                    }
                    let branch = if joints.knee_rad > 0.0 {
                        KneeBranch::Up
                    } else {
                        KneeBranch::Down
                    };
                    let Ok(back) = leg_ik(&geometry, &limits, &target, branch) else {
                        panic!("no solution for a pose the leg reaches: {joints:?}");
                    };
                    let again = leg_fk(&geometry, &back);
                    let d = ((target.x_m - again.x_m).powi(2)
                        + (target.y_m - again.y_m).powi(2)
                        + (target.z_m - again.z_m).powi(2))
                    .sqrt();
                    worst_m = worst_m.max(d);
                    worst_rad = worst_rad.max((target.pitch_rad - again.pitch_rad).abs());
                    solved += 1;
                }
            }
        }
    }
    println!(
        "FK(IK(p)) over {solved} grid poses: worst {:.3e} m, {:.3e} rad",
        worst_m, worst_rad
    );
    assert!(worst_m <= 0.5e-3 && worst_rad <= 0.1f32.to_radians());
}
