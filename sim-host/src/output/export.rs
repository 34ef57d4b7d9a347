//! The text logs made from a run's binary log: `run.mcap`'s `/can` into a candump `-L` log and
//! its `/telemetry` into the telemetry CSV, through the same writers a run uses, so an export
//! equals the logs the run wrote itself, byte for byte. The messages are decoded by the
//! schemas the file carries, not by this build's message types.
//!
//! A file cut short (a killed run: its last chunk unfinished, its summary never written) is
//! exported up to the cut, and the export reports the cut as an error naming how far it got.

use std::fs::File;
use std::io::{BufWriter, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use mcap::records::Record;
use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader};
use prost_reflect::{DescriptorPool, DynamicMessage, MessageDescriptor, ReflectMessage, Value};
use protocol::{ControllerMode, Frame, Joints};

use crate::output::output_error::OutputError;
use crate::output::telemetry::TelemetryRow;
use crate::output::telemetry_csv::CsvWriter;
use host_can::candump::{CandumpWriter, LoggedFrame};

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

/// Why an export stopped.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The MCAP could not be opened or read.
    #[error("cannot read {path}: {source}")]
    Read {
        /// The MCAP.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The file ends mid-record: a run cut short. What came before was exported.
    #[error("{path} ends early, after {:.3} s of the run (a killed run?): the text logs hold everything up to there ({} frames, {} rows)", exported.last_time_s, exported.frames, exported.rows)]
    CutShort {
        /// The MCAP.
        path: PathBuf,
        /// What was exported.
        exported: Exported,
    },
    /// The file is not an MCAP this export can read.
    #[error("{path} is not a readable MCAP: {source} (is it a sim-host run's run.mcap?)")]
    Mcap {
        /// The file.
        path: PathBuf,
        /// What the reader said.
        source: mcap::McapError,
    },
    /// A topic's schema or message does not decode, or lacks a field the text log needs.
    #[error("{path}: {topic}: {what} (written by an incompatible sim-host?)")]
    Message {
        /// The file.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// What is wrong.
        what: String,
    },
    /// A text log could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// The topics exported.
const CAN: &str = "/can";
const TELEMETRY: &str = "/telemetry";

/// Exports `mcap` into `targets`.
pub fn export(mcap: &Path, targets: &ExportTargets) -> Result<Exported, ExportError> {
    let mut file = File::open(mcap).map_err(|source| ExportError::Read {
        path: mcap.to_owned(),
        source,
    })?;
    let mut sinks = TextSinks::create(targets)?;
    let mut decoder = Decoder::new(mcap);
    // A whole MCAP ends with the magic its writer writes last: without it the file was cut
    // short (a killed run leaves its last chunk's header unfinished), and a reading error
    // where it ends is the cut, not damage.
    let cut = cut_short(&mut file).map_err(|source| ExportError::Read {
        path: mcap.to_owned(),
        source,
    })?;
    let mut reader = LinearReader::new();
    while let Some(event) = reader.next_event() {
        match event {
            Ok(LinearReadEvent::ReadRequest(wanted)) => {
                let read =
                    file.read(reader.insert(wanted))
                        .map_err(|source| ExportError::Read {
                            path: mcap.to_owned(),
                            source,
                        })?;
                reader.notify_read(read);
            }
            Ok(LinearReadEvent::Record { data, opcode }) => {
                let record =
                    mcap::parse_record(opcode, data).map_err(|source| decoder.mcap(source))?;
                decoder.record(record, &mut sinks)?;
            }
            Err(_) if cut => {
                let exported = sinks.finish()?;
                return Err(ExportError::CutShort {
                    path: mcap.to_owned(),
                    exported,
                });
            }
            Err(source) => return Err(decoder.mcap(source)),
        }
    }
    Ok(sinks.finish()?)
}

/// Whether `file` is an MCAP cut short: it starts with the MCAP magic and does not end with
/// it. Reads from its start again after.
fn cut_short(file: &mut File) -> std::io::Result<bool> {
    let mut magic_at = |from: SeekFrom| -> std::io::Result<bool> {
        let mut bytes = [0; 8];
        // A file shorter than the magic has neither.
        Ok(file.seek(from).is_ok() && file.read_exact(&mut bytes).is_ok() && bytes == *mcap::MAGIC)
    };
    let cut = magic_at(SeekFrom::Start(0))? && !magic_at(SeekFrom::End(-8))?;
    file.seek(SeekFrom::Start(0))?;
    Ok(cut)
}

/// The text logs being written.
struct TextSinks {
    candump: Option<(PathBuf, CandumpWriter<BufWriter<File>>)>,
    csv: Option<CsvWriter>,
    exported: Exported,
}

impl TextSinks {
    fn create(targets: &ExportTargets) -> Result<Self, OutputError> {
        let candump = match &targets.candump {
            Some((path, interface)) => {
                let io = |source| OutputError::Io {
                    path: path.clone(),
                    source,
                };
                let file = File::create(path).map_err(io)?;
                let writer = CandumpWriter::new(BufWriter::new(file), interface).map_err(io)?;
                Some((path.clone(), writer))
            }
            None => None,
        };
        let csv = targets.csv.as_deref().map(CsvWriter::create).transpose()?;
        Ok(Self {
            candump,
            csv,
            exported: Exported::default(),
        })
    }

    fn frame(&mut self, logged: &LoggedFrame) -> Result<(), OutputError> {
        if let Some((path, writer)) = &mut self.candump {
            writer.write(logged).map_err(|source| OutputError::Io {
                path: path.clone(),
                source,
            })?;
            self.exported.frames += 1;
        }
        self.exported.last_time_s = self.exported.last_time_s.max(logged.time_s);
        Ok(())
    }

    fn row(&mut self, row: &TelemetryRow) -> Result<(), OutputError> {
        if let Some(csv) = &mut self.csv {
            csv.write(row)?;
            self.exported.rows += 1;
        }
        self.exported.last_time_s = self.exported.last_time_s.max(row.time_s);
        Ok(())
    }

    fn finish(self) -> Result<Exported, OutputError> {
        if let Some((path, writer)) = self.candump {
            writer
                .finish()
                .map_err(|source| OutputError::Io { path, source })?;
        }
        if let Some(csv) = self.csv {
            csv.finish()?;
        }
        Ok(self.exported)
    }
}

/// The file's schemas and channels as they come, and the messages decoded by them.
struct Decoder<'a> {
    path: &'a Path,
    /// Schema id → its message descriptor (protobuf schemas only).
    schemas: Vec<(u16, MessageDescriptor)>,
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

    fn message_error(&self, topic: &str, what: impl Into<String>) -> ExportError {
        ExportError::Message {
            path: self.path.to_owned(),
            topic: topic.to_owned(),
            what: what.into(),
        }
    }

    fn record(&mut self, record: Record<'_>, sinks: &mut TextSinks) -> Result<(), ExportError> {
        match record {
            Record::Schema { header, data } if header.encoding == "protobuf" => {
                let pool = DescriptorPool::decode(data.as_ref())
                    .map_err(|e| self.message_error(&header.name, e.to_string()))?;
                let known = self.schemas.iter().any(|(id, _)| *id == header.id);
                if let Some(descriptor) = pool.get_message_by_name(&header.name).filter(|_| !known)
                {
                    self.schemas.push((header.id, descriptor));
                }
            }
            Record::Channel(channel) => {
                let topic = [CAN, TELEMETRY]
                    .into_iter()
                    .find(|topic| *topic == channel.topic);
                let schema = self.schemas.iter().find(|(id, _)| *id == channel.schema_id);
                let known = self.channels.iter().any(|(id, ..)| *id == channel.id);
                if let (Some(topic), Some((_, descriptor)), false) = (topic, schema, known) {
                    self.channels.push((channel.id, topic, descriptor.clone()));
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
                    .map_err(|e| self.message_error(topic, e.to_string()))?;
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
                    .ok_or_else(|| self.message_error(CAN, "a frame is not a message"))?;
                let id = fields.u32(frame, "id")?;
                let data = fields.bytes(frame, "data")?;
                let frame_of = u16::try_from(id)
                    .ok()
                    .and_then(|id| Frame::new(id, &data))
                    .ok_or_else(|| {
                        self.message_error(CAN, format!("frame {id:#x} is not a CAN frame"))
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
        let mode = fields.string(message, "mode")?;
        let mode = match mode.as_str() {
            "" => None,
            label => Some(
                ControllerMode::ALL
                    .iter()
                    .copied()
                    .find(|m| m.label() == label)
                    .ok_or_else(|| {
                        self.message_error(TELEMETRY, format!("unknown mode `{label}`"))
                    })?,
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
    fn value(&self, message: &DynamicMessage, name: &str) -> Result<Value, ExportError> {
        let descriptor = message.descriptor();
        let field = descriptor.get_field_by_name(name).ok_or_else(|| {
            self.decoder
                .message_error(self.topic, format!("no field `{name}`"))
        })?;
        Ok(message.get_field(&field).into_owned())
    }

    fn wrong(&self, name: &str) -> ExportError {
        self.decoder
            .message_error(self.topic, format!("field `{name}` has another type"))
    }

    fn f64(&self, message: &DynamicMessage, name: &str) -> Result<f64, ExportError> {
        self.value(message, name)?
            .as_f64()
            .ok_or_else(|| self.wrong(name))
    }

    fn u32(&self, message: &DynamicMessage, name: &str) -> Result<u32, ExportError> {
        self.value(message, name)?
            .as_u32()
            .ok_or_else(|| self.wrong(name))
    }

    fn bool(&self, message: &DynamicMessage, name: &str) -> Result<bool, ExportError> {
        self.value(message, name)?
            .as_bool()
            .ok_or_else(|| self.wrong(name))
    }

    fn string(&self, message: &DynamicMessage, name: &str) -> Result<String, ExportError> {
        self.value(message, name)?
            .as_str()
            .map(str::to_owned)
            .ok_or_else(|| self.wrong(name))
    }

    fn bytes(&self, message: &DynamicMessage, name: &str) -> Result<Vec<u8>, ExportError> {
        self.value(message, name)?
            .as_bytes()
            .map(|b| b.to_vec())
            .ok_or_else(|| self.wrong(name))
    }

    fn list(&self, message: &DynamicMessage, name: &str) -> Result<Vec<Value>, ExportError> {
        self.value(message, name)?
            .as_list()
            .map(<[Value]>::to_vec)
            .ok_or_else(|| self.wrong(name))
    }

    /// A repeated double of exactly `N` values.
    fn array<const N: usize>(
        &self,
        message: &DynamicMessage,
        name: &str,
    ) -> Result<[f64; N], ExportError> {
        let values = self.list(message, name)?;
        let mut array = [0.0; N];
        if values.len() != N {
            return Err(self.decoder.message_error(
                self.topic,
                format!("field `{name}` has {} values, not {N}", values.len()),
            ));
        }
        for (slot, value) in array.iter_mut().zip(&values) {
            *slot = value.as_f64().ok_or_else(|| self.wrong(name))?;
        }
        Ok(array)
    }
}
