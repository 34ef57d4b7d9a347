//! The MuJoCo side of the simulator: one model and its state, stepped at the model's timestep.
//! The emulated hardware reads and drives it through this type only; ground truth for tests and
//! telemetry comes from here too, never from the bus.

use std::path::Path;

use mujoco_rs::prelude::{MjData, MjModel};

use crate::robot::rotation;
use mujoco_rs::wrappers::mj_model::MjtGeomBase as MjtGeom;
use mujoco_rs::wrappers::mj_model::MjtObjBase as MjtObj;
use protocol::{Joints, Leg};

use crate::robot::model::{load, Layout, ModelError};
use crate::robot::variation::Variation;

/// Torso state from the simulator (ground truth).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TorsoState {
    /// Torso centre, world frame, m.
    pub pos_m: [f64; 3],
    /// Orientation quaternion world ← torso, w x y z.
    pub quat_wxyz: [f64; 4],
    /// Linear velocity of the torso centre, world frame, m/s.
    pub vel_m_s: [f64; 3],
    /// Angular velocity, torso frame, rad/s.
    pub ang_vel_rad_s: [f64; 3],
}

impl TorsoState {
    /// Roll, pitch, yaw (Z-Y-X Euler angles), rad. Pitch + = nose down (rotation about +y).
    pub fn rpy_rad(&self) -> [f64; 3] {
        rotation::rpy_rad(self.quat_wxyz)
    }

    /// Angle between the torso's up axis and the world's, rad: the tilt, whatever its direction.
    pub fn tilt_rad(&self) -> f64 {
        let [_, x, y, _] = self.quat_wxyz;
        // z-component of the torso's up axis in the world frame.
        let up_z = 1.0 - 2.0 * (x * x + y * y);
        up_z.clamp(-1.0, 1.0).acos()
    }

    /// `v_torso`, a vector in the torso frame, in the world frame.
    pub fn to_world(&self, v_torso: [f64; 3]) -> [f64; 3] {
        rotation::rotate(self.quat_wxyz, v_torso)
    }

    /// World velocity of the point `offset_m` from the torso's origin (torso frame), m/s: the
    /// torso's velocity plus its rotation about its origin.
    pub fn point_velocity_m_s(&self, offset_m: [f64; 3]) -> [f64; 3] {
        let spin = rotation::cross(self.to_world(self.ang_vel_rad_s), self.to_world(offset_m));
        [0, 1, 2].map(|i| self.vel_m_s[i] + spin[i])
    }
}

/// What touches the ground (any geom outside the robot's subtree).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct GroundContacts {
    /// Left and right wheel.
    pub wheels: [bool; 2],
    /// Feet FL, FR, BL, BR.
    pub feet: [bool; 4],
    /// Any other part of the robot: torso, a leg link.
    pub other: bool,
    /// The torso box itself.
    pub torso: bool,
}

/// A loaded model and its state.
pub struct Physics {
    data: MjData<Box<MjModel>>,
    layout: Layout,
}

impl std::fmt::Debug for Physics {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Physics")
            .field("time_s", &self.time_s())
            .finish_non_exhaustive()
    }
}

impl Physics {
    /// Loads the MJCF at `path`.
    pub fn load(path: &Path) -> Result<Self, ModelError> {
        Self::load_varied(path, &Variation::NOMINAL)
    }

    /// Loads the MJCF at `path` and makes it into the robot `variation` describes.
    pub fn load_varied(path: &Path, variation: &Variation) -> Result<Self, ModelError> {
        let (mut model, layout) = load(path)?;
        let nominal = variation.is_nominal();
        if !nominal {
            variation.apply(&mut model, &layout);
        }
        let mut data = MjData::new(Box::new(model));
        if !nominal {
            data.set_const();
        }
        Ok(Self { data, layout })
    }

    /// The MuJoCo model.
    pub fn model(&self) -> &MjModel {
        self.data.model()
    }

    /// The MuJoCo state (read-only: for renderers and viewers, which copy what they draw).
    pub fn data(&self) -> &MjData<Box<MjModel>> {
        &self.data
    }

    /// Indices of the robot's parts.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// The model's timestep, s.
    pub fn timestep_s(&self) -> f64 {
        self.data.model_opt().timestep
    }

    /// Simulation time, s.
    pub fn time_s(&self) -> f64 {
        self.data.time()
    }

    /// Advances one timestep.
    pub fn step(&mut self) {
        self.data.step();
    }

    /// Whether the state is finite (MuJoCo resets a diverged state and warns; this catches it
    /// for tests).
    pub fn is_finite(&self) -> bool {
        self.data.qpos().iter().all(|v| v.is_finite())
            && self.data.qvel().iter().all(|v| v.is_finite())
    }

    /// Places the torso at `height_m` (level, at the origin, at rest, turned `heading_rad`
    /// about the vertical) with the leg joints at `leg_joint_rad` and their servo targets
    /// there too.
    pub fn place(&mut self, height_m: f64, leg_joint_rad: &Joints<f64>, heading_rad: f64) {
        self.data.reset();
        let layout = self.layout.clone();
        {
            let qpos = self.data.qpos_mut();
            let (sin, cos) = (heading_rad / 2.0).sin_cos();
            qpos[..7].copy_from_slice(&[0.0, 0.0, height_m, cos, 0.0, 0.0, sin]);
            for (adr, angle) in layout.leg_qpos.iter().zip(leg_joint_rad) {
                qpos[*adr] = *angle;
            }
        }
        for act in layout.leg_actuator.iter() {
            self.data.ctrl_mut()[*act] = 0.0;
        }
        self.data.forward();
    }

    /// Sets the torques of `leg`'s four joint motors, N·m (`hip1`, `hip2`, knee, ankle),
    /// clamped by the model's control range.
    pub fn set_leg_torques(&mut self, leg: Leg, torques_nm: &[f64; 4]) {
        for (act, torque) in self.layout.leg_actuator.leg(leg).iter().zip(torques_nm) {
            self.data.ctrl_mut()[*act] = *torque;
        }
    }

    /// Turns a leg's four servos on or off (off: no torque at all, the joints only feel their
    /// damping).
    pub fn set_leg_enabled(&mut self, leg: usize, enabled: bool) {
        let bit = 1_i32 << self.layout.leg_group[leg];
        let opt = self.data.model_opt_mut();
        if enabled {
            opt.disableactuator &= !bit;
        } else {
            opt.disableactuator |= bit;
        }
    }

    /// Whether a leg's servos are on.
    pub fn leg_enabled(&self, leg: usize) -> bool {
        self.data.model_opt().disableactuator & (1_i32 << self.layout.leg_group[leg]) == 0
    }

    /// Sets both wheel torques, N·m (+ = forward), clamped by the model's control range.
    pub fn set_wheel_torques(&mut self, torque_nm: [f64; 2]) {
        for (act, torque) in self.layout.wheel_actuator.iter().zip(torque_nm) {
            self.data.ctrl_mut()[*act] = torque;
        }
    }

    /// Leg joint angles, rad.
    pub fn leg_positions_rad(&self) -> Joints<f64> {
        self.layout.leg_qpos.map(|adr| self.data.qpos()[adr])
    }

    /// Leg joint velocities, rad/s.
    pub fn leg_velocities_rad_s(&self) -> Joints<f64> {
        self.layout.leg_qvel.map(|adr| self.data.qvel()[adr])
    }

    /// Torque each leg servo applies, N·m.
    pub fn leg_efforts_nm(&self) -> Joints<f64> {
        self.layout
            .leg_force_sensor
            .map(|adr| self.data.sensordata()[adr])
    }

    /// Wheel angles (unwrapped), rad.
    pub fn wheel_positions_rad(&self) -> [f64; 2] {
        self.layout.wheel_qpos.map(|adr| self.data.qpos()[adr])
    }

    /// Wheel speeds, rad/s (+ = rolling forward).
    pub fn wheel_velocities_rad_s(&self) -> [f64; 2] {
        self.layout.wheel_qvel.map(|adr| self.data.qvel()[adr])
    }

    /// Torque each wheel motor applies, N·m.
    pub fn wheel_efforts_nm(&self) -> [f64; 2] {
        self.layout
            .wheel_force_sensor
            .map(|adr| self.data.sensordata()[adr])
    }

    /// The rangefinder's rays' exact lengths to what they meet first, m (centre, up, down,
    /// left, right; −1: nothing).
    pub fn range_rays_m(&self) -> [f64; 5] {
        self.layout
            .range_rays
            .map(|adr| self.data.sensordata()[adr])
    }

    /// The IMU's ideal readings: orientation world ← torso (w x y z), body-frame angular rate
    /// (rad/s), body-frame specific force (m/s²).
    pub fn imu(&self) -> ([f64; 4], [f64; 3], [f64; 3]) {
        let s = self.data.sensordata();
        let l = &self.layout;
        (
            [
                s[l.imu_quat],
                s[l.imu_quat + 1],
                s[l.imu_quat + 2],
                s[l.imu_quat + 3],
            ],
            [s[l.imu_gyro], s[l.imu_gyro + 1], s[l.imu_gyro + 2]],
            [s[l.imu_accel], s[l.imu_accel + 1], s[l.imu_accel + 2]],
        )
    }

    /// Normal force on each foot's touch sensor, N.
    pub fn foot_forces_n(&self) -> [f64; 4] {
        self.layout
            .foot_touch
            .map(|adr| self.data.sensordata()[adr])
    }

    /// Torso pose and velocity.
    pub fn torso(&self) -> TorsoState {
        let q = self.data.qpos();
        let v = self.data.qvel();
        TorsoState {
            pos_m: [q[0], q[1], q[2]],
            quat_wxyz: [q[3], q[4], q[5], q[6]],
            vel_m_s: [v[0], v[1], v[2]],
            ang_vel_rad_s: [v[3], v[4], v[5]],
        }
    }

    /// The id of the geom named `name` (`None` if the model has none).
    pub fn geom_id(&self, name: &str) -> Option<usize> {
        self.data.model().name_to_id(MjtObj::mjOBJ_GEOM, name)
    }

    /// Where geom `id`'s centre is, world frame, m (`None` for an id past the model's geoms).
    pub fn geom_position_m(&self, id: usize) -> Option<[f64; 3]> {
        self.data.geom_xpos().get(id).copied()
    }

    /// Whether anything touches the geom named `name` (an obstacle of a scene: `step`,
    /// `ramp_up`, …); `false` if the model has no such geom.
    pub fn touches_geom(&self, name: &str) -> bool {
        let Some(id) = self
            .data
            .model()
            .name_to_id(MjtObj::mjOBJ_GEOM, name)
            .and_then(|id| i32::try_from(id).ok())
        else {
            return false;
        };
        self.data
            .contact()
            .iter()
            .any(|c| c.geom1 == id || c.geom2 == id)
    }

    /// This step's contacts of a part of the robot with an obstacle (a geom of the world that
    /// is not a plane: a scene's steps and ramps, not the floor), as (obstacle geom, robot
    /// geom) ids; a pair may come more than once (several contact points).
    pub fn obstacle_contacts(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        let model = self.data.model();
        let (body_of, type_of) = (model.geom_bodyid(), model.geom_type());
        let world = move |id: usize| body_of.get(id) == Some(&0);
        let obstacle = move |id: usize| {
            world(id) && type_of.get(id).is_some_and(|t| *t != MjtGeom::mjGEOM_PLANE)
        };
        self.data.contact().iter().filter_map(move |c| {
            let (a, b) = (
                usize::try_from(c.geom1).ok()?,
                usize::try_from(c.geom2).ok()?,
            );
            match (obstacle(a), obstacle(b)) {
                (true, false) if !world(b) => Some((a, b)),
                (false, true) if !world(a) => Some((b, a)),
                _ => None,
            }
        })
    }

    /// The name of geom `id` (`(unnamed)` without one).
    pub fn geom_name(&self, id: usize) -> &str {
        self.data
            .model()
            .id_to_name(MjtObj::mjOBJ_GEOM, id)
            .unwrap_or("(unnamed)")
    }

    /// Names of the robot's geoms touching anything that is not the robot (diagnostics).
    pub fn ground_contact_names(&self) -> Vec<String> {
        let model = self.data.model();
        let mut names = Vec::new();
        for contact in self.data.contact() {
            for geom in [contact.geom1, contact.geom2] {
                let Ok(id) = usize::try_from(geom) else {
                    continue;
                };
                let body = model.geom_bodyid().get(id).copied().unwrap_or(0);
                if body != 0 {
                    let name = self.geom_name(id).to_owned();
                    if !names.contains(&name) {
                        names.push(name);
                    }
                }
            }
        }
        names
    }

    /// Which parts of the robot touch anything that is not the robot.
    pub fn ground_contacts(&self) -> GroundContacts {
        let model = self.data.model();
        let body_of = model.geom_bodyid();
        let root_of = model.body_rootid();
        let robot_root = root_of[self.layout.torso_body];
        let is_robot = |geom: i32| {
            usize::try_from(geom)
                .ok()
                .and_then(|g| body_of.get(g))
                .and_then(|b| root_of.get(*b as usize))
                == Some(&robot_root)
        };
        let mut contacts = GroundContacts::default();
        for contact in self.data.contact() {
            let (a, b) = (contact.geom1, contact.geom2);
            let part = match (is_robot(a), is_robot(b)) {
                (true, false) => a,
                (false, true) => b,
                _ => continue,
            };
            let part = part as usize;
            if let Some(w) = self.layout.wheel_geoms.iter().position(|g| *g == part) {
                contacts.wheels[w] = true;
            } else if let Some(f) = self.layout.foot_geoms.iter().position(|g| *g == part) {
                contacts.feet[f] = true;
            } else {
                contacts.other = true;
                contacts.torso |=
                    body_of.get(part).map(|b| *b as usize) == Some(self.layout.torso_body);
            }
        }
        contacts
    }
}
