//! One complete simulator run as a user starts it: build the simulator, attach it to a bus
//! (with the firmware in-process on the in-process bus), run it in lockstep or real time, and
//! leave the telemetry CSV, the candump log and the plots in an output folder.

use std::cell::Cell;
use std::num::NonZeroU32;
use std::path::PathBuf;
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};

use crate::imu::ImuNoise;
use crate::inproc_controller::InprocController;
use crate::lockstep::{self, LockstepOptions};
use crate::metrics::{BusCounters, SegmentSummary, SegmentTracker};
use crate::model::ModelError;
use crate::output_error::OutputError;
use crate::realtime::{self, RealtimeOptions};
use crate::recorder::Recorder;
use crate::run_stats::{RunError, RunStats};
use crate::simulator::{Simulator, StartPose};
use crate::telemetry::TelemetryRow;
use host_can::bus::{Bus, BusError};
use host_can::fault_plan::Faults;
use host_can::faulty_bus::{FaultStats, FaultyBus};
use host_can::inproc_bus::InprocBus;
use host_can::socketcan_bus::SocketCanBus;
use teleop_core::scripted::{PlanStep, ScriptedTeleop};

/// Which bus the simulator joins.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BusChoice {
    /// In-process, with the firmware's control core on it.
    Inproc,
    /// A SocketCAN interface; the controller is another process.
    SocketCan(String),
}

/// Which clock drives the run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Clock {
    /// The simulator is the clock (SYNC frames); as fast as possible.
    Lockstep,
    /// The wall clock at the control rate.
    Realtime,
}

/// Frames to render during a run (feature `renderer`): the model's `chase` camera, offscreen.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FrameSettings {
    /// Folder for `frame_00000.png`, `frame_00001.png`, …; created if missing.
    pub dir: PathBuf,
    /// One frame at the start and one every this many control cycles.
    pub every_cycles: NonZeroU32,
}

/// Everything a run needs.
#[derive(Debug, Clone)]
pub struct SessionConfig {
    /// The MJCF file.
    pub model: PathBuf,
    /// Bus.
    pub bus: BusChoice,
    /// Clock.
    pub clock: Clock,
    /// Simulated time to run, s.
    pub duration_s: f64,
    /// Control rate, Hz.
    pub control_hz: u32,
    /// Lockstep: how long to wait for the controller each cycle.
    pub reply_timeout: Duration,
    /// Lockstep: at most this many times real time (`None`: as fast as possible).
    pub max_speed: Option<f64>,
    /// IMU noise.
    pub imu_noise: ImuNoise,
    /// Operator commands to send (empty: no teleop node on the bus).
    pub teleop_plan: Vec<PlanStep>,
    /// Where to write outputs (`None`: keep telemetry in memory only).
    pub out_dir: Option<PathBuf>,
    /// Whether to draw the PNG plots.
    pub plots: bool,
    /// Show a progress bar.
    pub progress: bool,
    /// Set (by a Ctrl-C handler, say) to end the run early; the outputs are still written.
    pub stop: Option<Arc<AtomicBool>>,
    /// Segments to summarise, in time order (empty: the whole run is one segment).
    pub segments: Vec<SegmentSpec>,
    /// Frames to render (`None`: none). Without the `renderer` feature, `Some` is an error.
    pub frames: Option<FrameSettings>,
    /// Open the MuJoCo viewer, synced every cycle, and keep it open after the run until it is
    /// closed (closing it early ends the run). Without the `viewer` feature, `true` is an error.
    pub viewer: bool,
    /// Someone outside the session on the in-process bus (the interactive teleop), or `None`.
    pub attach: Option<Attach>,
    /// Faults on the simulator's bus connection: `tx` breaks the feedback it sends, `rx` the
    /// commands it receives (see [`host_can::fault_plan`]).
    pub faults: Faults,
}

/// An outside node's link to an in-process session: the session joins `bus` instead of making
/// its own, and publishes its latest telemetry row (ground truth) in `live` every 10 cycles.
/// Without an output folder the session then keeps no rows, so it can run for hours.
#[derive(Debug, Clone, Default)]
pub struct Attach {
    /// The bus the outside node is on.
    pub bus: InprocBus,
    /// The latest telemetry row, `None` until the first.
    pub live: Arc<Mutex<Option<TelemetryRow>>>,
}

/// Where a segment of the run starts and what it is called.
#[derive(Debug, Clone, PartialEq)]
pub struct SegmentSpec {
    /// Start, s.
    pub start_s: f64,
    /// Name in the summary.
    pub label: String,
    /// Commanded mode (W S A L K X, stand, fold).
    pub mode: String,
}

/// Why a session failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SessionError {
    /// The model.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The bus.
    #[error(transparent)]
    Bus(#[from] BusError),
    /// The run.
    #[error(transparent)]
    Run(#[from] RunError),
    /// An output file.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The control rate is not one the firmware runs at.
    #[error("the firmware cannot run at {0} Hz (it needs 1…10000 Hz)")]
    ControlRate(u32),
    /// The firmware's configuration was rejected.
    #[error("the firmware rejected its configuration: {0:?}")]
    Firmware(firmware::control::controller::ConfigError),
    /// Rendering frames.
    #[cfg(feature = "renderer")]
    #[error(transparent)]
    Render(#[from] crate::render::RenderError),
    /// The viewer.
    #[cfg(feature = "viewer")]
    #[error(transparent)]
    Viewer(#[from] crate::viewer::ViewerError),
    /// The configuration asks for a feature this build leaves out.
    #[error("{what} needs sim-host built with `--features {feature}` (cargo run -p sim-host --features {feature} -- run …)")]
    NotBuilt {
        /// What was asked for.
        what: &'static str,
        /// The cargo feature it needs.
        feature: &'static str,
    },
}

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
    /// Rendered frames, in order (empty without [`SessionConfig::frames`]).
    pub frames: Vec<PathBuf>,
    /// Whether [`SessionConfig::stop`] ended the run early.
    pub interrupted: bool,
    /// Figures per segment.
    pub segments: Vec<SegmentSummary>,
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
        config.imu_noise,
    )?;
    let cycles = (config.duration_s * f64::from(config.control_hz))
        .round()
        .max(0.0) as u64;
    let interface = match &config.bus {
        BusChoice::Inproc => "vcan0".to_owned(),
        BusChoice::SocketCan(ifname) => ifname.clone(),
    };
    let mut files = Vec::new();
    let mut recorder = match &config.out_dir {
        Some(dir) => {
            std::fs::create_dir_all(dir).map_err(|source| OutputError::Io {
                path: dir.clone(),
                source,
            })?;
            let log = dir.join("bus.log");
            files.push(log.clone());
            Recorder::with_candump(&log, &interface)?
        }
        None if config.attach.is_some() => Recorder::discarding(),
        None => Recorder::in_memory(),
    };
    let mut watch = Watch::open(config, &sim)?;
    let mut watch_error = None;
    let progress = progress_bar(config.progress, cycles);
    let mut interrupted = false;
    let firmware_counters = Rc::new(Cell::new((
        [0_u64; protocol::RejectCause::ALL.len()],
        0_u64,
    )));
    let specs: Vec<SegmentSpec> = if config.segments.is_empty() {
        vec![SegmentSpec {
            start_s: 0.0,
            label: "run".into(),
            mode: String::new(),
        }]
    } else {
        config.segments.clone()
    };
    let mut segments: Vec<SegmentSummary> = Vec::new();
    let mut tracker: Option<(usize, SegmentTracker)> = None;
    let counters_in_observe = Rc::clone(&firmware_counters);
    let bus_counters = move |s: &Simulator, stats: &RunStats| {
        let (firmware_rejected, firmware_lost) = counters_in_observe.get();
        BusCounters {
            frames_sent: stats.frames_sent,
            frames_received: stats.frames_received,
            firmware_rejected,
            firmware_lost,
            drives_rejected: s.hardware().rejected(),
            missed_cycles: stats.missed_cycles,
        }
    };
    let mut observe = |s: &Simulator, stats: &RunStats| {
        let counters = bus_counters(s, stats);
        let due = specs
            .iter()
            .rposition(|spec| spec.start_s <= s.time_s() + 1e-9)
            .unwrap_or(0);
        match &mut tracker {
            Some((index, current)) if *index == due => current.observe(s, counters),
            _ => {
                if let Some((_, done)) = tracker.take() {
                    segments.push(done.finish());
                }
                let spec = &specs[due];
                let mut fresh = SegmentTracker::start(&spec.label, &spec.mode, s, counters);
                fresh.observe(s, counters);
                tracker = Some((due, fresh));
            }
        }
        if u64::from(s.cycle()) % 25 == 0 {
            progress.set_position(u64::from(s.cycle()));
        }
        if let Some(attach) = &config.attach {
            if s.cycle() % 10 == 0 {
                let mut live = attach
                    .live
                    .lock()
                    .unwrap_or_else(|poisoned| poisoned.into_inner());
                *live = Some(s.telemetry());
            }
        }
        if config
            .stop
            .as_ref()
            .is_some_and(|stop| stop.load(Ordering::Relaxed))
        {
            interrupted = true;
            return false;
        }
        watch.cycle(s).unwrap_or_else(|e| {
            watch_error = Some(e);
            false
        })
    };
    let mut teleop = ScriptedTeleop::new(config.teleop_plan.clone());
    let has_teleop = !config.teleop_plan.is_empty();
    let period_us = 1_000_000 / u64::from(config.control_hz.max(1));

    // The simulator's bus and the nodes that share its thread: on the in-process bus the
    // firmware and a scripted operator; over SocketCAN only the operator (the firmware is
    // another process).
    let Nodes {
        sim: inner,
        teleop: mut teleop_bus,
        mut controller,
    } = match &config.bus {
        BusChoice::Inproc => {
            let bus = config
                .attach
                .as_ref()
                .map_or_else(InprocBus::new, |a| a.bus.clone());
            let firmware = firmware_config(config.control_hz)
                .ok_or(SessionError::ControlRate(config.control_hz))?;
            let controller =
                InprocController::new(firmware, bus.endpoint()).map_err(SessionError::Firmware)?;
            let teleop: Option<Box<dyn Bus>> = if has_teleop {
                Some(Box::new(bus.transmitter()))
            } else {
                None
            };
            Nodes {
                sim: Box::new(bus.endpoint()),
                teleop,
                controller: Some(controller),
            }
        }
        BusChoice::SocketCan(ifname) => {
            let teleop: Option<Box<dyn Bus>> = if has_teleop {
                Some(Box::new(SocketCanBus::open(ifname)?))
            } else {
                None
            };
            Nodes {
                sim: Box::new(SocketCanBus::open(ifname)?),
                teleop,
                controller: None,
            }
        }
    };
    let mut sim_bus = FaultyBus::new(inner, &config.faults);
    let peers = |cycle: u32| -> Result<(), RunError> {
        if let Some(bus) = &mut teleop_bus {
            for frame in teleop.frames(u64::from(cycle) * period_us)? {
                bus.send(&frame)?;
            }
        }
        if let Some(controller) = &mut controller {
            controller.service()?;
            let counters = controller.node().reject_counters();
            firmware_counters.set((
                counters.rejected.map(|n| u64::from(n.raw())),
                u64::from(counters.lost.raw()),
            ));
        }
        Ok(())
    };
    let stats = drive(
        &mut sim,
        &mut sim_bus,
        &mut recorder,
        config,
        cycles,
        peers,
        &mut observe,
    )?;
    let fault_stats = [sim_bus.tx_stats(), sim_bus.rx_stats()];
    let firmware_rejected = controller.as_ref().map(InprocController::rejected);
    progress.finish_and_clear();
    if let Some((_, done)) = tracker.take() {
        segments.push(done.finish());
    }
    if let Some(e) = watch_error {
        return Err(e);
    }
    let frames = watch.finish()?;
    let drives_rejected = sim.hardware().rejected();
    let rows = recorder.finish()?;
    if let Some(dir) = &config.out_dir {
        let csv = dir.join("telemetry.csv");
        crate::telemetry_csv::write_csv(&csv, &rows)?;
        files.push(csv);
        if config.plots {
            files.extend(crate::plots::write_plots(dir, &rows)?);
        }
    }
    Ok(SessionReport {
        stats,
        rows,
        files,
        firmware_rejected,
        drives_rejected,
        frames,
        interrupted,
        segments,
        fault_stats,
    })
}

/// The simulator's connection to the bus and the nodes that run on its thread.
struct Nodes {
    sim: Box<dyn Bus>,
    /// The scripted operator's connection (send only), if it has a plan.
    teleop: Option<Box<dyn Bus>>,
    /// The firmware, on the in-process bus only.
    controller: Option<InprocController>,
}

/// What watches a run besides the progress bar: frames (feature `renderer`) and the viewer
/// (feature `viewer`).
#[derive(Debug, Default)]
struct Watch {
    #[cfg(feature = "renderer")]
    frames: Option<crate::render::FrameRenderer>,
    #[cfg(feature = "viewer")]
    viewer: Option<crate::viewer::Viewer>,
}

impl Watch {
    /// Opens what `config` asks for and renders the starting frame.
    fn open(config: &SessionConfig, sim: &Simulator) -> Result<Self, SessionError> {
        #[allow(unused_mut)]
        let mut watch = Self::default();
        if let Some(frames) = &config.frames {
            #[cfg(feature = "renderer")]
            {
                let options = crate::render::FrameOptions::chase(&frames.dir, frames.every_cycles);
                let mut renderer =
                    crate::render::FrameRenderer::new(sim.physics().model(), options)?;
                renderer.render(sim.physics())?;
                watch.frames = Some(renderer);
            }
            #[cfg(not(feature = "renderer"))]
            {
                let _ = frames;
                return Err(SessionError::NotBuilt {
                    what: "rendering frames",
                    feature: "renderer",
                });
            }
        }
        if config.viewer {
            #[cfg(feature = "viewer")]
            {
                watch.viewer = Some(crate::viewer::Viewer::open(sim.physics().model())?);
            }
            #[cfg(not(feature = "viewer"))]
            return Err(SessionError::NotBuilt {
                what: "the viewer",
                feature: "viewer",
            });
        }
        let _ = sim;
        Ok(watch)
    }

    /// After a cycle: renders a frame if one is due, syncs the viewer. `false`: the viewer was
    /// closed, end the run.
    fn cycle(&mut self, sim: &Simulator) -> Result<bool, SessionError> {
        #[cfg(feature = "renderer")]
        if let Some(frames) = &mut self.frames {
            frames.observe(sim)?;
        }
        #[cfg(feature = "viewer")]
        if let Some(viewer) = &mut self.viewer {
            return Ok(viewer.observe(sim)?);
        }
        let _ = sim;
        Ok(true)
    }

    /// After the run: keeps the viewer open until it is closed; returns the frames written.
    fn finish(self) -> Result<Vec<PathBuf>, SessionError> {
        #[cfg(feature = "viewer")]
        if let Some(mut viewer) = self.viewer {
            if viewer.running() {
                tracing::info!("run finished: close the viewer window to exit");
            }
            viewer.hold()?;
        }
        #[cfg(feature = "renderer")]
        if let Some(frames) = self.frames {
            return Ok(frames.into_frames());
        }
        Ok(Vec::new())
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
        Clock::Realtime => realtime::run(
            sim,
            bus,
            recorder,
            RealtimeOptions {
                cycles,
                period: Duration::from_secs_f64(1.0 / f64::from(config.control_hz.max(1))),
            },
            peers,
            observe,
        ),
    }
}

/// The firmware's robot configuration at `control_hz`, `None` for a rate it cannot run.
pub fn firmware_config(control_hz: u32) -> Option<firmware::config::Config> {
    firmware::time::TickRate::new(control_hz)
        .map(|rate| firmware::config::Config::ROBOT.at_rate(rate))
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
