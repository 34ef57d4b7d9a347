//! One complete simulator run as a user starts it: build the simulator, attach it to a bus
//! (with the firmware in-process on the in-process bus), run it in lockstep or real time, and
//! leave the telemetry CSV, the candump log and the plots in an output folder.

use std::cell::Cell;
use std::path::PathBuf;
use std::rc::Rc;
use std::sync::atomic::Ordering;
use std::time::Duration;

use host_can::bus::Bus;
use host_can::faulty_bus::{FaultStats, FaultyBus};
use indicatif::{ProgressBar, ProgressStyle};
use teleop_core::scripted::ScriptedTeleop;

use crate::clock::lockstep::{self, LockstepOptions};
use crate::clock::wall::{self, WallOptions};
use crate::output::foxglove::{FoxgloveLog, FoxgloveOutputs};
use crate::output::metrics::{BusCounters, SegmentSummary};
use crate::output::output_error::OutputError;
use crate::output::recorder::Recorder;
use crate::output::telemetry::TelemetryRow;
use crate::session::config::{BusChoice, Clock, SessionConfig};
use crate::session::error::SessionError;
use crate::session::inproc_controller::InprocController;
use crate::session::nodes::{FirmwareCounters, Nodes, Peers};
use crate::session::resident::Resident;
use crate::session::run_stats::{RunError, RunStats};
use crate::session::segments::Segments;
use crate::session::simulator::{Simulator, StartPose};
use crate::session::watch::Watch;

/// What a session leaves behind.
#[derive(Debug)]
pub struct SessionReport {
    /// Run counters.
    pub stats: RunStats,
    /// Every recorded cycle.
    pub rows: Vec<TelemetryRow>,
    /// Files written.
    pub files: Vec<PathBuf>,
    /// Frames the in-process firmware rejected (`None` over SocketCAN).
    pub firmware_rejected: Option<u64>,
    /// Frames the emulated drives rejected.
    pub drives_rejected: u64,
    /// Commands the emulated drives clamped to their ratings.
    pub drives_clamped: u64,
    /// Rendered frames, in order (empty without [`SessionConfig::frames`]).
    pub frames: Vec<PathBuf>,
    /// Whether [`SessionConfig::stop`] ended the run early.
    pub interrupted: bool,
    /// Figures per segment.
    pub segments: Vec<SegmentSummary>,
    /// The process's resident memory, each simulated minute.
    pub resident: Resident,
    /// What [`SessionConfig::faults`] did: to the frames the simulator sent, and to those it
    /// received.
    pub fault_stats: [FaultStats; 2],
}

/// Runs one session.
pub fn run(config: &SessionConfig) -> Result<SessionReport, SessionError> {
    let mut sim = Simulator::new(
        &config.model,
        config.control_hz,
        StartPose::standing(),
        config.plant,
    )?;
    let cycles = (config.duration_s * f64::from(config.control_hz))
        .round()
        .max(0.0) as u64;
    let mut files = Vec::new();
    let mut recorder = open_recorder(config, &mut files)?;
    open_foxglove(config, &sim, &mut recorder, &mut files)?;
    let counters: FirmwareCounters = Rc::new(Cell::new(Default::default()));
    let camera = config
        .frames
        .as_ref()
        .and(recorder.foxglove_mut())
        .map(|log| log.camera());
    let watch = Watch::open(config, &sim, camera)?;
    let mut observer = Observer {
        config,
        segments: Segments::new(&config.segments, config.scene.features()),
        progress: progress_bar(config.progress, cycles),
        watch,
        watch_error: None,
        interrupted: false,
        counters: Rc::clone(&counters),
        resident: Resident::default(),
    };
    let mut nodes = Nodes::join(config)?;
    let mut peers = Peers {
        teleop_bus: nodes.teleop.take(),
        teleop: ScriptedTeleop::new(config.teleop_plan.clone()),
        controller: nodes.controller.take(),
        period_us: 1_000_000 / u64::from(config.control_hz.max(1)),
        counters,
    };
    let mut sim_bus = FaultyBus::new(nodes.sim, &config.plant.link_faults(&config.faults));
    let stats = drive(
        &mut sim,
        &mut sim_bus,
        &mut recorder,
        config,
        cycles,
        |cycle| peers.cycle(cycle),
        |s, stats| observer.observe(s, stats),
    )?;
    let fault_stats = [sim_bus.tx_stats(), sim_bus.rx_stats()];
    let firmware_rejected = peers.controller.as_ref().map(InprocController::rejected);
    observer.progress.finish_and_clear();
    let segments = observer.segments.finish();
    if let Some(e) = observer.watch_error {
        return Err(e);
    }
    let frames = observer.watch.finish()?;
    if let Some(settings) = config.frames.as_ref().filter(|_| !frames.is_empty()) {
        files.push(settings.animation_path());
    }
    let drives_rejected = sim.hardware().rejected();
    let drives_clamped = sim.hardware().clamped();
    let rows = recorder.finish()?;
    write_outputs(config, &rows, &mut files)?;
    Ok(SessionReport {
        stats,
        rows,
        files,
        firmware_rejected,
        drives_rejected,
        drives_clamped,
        frames,
        interrupted: observer.interrupted,
        segments,
        fault_stats,
        resident: observer.resident,
    })
}

/// The recorder `config` asks for: the candump log in the output folder (created here), or
/// rows in memory only — or none at all for an attached session without outputs, which may run
/// for hours.
fn open_recorder(
    config: &SessionConfig,
    files: &mut Vec<PathBuf>,
) -> Result<Recorder, SessionError> {
    let interface = match &config.bus {
        BusChoice::Inproc => "vcan0",
        BusChoice::SocketCan(ifname) => ifname.as_str(),
    };
    Ok(match &config.out_dir {
        Some(dir) => {
            std::fs::create_dir_all(dir).map_err(|source| OutputError::Io {
                path: dir.clone(),
                source,
            })?;
            if !config.text_logs {
                // The MCAP, opened next, holds the bus and the telemetry.
                return Ok(Recorder::in_memory());
            }
            let (log, csv) = (dir.join("bus.log"), dir.join("telemetry.csv"));
            files.push(log.clone());
            files.push(csv.clone());
            Recorder::with_files(&log, &csv, interface)?
        }
        None if config.attach.is_some() => Recorder::discarding(),
        None => Recorder::in_memory(),
    })
}

/// The Foxglove outputs `config` asks for: `run.mcap` and `robot.urdf` in the output folder,
/// and the live server.
fn open_foxglove(
    config: &SessionConfig,
    sim: &Simulator,
    recorder: &mut Recorder,
    files: &mut Vec<PathBuf>,
) -> Result<(), SessionError> {
    let outputs = FoxgloveOutputs {
        mcap: config.out_dir.as_ref().map(|dir| dir.join("run.mcap")),
        live_port: config.live_port,
    };
    let Some(log) = FoxgloveLog::open(sim, &outputs)? else {
        return Ok(());
    };
    if let Some(dir) = &config.out_dir {
        let urdf = dir.join("robot.urdf");
        std::fs::write(&urdf, log.urdf()).map_err(|source| OutputError::Io {
            path: urdf.clone(),
            source,
        })?;
        files.extend(outputs.mcap);
        files.push(urdf);
    }
    if let Some(port) = log.live_port() {
        tracing::info!(
            port,
            "Foxglove: open ws://127.0.0.1:{port} in the Foxglove app"
        );
    }
    recorder.set_foxglove(log);
    Ok(())
}

/// The plots, after the run (the logs were written as it went).
fn write_outputs(
    config: &SessionConfig,
    rows: &[TelemetryRow],
    files: &mut Vec<PathBuf>,
) -> Result<(), SessionError> {
    if let Some(dir) = &config.out_dir {
        if config.plots {
            files.extend(crate::output::plots::write_plots(dir, rows)?);
        }
    }
    Ok(())
}

/// What looks at the simulator after every cycle: the segments, the progress bar, an attached
/// node's live view, the stop flag and the frames or viewer.
struct Observer<'a> {
    config: &'a SessionConfig,
    segments: Segments,
    progress: ProgressBar,
    watch: Watch,
    watch_error: Option<SessionError>,
    interrupted: bool,
    counters: FirmwareCounters,
    resident: Resident,
}

impl Observer<'_> {
    /// One cycle; `false` ends the run (stop requested, viewer closed, a watch failed).
    fn observe(&mut self, s: &Simulator, stats: &RunStats) -> bool {
        let (firmware_rejected, firmware_lost) = self.counters.get();
        let counters = BusCounters {
            frames_sent: stats.frames_sent,
            frames_received: stats.frames_received,
            firmware_rejected,
            firmware_lost,
            drives_rejected: s.hardware().rejected(),
            missed_cycles: stats.missed_cycles,
        };
        self.segments.observe(s, counters);
        self.resident
            .cycle(s.cycle(), self.config.control_hz, s.time_s());
        if u64::from(s.cycle()) % 25 == 0 {
            self.progress.set_position(u64::from(s.cycle()));
        }
        if let Some(attach) = &self.config.attach {
            if s.cycle() % 10 == 0 {
                let mut live = attach
                    .live
                    .lock()
                    .unwrap_or_else(|poisoned| poisoned.into_inner());
                *live = Some(s.telemetry());
            }
        }
        if self
            .config
            .stop
            .as_ref()
            .is_some_and(|stop| stop.load(Ordering::Relaxed))
        {
            self.interrupted = true;
            return false;
        }
        self.watch.cycle(s).unwrap_or_else(|e| {
            self.watch_error = Some(e);
            false
        })
    }
}

fn drive(
    sim: &mut Simulator,
    bus: &mut dyn Bus,
    recorder: &mut Recorder,
    config: &SessionConfig,
    cycles: u64,
    peers: impl FnMut(u32) -> Result<(), RunError>,
    observe: impl FnMut(&Simulator, &RunStats) -> bool,
) -> Result<RunStats, RunError> {
    match config.clock {
        Clock::Lockstep => lockstep::run(
            sim,
            bus,
            recorder,
            LockstepOptions {
                cycles,
                reply_timeout: config.reply_timeout,
                max_speed: config.max_speed,
            },
            peers,
            observe,
        ),
        Clock::Wall => wall::run(
            sim,
            bus,
            recorder,
            WallOptions {
                cycles,
                period: Duration::from_secs_f64(1.0 / f64::from(config.control_hz.max(1))),
            },
            peers,
            observe,
        ),
    }
}

fn progress_bar(show: bool, cycles: u64) -> ProgressBar {
    if !show {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(cycles);
    if let Ok(style) = ProgressStyle::with_template(
        "{spinner} simulating [{bar:30}] {percent:>3}% {elapsed} ({eta} left)",
    ) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}
