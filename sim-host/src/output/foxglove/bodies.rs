//! The robot as a tree of links and joints, as URDF and Foxglove's transforms see it, built
//! from the MuJoCo model: each body is a link; a body with several hinges (a hip's abduction
//! and pitch) becomes a chain of links, one joint each, the inner ones named after their joint.
//! Joints must sit at their body's origin (true of this robot's model): URDF has no joint anchor
//! off the link frame.

use mujoco_rs::prelude::MjModel;

use crate::robot::rotation::{multiply, rotate};
use mujoco_rs::wrappers::mj_model::{MjtJoint, MjtObjBase as MjtObj};

/// The frame the world is in.
pub const WORLD_FRAME: &str = "world";

/// A hinge joint of the model.
#[derive(Debug, Clone, PartialEq)]
pub struct Hinge {
    /// The joint's name.
    pub name: String,
    /// Its axis in its link's frame.
    pub axis: [f64; 3],
    /// Its range, rad (`None`: unlimited, a wheel).
    pub range_rad: Option<[f64; 2]>,
    /// Its position in `qpos`.
    pub qpos: usize,
    /// Its position in `qvel` (and the actuator force's).
    pub dof: usize,
}

/// One link and the joint that carries it.
#[derive(Debug, Clone, PartialEq)]
pub struct Link {
    /// The link's name: its frame id.
    pub name: String,
    /// The parent link's name.
    pub parent: String,
    /// The joint frame in the parent link's frame at zero angle: translation, m, and rotation
    /// `[w, x, y, z]`.
    pub origin: Pose,
    /// The hinge that turns it (`None`: fixed).
    pub hinge: Option<Hinge>,
    /// The MuJoCo body whose geoms it carries (`None` for a link inside a hinge chain).
    pub body: Option<usize>,
}

/// A rigid transform: translation, m, then rotation `[w, x, y, z]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Translation, m.
    pub translation_m: [f64; 3],
    /// Rotation, unit quaternion `[w, x, y, z]`.
    pub rotation_wxyz: [f64; 4],
}

impl Pose {
    /// No motion.
    pub const IDENTITY: Self = Self {
        translation_m: [0.0; 3],
        rotation_wxyz: [1.0, 0.0, 0.0, 0.0],
    };

    /// This pose followed by `other` (expressed in this one's frame).
    pub fn then(&self, other: &Pose) -> Pose {
        let moved = rotate(self.rotation_wxyz, other.translation_m);
        Pose {
            translation_m: [
                self.translation_m[0] + moved[0],
                self.translation_m[1] + moved[1],
                self.translation_m[2] + moved[2],
            ],
            rotation_wxyz: multiply(self.rotation_wxyz, other.rotation_wxyz),
        }
    }
}

/// The robot's links, parents first, and the body at their root.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotTree {
    /// The root link (the body with the free joint): its pose is the world's transform.
    pub root: String,
    /// Its MuJoCo body id.
    pub root_body: usize,
    /// Where its free joint's position and orientation start in `qpos`.
    pub root_qpos: usize,
    /// Every other link, parents before children.
    pub links: Vec<Link>,
}

impl RobotTree {
    /// The tree under the body named `root` in `model`; `None` if there is no such body.
    pub fn of(model: &MjModel, root: &str) -> Option<Self> {
        let root_body = model.name_to_id(MjtObj::mjOBJ_BODY, root)?;
        let root_joint = model.jnt_type().iter().enumerate().position(|(j, kind)| {
            *kind == MjtJoint::mjJNT_FREE
                && model
                    .jnt_bodyid()
                    .get(j)
                    .and_then(|b| usize::try_from(*b).ok())
                    == Some(root_body)
        })?;
        let root_qpos = usize::try_from(*model.jnt_qposadr().get(root_joint)?).ok()?;
        let parents = model.body_parentid();
        let body_name = |id: usize| {
            model
                .id_to_name(MjtObj::mjOBJ_BODY, id)
                .map_or_else(|| format!("body_{id}"), str::to_owned)
        };
        let mut links = Vec::new();
        // Bodies are numbered parents first, so a descendant of the root comes after it.
        let mut inside = vec![false; parents.len()];
        for body in root_body..parents.len() {
            let parent = usize::try_from(*parents.get(body)?).ok()?;
            let is_inside = body == root_body || inside.get(parent).copied().unwrap_or(false);
            if let Some(flag) = inside.get_mut(body) {
                *flag = is_inside;
            }
            if body == root_body || !is_inside {
                continue;
            }
            let origin = Pose {
                translation_m: *model.body_pos().get(body)?,
                rotation_wxyz: *model.body_quat().get(body)?,
            };
            let hinges = hinges_of(model, body);
            let name = body_name(body);
            let mut parent_link = body_name(parent);
            let count = hinges.len();
            for (k, hinge) in hinges.into_iter().enumerate() {
                let last = k + 1 == count;
                let link_name = if last {
                    name.clone()
                } else {
                    format!("{}_link", hinge.name)
                };
                links.push(Link {
                    name: link_name.clone(),
                    parent: std::mem::replace(&mut parent_link, link_name),
                    origin: if k == 0 { origin } else { Pose::IDENTITY },
                    hinge: Some(hinge),
                    body: last.then_some(body),
                });
            }
            if count == 0 {
                links.push(Link {
                    name,
                    parent: parent_link,
                    origin,
                    hinge: None,
                    body: Some(body),
                });
            }
        }
        Some(Self {
            root: body_name(root_body),
            root_body,
            root_qpos,
            links,
        })
    }

    /// The root's pose in the world at the state `qpos` (its free joint's; MuJoCo's `xpos` and
    /// `xquat` are those of the step's start, one physics step behind the state).
    pub fn root_pose(&self, qpos: &[f64]) -> Option<Pose> {
        let state = qpos.get(self.root_qpos..self.root_qpos + 7)?;
        Some(Pose {
            translation_m: [state[0], state[1], state[2]],
            rotation_wxyz: [state[3], state[4], state[5], state[6]],
        })
    }

    /// `link`'s pose in its parent's frame at the joint angles of `qpos`.
    pub fn link_pose(link: &Link, qpos: &[f64]) -> Pose {
        let Some(hinge) = &link.hinge else {
            return link.origin;
        };
        let angle = qpos.get(hinge.qpos).copied().unwrap_or(0.0);
        let (sin, cos) = (0.5 * angle).sin_cos();
        let [x, y, z] = hinge.axis;
        link.origin.then(&Pose {
            translation_m: [0.0; 3],
            rotation_wxyz: [cos, sin * x, sin * y, sin * z],
        })
    }

    /// Every hinge of the tree, in link order.
    pub fn hinges(&self) -> impl Iterator<Item = &Hinge> {
        self.links.iter().filter_map(|link| link.hinge.as_ref())
    }
}

/// The hinges of `body`, in the model's order.
fn hinges_of(model: &MjModel, body: usize) -> Vec<Hinge> {
    let bodies = model.jnt_bodyid();
    model
        .jnt_type()
        .iter()
        .enumerate()
        .filter(|&(j, kind)| {
            *kind == MjtJoint::mjJNT_HINGE
                && bodies.get(j).and_then(|b| usize::try_from(*b).ok()) == Some(body)
        })
        .filter_map(|(j, _)| {
            let limited = model.jnt_limited().get(j).copied().unwrap_or(false);
            Some(Hinge {
                name: model
                    .id_to_name(MjtObj::mjOBJ_JOINT, j)
                    .map_or_else(|| format!("joint_{j}"), str::to_owned),
                axis: *model.jnt_axis().get(j)?,
                range_rad: if limited {
                    Some(*model.jnt_range().get(j)?)
                } else {
                    None
                },
                qpos: usize::try_from(*model.jnt_qposadr().get(j)?).ok()?,
                dof: usize::try_from(*model.jnt_dofadr().get(j)?).ok()?,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pose_then_another_composes_translation_and_rotation() {
        let half = std::f64::consts::FRAC_PI_4;
        let turned = Pose {
            translation_m: [1.0, 0.0, 0.0],
            rotation_wxyz: [half.cos(), 0.0, 0.0, half.sin()],
        };
        let composed = turned.then(&turned);
        assert!((composed.translation_m[0] - 1.0).abs() < 1e-12);
        assert!((composed.translation_m[1] - 1.0).abs() < 1e-12);
        assert_eq!(Pose::IDENTITY.then(&turned), turned);
    }
}
