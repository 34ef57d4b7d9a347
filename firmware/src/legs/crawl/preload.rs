//! Targets led by the servos' deflection under the loads the crawl plans: each leg drive is a
//! position servo (τ = kp·(target − angle)), so a leg that holds a load stands short of its
//! target by τ/kp; the targets are moved by as much beforehand.

use protocol::Leg;

use super::frame::{PerLeg, Point};
use super::{Crawl, CrawlConfig, Running};
use crate::legs::kinematics::{leg_fk, IkError, LegGeometry, LegJoints};
use crate::limits::JointLimits;

impl Crawl {
    /// Joint targets of all four legs led by the servos' deflection under the planned loads:
    /// `weight_n` over the body's centre, shared by the feet that stand.
    pub fn preloaded_targets(
        &self,
        config: &CrawlConfig,
        geometry: &LegGeometry,
        limits: &JointLimits,
        weight_n: f32,
        kp_nm_rad: &[f32; 4],
    ) -> [Result<LegJoints, IkError>; 4] {
        // A swinging foot carries nothing; a foot being freed hands its share to the other
        // three as the sway goes on.
        let (lifted, handed) = match self.running {
            Running::Swing { leg, .. } => (Some(leg), 1.0),
            Running::Unload { leg, max_m, .. } if max_m > 0.0 => (
                Some(leg),
                crate::math::clamp(self.swayed_m(config, max_m) / max_m, 0.0, 1.0),
            ),
            _ => (None, 0.0),
        };
        let centre = self.body.centre;
        let all = PerLeg::splat(true);
        let four = planned_loads_n(&self.feet, &all, centre.x_m, centre.y_m, weight_n);
        let three = match lifted {
            Some(leg) => {
                let mut stance = all;
                *stance.get_mut(leg) = false;
                planned_loads_n(&self.feet, &stance, centre.x_m, centre.y_m, weight_n)
            }
            None => four,
        };
        let blend = |leg: Leg| four.get(leg) + (three.get(leg) - four.get(leg)) * handed;
        let loads = PerLeg::from_fn(blend);
        let mut targets = self.targets(config, geometry, limits);
        for (leg, target) in Leg::ALL.into_iter().zip(targets.iter_mut()) {
            if let Ok(joints) = target {
                let torques = holding_torques_nm(geometry, joints, loads.get(leg));
                *joints = led(joints, &torques, kp_nm_rad);
            }
        }
        targets
    }
}

/// The loads, N, that `weight_n` puts on the feet standing at `feet` (`stance`: which stand),
/// with the centre of mass over `com`: exact on three feet, the least-squares share on four.
pub fn planned_loads_n(
    feet: &PerLeg<Point>,
    stance: &PerLeg<bool>,
    com_x_m: f32,
    com_y_m: f32,
    weight_n: f32,
) -> PerLeg<f32> {
    // Minimum-norm F with Σ F = W, Σ F x = W x_c, Σ F y = W y_c: F = Aᵀ (A Aᵀ)⁻¹ b.
    let mut a = [[0.0_f32; 3]; 3];
    let rows = |leg: Leg| {
        let p = feet.get(leg);
        [1.0, p.x_m - com_x_m, p.y_m - com_y_m]
    };
    for leg in Leg::ALL {
        if !stance.get(leg) {
            continue;
        }
        let r = rows(leg);
        for (i, row) in a.iter_mut().enumerate() {
            for (j, cell) in row.iter_mut().enumerate() {
                *cell += r.get(i).copied().unwrap_or(0.0) * r.get(j).copied().unwrap_or(0.0);
            }
        }
    }
    let Some(lambda) = solve3(&a, [weight_n, 0.0, 0.0]) else {
        return PerLeg::splat(0.0);
    };
    let load = |leg: Leg| {
        if !stance.get(leg) {
            return 0.0;
        }
        let [r0, r1, r2] = rows(leg);
        let [l0, l1, l2] = lambda;
        (r0 * l0 + r1 * l1 + r2 * l2).max(0.0)
    };
    PerLeg::from_fn(load)
}

/// The torques a leg's drives apply to hold `fz_n` up at the foot, N·m, wire order: by
/// virtual work on the leg's FK, `τ = −(∂z/∂q)·F`.
pub fn holding_torques_nm(geometry: &LegGeometry, joints: &LegJoints, fz_n: f32) -> [f32; 4] {
    const STEP_RAD: f32 = 1e-3;
    let base = joints.to_array();
    core::array::from_fn(|i| {
        let (mut plus, mut minus) = (base, base);
        if let (Some(p), Some(m)) = (plus.get_mut(i), minus.get_mut(i)) {
            *p += STEP_RAD;
            *m -= STEP_RAD;
        }
        let up = leg_fk(geometry, &LegJoints::from_array(plus)).z_m;
        let down = leg_fk(geometry, &LegJoints::from_array(minus)).z_m;
        -(up - down) / (2.0 * STEP_RAD) * fz_n
    })
}

/// `joints` moved by the deflection `torques_nm` cause on servos of stiffness `kp_nm_rad`.
pub fn led(joints: &LegJoints, torques_nm: &[f32; 4], kp_nm_rad: &[f32; 4]) -> LegJoints {
    let mut angles = joints.to_array();
    for ((angle, torque), kp) in angles.iter_mut().zip(torques_nm).zip(kp_nm_rad) {
        let lead = torque / kp;
        if lead.is_finite() {
            *angle += lead;
        }
    }
    LegJoints::from_array(angles)
}

/// `a x = b` for a 3×3 system by Cramer's rule; `None` when singular.
fn solve3(a: &[[f32; 3]; 3], b: [f32; 3]) -> Option<[f32; 3]> {
    let det = |m: &[[f32; 3]; 3]| {
        let [[a, b, c], [d, e, f], [g, h, i]] = *m;
        a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    };
    let d = det(a);
    if !(d.is_finite() && d.abs() > 1e-9) {
        return None;
    }
    let column = |k: usize| {
        let mut m = *a;
        for (row, value) in m.iter_mut().zip(b) {
            if let Some(cell) = row.get_mut(k) {
                *cell = value;
            }
        }
        det(&m) / d
    };
    Some([column(0), column(1), column(2)])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::legs::kinematics::foot_force_n;

    fn corner(x_m: f32, y_m: f32) -> Point {
        Point {
            x_m,
            y_m,
            z_m: -0.35,
        }
    }

    fn feet() -> PerLeg<Point> {
        PerLeg {
            fl: corner(0.22, 0.15),
            fr: corner(0.22, -0.15),
            bl: corner(-0.22, 0.15),
            br: corner(-0.22, -0.15),
        }
    }

    /// Σ F, Σ F·x and Σ F·y about the centre of mass.
    fn balance(loads: &PerLeg<f32>, com_x_m: f32, com_y_m: f32) -> (f32, f32, f32) {
        let f = feet();
        Leg::ALL
            .into_iter()
            .fold((0.0, 0.0, 0.0), |(s, mx, my), leg| {
                let (load, p) = (loads.get(leg), f.get(leg));
                (
                    s + load,
                    mx + load * (p.x_m - com_x_m),
                    my + load * (p.y_m - com_y_m),
                )
            })
    }

    #[test]
    fn the_weight_is_shared_so_that_the_feet_hold_the_mass_where_it_is() {
        let all = PerLeg::splat(true);
        let even = planned_loads_n(&feet(), &all, 0.0, 0.0, 400.0);
        for leg in Leg::ALL {
            assert!((even.get(leg) - 100.0).abs() < 1e-3, "{even:?}");
        }
        let ahead = planned_loads_n(&feet(), &all, 0.05, -0.02, 400.0);
        let (sum, mx, my) = balance(&ahead, 0.05, -0.02);
        assert!((sum - 400.0).abs() < 1e-2 && mx.abs() < 1e-3 && my.abs() < 1e-3);
        assert!(ahead.fr > ahead.bl, "{ahead:?}");
        // On three feet the share is the only one that balances.
        let mut three = all;
        *three.get_mut(Leg::Fl) = false;
        let lifted = planned_loads_n(&feet(), &three, -0.02, -0.03, 400.0);
        assert_eq!(lifted.fl, 0.0);
        let (sum, mx, my) = balance(&lifted, -0.02, -0.03);
        assert!((sum - 400.0).abs() < 1e-2 && mx.abs() < 1e-3 && my.abs() < 1e-3);
    }

    #[test]
    fn the_lead_is_the_holding_torque_over_the_stiffness() {
        let geometry = LegGeometry::ROBOT;
        let joints = LegJoints {
            hip_abduction_rad: 0.05,
            hip_pitch_rad: 0.4,
            knee_rad: -0.95,
            ankle_rad: 0.5,
        };
        let torques = holding_torques_nm(&geometry, &joints, 120.0);
        let force = foot_force_n(&geometry, &joints, torques[1], torques[2]);
        assert!(
            force.is_some_and(|f| (f.fz_n - 120.0).abs() < 1.0),
            "{force:?}"
        );
        let kp = [180.0, 200.0, 260.0, 160.0];
        let led_joints = led(&joints, &torques, &kp).to_array();
        for ((led, base), (torque, kp)) in led_joints
            .iter()
            .zip(joints.to_array())
            .zip(torques.iter().zip(kp))
        {
            assert!((led - base - torque / kp).abs() < 1e-6);
        }
    }
}
