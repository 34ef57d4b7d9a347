//! The run as robotics tools open it: an MCAP file and, optionally, a live Foxglove WebSocket
//! server, both fed through the Foxglove SDK, with the robot's URDF ([`urdf`]).
//!
//! | topic | schema | what |
//! |---|---|---|
//! | `/tf` | `foxglove.FrameTransforms` | `world` → the torso from MuJoCo's free joint, and every link from its joint angle ([`bodies`]) |
//! | `/joint_states` | JSON `JointState` | every hinge's angle, rate and actuator effort, from MuJoCo |
//! | `/imu` | JSON `Imu` | what the IMU node sent: angular rate, specific force |
//! | `/wheels` | JSON `WheelFeedback` | what the wheel drive sent: speed and torque of each wheel |
//! | `/controller/status` | JSON `ControllerStatus` | the controller's mode, faults, pitch, roll, body height |
//! | `/controller/log` | `foxglove.Log` | a line per change of mode or fault flags |
//! | `/can` | JSON `CanFrame` | every frame on the bus: id, message name, data |
//! | `/robot_description` | JSON `std_msgs/String` | the URDF (also attached to the MCAP, and `robot.urdf` beside it) |
//! | `/camera` | `foxglove.CompressedImage` | the rendered frames, PNG (only with frames: feature `renderer`) |
//!
//! Log times are simulation time. The MCAP is lz4-chunked and flushed with the other logs (at
//! least once a second), so a killed run leaves it readable up to its last flush (MCAP readers
//! recover the chunks of a file without a footer).

pub mod bodies;
pub mod urdf;

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use foxglove::messages::log::Level as LogLevel;
pub use foxglove::messages::CompressedImage;
use foxglove::messages::{FrameTransform, FrameTransforms, Log, Quaternion, Timestamp, Vector3};
use foxglove::{
    Channel, Context, McapCompression, McapWriteOptions, McapWriterHandle, PartialMetadata,
    RawChannel, Schema, WebSocketServerHandle,
};
use protocol::signal::WireField;
use protocol::{decode_frame, AnyMessage, ControllerMode, FaultFlags, Frame};
use serde_json::json;

use crate::output::output_error::OutputError;
use crate::session::simulator::Simulator;
use bodies::{RobotTree, WORLD_FRAME};

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
    /// When the description was last logged, s (repeated so that a late viewer gets it).
    described_s: Option<f64>,
    camera: Option<Arc<Channel<CompressedImage>>>,
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

struct Channels {
    tf: Channel<FrameTransforms>,
    log: Channel<Log>,
    joints: Arc<RawChannel>,
    imu: Arc<RawChannel>,
    wheels: Arc<RawChannel>,
    status: Arc<RawChannel>,
    can: Arc<RawChannel>,
    description: Arc<RawChannel>,
}

/// The robot description is logged again this often, s.
const DESCRIBE_EVERY_S: f64 = 1.0;

impl FoxgloveLog {
    /// Opens the outputs of `outputs` for the robot of `sim`; `None` when there are none.
    pub fn open(sim: &Simulator, outputs: &FoxgloveOutputs) -> Result<Option<Self>, OutputError> {
        if outputs.mcap.is_none() && outputs.live_port.is_none() {
            return Ok(None);
        }
        let model = sim.physics().model();
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
        let channels = Channels::open(&context)?;
        Ok(Some(Self {
            context,
            mcap,
            server,
            tree,
            urdf,
            channels,
            last_status: None,
            described_s: None,
            camera: None,
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
        let at = meta(time_s);
        let decoded = decode_frame(frame.id(), frame.data()).ok();
        let name = protocol::MessageId::from_raw(frame.id()).map(|id| id.layout().name);
        let can = json!({
            "id": frame.id(),
            "name": name.unwrap_or("unknown"),
            "data": hex(frame.data()),
        });
        log_json(&self.channels.can, &can, at);
        match decoded.map(|d| d.message) {
            Some(AnyMessage::Imu(imu)) => {
                let [gx, gy, gz] = imu.angular_rate.map(|r| r.si());
                let [ax, ay, az] = imu.acceleration.map(|a| a.si());
                let message = json!({
                    "angular_velocity": {"x": gx, "y": gy, "z": gz},
                    "linear_acceleration": {"x": ax, "y": ay, "z": az},
                });
                log_json(&self.channels.imu, &message, at);
            }
            Some(AnyMessage::WheelFeedback(wheels)) => {
                let message = json!({
                    "velocity_rad_s": wheels.velocity.map(|v| v.si()),
                    "effort_nm": wheels.effort.map(|e| e.si()),
                });
                log_json(&self.channels.wheels, &message, at);
            }
            Some(AnyMessage::ControllerStatus(status)) => self.status(time_s, &status),
            _ => {}
        }
    }

    fn status(&mut self, time_s: f64, status: &protocol::ControllerStatus) {
        let bits = status.faults.bits();
        let faults: Vec<&str> = FaultFlags::FLAGS
            .iter()
            .enumerate()
            .filter(|(bit, _)| bits & (1 << bit) != 0)
            .map(|(_, name)| *name)
            .collect();
        let message = json!({
            "mode": status.mode.label(),
            "faults": faults,
            "pitch_rad": status.pitch.si(),
            "roll_rad": status.roll.si(),
            "body_height_m": status.body_height.si(),
        });
        log_json(&self.channels.status, &message, meta(time_s));
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

    /// Logs the robot's pose and joints at the simulator's present step.
    pub fn cycle(&mut self, sim: &Simulator) {
        let time_s = sim.time_s();
        let data = sim.physics().data();
        let stamp = Some(timestamp(time_s));
        let mut transforms = Vec::with_capacity(self.tree.links.len() + 1);
        if let Some(root) = self.tree.root_pose(data.qpos()) {
            transforms.push(transform(stamp, WORLD_FRAME, &self.tree.root, &root));
        }
        for link in &self.tree.links {
            let pose = RobotTree::link_pose(link, data.qpos());
            transforms.push(transform(stamp, &link.parent, &link.name, &pose));
        }
        self.channels
            .tf
            .log_with_time(&FrameTransforms { transforms }, nanos(time_s));
        let (qpos, qvel, effort) = (data.qpos(), data.qvel(), data.qfrc_actuator());
        let hinges: Vec<_> = self.tree.hinges().collect();
        let joints = json!({
            "name": hinges.iter().map(|h| h.name.as_str()).collect::<Vec<_>>(),
            "position": hinges.iter().map(|h| qpos.get(h.qpos).copied().unwrap_or(0.0)).collect::<Vec<_>>(),
            "velocity": hinges.iter().map(|h| qvel.get(h.dof).copied().unwrap_or(0.0)).collect::<Vec<_>>(),
            "effort": hinges.iter().map(|h| effort.get(h.dof).copied().unwrap_or(0.0)).collect::<Vec<_>>(),
        });
        log_json(&self.channels.joints, &joints, meta(time_s));
        if self
            .described_s
            .is_none_or(|at| time_s - at >= DESCRIBE_EVERY_S)
        {
            self.described_s = Some(time_s);
            log_json(
                &self.channels.description,
                &json!({ "data": self.urdf }),
                meta(time_s),
            );
        }
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

impl Channels {
    fn open(context: &Arc<Context>) -> Result<Self, OutputError> {
        let json = |topic: &str, schema: &str, properties: serde_json::Value| {
            let schema_json = json!({
                "type": "object",
                "title": schema,
                "properties": properties,
            });
            context
                .channel_builder(topic)
                .message_encoding("json")
                .schema(Schema::new(
                    schema,
                    "jsonschema",
                    schema_json.to_string().into_bytes(),
                ))
                .build_raw()
                .map_err(|source| OutputError::Channel {
                    topic: topic.to_owned(),
                    source,
                })
        };
        let numbers = json!({"type": "array", "items": {"type": "number"}});
        let strings = json!({"type": "array", "items": {"type": "string"}});
        let vector = json!({"type": "object", "properties": {
            "x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}}});
        Ok(Self {
            tf: context.channel_builder("/tf").build(),
            log: context.channel_builder("/controller/log").build(),
            joints: json(
                "/joint_states",
                "JointState",
                json!({"name": strings, "position": numbers, "velocity": numbers, "effort": numbers}),
            )?,
            imu: json(
                "/imu",
                "Imu",
                json!({"angular_velocity": vector, "linear_acceleration": vector}),
            )?,
            wheels: json(
                "/wheels",
                "WheelFeedback",
                json!({"velocity_rad_s": numbers, "effort_nm": numbers}),
            )?,
            status: json(
                "/controller/status",
                "ControllerStatus",
                json!({"mode": {"type": "string"}, "faults": strings,
                    "pitch_rad": {"type": "number"}, "roll_rad": {"type": "number"},
                    "body_height_m": {"type": "number"}}),
            )?,
            can: json(
                "/can",
                "CanFrame",
                json!({"id": {"type": "integer"}, "name": {"type": "string"},
                    "data": {"type": "string"}}),
            )?,
            description: json(
                "/robot_description",
                "std_msgs/String",
                json!({"data": {"type": "string"}}),
            )?,
        })
    }
}

/// The MCAP writer on `context`, lz4-chunked, with the URDF attached.
fn open_mcap(
    context: &Arc<Context>,
    path: &Path,
    urdf: &str,
) -> Result<McapWriterHandle<BufWriter<File>>, OutputError> {
    let failed = |source| OutputError::Mcap {
        path: path.to_owned(),
        source,
    };
    let options = McapWriteOptions::default().compression(Some(McapCompression::Lz4));
    let writer = context
        .mcap_writer_with_options(options)
        .create_new_buffered_file(path)
        .map_err(failed)?;
    writer
        .attach(&foxglove::McapAttachment {
            log_time: 0,
            create_time: 0,
            name: "robot.urdf".into(),
            media_type: "application/xml".into(),
            data: urdf.as_bytes().into(),
        })
        .map_err(failed)?;
    Ok(writer)
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

fn log_json(channel: &RawChannel, message: &serde_json::Value, at: PartialMetadata) {
    channel.log_with_meta(message.to_string().as_bytes(), at);
}

/// Simulation time `time_s` as a log time, ns.
pub fn nanos(time_s: f64) -> u64 {
    (time_s.max(0.0) * 1e9).round() as u64
}

fn meta(time_s: f64) -> PartialMetadata {
    PartialMetadata {
        log_time: Some(nanos(time_s)),
    }
}

/// The timestamp of simulation time `time_s`.
pub fn timestamp(time_s: f64) -> Timestamp {
    let ns = nanos(time_s);
    Timestamp::new((ns / 1_000_000_000) as u32, (ns % 1_000_000_000) as u32)
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02X}")).collect()
}
