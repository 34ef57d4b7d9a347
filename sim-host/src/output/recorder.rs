//! Collects what a run leaves behind: every frame on the bus for the candump log, every
//! telemetry row for the CSV file (and kept in bounded memory for the plots drawn at the end),
//! and the robot's state for the Foxglove MCAP. The files are written off the simulation's
//! thread by the [`log_writer`](crate::output::log_writer), started on the first record.
//!
//! The logs are on disk as the run goes: flushed at least every quarter second (wall clock), so
//! a run that is killed outright leaves them readable up to within a second of the kill; a run
//! that fails or is stopped completes them as it ends.

use std::path::Path;

use protocol::Frame;

use crate::output::decimated::Decimated;
use crate::output::foxglove::{FoxgloveLog, RobotSample};
use crate::output::log_writer::{LogWriter, Record, Sinks};
use crate::output::output_error::OutputError;
use crate::output::telemetry::TelemetryRow;
use crate::session::simulator::Simulator;

pub use crate::output::log_writer::FLUSH_EVERY;

/// The recorder of one run.
#[derive(Debug, Default)]
pub struct Recorder {
    rows: Decimated<TelemetryRow>,
    /// The files, until the first record starts their writer.
    sinks: Option<Sinks>,
    writer: Option<LogWriter>,
    frames: u64,
    discard_rows: bool,
    /// Whether a Foxglove log wants the robot's state every cycle.
    sampling: bool,
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

    /// A recorder that streams every frame to `log` in candump format, labelled with
    /// `interface` (so that `canplayer` can replay it there), and every row to the CSV file
    /// `csv`.
    pub fn with_files(log: &Path, csv: &Path, interface: &str) -> Result<Self, OutputError> {
        let mut recorder = Self::with_candump(log, interface)?;
        recorder.sinks_mut().open_csv(csv)?;
        Ok(recorder)
    }

    /// A recorder that also writes every frame to `path` in candump format, labelled with
    /// `interface` (so that `canplayer` can replay it there).
    pub fn with_candump(path: &Path, interface: &str) -> Result<Self, OutputError> {
        let mut recorder = Self::default();
        recorder.sinks_mut().open_candump(path, interface)?;
        Ok(recorder)
    }

    fn sinks_mut(&mut self) -> &mut Sinks {
        self.sinks.get_or_insert_with(Sinks::default)
    }

    /// Also logs to `foxglove` (an MCAP file, a live server). Before the first record only.
    pub fn set_foxglove(&mut self, foxglove: FoxgloveLog) {
        self.sinks_mut().foxglove = Some(foxglove);
        self.sampling = true;
    }

    /// The Foxglove log, to add a channel to, before the first record.
    pub fn foxglove_mut(&mut self) -> Option<&mut FoxgloveLog> {
        self.sinks
            .as_mut()
            .and_then(|sinks| sinks.foxglove.as_mut())
    }

    /// The writer of the files, started on the first record (`None` without files).
    fn writer(&mut self) -> Result<Option<&mut LogWriter>, OutputError> {
        if let Some(sinks) = self.sinks.take().filter(|sinks| !sinks.is_empty()) {
            self.writer = Some(LogWriter::start(sinks)?);
        }
        Ok(self.writer.as_mut())
    }

    /// Logs one frame seen on the bus at `time_s`.
    pub fn frame(&mut self, time_s: f64, frame: &Frame) -> Result<(), OutputError> {
        self.frames += 1;
        if let Some(writer) = self.writer()? {
            writer.push(Record::Frame {
                time_s,
                frame: *frame,
            })?;
        }
        Ok(())
    }

    /// Records the simulator's present step: its telemetry row and, with a Foxglove log, the
    /// robot's state.
    pub fn cycle(&mut self, sim: &Simulator) -> Result<(), OutputError> {
        let sample = self.sampling.then(|| RobotSample::of(sim));
        self.record_row(sim.telemetry(), sample)
    }

    /// Keeps one telemetry row in bounded memory, for the plots (and writes it to the CSV file).
    pub fn row(&mut self, row: TelemetryRow) -> Result<(), OutputError> {
        self.record_row(row, None)
    }

    fn record_row(
        &mut self,
        row: TelemetryRow,
        sample: Option<RobotSample>,
    ) -> Result<(), OutputError> {
        if let Some(writer) = self.writer()? {
            writer.push(Record::Cycle {
                row: row.clone(),
                sample,
            })?;
            writer.tick()?;
        }
        if !self.discard_rows {
            self.rows.push(row);
        }
        Ok(())
    }

    /// The rows kept so far (every one for 4.4 simulated minutes at 250 Hz, then fewer: see
    /// [`Decimated`]).
    pub fn rows(&self) -> &[TelemetryRow] {
        self.rows.kept()
    }

    /// Frames logged so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Completes the logs and returns the rows.
    pub fn finish(self) -> Result<Vec<TelemetryRow>, OutputError> {
        if let Some(writer) = self.writer {
            writer.finish()?;
        }
        if let Some(sinks) = self.sinks {
            sinks.finish()?;
        }
        Ok(self.rows.into_vec())
    }
}
