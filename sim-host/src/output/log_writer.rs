//! The run's log files written off the simulation's thread: the recorder hands its records over
//! in batches (at most every [`HANDOFF_EVERY`] or [`BATCH`] records, never a hand-off per
//! cycle), and a writer thread formats and writes them — the candump log, the telemetry CSV and
//! the Foxglove MCAP — and flushes them every [`FLUSH_EVERY`]. Memory stays bounded: at most
//! [`BATCHES`] batches are in flight, and the simulation waits for the writer rather than
//! queueing without end. Emptied batches come back to be filled again.
//!
//! A run killed outright leaves the files readable up to within a hand-off and a flush of the
//! kill (under half a second); a writer that fails (a full disk) stops the run at its next
//! hand-off with the error naming the file.

use std::fs::File;
use std::io::BufWriter;
use std::path::PathBuf;
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, SyncSender};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use host_can::candump::{CandumpWriter, LoggedFrame};
use protocol::Frame;

use crate::output::foxglove::{FoxgloveLog, RobotSample};
use crate::output::output_error::OutputError;
use crate::output::telemetry::TelemetryRow;
use crate::output::telemetry_csv::CsvWriter;

/// Longest the logs stay in memory buffers before they are flushed to disk.
pub const FLUSH_EVERY: Duration = Duration::from_millis(250);

/// Longest the recorder keeps records before it hands them to the writer.
pub const HANDOFF_EVERY: Duration = Duration::from_millis(50);

/// Records a batch holds before it is handed over (about 20 control cycles of frames).
pub const BATCH: usize = 256;

/// Batches in flight at most.
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

    fn record(&mut self, record: &Record) -> Result<(), OutputError> {
        match record {
            Record::Frame { time_s, frame } => {
                if let Some(foxglove) = &mut self.foxglove {
                    foxglove.frame(*time_s, frame);
                }
                if let Some((path, writer)) = &mut self.candump {
                    let logged = LoggedFrame {
                        time_s: *time_s,
                        frame: *frame,
                    };
                    writer.write(&logged).map_err(|source| OutputError::Io {
                        path: path.clone(),
                        source,
                    })?;
                }
            }
            Record::Cycle { row, sample } => {
                if let (Some(foxglove), Some(sample)) = (&mut self.foxglove, sample) {
                    foxglove.cycle(sample);
                }
                if let Some(csv) = &mut self.csv {
                    csv.write(row)?;
                }
            }
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
    to_writer: Option<SyncSender<Vec<Record>>>,
    spares: Receiver<Vec<Record>>,
    thread: Option<JoinHandle<Result<(), OutputError>>>,
    batch: Vec<Record>,
    since: Instant,
}

impl LogWriter {
    /// Starts the writer thread on `sinks`.
    pub fn start(sinks: Sinks) -> Result<Self, OutputError> {
        let (to_writer, from_sim) = mpsc::sync_channel(BATCHES);
        let (to_sim, spares) = mpsc::channel();
        let thread = std::thread::Builder::new()
            .name("log-writer".into())
            .spawn(move || write_all(sinks, &from_sim, &to_sim))
            .map_err(|source| OutputError::Io {
                path: PathBuf::from("<log writer thread>"),
                source,
            })?;
        Ok(Self {
            to_writer: Some(to_writer),
            spares,
            thread: Some(thread),
            batch: Vec::with_capacity(BATCH),
            since: Instant::now(),
        })
    }

    /// Adds `record`; hands the batch over when it is full or old enough.
    pub fn push(&mut self, record: Record) -> Result<(), OutputError> {
        self.batch.push(record);
        if self.batch.len() >= BATCH || self.since.elapsed() >= HANDOFF_EVERY {
            self.hand_off()?;
        }
        Ok(())
    }

    fn hand_off(&mut self) -> Result<(), OutputError> {
        self.since = Instant::now();
        if self.batch.is_empty() {
            return Ok(());
        }
        let next = self
            .spares
            .try_recv()
            .unwrap_or_else(|_| Vec::with_capacity(BATCH));
        let full = std::mem::replace(&mut self.batch, next);
        let sent = self.to_writer.as_ref().map(|tx| tx.send(full));
        if matches!(sent, Some(Err(_))) {
            // The writer stopped: its error says why.
            return self.join();
        }
        Ok(())
    }

    /// Hands over the rest, waits for the writer to complete every file, and reports its
    /// error if it had one.
    pub fn finish(mut self) -> Result<(), OutputError> {
        self.hand_off()?;
        self.join()
    }

    fn join(&mut self) -> Result<(), OutputError> {
        drop(self.to_writer.take());
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

/// The writer thread: every batch into the files, a flush every [`FLUSH_EVERY`], the files
/// completed when the recorder hangs up.
fn write_all(
    mut sinks: Sinks,
    batches: &Receiver<Vec<Record>>,
    spares: &mpsc::Sender<Vec<Record>>,
) -> Result<(), OutputError> {
    let mut flushed = Instant::now();
    loop {
        match batches.recv_timeout(FLUSH_EVERY) {
            Ok(mut batch) => {
                for record in &batch {
                    sinks.record(record)?;
                }
                batch.clear();
                // The recorder may be gone at the end: the batch is then simply dropped.
                let _ = spares.send(batch);
            }
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => return sinks.finish(),
        }
        if flushed.elapsed() >= FLUSH_EVERY {
            sinks.flush()?;
            flushed = Instant::now();
        }
    }
}
