//! `--bus inproc`: the simulator and the firmware's control core in this process, on an
//! in-process CAN bus that teleop joins like any other node. The simulator runs on its own
//! thread on the wall clock (or in lockstep); teleop still only talks to it in CAN frames.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

use host_can::inproc_bus::InprocEndpoint;
use sim_host::output::telemetry::TelemetryRow;
use sim_host::robot::plant::Plant;
use sim_host::session::{
    self, Attach, BusChoice, Clock, SessionConfig, SessionError, SessionReport,
};

use crate::app::SimView;

/// How to run the in-process robot.
#[derive(Debug, Clone)]
pub struct InprocOptions {
    /// The MJCF model.
    pub model: PathBuf,
    /// Where to write telemetry, the candump log and plots (`None`: nothing is kept).
    pub out_dir: Option<PathBuf>,
    /// Real time (interactive) or lockstep.
    pub clock: Clock,
    /// Longest run, simulated s.
    pub duration_s: f64,
    /// Serve the simulated robot live to Foxglove on this WebSocket port of 127.0.0.1 (`None`:
    /// no server).
    pub foxglove_port: Option<u16>,
}

impl InprocOptions {
    /// The report's robot on flat ground in real time, for up to a day.
    pub fn wall_clock() -> Self {
        Self {
            model: PathBuf::from(sim_host::robot::model::DEFAULT_MODEL),
            out_dir: None,
            clock: Clock::Wall,
            duration_s: 86_400.0,
            foxglove_port: None,
        }
    }
}

/// The simulated robot and its firmware, running.
#[derive(Debug)]
pub struct InprocRobot {
    live: Arc<Mutex<Option<TelemetryRow>>>,
    stop: Arc<AtomicBool>,
    thread: JoinHandle<Result<SessionReport, SessionError>>,
}

impl InprocRobot {
    /// Starts the simulator and the firmware; returns them and teleop's node on their bus,
    /// which hears everything from the start.
    pub fn start(options: InprocOptions) -> (Self, InprocEndpoint) {
        let attach = Attach::default();
        let endpoint = attach.bus.endpoint();
        let live = Arc::clone(&attach.live);
        let stop = Arc::new(AtomicBool::new(false));
        let config = SessionConfig {
            model: options.model,
            scene: sim_host::scene::Scene::Flat,
            bus: BusChoice::Inproc,
            clock: options.clock,
            duration_s: options.duration_s,
            control_hz: 250,
            reply_timeout: Duration::from_millis(500),
            max_speed: None,
            plant: Plant::default(),
            teleop_plan: Vec::new(),
            plots: options.out_dir.is_some(),
            text_logs: true,
            out_dir: options.out_dir,
            progress: false,
            stop: Some(Arc::clone(&stop)),
            segments: Vec::new(),
            frames: None,
            viewer: false,
            live_port: options.foxglove_port,
            attach: Some(attach),
            faults: Default::default(),
        };
        let thread = std::thread::spawn(move || session::run(&config));
        (Self { live, stop, thread }, endpoint)
    }

    /// The latest ground truth (`None` before the first cycles).
    pub fn view(&self) -> Option<SimView> {
        let live = self
            .live
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        live.as_ref().map(view_of)
    }

    /// Whether the simulation thread has ended (its run is over, or it failed).
    pub fn finished(&self) -> bool {
        self.thread.is_finished()
    }

    /// Ends the run and returns its report (outputs written, if an output folder was given).
    pub fn finish(self) -> Result<SessionReport, SessionError> {
        self.stop.store(true, Ordering::Relaxed);
        self.thread
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
    }
}

/// The operator's view of one telemetry row.
pub fn view_of(row: &TelemetryRow) -> SimView {
    let [roll_deg, pitch_deg, yaw_deg] = row.torso_rpy_deg;
    let tilt = (roll_deg.to_radians().cos() * pitch_deg.to_radians().cos())
        .clamp(-1.0, 1.0)
        .acos();
    SimView {
        time_s: row.time_s,
        position_m: [row.torso_pos_m[0], row.torso_pos_m[1]],
        yaw_deg,
        height_m: row.torso_pos_m[2],
        tilt_deg: tilt.to_degrees(),
    }
}
