//! Loading the robot's MJCF and finding, by the report's names, every joint, actuator and sensor
//! the emulated hardware uses. A model that lacks one is rejected with its name, before any step.

use std::path::{Path, PathBuf};

use mujoco_rs::prelude::MjModel;
use mujoco_rs::wrappers::mj_model::MjtObjBase as MjtObj;
use protocol::{Joints, Leg, JOINT_NAMES, WHEEL_NAMES};

/// The robot on flat ground, shipped with the crate.
pub const DEFAULT_MODEL: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/models/hybrid_robot.xml");
/// The robot with a 6 cm step and a 10° ramp ahead of it.
pub const OBSTACLES_MODEL: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/models/obstacles.xml");

/// Why a model cannot be simulated.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ModelError {
    /// MuJoCo rejected the file; its message names the element and line.
    #[error("cannot load the model {path}: {message}")]
    Load {
        /// The file.
        path: PathBuf,
        /// MuJoCo's message.
        message: String,
    },
    /// An object the emulated hardware needs is missing.
    #[error(
        "the model {path} has no {kind} named `{name}` (the simulator needs the report's names)"
    )]
    Missing {
        /// The file.
        path: PathBuf,
        /// "joint", "actuator", "sensor", "body" or "site".
        kind: &'static str,
        /// The missing name.
        name: String,
    },
    /// The leg drives cannot go torque-free one leg at a time: each leg's four actuators must
    /// share an actuator group of their own (0…30), apart from the wheels'.
    #[error("the model {path} needs each leg's actuators in a group of their own (hybrid_robot.xml uses FL 1, FR 2, BL 3, BR 4; wheels 0): {detail}")]
    ActuatorGroups {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        detail: String,
    },
    /// A sensor the hardware reads has the wrong number of values (the IMU's quaternion 4, its
    /// gyro and accelerometer 3, a force or touch sensor 1).
    #[error("the model {path}: sensor `{name}` has {found} values; the simulator reads {expected} (check its type in <sensor>)")]
    SensorSize {
        /// The file.
        path: PathBuf,
        /// The sensor.
        name: String,
        /// Values the hardware reads.
        expected: usize,
        /// Values the model gives.
        found: usize,
    },
    /// A leg joint without a range: its drive needs the joint's limits to enforce them.
    #[error("the model {path}: joint `{name}` needs limited=\"true\" and a range low < high (its drive enforces it)")]
    JointRange {
        /// The file.
        path: PathBuf,
        /// The joint.
        name: String,
    },
    /// The model's timestep does not divide the control period.
    #[error("the model {path} has timestep {timestep_s} s, which does not divide the control period {period_s} s")]
    Timestep {
        /// The file.
        path: PathBuf,
        /// Model timestep, s.
        timestep_s: f64,
        /// Control period, s.
        period_s: f64,
    },
}

/// Indices into MuJoCo's arrays for everything the hardware reads or drives.
#[derive(Debug, Clone)]
pub struct Layout {
    /// `qpos` address of each leg joint.
    pub leg_qpos: Joints<usize>,
    /// `qvel` address of each leg joint.
    pub leg_qvel: Joints<usize>,
    /// Actuator of each leg joint (`m_<joint>`).
    pub leg_actuator: Joints<usize>,
    /// Actuator group of each leg (FL, FR, BL, BR), for going torque-free.
    pub leg_group: [u32; 4],
    /// `qpos` address of each wheel joint (left, right).
    pub wheel_qpos: [usize; 2],
    /// `qvel` address of each wheel joint.
    pub wheel_qvel: [usize; 2],
    /// Wheel actuators (`m_wheel_left`, `m_wheel_right`).
    pub wheel_actuator: [usize; 2],
    /// `sensordata` address of each leg actuator's force sensor.
    pub leg_force_sensor: Joints<usize>,
    /// Each leg joint's range (the model's `range`), [low, high] rad: what its drive enforces.
    pub leg_range_rad: Joints<[f64; 2]>,
    /// `sensordata` address of each wheel actuator's force sensor.
    pub wheel_force_sensor: [usize; 2],
    /// `sensordata` addresses of the IMU: quaternion (4), gyro (3), accelerometer (3).
    pub imu_quat: usize,
    /// Gyro.
    pub imu_gyro: usize,
    /// Accelerometer.
    pub imu_accel: usize,
    /// `sensordata` address of each rangefinder ray (centre, up, down, left, right).
    pub range_rays: [usize; 5],
    /// `sensordata` address of each foot's touch sensor (FL, FR, BL, BR).
    pub foot_touch: [usize; 4],
    /// The torso body.
    pub torso_body: usize,
    /// The two wheel geoms (left, right).
    pub wheel_geoms: [usize; 2],
    /// The four foot geoms (FL, FR, BL, BR).
    pub foot_geoms: [usize; 4],
    /// The body each leg hangs from (`leg_fl` …): the leg is its subtree.
    pub leg_bodies: [usize; 4],
}

/// Loads `path` and finds the layout the hardware needs.
pub fn load(path: &Path) -> Result<(MjModel, Layout), ModelError> {
    let model = MjModel::from_xml(path).map_err(|e| ModelError::Load {
        path: path.to_owned(),
        message: e.to_string(),
    })?;
    let layout = Layout::find(&model, path)?;
    Ok((model, layout))
}

impl Layout {
    fn find(model: &MjModel, path: &Path) -> Result<Self, ModelError> {
        let find = Lookup { model, path };
        let mut layout = Layout {
            leg_qpos: Joints::splat(0),
            leg_qvel: Joints::splat(0),
            leg_actuator: Joints::splat(0),
            leg_group: [0; 4],
            wheel_qpos: [0; 2],
            wheel_qvel: [0; 2],
            wheel_actuator: [0; 2],
            leg_force_sensor: Joints::splat(0),
            leg_range_rad: Joints::splat([0.0; 2]),
            wheel_force_sensor: [0; 2],
            imu_quat: find.sensor("imu_quat", 4)?,
            imu_gyro: find.sensor("imu_gyro", 3)?,
            imu_accel: find.sensor("imu_accel", 3)?,
            range_rays: [
                find.sensor("range_c", 1)?,
                find.sensor("range_up", 1)?,
                find.sensor("range_down", 1)?,
                find.sensor("range_l", 1)?,
                find.sensor("range_r", 1)?,
            ],
            foot_touch: [0; 4],
            torso_body: find.id("body", MjtObj::mjOBJ_BODY, "torso")?,
            wheel_geoms: [find.geom("wheel_left")?, find.geom("wheel_right")?],
            foot_geoms: [0; 4],
            leg_bodies: [0; 4],
        };
        for (leg, names) in Joints::new(JOINT_NAMES).iter_legs() {
            for (k, name) in names.iter().enumerate() {
                let j = find.joint(name)?;
                layout.leg_qpos.leg_mut(leg)[k] = find.qpos(j);
                layout.leg_qvel.leg_mut(leg)[k] = find.qvel(j);
                layout.leg_actuator.leg_mut(leg)[k] = find.actuator(&format!("m_{name}"))?;
                layout.leg_force_sensor.leg_mut(leg)[k] = find.sensor(&format!("frc_{name}"), 1)?;
                layout.leg_range_rad.leg_mut(leg)[k] = find.range(j, name)?;
            }
        }
        for leg in Leg::ALL {
            let (i, suffix) = (leg as usize, leg.suffix());
            layout.leg_group[i] = model.actuator_group()[layout.leg_actuator.leg(leg)[0]] as u32;
            layout.foot_touch[i] = find.sensor(&format!("touch_{suffix}"), 1)?;
            layout.foot_geoms[i] = find.geom(&format!("foot_{suffix}"))?;
            layout.leg_bodies[i] = find.id("body", MjtObj::mjOBJ_BODY, &format!("leg_{suffix}"))?;
        }
        layout.check_leg_groups(model, path)?;
        layout.find_wheels(&find)?;
        Ok(layout)
    }

    /// The wheels' joints, actuators and force sensors; their actuators in a group of no leg.
    fn find_wheels(&mut self, find: &Lookup<'_>) -> Result<(), ModelError> {
        let groups = find.model.actuator_group();
        for (i, side) in WHEEL_NAMES.iter().enumerate() {
            let j = find.joint(&format!("wheel_{side}_joint"))?;
            self.wheel_qpos[i] = find.qpos(j);
            self.wheel_qvel[i] = find.qvel(j);
            self.wheel_actuator[i] = find.actuator(&format!("m_wheel_{side}"))?;
            self.wheel_force_sensor[i] = find.sensor(&format!("frc_wheel_{side}"), 1)?;
            let group = groups[self.wheel_actuator[i]] as u32;
            if self.leg_group.contains(&group) {
                return Err(ModelError::ActuatorGroups {
                    path: find.path.to_owned(),
                    detail: format!("m_wheel_{side} shares group {group} with a leg"),
                });
            }
        }
        Ok(())
    }

    /// Each leg's actuators in one group of its own (0…30), so that a leg can go torque-free
    /// by disabling its group.
    fn check_leg_groups(&self, model: &MjModel, path: &Path) -> Result<(), ModelError> {
        let groups = model.actuator_group();
        for (leg, joints) in Joints::new(JOINT_NAMES).zip(self.leg_actuator).iter_legs() {
            for (name, act) in joints {
                let group = groups[*act];
                if group as u32 != self.leg_group[leg as usize] || !(0..=30).contains(&group) {
                    return Err(ModelError::ActuatorGroups {
                        path: path.to_owned(),
                        detail: format!("m_{name} is in group {group}"),
                    });
                }
            }
        }
        let mut distinct = self.leg_group.to_vec();
        distinct.sort_unstable();
        distinct.dedup();
        if distinct.len() != 4 {
            return Err(ModelError::ActuatorGroups {
                path: path.to_owned(),
                detail: format!("leg groups {:?} are not distinct", self.leg_group),
            });
        }
        Ok(())
    }
}

/// Finding the model's objects by name, each miss an error naming the file and the object.
struct Lookup<'a> {
    model: &'a MjModel,
    path: &'a Path,
}

impl Lookup<'_> {
    fn id(&self, kind: &'static str, obj: MjtObj, name: &str) -> Result<usize, ModelError> {
        self.model
            .name_to_id(obj, name)
            .ok_or_else(|| ModelError::Missing {
                path: self.path.to_owned(),
                kind,
                name: name.to_owned(),
            })
    }

    fn joint(&self, name: &str) -> Result<usize, ModelError> {
        self.id("joint", MjtObj::mjOBJ_JOINT, name)
    }

    fn actuator(&self, name: &str) -> Result<usize, ModelError> {
        self.id("actuator", MjtObj::mjOBJ_ACTUATOR, name)
    }

    fn geom(&self, name: &str) -> Result<usize, ModelError> {
        self.id("geom", MjtObj::mjOBJ_GEOM, name)
    }

    /// The `sensordata` address of sensor `name`, which must give `expected` values.
    fn sensor(&self, name: &str, expected: usize) -> Result<usize, ModelError> {
        let s = self.id("sensor", MjtObj::mjOBJ_SENSOR, name)?;
        let found = self.model.sensor_dim()[s] as usize;
        if found != expected {
            return Err(ModelError::SensorSize {
                path: self.path.to_owned(),
                name: name.to_owned(),
                expected,
                found,
            });
        }
        Ok(self.model.sensor_adr()[s] as usize)
    }

    fn qpos(&self, joint: usize) -> usize {
        self.model.jnt_qposadr()[joint] as usize
    }

    fn qvel(&self, joint: usize) -> usize {
        self.model.jnt_dofadr()[joint] as usize
    }

    /// Joint `name`'s range, [low, high] rad; an error unless it is limited with low < high.
    fn range(&self, joint: usize, name: &str) -> Result<[f64; 2], ModelError> {
        let [low, high] = self.model.jnt_range()[joint];
        if self.model.jnt_limited()[joint] && low < high {
            Ok([low, high])
        } else {
            Err(ModelError::JointRange {
                path: self.path.to_owned(),
                name: name.to_owned(),
            })
        }
    }
}

/// Geom ids of the obstacle scene's `step` and `ramp`; `None` in a scene without them.
pub fn obstacle_ids(physics: &crate::robot::physics::Physics) -> Option<Vec<usize>> {
    let model = physics.model();
    ["step", "ramp"]
        .iter()
        .map(|name| model.name_to_id(MjtObj::mjOBJ_GEOM, name))
        .collect()
}
