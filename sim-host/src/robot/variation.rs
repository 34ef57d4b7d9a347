//! One robot as built, not as drawn: its masses, centre of mass, ground friction and wheel
//! damping may differ from the model's nominal values. A robustness campaign draws these per
//! trial; a test of one effect (a torso centre of mass 3 cm off) sets one.
//!
//! Applied to the compiled model before the run starts, then MuJoCo's derived constants are
//! recomputed (`mj_setConst`), as its docs ask after changing masses or inertias.

use mujoco_rs::prelude::MjModel;

use crate::robot::model::Layout;

/// How this robot differs from the model.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Variation {
    /// Every body of the robot: mass and inertia scaled by this (1 = as modelled).
    pub mass_scale: f64,
    /// The leg bodies (hip to foot), on top of `mass_scale`: heavier actuators or links.
    pub leg_mass_scale: f64,
    /// The torso's centre of mass moved by this in its own frame, m (x forward, z up).
    pub torso_com_offset_m: [f64; 3],
    /// Sliding friction of every contact (all geoms, robot and ground; MuJoCo takes the larger
    /// of two), or the model's own.
    pub friction: Option<f64>,
    /// Viscous damping of each wheel joint, N·m·s/rad, or the model's own.
    pub wheel_damping_nm_s_rad: Option<f64>,
}

impl Variation {
    /// The robot as modelled.
    pub const NOMINAL: Self = Self {
        mass_scale: 1.0,
        leg_mass_scale: 1.0,
        torso_com_offset_m: [0.0; 3],
        friction: None,
        wheel_damping_nm_s_rad: None,
    };

    /// Whether this is the robot as modelled.
    pub fn is_nominal(&self) -> bool {
        *self == Self::NOMINAL
    }

    /// Changes `model` (whose parts `layout` names) into this robot. The caller recomputes the
    /// derived constants before stepping.
    pub fn apply(&self, model: &mut MjModel, layout: &Layout) {
        let robot_root = layout.torso_body;
        let parents: Vec<usize> = model
            .body_parentid()
            .iter()
            .map(|p| usize::try_from(*p).unwrap_or(0))
            .collect();
        let leg_roots = layout.leg_bodies;
        let under = |body: usize, ancestor: usize| {
            let mut b = body;
            // Bounded: a body's parent has a lower id, and the world (0) is its own parent.
            for _ in 0..parents.len() {
                if b == ancestor {
                    return true;
                }
                if b == 0 {
                    return false;
                }
                b = parents.get(b).copied().unwrap_or(0);
            }
            false
        };
        let scales: Vec<f64> = (0..parents.len())
            .map(|body| {
                if !under(body, robot_root) {
                    return 1.0;
                }
                let leg = leg_roots.iter().any(|&root| under(body, root));
                self.mass_scale * if leg { self.leg_mass_scale } else { 1.0 }
            })
            .collect();
        for (mass, scale) in model.body_mass_mut().iter_mut().zip(&scales) {
            *mass *= scale;
        }
        for (inertia, scale) in model.body_inertia_mut().iter_mut().zip(&scales) {
            for value in inertia.iter_mut() {
                *value *= scale;
            }
        }
        if let Some(ipos) = model.body_ipos_mut().get_mut(robot_root) {
            for (value, offset) in ipos.iter_mut().zip(self.torso_com_offset_m) {
                *value += offset;
            }
        }
        if let Some(friction) = self.friction {
            for geom in model.geom_friction_mut().iter_mut() {
                geom[0] = friction;
            }
        }
        if let Some(damping) = self.wheel_damping_nm_s_rad {
            let dofs = model.dof_damping_mut();
            for dof in layout.wheel_qvel {
                if let Some(value) = dofs.get_mut(dof) {
                    *value = damping;
                }
            }
        }
    }
}

impl Default for Variation {
    fn default() -> Self {
        Self::NOMINAL
    }
}
