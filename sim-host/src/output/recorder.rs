//! Collects what a run leaves behind: every frame on the bus streamed to a candump log, every
//! telemetry row streamed to a CSV file and kept in memory for the plots drawn at the end.
//!
//! The logs are on disk as the run goes: both files are flushed at least once a second (wall
//! clock), so a run that is killed outright leaves them readable up to within a second of the
//! kill; a run that fails or is stopped flushes them as it ends (dropping the writers flushes
//! too).

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use protocol::Frame;

use crate::output::decimated::Decimated;
use crate::output::foxglove::FoxgloveLog;
use crate::output::output_error::OutputError;
use crate::output::telemetry::TelemetryRow;
use crate::output::telemetry_csv::CsvWriter;
use crate::session::simulator::Simulator;
use host_can::candump::{CandumpWriter, LoggedFrame};

/// Longest the logs stay in memory buffers before they are flushed to disk.
pub const FLUSH_EVERY: Duration = Duration::from_millis(250);

/// The recorder of one run.
#[derive(Debug, Default)]
pub struct Recorder {
    rows: Decimated<TelemetryRow>,
    candump: Option<(PathBuf, CandumpWriter<BufWriter<File>>)>,
    csv: Option<CsvWriter>,
    last_flush: Option<Instant>,
    frames: u64,
    discard_rows: bool,
    foxglove: Option<FoxgloveLog>,
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
        recorder.csv = Some(CsvWriter::create(csv)?);
        Ok(recorder)
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
            last_flush: Some(Instant::now()),
            ..Self::default()
        })
    }

    /// Also logs to `foxglove` (an MCAP file, a live server).
    pub fn set_foxglove(&mut self, foxglove: FoxgloveLog) {
        self.last_flush.get_or_insert_with(Instant::now);
        self.foxglove = Some(foxglove);
    }

    /// The Foxglove log, if there is one.
    pub fn foxglove(&self) -> Option<&FoxgloveLog> {
        self.foxglove.as_ref()
    }

    /// The Foxglove log, to add a channel to.
    pub fn foxglove_mut(&mut self) -> Option<&mut FoxgloveLog> {
        self.foxglove.as_mut()
    }

    /// Logs one frame seen on the bus at `time_s`.
    pub fn frame(&mut self, time_s: f64, frame: &Frame) -> Result<(), OutputError> {
        self.frames += 1;
        if let Some(foxglove) = &mut self.foxglove {
            foxglove.frame(time_s, frame);
        }
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

    /// Records the simulator's present step: its telemetry row ([`Recorder::row`]) and, with a
    /// Foxglove log, the robot's transforms and joints.
    pub fn cycle(&mut self, sim: &Simulator) -> Result<(), OutputError> {
        if let Some(foxglove) = &mut self.foxglove {
            foxglove.cycle(sim);
        }
        self.row(sim.telemetry())
    }

    /// Keeps one telemetry row in bounded memory, for the plots (and writes it to the CSV file);
    /// once a second, flushes the logs to disk.
    pub fn row(&mut self, row: TelemetryRow) -> Result<(), OutputError> {
        if let Some(csv) = &mut self.csv {
            csv.write(&row)?;
        }
        if !self.discard_rows {
            self.rows.push(row);
        }
        if self
            .last_flush
            .is_some_and(|at| at.elapsed() >= FLUSH_EVERY)
        {
            self.flush()?;
        }
        Ok(())
    }

    /// Puts everything logged so far on disk.
    pub fn flush(&mut self) -> Result<(), OutputError> {
        if let Some(csv) = &mut self.csv {
            csv.flush()?;
        }
        if let Some((path, writer)) = &mut self.candump {
            writer.flush().map_err(|source| OutputError::Io {
                path: path.clone(),
                source,
            })?;
        }
        if let Some(foxglove) = &mut self.foxglove {
            foxglove.flush()?;
        }
        self.last_flush = Some(Instant::now());
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

    /// Flushes the logs and returns the rows.
    pub fn finish(self) -> Result<Vec<TelemetryRow>, OutputError> {
        if let Some(csv) = self.csv {
            csv.finish()?;
        }
        if let Some((path, writer)) = self.candump {
            writer
                .finish()
                .map_err(|source| OutputError::Io { path, source })?;
        }
        if let Some(foxglove) = self.foxglove {
            foxglove.finish()?;
        }
        Ok(self.rows.into_vec())
    }
}
