//! Collects what a run leaves behind: telemetry rows in memory (written as CSV and plots at the
//! end) and every frame on the bus, streamed to a candump log.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use protocol::Frame;

use crate::output::output_error::OutputError;
use crate::output::telemetry::TelemetryRow;
use host_can::candump::{CandumpWriter, LoggedFrame};

/// The recorder of one run.
#[derive(Debug, Default)]
pub struct Recorder {
    rows: Vec<TelemetryRow>,
    candump: Option<(PathBuf, CandumpWriter<BufWriter<File>>)>,
    frames: u64,
    discard_rows: bool,
}

impl Recorder {
    /// A recorder that keeps telemetry only.
    pub fn in_memory() -> Self {
        Self::default()
    }

    /// A recorder that keeps nothing but counts (benchmarks, very long runs).
    pub fn discarding() -> Self {
        Self {
            discard_rows: true,
            ..Self::default()
        }
    }

    /// A recorder that also writes every frame to `path` in candump format, labelled with
    /// `interface` (so that `canplayer` can replay it there).
    pub fn with_candump(path: &Path, interface: &str) -> Result<Self, OutputError> {
        let file = File::create(path).map_err(|source| OutputError::Io {
            path: path.to_owned(),
            source,
        })?;
        let writer = CandumpWriter::new(BufWriter::new(file), interface).map_err(|source| {
            OutputError::Io {
                path: path.to_owned(),
                source,
            }
        })?;
        Ok(Self {
            candump: Some((path.to_owned(), writer)),
            ..Self::default()
        })
    }

    /// Logs one frame seen on the bus at `time_s`.
    pub fn frame(&mut self, time_s: f64, frame: &Frame) -> Result<(), OutputError> {
        self.frames += 1;
        if let Some((path, writer)) = &mut self.candump {
            writer
                .write(&LoggedFrame {
                    time_s,
                    frame: *frame,
                })
                .map_err(|source| OutputError::Io {
                    path: path.clone(),
                    source,
                })?;
        }
        Ok(())
    }

    /// Keeps one telemetry row.
    pub fn row(&mut self, row: TelemetryRow) {
        if !self.discard_rows {
            self.rows.push(row);
        }
    }

    /// The rows so far.
    pub fn rows(&self) -> &[TelemetryRow] {
        &self.rows
    }

    /// Frames logged so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Flushes the candump log and returns the rows.
    pub fn finish(self) -> Result<Vec<TelemetryRow>, OutputError> {
        if let Some((path, writer)) = self.candump {
            writer
                .finish()
                .map_err(|source| OutputError::Io { path, source })?;
        }
        Ok(self.rows)
    }
}
