//! A URDF of the robot, generated from the MuJoCo model it runs (so that Foxglove's 3D panel,
//! RViz or any URDF tool shows the robot the simulator steps): links and joints from
//! [`RobotTree`], each visible geom as a visual. URDF has no capsule or ellipsoid: a capsule is
//! drawn as a cylinder of its length, an ellipsoid as a sphere of its largest semi-axis.

use std::fmt::Write as _;

use mujoco_rs::prelude::MjModel;
use mujoco_rs::wrappers::mj_model::MjtGeomBase as MjtGeom;

use super::bodies::{Pose, RobotTree};
use crate::robot::rotation::rpy_rad;

/// The URDF text of `tree` in `model`, named `name`.
pub fn urdf(model: &MjModel, tree: &RobotTree, name: &str) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "<?xml version=\"1.0\"?>");
    let _ = writeln!(
        out,
        "<!-- Generated from the MuJoCo model by sim-host; do not edit. -->"
    );
    let _ = writeln!(out, "<robot name=\"{}\">", escape(name));
    link(&mut out, model, &tree.root, Some(tree.root_body));
    for l in &tree.links {
        link(&mut out, model, &l.name, l.body);
    }
    for l in &tree.links {
        let kind = match &l.hinge {
            None => "fixed",
            Some(h) if h.range_rad.is_some() => "revolute",
            Some(_) => "continuous",
        };
        let joint_name = l
            .hinge
            .as_ref()
            .map_or_else(|| format!("{}_fixed", l.name), |h| h.name.clone());
        let _ = writeln!(
            out,
            "  <joint name=\"{}\" type=\"{kind}\">",
            escape(&joint_name)
        );
        let _ = writeln!(out, "    <parent link=\"{}\"/>", escape(&l.parent));
        let _ = writeln!(out, "    <child link=\"{}\"/>", escape(&l.name));
        let _ = writeln!(out, "    {}", origin(&l.origin));
        if let Some(h) = &l.hinge {
            let [x, y, z] = h.axis;
            let _ = writeln!(out, "    <axis xyz=\"{x} {y} {z}\"/>");
            if let Some([lower, upper]) = h.range_rad {
                let _ = writeln!(
                    out,
                    "    <limit lower=\"{lower}\" upper=\"{upper}\" effort=\"0\" velocity=\"0\"/>"
                );
            }
        }
        let _ = writeln!(out, "  </joint>");
    }
    let _ = writeln!(out, "</robot>");
    out
}

/// One `<link>` with the visible geoms of `body`.
fn link(out: &mut String, model: &MjModel, name: &str, body: Option<usize>) {
    let _ = writeln!(out, "  <link name=\"{}\">", escape(name));
    if let Some(body) = body {
        for geom in geoms_of(model, body) {
            visual(out, model, geom);
        }
    }
    let _ = writeln!(out, "  </link>");
}

/// The geoms of `body` that are drawn (not fully transparent).
fn geoms_of(model: &MjModel, body: usize) -> Vec<usize> {
    let rgba = model.geom_rgba();
    model
        .geom_bodyid()
        .iter()
        .enumerate()
        .filter(|&(g, b)| {
            usize::try_from(*b).ok() == Some(body) && rgba.get(g).is_some_and(|c| c[3] > 0.0)
        })
        .map(|(g, _)| g)
        .collect()
}

/// One `<visual>` for `geom`, if URDF can draw its shape.
fn visual(out: &mut String, model: &MjModel, geom: usize) {
    let (Some(kind), Some(size), Some(pos), Some(quat), Some(rgba)) = (
        model.geom_type().get(geom),
        model.geom_size().get(geom),
        model.geom_pos().get(geom),
        model.geom_quat().get(geom),
        model.geom_rgba().get(geom),
    ) else {
        return;
    };
    let shape = match *kind {
        MjtGeom::mjGEOM_BOX => format!(
            "<box size=\"{} {} {}\"/>",
            2.0 * size[0],
            2.0 * size[1],
            2.0 * size[2]
        ),
        MjtGeom::mjGEOM_SPHERE => format!("<sphere radius=\"{}\"/>", size[0]),
        MjtGeom::mjGEOM_CAPSULE | MjtGeom::mjGEOM_CYLINDER => format!(
            "<cylinder radius=\"{}\" length=\"{}\"/>",
            size[0],
            2.0 * size[1]
        ),
        MjtGeom::mjGEOM_ELLIPSOID => {
            format!("<sphere radius=\"{}\"/>", size[0].max(size[1]).max(size[2]))
        }
        _ => return,
    };
    let pose = Pose {
        translation_m: *pos,
        rotation_wxyz: *quat,
    };
    let [r, g, b, a] = *rgba;
    let _ = writeln!(out, "    <visual>");
    let _ = writeln!(out, "      {}", origin(&pose));
    let _ = writeln!(out, "      <geometry>{shape}</geometry>");
    let _ = writeln!(
        out,
        "      <material name=\"geom_{geom}\"><color rgba=\"{r} {g} {b} {a}\"/></material>"
    );
    let _ = writeln!(out, "    </visual>");
}

/// `<origin>` of `pose`: URDF's fixed-axis roll, pitch, yaw.
fn origin(pose: &Pose) -> String {
    let [x, y, z] = pose.translation_m;
    let [roll, pitch, yaw] = rpy_rad(pose.rotation_wxyz);
    format!("<origin xyz=\"{x} {y} {z}\" rpy=\"{roll} {pitch} {yaw}\"/>")
}

/// `text` safe inside an XML attribute.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('"', "&quot;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
