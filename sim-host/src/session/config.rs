//! What a session is asked to do: the bus, the clock, the run's length and rate, the operator's
//! plan, outputs, segments, and faults on the simulator's own connection.

use std::num::NonZeroU32;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use host_can::fault_plan::Faults;
use host_can::inproc_bus::InprocBus;
use teleop_core::scripted::PlanStep;

use crate::output::telemetry::TelemetryRow;
use crate::robot::plant::Plant;
use crate::scene::Scene;

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
    Wall,
}

/// Frames to render during a run (feature `renderer`): the model's `chase` camera, offscreen.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FrameSettings {
    /// Folder for `frame_00000.png`, `frame_00001.png`, …; created if missing.
    pub dir: PathBuf,
    /// One frame at the start and one every this many control cycles.
    pub every_cycles: NonZeroU32,
}

impl FrameSettings {
    /// The run's animation: `run.gif` beside the frames' folder.
    pub fn animation_path(&self) -> PathBuf {
        self.dir
            .parent()
            .map_or_else(|| PathBuf::from("run.gif"), |dir| dir.join("run.gif"))
    }
}

/// Everything a run needs.
#[derive(Debug, Clone)]
pub struct SessionConfig {
    /// The MJCF file.
    pub model: PathBuf,
    /// The scene the model was made for (its obstacles, for the summary's crossings; flat
    /// for a model with none made).
    pub scene: Scene,
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
    pub plant: Plant,
    /// Operator commands to send (empty: no teleop node on the bus).
    pub teleop_plan: Vec<PlanStep>,
    /// Where to write outputs (`None`: keep telemetry in memory only).
    pub out_dir: Option<PathBuf>,
    /// Whether to draw the PNG plots.
    pub plots: bool,
    /// With an output folder: write bus.log and telemetry.csv as the run goes. Without them,
    /// `run.mcap` alone holds the bus and the telemetry, and `sim-host export` makes the text
    /// logs from it.
    pub text_logs: bool,
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
    /// Serve the run live to Foxglove on this WebSocket port of 127.0.0.1 (`None`: no server; 0:
    /// any free port, logged). The output folder gets `run.mcap` with the same topics.
    pub live_port: Option<u16>,
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

/// The firmware's robot configuration at `control_hz`, `None` for a rate it cannot run.
pub fn firmware_config(control_hz: u32) -> Option<firmware::config::Config> {
    firmware::time::TickRate::new(control_hz)
        .map(|rate| firmware::config::Config::ROBOT.at_rate(rate))
}
