//! The run's log files written off the simulation's thread: the recorder hands its records over
//! in batches (at most every [`HANDOFF_EVERY`] or [`BATCH`] records, never a hand-off per
//! cycle), and a writer thread formats and writes them — the candump log, the telemetry CSV and
//! the Foxglove MCAP — and flushes them every [`FLUSH_EVERY`]. Memory stays bounded and is
//! allocated once: [`BATCHES`] batches and the one being filled, which go round
//! ([`crate::output::handoff`]) — the simulation waits for an emptied one rather than making
//! another.
//!
//! A run killed outright leaves the files readable up to within a hand-off and a flush of the
//! kill (under half a second); a writer that fails (a full disk) stops the run at its next
//! hand-off with the error naming the file.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use host_can::candump::{CandumpWriter, LoggedFrame};
use protocol::Frame;

use crate::output::foxglove::{FoxgloveLog, RobotSample};
use crate::output::handoff::{Handoff, Next};
use crate::output::output_error::OutputError;
use crate::output::telemetry::TelemetryRow;
use crate::output::telemetry_csv::CsvWriter;

/// Longest the logs stay in memory buffers before they are flushed to disk.
pub const FLUSH_EVERY: Duration = Duration::from_millis(250);

/// Longest the recorder keeps records before it hands them to the writer.
pub const HANDOFF_EVERY: Duration = Duration::from_millis(50);

/// Records a batch holds before it is handed over (about 20 control cycles of frames).
pub const BATCH: usize = 256;

/// Batches there are besides the one being filled: queued for the writer, being written, or
/// spare.
pub const BATCHES: usize = 4;

/// One thing to log.
// The batches are reused, so a frame's record carrying a row's size costs memory once; boxing
// the row would allocate every cycle.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
pub enum Record {
    /// A frame seen on the bus at `time_s`.
    Frame {
        /// When, s.
        time_s: f64,
        /// The frame.
        frame: Frame,
    },
    /// A control cycle's telemetry, and the robot's state for the Foxglove log.
    Cycle {
        /// The row.
        row: TelemetryRow,
        /// The joints and the torso, with a Foxglove log.
        sample: Option<RobotSample>,
    },
}

/// The files a run writes.
#[derive(Debug, Default)]
pub struct Sinks {
    /// The candump log.
    pub candump: Option<(PathBuf, CandumpWriter<BufWriter<File>>)>,
    /// The telemetry CSV.
    pub csv: Option<CsvWriter>,
    /// The Foxglove MCAP and live server.
    pub foxglove: Option<FoxgloveLog>,
}

impl Sinks {
    /// Whether there is anything to write to.
    pub fn is_empty(&self) -> bool {
        self.candump.is_none() && self.csv.is_none() && self.foxglove.is_none()
    }

    /// Adds the candump log `path` (created or truncated), its lines labelled with
    /// `interface` (so that `canplayer` can replay it there).
    pub fn open_candump(&mut self, path: &Path, interface: &str) -> Result<(), OutputError> {
        let io = |source| OutputError::Io {
            path: path.to_owned(),
            source,
        };
        let file = File::create(path).map_err(io)?;
        let writer = CandumpWriter::new(BufWriter::new(file), interface).map_err(io)?;
        self.candump = Some((path.to_owned(), writer));
        Ok(())
    }

    /// Adds the telemetry CSV `path` (created or truncated).
    pub fn open_csv(&mut self, path: &Path) -> Result<(), OutputError> {
        self.csv = Some(CsvWriter::create(path)?);
        Ok(())
    }

    fn record(&mut self, record: &Record) -> Result<(), OutputError> {
        match record {
            Record::Frame { time_s, frame } => self.frame(*time_s, frame),
            Record::Cycle { row, sample } => self.cycle(row, sample.as_ref()),
        }
    }

    /// Writes a frame seen on the bus at `time_s`.
    pub fn frame(&mut self, time_s: f64, frame: &Frame) -> Result<(), OutputError> {
        if let Some(foxglove) = &mut self.foxglove {
            foxglove.frame(time_s, frame);
        }
        if let Some((path, writer)) = &mut self.candump {
            let logged = LoggedFrame {
                time_s,
                frame: *frame,
            };
            writer.write(&logged).map_err(|source| OutputError::Io {
                path: path.clone(),
                source,
            })?;
        }
        Ok(())
    }

    /// Writes a control cycle's telemetry `row` and, to the Foxglove log, the robot's `sample`.
    pub fn cycle(
        &mut self,
        row: &TelemetryRow,
        sample: Option<&RobotSample>,
    ) -> Result<(), OutputError> {
        if let Some(foxglove) = &mut self.foxglove {
            foxglove.telemetry(row);
            if let Some(sample) = sample {
                foxglove.cycle(sample);
            }
        }
        if let Some(csv) = &mut self.csv {
            csv.write(row)?;
        }
        Ok(())
    }

    fn flush(&mut self) -> Result<(), OutputError> {
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
        Ok(())
    }

    /// Completes every file.
    pub fn finish(self) -> Result<(), OutputError> {
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
        Ok(())
    }
}

/// The writer thread and the batch being filled.
#[derive(Debug)]
pub struct LogWriter {
    handoff: Arc<Handoff<Vec<Record>>>,
    thread: Option<JoinHandle<Result<(), OutputError>>>,
    batch: Vec<Record>,
    since: Instant,
}

impl LogWriter {
    /// Starts the writer thread on `sinks`.
    pub fn start(sinks: Sinks) -> Result<Self, OutputError> {
        // Every batch there will be, made now: the simulation's thread never allocates one.
        let spares = (0..BATCHES).map(|_| Vec::with_capacity(BATCH)).collect();
        let handoff = Arc::new(Handoff::new(spares));
        let writer_side = Arc::clone(&handoff);
        let thread = std::thread::Builder::new()
            .name("log-writer".into())
            .spawn(move || {
                let stopped = Stopped(&writer_side);
                let result = write_all(sinks, stopped.0);
                drop(stopped);
                result
            })
            .map_err(|source| OutputError::Io {
                path: PathBuf::from("<log writer thread>"),
                source,
            })?;
        Ok(Self {
            handoff,
            thread: Some(thread),
            batch: Vec::with_capacity(BATCH),
            since: Instant::now(),
        })
    }

    /// Adds `record`; hands the batch over when it is full.
    pub fn push(&mut self, record: Record) -> Result<(), OutputError> {
        self.batch.push(record);
        if self.batch.len() >= BATCH {
            self.hand_off()?;
        }
        Ok(())
    }

    /// Hands the batch over if it is old enough: once a cycle (a clock read per record would
    /// cost more than the record).
    pub fn tick(&mut self) -> Result<(), OutputError> {
        if self.since.elapsed() >= HANDOFF_EVERY {
            self.hand_off()?;
        }
        Ok(())
    }

    fn hand_off(&mut self) -> Result<(), OutputError> {
        self.since = Instant::now();
        if self.batch.is_empty() || self.thread.is_none() {
            return Ok(());
        }
        // An emptied batch comes back as soon as the writer has written one: waiting for it is
        // the bound on memory.
        let full = std::mem::take(&mut self.batch);
        match self.handoff.exchange(full) {
            Ok(empty) => {
                self.batch = empty;
                Ok(())
            }
            // The writer stopped: its error says why.
            Err(_) => self.join(),
        }
    }

    /// Hands over the rest, waits for the writer to complete every file, and reports its
    /// error if it had one.
    pub fn finish(mut self) -> Result<(), OutputError> {
        self.hand_off()?;
        self.join()
    }

    fn join(&mut self) -> Result<(), OutputError> {
        self.handoff.hang_up();
        match self.thread.take().map(JoinHandle::join) {
            Some(Ok(result)) => result,
            Some(Err(_)) => Err(OutputError::Io {
                path: PathBuf::from("<log writer thread>"),
                source: std::io::Error::other("the log writer panicked"),
            }),
            None => Ok(()),
        }
    }
}

impl Drop for LogWriter {
    /// A run that fails drops its recorder: what was recorded up to the failure still reaches
    /// the files, whole, before the process ends.
    fn drop(&mut self) {
        let _ = self.hand_off();
        let _ = self.join();
    }
}

/// Tells the recorder the writer has stopped, however it stops (a panic included).
struct Stopped<'a>(&'a Handoff<Vec<Record>>);

impl Drop for Stopped<'_> {
    fn drop(&mut self) {
        self.0.writer_stopped();
    }
}

/// The writer thread: every batch into the files, a flush every [`FLUSH_EVERY`], the files
/// completed when the recorder hangs up.
fn write_all(mut sinks: Sinks, handoff: &Handoff<Vec<Record>>) -> Result<(), OutputError> {
    let mut flushed = Instant::now();
    loop {
        match handoff.next(FLUSH_EVERY) {
            Next::Full(mut batch) => {
                for record in &batch {
                    sinks.record(record)?;
                }
                batch.clear();
                handoff.give_back(batch);
            }
            Next::Timeout => {}
            Next::Finished => return sinks.finish(),
        }
        if flushed.elapsed() >= FLUSH_EVERY {
            sinks.flush()?;
            flushed = Instant::now();
        }
    }
}
