//! `sim-host run`: its flags, and the session they describe.

use std::num::NonZeroU32;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use clap::ValueEnum;
use host_can::fault_plan::Faults;
use sim_host::robot::imu::{ImuModel, ImuNoise};
use sim_host::robot::imu_chip::ChipSpec;
use sim_host::robot::model::{DEFAULT_MODEL, OBSTACLES_MODEL};
use sim_host::robot::plant::{DriveRatings, Plant};
use sim_host::robot::rangefinder::{RangeModel, RangeSpec};
use sim_host::robot::sensing::DriveSensing;
use sim_host::robot::variation::Variation;
use sim_host::scene::{Scene, SceneError};
use sim_host::session::{self, BusChoice, Clock, FrameSettings, SegmentSpec, SessionConfig};
use teleop_core::scenario::{mode_name, Scenario, ScenarioError};
use teleop_core::scripted::PlanStep;

/// What paces a run; the same names as `firmware-host --clock`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum ClockArg {
    /// The simulator sends SYNC each cycle, waits for the controller, then steps:
    /// deterministic, faster than real time.
    Lockstep,
    /// Steps on the wall clock at the control rate; reports real-time factor and overruns.
    #[value(alias = "realtime")]
    Wall,
}

/// What the emulated IMU measures with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum ImuArg {
    /// A Bosch BMI088: noise, turn-on bias and drift, range, resolution, sample rate, filter
    /// delay.
    Chip,
    /// A perfect chip: the true rate and specific force (for debugging).
    Ideal,
}

/// What the emulated rangefinder measures with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum RangeArg {
    /// An ST VL53L1X: 1.3 m, 20 ms rangings over its field of view, offset and noise, 1 mm.
    Part,
    /// The centre ray's exact length (for debugging).
    Ideal,
}

/// What the emulated drives can deliver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum DrivesArg {
    /// Real parts' ratings: peak, torque-speed line, thermal foldback.
    Rated,
    /// No torque limit on the legs, a flat 30 N·m on the wheels (for debugging).
    Ideal,
}

/// How the emulated drives measure their joints.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum SensingArg {
    /// Named parts: counted encoders, velocity from counts, effort with gain error.
    Real,
    /// MuJoCo's exact joint state (for debugging).
    Ideal,
}

impl ClockArg {
    /// The name in `summary.json`.
    pub(crate) fn name(self) -> &'static str {
        match self {
            ClockArg::Lockstep => "lockstep",
            ClockArg::Wall => "wall",
        }
    }
}

/// The ground: the shipped obstacle file, or a scene made from parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum SceneArg {
    /// `models/obstacles.xml`: a 6 cm step at 1.5 m and a 10° ramp from 3 m.
    Obstacles,
    /// A scene of `sim_host::scene`.
    Made(Scene),
}

/// `--scene`: `obstacles`, or `KIND[:KEY=VALUE,…]` of [`Scene::from_arg`].
fn parse_scene(text: &str) -> Result<SceneArg, String> {
    if text.trim() == "obstacles" {
        return Ok(SceneArg::Obstacles);
    }
    if text.trim().starts_with("obstacles:") {
        return Err("`obstacles` is a fixed file and takes no keys: use `step`, `ramp` or `course` with keys".into());
    }
    Scene::from_arg(text)
        .map(SceneArg::Made)
        .map_err(|e| match e {
            SceneError::UnknownKind { .. } => format!("{e}, or obstacles (the shipped file)"),
            other => other.to_string(),
        })
}

#[derive(Debug, clap::Args)]
pub(crate) struct RunArgs {
    /// `inproc` (the firmware runs in this process) or a SocketCAN interface such as `vcan0`.
    #[arg(long, default_value = "inproc")]
    pub(crate) bus: String,
    /// What paces the run (`--mode` and `realtime` are the old names, kept for one release).
    #[arg(long, value_enum, default_value = "lockstep", alias = "mode")]
    pub(crate) clock: ClockArg,
    /// Simulated seconds to run (default 10, or the scenario's `duration_s`; `--duration` is the
    /// old name).
    #[arg(long = "duration-s", alias = "duration", value_parser = parse_duration_s)]
    pub(crate) duration_s: Option<f64>,
    /// A scenario file (`scenarios/*.toml`: times and commands); writes `summary.json` with
    /// figures per segment and prints them as a table. Replaces `--drive`.
    #[arg(long, conflicts_with = "drive")]
    pub(crate) scenario: Option<PathBuf>,
    /// Folder for telemetry.csv, bus.log (candump format) and the PNG plots.
    #[arg(long, default_value = "out/sim")]
    pub(crate) out: PathBuf,
    /// The ground: `flat`, `step`, `flight`, `ramp` or `course`, each with its keys
    /// (`step:height_m=0.08,riser_x_m=1.5`; docs/simulator.md lists them), or `obstacles` (the
    /// shipped obstacles.xml). Overrides a scenario's `[scene]`; the scene's MJCF is written
    /// to `--out` as scene.xml. Default: the scenario's scene, else flat.
    #[arg(long, value_parser = parse_scene)]
    pub(crate) scene: Option<SceneArg>,
    /// The robot's MJCF (a scene is built around it) instead of the shipped model.
    #[arg(long)]
    pub(crate) model: Option<PathBuf>,
    /// Operator command at a time, `SECONDS:MODE[,speed=M_S][,yaw=RAD_S]` with MODE one of the
    /// report's keys W S A L K X, `stand`, `fold`, or `drive` / `walk` (at `speed`); `yaw`
    /// steers W S L K drive walk (+ left); repeat for a sequence, e.g. `--drive 0:fold --drive
    /// 4:drive,speed=0.3,yaw=0.3`. Without it no teleop node is on the bus and
    /// the controller holds the robot where it stands.
    #[arg(long = "drive", value_parser = teleop_core::scenario::parse_drive_step)]
    pub(crate) drive: Vec<PlanStep>,
    /// Control rate, Hz (the model's timestep must divide the period).
    #[arg(long, default_value_t = 250)]
    pub(crate) control_hz: u32,
    /// Lockstep: run at most this many times real time (1 = real time, 0.001…1000000), still
    /// deterministic — for watching, and for outside tools such as cansend and canplayer.
    #[arg(long, value_parser = parse_pace)]
    pub(crate) pace: Option<f64>,
    /// Lockstep: how long to wait for the controller's command each cycle, ms.
    #[arg(long, default_value_t = 100)]
    pub(crate) reply_timeout_ms: u64,
    /// Extra IMU gyro white noise on top of the chip's, standard deviation, rad/s
    /// (`--gyro-noise`: the old name).
    #[arg(long, default_value_t = 0.0, alias = "gyro-noise")]
    pub(crate) gyro_noise_rad_s: f64,
    /// Extra IMU gyro bias on every axis, rad/s (`--gyro-bias`: the old name).
    #[arg(long, default_value_t = 0.0, alias = "gyro-bias")]
    pub(crate) gyro_bias_rad_s: f64,
    /// Extra IMU accelerometer white noise, standard deviation, m/s² (`--accel-noise`: the old
    /// name).
    #[arg(long, default_value_t = 0.0, alias = "accel-noise")]
    pub(crate) accel_noise_m_s2: f64,
    /// Seed of the IMU chip's turn-on bias and noise (and of the extra noise above).
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    /// What the IMU measures with: `chip` (a Bosch BMI088 with its data sheet's noise, turn-on
    /// bias and drift, ±1000 °/s and ±6 g at 16 bits, 2 kHz / 1.6 kHz sampling, ~1 ms filter
    /// delay) or `ideal` (the true rate and specific force, for debugging).
    #[arg(long, value_enum, default_value_t = ImuArg::Chip)]
    pub(crate) imu: ImuArg,
    /// What the rangefinder measures with: `part` (an ST VL53L1X in its short distance mode:
    /// 1.3 m, a ranging every 20 ms over its field of view, ±20 mm typical error, whole
    /// millimetres; its offset drawn with `--seed`) or `ideal` (the exact distance, for
    /// debugging).
    #[arg(long, value_enum, default_value_t = RangeArg::Part)]
    pub(crate) rangefinder: RangeArg,
    /// What the drives can deliver: `rated` (a quasi-direct-drive leg actuator, 33.5 N·m peak
    /// with its torque-speed line and thermal foldback; 30 N·m hub motors) or `ideal` (the
    /// report's unlimited leg servos, flat 30 N·m wheels, for debugging).
    #[arg(long, value_enum, default_value_t = DrivesArg::Rated)]
    pub(crate) drives: DrivesArg,
    /// How the drives measure their joints: `real` (14-bit encoders, velocity from count
    /// differences, effort within ±5 % gain error; see docs/simulator.md) or `ideal` (MuJoCo's
    /// exact state, for debugging).
    #[arg(long, value_enum, default_value_t = SensingArg::Real)]
    pub(crate) sensing: SensingArg,
    /// Control cycles every frame between the simulator's nodes and the controller is held
    /// back, each way: the CAN loop's transport delay, on top of what the bus itself takes
    /// (nothing in lockstep). The tests' plant holds 1; the command line defaults to 0 because
    /// over SocketCAN the lockstep clock waits for each cycle's reply, which a held-back reply
    /// turns into a timeout per cycle.
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u32).range(0..=50))]
    pub(crate) delay_cycles: u32,
    /// Skip the PNG plots.
    #[arg(long)]
    pub(crate) no_plots: bool,
    /// Write the bus and the telemetry only into run.mcap, not also as bus.log and
    /// telemetry.csv: `sim-host export` makes those from it afterwards, byte for byte.
    #[arg(long)]
    pub(crate) no_text_logs: bool,
    /// Keep nothing on disk: no logs, no plots, no MCAP. A bare run, to time the loop against
    /// one with every output, or to soak for hours.
    #[arg(long, conflicts_with_all = ["out", "scenario", "scene", "render_every"])]
    pub(crate) no_out: bool,
    /// No progress bar (for logs and scripts).
    #[arg(long)]
    pub(crate) no_progress: bool,
    /// Open the interactive MuJoCo viewer, synced every control cycle; it stays open after the
    /// run until closed, and closing it early ends the run. Needs a display; best with
    /// `--clock wall` (lockstep plays faster than real time). Build with `--features viewer`.
    #[arg(long)]
    pub(crate) viewer: bool,
    /// Serve the run live to the Foxglove app on this WebSocket port of 127.0.0.1 (0: any free
    /// port; the log says which). Best with `--pace 1`. The output folder gets the same topics
    /// in run.mcap either way.
    #[arg(long, value_name = "PORT")]
    pub(crate) foxglove_port: Option<u16>,
    /// Render the model's `chase` camera to <out>/frames/frame_00000.png, … at the start and
    /// every N control cycles (25 at 250 Hz: 10 frames per simulated second). Headless, through
    /// EGL (Mesa: libegl1 libegl-mesa0 libgl1-mesa-dri). Build with `--features renderer`.
    #[arg(long, value_name = "N")]
    pub(crate) render_every: Option<NonZeroU32>,
    /// Break the simulator's bus connection on purpose: `tx.*` faults hit the feedback it
    /// sends, `rx.*` the commands it receives. Comma-separated, e.g.
    /// `tx.drop=0.05,rx.delay=3,tx.flip=0.01,seed=7`; faults: drop, delay, duplicate, reorder,
    /// flip, replay (probabilities 0…1, delay in control cycles), silence=NODE (`feedback`,
    /// `Imu`, `LegDrive_FL`, …). SYNC is never faulted.
    #[arg(long, value_name = "PLAN", default_value = "")]
    pub(crate) faults: Faults,
}

/// A number within `range`, or a message naming the text and the range.
fn number_within(
    text: &str,
    range: std::ops::RangeInclusive<f64>,
    what: &str,
) -> Result<f64, String> {
    text.trim()
        .parse::<f64>()
        .ok()
        .filter(|x| range.contains(x))
        .ok_or_else(|| {
            format!(
                "`{text}`: give {what} from {} to {}",
                range.start(),
                range.end()
            )
        })
}

/// `--pace`: times real time.
fn parse_pace(text: &str) -> Result<f64, String> {
    number_within(text, 0.001..=1e6, "a factor of real time")
}

/// `--duration-s`: simulated seconds, up to 1e6 (11.6 days; a soak run is 86,400).
fn parse_duration_s(text: &str) -> Result<f64, String> {
    number_within(text, f64::MIN_POSITIVE..=1e6, "simulated seconds")
}

/// Runs the session `args` describe and prints what it did.
pub(crate) fn run(args: RunArgs) -> Result<(), String> {
    if args.viewer && !cfg!(feature = "viewer") {
        return Err(
            "this sim-host was built without the viewer: cargo run -p sim-host --features viewer -- run --viewer …"
                .into(),
        );
    }
    if args.render_every.is_some() && !cfg!(feature = "renderer") {
        return Err(
            "this sim-host was built without the renderer: cargo run -p sim-host --features renderer -- run --render-every 25 …"
                .into(),
        );
    }
    // One read of the scenario file: the operator's plan and the simulator's `[scene]`.
    let (scenario, scenario_scene) = match &args.scenario {
        Some(path) => {
            let text = std::fs::read_to_string(path).map_err(|source| {
                ScenarioError::Read {
                    path: path.clone(),
                    source,
                }
                .to_string()
            })?;
            let scenario = Scenario::parse(path, &text).map_err(|e| e.to_string())?;
            // Checked even when --scene replaces it: a bad file is an error.
            let scene = Scene::from_scenario(path, &text).map_err(|e| e.to_string())?;
            (Some(scenario), scene)
        }
        None => (None, None),
    };
    let duration_s = args
        .duration_s
        .or(scenario.as_ref().map(|s| s.duration_s))
        .unwrap_or(10.0);
    if !(duration_s.is_finite() && duration_s > 0.0) {
        return Err(format!(
            "--duration-s {duration_s} must be a positive number of seconds"
        ));
    }
    let model = model_path(&args, scenario_scene)?;
    let mut config = session_config(&args, scenario.as_ref(), duration_s, model);
    config.scene = made_scene(&args, scenario_scene);
    tracing::info!(model = %config.model.display(), bus = %args.bus, "starting");
    let report = session::run(&config).map_err(|e| match e {
        session::SessionError::Bus(bus) if bus.is_missing_interface() => {
            format!("{bus}\n(or run the firmware in this process: `--bus inproc`)")
        }
        other => other.to_string(),
    })?;
    crate::report::print(&args, scenario.as_ref(), &report)
}

/// The MJCF the run loads: `--scene` (or else the scenario's `[scene]`, `from_scenario`)
/// around `--model` (or the shipped robot), written to `--out` as scene.xml; the robot's own
/// file on flat ground.
fn model_path(args: &RunArgs, from_scenario: Option<Scene>) -> Result<PathBuf, String> {
    let robot = args
        .model
        .clone()
        .unwrap_or_else(|| PathBuf::from(DEFAULT_MODEL));
    match args.scene.or(from_scenario.map(SceneArg::Made)) {
        None | Some(SceneArg::Made(Scene::Flat)) => Ok(robot),
        Some(SceneArg::Obstacles) if args.model.is_none() => Ok(PathBuf::from(OBSTACLES_MODEL)),
        Some(SceneArg::Obstacles) => Err(
            "--scene obstacles is the shipped robot's file; with --model give a made scene (step, flight, ramp, course)".into(),
        ),
        Some(SceneArg::Made(scene)) => {
            sim_host::scene::mjcf::write(&scene, &robot, &args.out).map_err(|e| e.to_string())
        }
    }
}

/// The scene made from parameters (`--scene`, else the scenario's), whose obstacles the summary
/// judges crossings against; flat for the shipped obstacles file, whose parts it does not know.
fn made_scene(args: &RunArgs, from_scenario: Option<Scene>) -> Scene {
    match args.scene.or(from_scenario.map(SceneArg::Made)) {
        Some(SceneArg::Made(scene)) => scene,
        None | Some(SceneArg::Obstacles) => Scene::Flat,
    }
}

/// The session `args` (and the scenario, if one was given) describe.
fn session_config(
    args: &RunArgs,
    scenario: Option<&Scenario>,
    duration_s: f64,
    model: PathBuf,
) -> SessionConfig {
    let (teleop_plan, segments) = match scenario {
        Some(s) => (
            s.plan(),
            s.steps
                .iter()
                .map(|step| SegmentSpec {
                    start_s: step.plan.at_us as f64 * 1e-6,
                    label: step.label.clone(),
                    mode: mode_name(step.plan.mode),
                })
                .collect(),
        ),
        None => (args.drive.clone(), Vec::new()),
    };
    let bus = match args.bus.as_str() {
        "inproc" => BusChoice::Inproc,
        ifname => BusChoice::SocketCan(ifname.to_owned()),
    };
    SessionConfig {
        model,
        scene: Scene::Flat,
        bus,
        clock: match args.clock {
            ClockArg::Lockstep => Clock::Lockstep,
            ClockArg::Wall => Clock::Wall,
        },
        duration_s,
        control_hz: args.control_hz,
        reply_timeout: Duration::from_millis(args.reply_timeout_ms),
        max_speed: args.pace,
        plant: Plant {
            imu: match args.imu {
                ImuArg::Chip => ImuModel::Chip(ChipSpec::BMI088),
                ImuArg::Ideal => ImuModel::Ideal,
            },
            imu_noise: ImuNoise {
                gyro_std_rad_s: args.gyro_noise_rad_s,
                gyro_bias_rad_s: [args.gyro_bias_rad_s; 3],
                accel_std_m_s2: args.accel_noise_m_s2,
                seed: args.seed,
                ..ImuNoise::default()
            },
            rangefinder: match args.rangefinder {
                RangeArg::Part => RangeModel::Part {
                    spec: RangeSpec::VL53L1X,
                    seed: args.seed,
                },
                RangeArg::Ideal => RangeModel::Ideal,
            },
            drives: match args.drives {
                DrivesArg::Rated => DriveRatings::RATED,
                DrivesArg::Ideal => DriveRatings::IDEAL,
            },
            sensing: match args.sensing {
                SensingArg::Real => DriveSensing::REAL,
                SensingArg::Ideal => DriveSensing::IDEAL,
            },
            transport_delay_cycles: args.delay_cycles,
            variation: Variation::NOMINAL,
        },
        teleop_plan,
        attach: None,
        faults: args.faults.clone(),
        out_dir: (!args.no_out).then(|| args.out.clone()),
        plots: !args.no_plots,
        text_logs: !args.no_text_logs,
        progress: !args.no_progress,
        frames: args.render_every.map(|every_cycles| FrameSettings {
            dir: args.out.join("frames"),
            every_cycles,
        }),
        viewer: args.viewer,
        live_port: args.foxglove_port,
        stop: Some(stop_on_ctrl_c()),
        segments,
    }
}

/// A flag that Ctrl-C sets, so that an interrupted run still writes its outputs. If the handler
/// cannot be installed, Ctrl-C keeps its default effect (the process ends) and the run says so.
fn stop_on_ctrl_c() -> Arc<AtomicBool> {
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    if let Err(e) = ctrlc::set_handler(move || flag.store(true, Ordering::Relaxed)) {
        tracing::warn!("Ctrl-C will end the run without writing its outputs: {e}");
    }
    stop
}
