//! The log's channels on its Foxglove context, and the MCAP file they are written to.

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;
use std::sync::Arc;

use foxglove::messages::{FrameTransforms, Log};
use foxglove::{
    Channel, Context, McapCompression, McapWriteOptions, McapWriterHandle, PartialMetadata,
    RawChannel, Schema,
};
use serde_json::json;

use super::{messages, nanos};
use crate::output::output_error::OutputError;

/// Every topic of the log but the camera's (made on demand).
pub(super) struct Channels {
    pub(super) tf: Channel<FrameTransforms>,
    pub(super) log: Channel<Log>,
    pub(super) joints: Channel<messages::JointState>,
    pub(super) imu: Channel<messages::Imu>,
    pub(super) wheels: Channel<messages::WheelFeedback>,
    pub(super) status: Channel<messages::ControllerStatus>,
    pub(super) can: Channel<messages::CanFrames>,
    pub(super) telemetry: Channel<messages::Telemetry>,
    description: Arc<RawChannel>,
    /// The robot description's message, encoded once: the URDF does not change.
    description_json: Vec<u8>,
}

impl Channels {
    /// The channels on `context`; `/robot_description` carries `urdf`.
    pub(super) fn open(context: &Arc<Context>, urdf: &str) -> Result<Self, OutputError> {
        let topic = "/robot_description";
        let schema = json!({
            "type": "object",
            "title": "std_msgs/String",
            "properties": {"data": {"type": "string"}},
        });
        let description = context
            .channel_builder(topic)
            .message_encoding("json")
            .schema(Schema::new(
                "std_msgs/String",
                "jsonschema",
                schema.to_string().into_bytes(),
            ))
            .build_raw()
            .map_err(|source| OutputError::Channel {
                topic: topic.to_owned(),
                source,
            })?;
        Ok(Self {
            tf: context.channel_builder("/tf").build(),
            log: context.channel_builder("/controller/log").build(),
            joints: context.channel_builder("/joint_states").build(),
            imu: context.channel_builder("/imu").build(),
            wheels: context.channel_builder("/wheels").build(),
            status: context.channel_builder("/controller/status").build(),
            can: context.channel_builder("/can").build(),
            telemetry: context.channel_builder("/telemetry").build(),
            description,
            description_json: json!({ "data": urdf }).to_string().into_bytes(),
        })
    }

    /// Logs the robot description at `time_s`.
    pub(super) fn describe(&self, time_s: f64) {
        self.description.log_with_meta(
            &self.description_json,
            PartialMetadata {
                log_time: Some(nanos(time_s)),
            },
        );
    }
}

/// The MCAP writer on `context`, lz4-chunked, with the URDF attached.
pub(super) fn open_mcap(
    context: &Arc<Context>,
    path: &Path,
    urdf: &str,
) -> Result<McapWriterHandle<BufWriter<File>>, OutputError> {
    let failed = |source| OutputError::Mcap {
        path: path.to_owned(),
        source,
    };
    let options = McapWriteOptions::default().compression(Some(McapCompression::Lz4));
    // Replaced, as the run's other logs are: a second run into the same folder is the usual
    // case (the demo's `out/`).
    let file = File::create(path).map_err(|source| OutputError::Io {
        path: path.to_owned(),
        source,
    })?;
    let writer = context
        .mcap_writer_with_options(options)
        .create(BufWriter::new(file))
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
