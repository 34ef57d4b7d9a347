//! Why an export stops, and what is wrong with a message it cannot read.

use std::path::PathBuf;

use super::Exported;
use crate::output::output_error::OutputError;

/// Why an export stopped.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The MCAP could not be opened or read.
    #[error("cannot read {path}: {source} (check the path and that it is readable)")]
    Read {
        /// The MCAP.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The file does not start as an MCAP does. Nothing was written.
    #[error("{path} is not an MCAP (it does not start with the MCAP magic): give a sim-host run's run.mcap")]
    NotMcap {
        /// The file.
        path: PathBuf,
    },
    /// The file ends mid-record: a run cut short. What came before was exported.
    #[error("{path} ends early, after {:.3} s of the run (a killed run?): the text logs hold everything up to there ({} frames, {} rows)", exported.last_time_s, exported.frames, exported.rows)]
    CutShort {
        /// The MCAP.
        path: PathBuf,
        /// What was exported.
        exported: Exported,
    },
    /// A whole MCAP that does not read: damaged inside.
    #[error("{path} is damaged: {source} (the text logs stop where it is)")]
    Mcap {
        /// The file.
        path: PathBuf,
        /// What the reader said.
        source: mcap::McapError,
    },
    /// A message of an exported topic is not what this export reads.
    #[error("{path}: {topic}: {fault} (written by an incompatible sim-host? run the simulation again with this one)")]
    Message {
        /// The file.
        path: PathBuf,
        /// The topic.
        topic: &'static str,
        /// What is wrong with it.
        fault: MessageFault,
    },
    /// A text log was asked for whose topic the file does not have.
    #[error("{path} has no {topic} channel with a protobuf schema (written by a sim-host before the export step?): run the simulation again with this sim-host")]
    MissingTopic {
        /// The file.
        path: PathBuf,
        /// The topic.
        topic: &'static str,
    },
    /// A text log could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// What is wrong with an exported topic's schema or message.
#[derive(Debug, thiserror::Error)]
pub enum MessageFault {
    /// The schema in the file does not decode.
    #[error("its schema does not decode: {0}")]
    Schema(#[source] prost_reflect::DescriptorError),
    /// The schema does not define the message its name says.
    #[error("its schema has no message `{0}`")]
    MissingMessage(String),
    /// A message does not decode by its schema.
    #[error("a message does not decode: {0}")]
    Decode(#[source] prost_reflect::prost::DecodeError),
    /// The schema lacks a field the text log needs.
    #[error("no field `{0}`")]
    MissingField(&'static str),
    /// A field has another type than the text log needs.
    #[error("field `{0}` has another type")]
    WrongType(&'static str),
    /// A repeated field has another length.
    #[error("field `{field}` has {found} values, not {expected}")]
    WrongLength {
        /// The field.
        field: &'static str,
        /// Its values.
        found: usize,
        /// What the row has.
        expected: usize,
    },
    /// A mode the protocol does not name.
    #[error("unknown controller mode `{0}`")]
    UnknownMode(String),
    /// An identifier or data length no CAN frame has.
    #[error("frame {id:#x} with {bytes} data bytes is not a CAN frame of this protocol")]
    NotCanFrame {
        /// The identifier.
        id: u32,
        /// The data length.
        bytes: usize,
    },
}
