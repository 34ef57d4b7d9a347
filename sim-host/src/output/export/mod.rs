//! The text logs made from a run's binary log: `run.mcap`'s `/can` into a candump `-L` log and
//! its `/telemetry` into the telemetry CSV, through the same writers a run uses, so an export
//! equals the logs the run wrote itself, byte for byte. The messages are decoded by the
//! schemas the file carries, not by this build's message types.
//!
//! A file cut short (a killed run: its last chunk unfinished, its summary never written) is
//! exported up to the cut, and the export reports the cut as an error naming how far it got.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use mcap::records::Record;
use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader};
use prost_reflect::{DescriptorPool, DynamicMessage, MessageDescriptor, ReflectMessage, Value};
use protocol::{ControllerMode, Frame, Joints};

mod error;

pub use error::{ExportError, MessageFault};

use crate::output::log_writer::Sinks;
use crate::output::output_error::OutputError;
use crate::output::telemetry::TelemetryRow;
use host_can::candump::LoggedFrame;

/// Where the text logs go.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ExportTargets {
    /// The candump log and the interface its lines name (`None`: not written).
    pub candump: Option<(PathBuf, String)>,
    /// The telemetry CSV (`None`: not written).
    pub csv: Option<PathBuf>,
}

/// What an export wrote.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Exported {
    /// Frames written to the candump log.
    pub frames: u64,
    /// Rows written to the CSV.
    pub rows: u64,
    /// The last time exported, s.
    pub last_time_s: f64,
}

/// The topics exported.
const CAN: &str = "/can";
const TELEMETRY: &str = "/telemetry";

/// Exports `mcap` into `targets`. The file is checked to be an MCAP before any text log is
/// created.
pub fn export(mcap: &Path, targets: &ExportTargets) -> Result<Exported, ExportError> {
    let read_error = |source| ExportError::Read {
        path: mcap.to_owned(),
        source,
    };
    let mut file = File::open(mcap).map_err(read_error)?;
    let (starts, ends) = magic_at_ends(&mut file).map_err(read_error)?;
    if !starts {
        return Err(ExportError::NotMcap {
            path: mcap.to_owned(),
        });
    }
    let mut sinks = TextSinks::create(targets)?;
    let mut decoder = Decoder::new(mcap);
    let mut reader = LinearReader::new();
    while let Some(event) = reader.next_event() {
        match event {
            Ok(LinearReadEvent::ReadRequest(wanted)) => {
                let read = file.read(reader.insert(wanted)).map_err(read_error)?;
                reader.notify_read(read);
            }
            Ok(LinearReadEvent::Record { data, opcode }) => {
                let record =
                    mcap::parse_record(opcode, data).map_err(|source| decoder.mcap(source))?;
                decoder.record(record, &mut sinks)?;
            }
            // A whole MCAP ends with the magic its writer writes last: without it the file was
            // cut short (a killed run leaves its last chunk's header unfinished), and a reading
            // error where it ends is the cut, not damage.
            Err(_) if !ends => {
                let exported = sinks.finish()?;
                return Err(ExportError::CutShort {
                    path: mcap.to_owned(),
                    exported,
                });
            }
            Err(source) => return Err(decoder.mcap(source)),
        }
    }
    let wanted = [
        (targets.candump.is_some(), CAN),
        (targets.csv.is_some(), TELEMETRY),
    ];
    if let Some((_, topic)) = wanted
        .into_iter()
        .find(|(asked, topic)| *asked && !decoder.has(topic))
    {
        return Err(ExportError::MissingTopic {
            path: mcap.to_owned(),
            topic,
        });
    }
    Ok(sinks.finish()?)
}

/// Whether `file` starts and ends with the MCAP magic; reads from its start again after.
fn magic_at_ends(file: &mut File) -> std::io::Result<(bool, bool)> {
    let mut magic_at = |from: SeekFrom| -> std::io::Result<bool> {
        let mut bytes = [0; 8];
        // A file shorter than the magic has neither.
        Ok(file.seek(from).is_ok() && file.read_exact(&mut bytes).is_ok() && bytes == *mcap::MAGIC)
    };
    let ends = (magic_at(SeekFrom::Start(0))?, magic_at(SeekFrom::End(-8))?);
    file.seek(SeekFrom::Start(0))?;
    Ok(ends)
}

/// The text logs being written (the run's own writers), and what went into them.
struct TextSinks {
    sinks: Sinks,
    exported: Exported,
}

impl TextSinks {
    fn create(targets: &ExportTargets) -> Result<Self, OutputError> {
        let mut sinks = Sinks::default();
        if let Some((path, interface)) = &targets.candump {
            sinks.open_candump(path, interface)?;
        }
        if let Some(path) = &targets.csv {
            sinks.open_csv(path)?;
        }
        Ok(Self {
            sinks,
            exported: Exported::default(),
        })
    }

    fn frame(&mut self, logged: &LoggedFrame) -> Result<(), OutputError> {
        self.sinks.frame(logged.time_s, &logged.frame)?;
        if self.sinks.candump.is_some() {
            self.exported.frames += 1;
        }
        self.exported.last_time_s = self.exported.last_time_s.max(logged.time_s);
        Ok(())
    }

    fn row(&mut self, row: &TelemetryRow) -> Result<(), OutputError> {
        self.sinks.cycle(row, None)?;
        if self.sinks.csv.is_some() {
            self.exported.rows += 1;
        }
        self.exported.last_time_s = self.exported.last_time_s.max(row.time_s);
        Ok(())
    }

    fn finish(self) -> Result<Exported, OutputError> {
        self.sinks.finish()?;
        Ok(self.exported)
    }
}

/// The file's schemas and channels as they come, and the messages decoded by them.
struct Decoder<'a> {
    path: &'a Path,
    /// Protobuf schemas by id: their message's name and the file descriptor set, decoded when
    /// an exported topic's channel names them.
    schemas: Vec<(u16, String, Vec<u8>)>,
    /// Channel id → the exported topic it carries and its message.
    channels: Vec<(u16, &'static str, MessageDescriptor)>,
}

impl<'a> Decoder<'a> {
    fn new(path: &'a Path) -> Self {
        Self {
            path,
            schemas: Vec::new(),
            channels: Vec::new(),
        }
    }

    fn mcap(&self, source: mcap::McapError) -> ExportError {
        ExportError::Mcap {
            path: self.path.to_owned(),
            source,
        }
    }

    fn fault(&self, topic: &'static str, fault: MessageFault) -> ExportError {
        ExportError::Message {
            path: self.path.to_owned(),
            topic,
            fault,
        }
    }

    /// Whether `topic` has a channel this export reads.
    fn has(&self, topic: &str) -> bool {
        self.channels.iter().any(|(_, t, _)| *t == topic)
    }

    fn record(&mut self, record: Record<'_>, sinks: &mut TextSinks) -> Result<(), ExportError> {
        match record {
            // The summary repeats the schemas and channels: the first of each counts.
            Record::Schema { header, data }
                if header.encoding == "protobuf"
                    && !self.schemas.iter().any(|(id, ..)| *id == header.id) =>
            {
                self.schemas
                    .push((header.id, header.name, data.into_owned()));
            }
            Record::Channel(channel) => {
                let topic = [CAN, TELEMETRY]
                    .into_iter()
                    .find(|topic| *topic == channel.topic);
                let schema = self
                    .schemas
                    .iter()
                    .find(|(id, ..)| *id == channel.schema_id);
                let known = self.channels.iter().any(|(id, ..)| *id == channel.id);
                if let (Some(topic), Some((_, name, data)), false) = (topic, schema, known) {
                    let pool = DescriptorPool::decode(data.as_slice())
                        .map_err(|e| self.fault(topic, MessageFault::Schema(e)))?;
                    let descriptor = pool.get_message_by_name(name).ok_or_else(|| {
                        self.fault(topic, MessageFault::MissingMessage(name.clone()))
                    })?;
                    self.channels.push((channel.id, topic, descriptor));
                }
            }
            Record::Message { header, data } => {
                let Some((_, topic, descriptor)) = self
                    .channels
                    .iter()
                    .find(|(id, ..)| *id == header.channel_id)
                else {
                    return Ok(());
                };
                let message = DynamicMessage::decode(descriptor.clone(), data.as_ref())
                    .map_err(|e| self.fault(topic, MessageFault::Decode(e)))?;
                if *topic == CAN {
                    for logged in self.frames(&message)? {
                        sinks.frame(&logged)?;
                    }
                } else {
                    sinks.row(&self.row(&message)?)?;
                }
            }
            _ => {}
        }
        Ok(())
    }

    /// The frames of a `/can` message.
    fn frames(&self, message: &DynamicMessage) -> Result<Vec<LoggedFrame>, ExportError> {
        let fields = Fields {
            decoder: self,
            topic: CAN,
        };
        let frames = fields.list(message, "frames")?;
        frames
            .iter()
            .map(|value| {
                let frame = value
                    .as_message()
                    .ok_or_else(|| fields.fault(MessageFault::WrongType("frames")))?;
                let id = fields.u32(frame, "id")?;
                let data = fields.bytes(frame, "data")?;
                let frame_of = u16::try_from(id)
                    .ok()
                    .and_then(|id| Frame::new(id, &data))
                    .ok_or_else(|| {
                        fields.fault(MessageFault::NotCanFrame {
                            id,
                            bytes: data.len(),
                        })
                    })?;
                Ok(LoggedFrame {
                    time_s: fields.f64(frame, "time_s")?,
                    frame: frame_of,
                })
            })
            .collect()
    }

    /// The row of a `/telemetry` message.
    fn row(&self, message: &DynamicMessage) -> Result<TelemetryRow, ExportError> {
        let fields = Fields {
            decoder: self,
            topic: TELEMETRY,
        };
        let mode = match fields.string(message, "mode")?.as_str() {
            "" => None,
            label => Some(
                ControllerMode::ALL
                    .iter()
                    .copied()
                    .find(|m| m.label() == label)
                    .ok_or_else(|| fields.fault(MessageFault::UnknownMode(label.to_owned())))?,
            ),
        };
        Ok(TelemetryRow {
            time_s: fields.f64(message, "time_s")?,
            torso_pos_m: fields.array(message, "torso_pos_m")?,
            torso_rpy_deg: fields.array(message, "torso_rpy_deg")?,
            leg_joint_rad: Joints::new(fields.array(message, "leg_joint_rad")?),
            wheel_torque_nm: fields.array(message, "wheel_torque_nm")?,
            wheel_speed_rad_s: fields.array(message, "wheel_speed_rad_s")?,
            foot_force_n: fields.array(message, "foot_force_n")?,
            body_contact: fields.bool(message, "body_contact")?,
            mode,
        })
    }
}

/// A message's fields by name, with an error naming the topic and field.
struct Fields<'d, 'a> {
    decoder: &'d Decoder<'a>,
    topic: &'static str,
}

impl Fields<'_, '_> {
    fn fault(&self, fault: MessageFault) -> ExportError {
        self.decoder.fault(self.topic, fault)
    }

    fn value(&self, message: &DynamicMessage, name: &'static str) -> Result<Value, ExportError> {
        let descriptor = message.descriptor();
        let field = descriptor
            .get_field_by_name(name)
            .ok_or_else(|| self.fault(MessageFault::MissingField(name)))?;
        Ok(message.get_field(&field).into_owned())
    }

    fn typed<T>(
        &self,
        message: &DynamicMessage,
        name: &'static str,
        read: impl FnOnce(&Value) -> Option<T>,
    ) -> Result<T, ExportError> {
        read(&self.value(message, name)?).ok_or_else(|| self.fault(MessageFault::WrongType(name)))
    }

    fn f64(&self, message: &DynamicMessage, name: &'static str) -> Result<f64, ExportError> {
        self.typed(message, name, Value::as_f64)
    }

    fn u32(&self, message: &DynamicMessage, name: &'static str) -> Result<u32, ExportError> {
        self.typed(message, name, Value::as_u32)
    }

    fn bool(&self, message: &DynamicMessage, name: &'static str) -> Result<bool, ExportError> {
        self.typed(message, name, Value::as_bool)
    }

    fn string(&self, message: &DynamicMessage, name: &'static str) -> Result<String, ExportError> {
        self.typed(message, name, |v| v.as_str().map(str::to_owned))
    }

    fn bytes(&self, message: &DynamicMessage, name: &'static str) -> Result<Vec<u8>, ExportError> {
        self.typed(message, name, |v| v.as_bytes().map(|b| b.to_vec()))
    }

    fn list(
        &self,
        message: &DynamicMessage,
        name: &'static str,
    ) -> Result<Vec<Value>, ExportError> {
        self.typed(message, name, |v| v.as_list().map(<[Value]>::to_vec))
    }

    /// A repeated double of exactly `N` values.
    fn array<const N: usize>(
        &self,
        message: &DynamicMessage,
        name: &'static str,
    ) -> Result<[f64; N], ExportError> {
        let values = self.list(message, name)?;
        if values.len() != N {
            return Err(self.fault(MessageFault::WrongLength {
                field: name,
                found: values.len(),
                expected: N,
            }));
        }
        let mut array = [0.0; N];
        for (slot, value) in array.iter_mut().zip(&values) {
            *slot = value
                .as_f64()
                .ok_or_else(|| self.fault(MessageFault::WrongType(name)))?;
        }
        Ok(array)
    }
}
