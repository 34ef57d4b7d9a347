//! The run as robotics tools open it: an MCAP file and, optionally, a live Foxglove WebSocket
//! server, both fed through the Foxglove SDK, with the robot's URDF ([`urdf`]).
//!
//! | topic | schema | what |
//! |---|---|---|
//! | `/tf` | `foxglove.FrameTransforms` | `world` → the torso from MuJoCo's free joint, and every link from its joint angle ([`bodies`]), at [`TF_HZ`] |
//! | `/joint_states` | `JointState` | every hinge's angle, rate and actuator effort, from MuJoCo, at [`JOINTS_HZ`] |
//! | `/imu` | `Imu` | what the IMU node sent: angular rate, specific force |
//! | `/wheels` | `WheelFeedback` | what the wheel drive sent: speed and torque of each wheel |
//! | `/controller/status` | `ControllerStatus` | the controller's mode, faults, pitch, roll, body height |
//! | `/controller/log` | `foxglove.Log` | a line per change of mode or fault flags |
//! | `/can` | `CanFrames` | every frame on the bus (time, id, message name, data), a message per control cycle: the candump log's content |
//! | `/telemetry` | `Telemetry` | the simulator's ground truth each control cycle: the telemetry CSV's row |
//! | `/robot_description` | JSON `std_msgs/String` | the URDF (also attached to the MCAP, and `robot.urdf` beside it) |
//! | `/camera` | `foxglove.CompressedImage` | the rendered frames, PNG (only with frames: feature `renderer`) |
//!
//! The log's own messages ([`messages`]) are protobuf with their schemas in the file. Log times
//! are simulation time. The MCAP is lz4-chunked and flushed with the other logs (a chunk ends
//! at each flush), so a killed run leaves it whole up to its last flush but for an unfinished
//! last chunk: `sim-host export` ([`crate::output::export`]) reads it up to there.

pub mod bodies;
mod channels;
pub mod messages;
pub mod urdf;

use std::fs::File;
use std::io::BufWriter;
use std::path::PathBuf;
use std::sync::Arc;

use foxglove::messages::log::Level as LogLevel;
pub use foxglove::messages::CompressedImage;
use foxglove::messages::{FrameTransform, FrameTransforms, Log, Quaternion, Timestamp, Vector3};
use foxglove::{Channel, Context, McapWriterHandle, WebSocketServerHandle};
use protocol::signal::WireField;
use protocol::{decode_frame, AnyMessage, ControllerMode, FaultFlags, Frame};

use crate::output::output_error::OutputError;
use crate::output::telemetry::TelemetryRow;
use crate::session::simulator::Simulator;
use bodies::{RobotTree, WORLD_FRAME};
use channels::{open_mcap, Channels};

/// The body the robot hangs from (its free joint).
pub const ROOT_BODY: &str = "torso";

/// Where a run's Foxglove outputs go.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct FoxgloveOutputs {
    /// The MCAP file (`None`: none).
    pub mcap: Option<PathBuf>,
    /// Serve the run live on this WebSocket port of 127.0.0.1 (`None`: no server; 0: any free
    /// port).
    pub live_port: Option<u16>,
}

/// The open log.
pub struct FoxgloveLog {
    context: Arc<Context>,
    mcap: Option<(PathBuf, McapWriterHandle<BufWriter<File>>)>,
    server: Option<WebSocketServerHandle>,
    tree: RobotTree,
    urdf: String,
    channels: Channels,
    last_status: Option<(ControllerMode, FaultFlags)>,
    /// When the description is logged next (repeated so that a late viewer gets it).
    description_due: Due,
    camera: Option<Arc<Channel<CompressedImage>>>,
    tf_due: Due,
    joints_due: Due,
    /// The frames seen since the last cycle, and when the last was.
    pending_can: (Vec<messages::CanFrame>, f64),
}

impl std::fmt::Debug for FoxgloveLog {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FoxgloveLog")
            .field("mcap", &self.mcap.as_ref().map(|(path, _)| path))
            .field(
                "live",
                &self.server.as_ref().map(WebSocketServerHandle::port),
            )
            .finish_non_exhaustive()
    }
}

/// The robot description's rate, Hz (repeated so that a late viewer gets it).
const DESCRIPTION_HZ: f64 = 1.0;

/// The transforms' rate, Hz: smooth in a 3D view, and a fifth of the data the control rate's
/// would be (23 transforms a message are most of the file).
pub const TF_HZ: f64 = 50.0;

/// The joint states' rate, Hz: half the control rate of 250 Hz, for plots.
pub const JOINTS_HZ: f64 = 125.0;

/// Coordinates a [`RobotSample`] holds at most, per vector: the robot's 25 positions and 24
/// velocities with room for a scene's free bodies.
pub const MAX_COORDINATES: usize = 64;

/// A vector of MuJoCo's coordinates, held without the heap.
pub type Coordinates = heapless::Vec<f64, MAX_COORDINATES>;

/// The robot's state at one step, copied off the simulator for the log writer's thread without
/// an allocation (the simulation's thread allocates nothing per cycle).
#[derive(Debug, Clone, PartialEq)]
pub struct RobotSample {
    /// Simulated time, s.
    pub time_s: f64,
    /// MuJoCo's `qpos`.
    pub qpos: Coordinates,
    /// MuJoCo's `qvel`.
    pub qvel: Coordinates,
    /// MuJoCo's `qfrc_actuator`.
    pub qfrc_actuator: Coordinates,
}

impl RobotSample {
    /// The state of `sim` now. [`FoxgloveLog::open`] refuses a model with more coordinates than
    /// a sample holds, so none is cut short.
    pub fn of(sim: &Simulator) -> Self {
        let data = sim.physics().data();
        let copy = |values: &[f64]| values.iter().copied().take(MAX_COORDINATES).collect();
        Self {
            time_s: sim.time_s(),
            qpos: copy(data.qpos()),
            qvel: copy(data.qvel()),
            qfrc_actuator: copy(data.qfrc_actuator()),
        }
    }
}

/// When a decimated topic is next due, s.
#[derive(Debug, Clone, Copy, Default)]
struct Due {
    next_s: Option<f64>,
}

impl Due {
    /// Whether a message at `time_s` is due at `rate_hz`; if so the next is a period on.
    fn now(&mut self, time_s: f64, rate_hz: f64) -> bool {
        // A little slack, so that 4 ms steps land on a 20 ms grid despite rounding.
        if self.next_s.is_some_and(|next| time_s + 1e-4 < next) {
            return false;
        }
        let period_s = 1.0 / rate_hz;
        let base = self.next_s.unwrap_or(time_s);
        self.next_s = Some(base.max(time_s - period_s) + period_s);
        true
    }
}

impl FoxgloveLog {
    /// Opens the outputs of `outputs` for the robot of `sim`; `None` when there are none.
    pub fn open(sim: &Simulator, outputs: &FoxgloveOutputs) -> Result<Option<Self>, OutputError> {
        if outputs.mcap.is_none() && outputs.live_port.is_none() {
            return Ok(None);
        }
        let model = sim.physics().model();
        let coordinates = sim.physics().data().qpos().len();
        if coordinates > MAX_COORDINATES {
            return Err(OutputError::TooManyCoordinates {
                coordinates,
                max: MAX_COORDINATES,
            });
        }
        let tree =
            RobotTree::of(model, ROOT_BODY).ok_or(OutputError::NoRootBody { body: ROOT_BODY })?;
        let urdf = urdf::urdf(model, &tree, "hybrid_robot");
        let context = Context::new();
        let mcap = match &outputs.mcap {
            Some(path) => Some((path.clone(), open_mcap(&context, path, &urdf)?)),
            None => None,
        };
        let server = match outputs.live_port {
            Some(port) => Some(
                context
                    .websocket_server()
                    .name("hybrid-robot sim-host")
                    .bind("127.0.0.1", port)
                    .start_blocking()
                    .map_err(|source| OutputError::LiveServer { port, source })?,
            ),
            None => None,
        };
        let channels = Channels::open(&context, &urdf)?;
        Ok(Some(Self {
            context,
            mcap,
            server,
            tree,
            urdf,
            channels,
            last_status: None,
            description_due: Due::default(),
            camera: None,
            tf_due: Due::default(),
            joints_due: Due::default(),
            pending_can: (Vec::with_capacity(32), 0.0),
        }))
    }

    /// The live server's port, if one runs.
    pub fn live_port(&self) -> Option<u16> {
        self.server.as_ref().map(WebSocketServerHandle::port)
    }

    /// A channel for the rendered camera's frames (`/camera`, `foxglove.CompressedImage`, PNG),
    /// made on first use: a run without frames has none.
    pub fn camera(&mut self) -> Arc<Channel<CompressedImage>> {
        Arc::clone(
            self.camera
                .get_or_insert_with(|| Arc::new(self.context.channel_builder("/camera").build())),
        )
    }

    /// The URDF of the robot.
    pub fn urdf(&self) -> &str {
        &self.urdf
    }

    /// Logs one frame seen on the bus at `time_s`, and what it says where a topic shows it.
    pub fn frame(&mut self, time_s: f64, frame: &Frame) {
        let decoded = decode_frame(frame.id(), frame.data()).ok();
        let name = protocol::MessageId::from_raw(frame.id()).map(|id| id.layout().name);
        self.pending_can.0.push(messages::CanFrame {
            time_s,
            id: u32::from(frame.id()),
            name: name.unwrap_or("unknown"),
            data: foxglove::bytes::Bytes::copy_from_slice(frame.data()),
        });
        self.pending_can.1 = time_s;
        let at = nanos(time_s);
        match decoded.map(|d| d.message) {
            Some(AnyMessage::Imu(imu)) => {
                let vector = |[x, y, z]: [f32; 3]| messages::Vector {
                    x: f64::from(x),
                    y: f64::from(y),
                    z: f64::from(z),
                };
                let message = messages::Imu {
                    angular_velocity: vector(imu.angular_rate.map(|r| r.si())),
                    linear_acceleration: vector(imu.acceleration.map(|a| a.si())),
                };
                self.channels.imu.log_with_time(&message, at);
            }
            Some(AnyMessage::WheelFeedback(wheels)) => {
                let message = messages::WheelFeedback {
                    velocity_rad_s: wheels.velocity.map(|v| f64::from(v.si())),
                    effort_nm: wheels.effort.map(|e| f64::from(e.si())),
                };
                self.channels.wheels.log_with_time(&message, at);
            }
            Some(AnyMessage::ControllerStatus(status)) => self.status(time_s, &status),
            _ => {}
        }
    }

    fn status(&mut self, time_s: f64, status: &protocol::ControllerStatus) {
        let bits = status.faults.bits();
        let faults: Vec<&'static str> = FaultFlags::FLAGS
            .iter()
            .enumerate()
            .filter(|(bit, _)| bits & (1 << bit) != 0)
            .map(|(_, name)| *name)
            .collect();
        let message = messages::ControllerStatus {
            mode: status.mode.label(),
            faults: faults.clone(),
            pitch_rad: f64::from(status.pitch.si()),
            roll_rad: f64::from(status.roll.si()),
            body_height_m: f64::from(status.body_height.si()),
        };
        self.channels.status.log_with_time(&message, nanos(time_s));
        let now = (status.mode, status.faults);
        if self.last_status != Some(now) {
            self.last_status = Some(now);
            let level = if status.faults.is_empty() {
                LogLevel::Info
            } else {
                LogLevel::Warning
            };
            let text = if faults.is_empty() {
                format!("mode {}", status.mode.label())
            } else {
                format!("mode {}, faults {}", status.mode.label(), faults.join(", "))
            };
            self.channels.log.log_with_time(
                &Log {
                    timestamp: Some(timestamp(time_s)),
                    level: level as i32,
                    message: text,
                    name: "controller".into(),
                    ..Default::default()
                },
                nanos(time_s),
            );
        }
    }

    /// Logs the robot's pose and joints at the step `sample` was taken.
    pub fn cycle(&mut self, sample: &RobotSample) {
        self.log_can();
        let time_s = sample.time_s;
        if self.tf_due.now(time_s, TF_HZ) {
            self.transforms(time_s, &sample.qpos);
        }
        if self.joints_due.now(time_s, JOINTS_HZ) {
            self.joint_states(sample);
        }
        if self.description_due.now(time_s, DESCRIPTION_HZ) {
            self.channels.describe(time_s);
        }
    }

    /// Logs the simulator's ground truth of a cycle (`/telemetry`).
    pub fn telemetry(&self, row: &TelemetryRow) {
        let message = messages::Telemetry {
            time_s: row.time_s,
            torso_pos_m: row.torso_pos_m,
            torso_rpy_deg: row.torso_rpy_deg,
            leg_joint_rad: *row.leg_joint_rad.as_array(),
            wheel_torque_nm: row.wheel_torque_nm,
            wheel_speed_rad_s: row.wheel_speed_rad_s,
            foot_force_n: row.foot_force_n,
            body_contact: row.body_contact,
            mode: row.mode.map_or("", ControllerMode::label),
        };
        self.channels
            .telemetry
            .log_with_time(&message, nanos(row.time_s));
    }

    /// Logs the frames seen since the last cycle as one `/can` message.
    fn log_can(&mut self) {
        if self.pending_can.0.is_empty() {
            return;
        }
        let message = messages::CanFrames {
            frames: std::mem::take(&mut self.pending_can.0),
        };
        self.channels
            .can
            .log_with_time(&message, nanos(self.pending_can.1));
        // The list is kept for the next cycle's frames: no allocation a cycle.
        self.pending_can.0 = message.frames;
        self.pending_can.0.clear();
    }

    fn transforms(&self, time_s: f64, qpos: &[f64]) {
        let stamp = Some(timestamp(time_s));
        let mut transforms = Vec::with_capacity(self.tree.links.len() + 1);
        if let Some(root) = self.tree.root_pose(qpos) {
            transforms.push(transform(stamp, WORLD_FRAME, &self.tree.root, &root));
        }
        for link in &self.tree.links {
            let pose = RobotTree::link_pose(link, qpos);
            transforms.push(transform(stamp, &link.parent, &link.name, &pose));
        }
        self.channels
            .tf
            .log_with_time(&FrameTransforms { transforms }, nanos(time_s));
    }

    fn joint_states(&self, sample: &RobotSample) {
        let time_s = sample.time_s;
        let (qpos, qvel, effort) = (&sample.qpos, &sample.qvel, &sample.qfrc_actuator);
        let hinges: Vec<_> = self.tree.hinges().collect();
        let value = |values: &[f64], at: usize| values.get(at).copied().unwrap_or(0.0);
        let joints = messages::JointState {
            name: hinges.iter().map(|h| h.name.clone()).collect(),
            position: hinges.iter().map(|h| value(qpos, h.qpos)).collect(),
            velocity: hinges.iter().map(|h| value(qvel, h.dof)).collect(),
            effort: hinges.iter().map(|h| value(effort, h.dof)).collect(),
        };
        self.channels.joints.log_with_time(&joints, nanos(time_s));
    }

    /// Puts what was logged so far into the file.
    pub fn flush(&mut self) -> Result<(), OutputError> {
        if let Some((path, mcap)) = &self.mcap {
            mcap.flush().map_err(|source| OutputError::Mcap {
                path: path.clone(),
                source,
            })?;
        }
        Ok(())
    }

    /// Closes the file (its summary and index written) and stops the live server.
    pub fn finish(mut self) -> Result<(), OutputError> {
        self.log_can();
        if let Some(server) = self.server.take() {
            server.stop().wait_blocking();
        }
        if let Some((path, mcap)) = self.mcap.take() {
            mcap.close()
                .map_err(|source| OutputError::Mcap { path, source })?;
        }
        drop(self.context);
        Ok(())
    }
}

fn transform(
    timestamp: Option<Timestamp>,
    parent: &str,
    child: &str,
    pose: &bodies::Pose,
) -> FrameTransform {
    let [x, y, z] = pose.translation_m;
    let [qw, qx, qy, qz] = pose.rotation_wxyz;
    FrameTransform {
        timestamp,
        parent_frame_id: parent.to_owned(),
        child_frame_id: child.to_owned(),
        translation: Some(Vector3 { x, y, z }),
        rotation: Some(Quaternion {
            x: qx,
            y: qy,
            z: qz,
            w: qw,
        }),
    }
}

/// Simulation time `time_s` as a log time, ns.
pub fn nanos(time_s: f64) -> u64 {
    (time_s.max(0.0) * 1e9).round() as u64
}

/// The timestamp of simulation time `time_s`.
pub fn timestamp(time_s: f64) -> Timestamp {
    let ns = nanos(time_s);
    Timestamp::new((ns / 1_000_000_000) as u32, (ns % 1_000_000_000) as u32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_decimated_topic_keeps_its_rate_on_a_control_grid() {
        let mut due = Due::default();
        // 250 Hz for 2 s at 50 Hz: every fifth step, 100 in all.
        let logged: Vec<usize> = (1..=500)
            .filter(|&k| due.now(k as f64 * 0.004, 50.0))
            .collect();
        assert_eq!(logged.len(), 100);
        assert!(logged.windows(2).all(|w| w[1] - w[0] == 5), "{logged:?}");
        // 125 Hz from 250 Hz: every other step.
        let mut due = Due::default();
        assert_eq!(
            (1..=500)
                .filter(|&k| due.now(k as f64 * 0.004, 125.0))
                .count(),
            250
        );
    }
}
