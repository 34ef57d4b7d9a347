//! `sim-host`: the hybrid wheel–leg robot in MuJoCo, playing its leg drives, wheel drive and IMU
//! on a CAN bus.

use std::num::NonZeroU32;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use clap::{Parser, Subcommand, ValueEnum};
use host_can::fault_plan::Faults;
use protocol::TeleopMode;
use sim_host::output::summary::{self, Summary};
use sim_host::robot::imu::ImuNoise;
use sim_host::robot::model::{DEFAULT_MODEL, OBSTACLES_MODEL};
use sim_host::session::{self, BusChoice, Clock, FrameSettings, SegmentSpec, SessionConfig};
use teleop_core::scenario::{mode_name, Scenario};
use teleop_core::scripted::PlanStep;

/// The hybrid wheel–leg robot in MuJoCo, on a CAN bus.
///
/// The simulator plays the robot's hardware: four leg drives (position servos), a wheel drive
/// (torque) and a torso IMU, each a CAN node with the project's frames, E2E checks and a 100 ms
/// command timeout. On the in-process bus the firmware's control core runs beside it; on a
/// SocketCAN interface the controller is another process.
#[derive(Debug, Parser)]
#[command(version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run the simulation.
    ///
    /// Example: sim-host run --duration 10 --drive 0:stand --drive 2:W --out out/sim
    Run(Box<RunArgs>),
    /// Run the fault matrix: the closed loop (in-process, lockstep) under lost, late,
    /// duplicated, reordered, corrupted and replayed frames, a teleop flood, silent feedback, a
    /// killed firmware, a restarted simulator and E-stops; each cell judged. Prints a Markdown
    /// table; exits 1 if a cell fails.
    ///
    /// Example: sim-host faults
    Faults {
        /// The MJCF model.
        #[arg(long, default_value = DEFAULT_MODEL)]
        model: PathBuf,
    },
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum Mode {
    /// The simulator sends SYNC each cycle, waits for the controller, then steps:
    /// deterministic, faster than real time.
    Lockstep,
    /// Steps on the wall clock at the control rate; reports real-time factor and overruns.
    Realtime,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum Scene {
    /// Flat ground.
    Flat,
    /// A 6 cm step at 1.5 m and a 10° ramp from 3 m.
    Obstacles,
}

#[derive(Debug, clap::Args)]
struct RunArgs {
    /// `inproc` (the firmware runs in this process) or a SocketCAN interface such as `vcan0`.
    #[arg(long, default_value = "inproc")]
    bus: String,
    /// Clock.
    #[arg(long, value_enum, default_value = "lockstep")]
    mode: Mode,
    /// Simulated seconds to run (default 10, or the scenario's `duration_s`).
    #[arg(long)]
    duration: Option<f64>,
    /// A scenario file (`scenarios/*.toml`: times and commands); writes `summary.json` with
    /// figures per segment and prints them as a table. Replaces `--drive`.
    #[arg(long, conflicts_with = "drive")]
    scenario: Option<PathBuf>,
    /// Folder for telemetry.csv, bus.log (candump format) and the PNG plots.
    #[arg(long, default_value = "out/sim")]
    out: PathBuf,
    /// Which shipped scene to load.
    #[arg(long, value_enum, default_value = "flat")]
    scene: Scene,
    /// An MJCF file instead of a shipped scene.
    #[arg(long)]
    model: Option<PathBuf>,
    /// Operator command at a time, `SECONDS:MODE` with MODE one of the report's keys W S A L K X
    /// or `stand` / `fold`; repeat for a sequence. Without it no teleop node is on the bus and
    /// the controller holds the robot where it stands.
    #[arg(long = "drive", value_parser = parse_step)]
    drive: Vec<PlanStep>,
    /// Control rate, Hz (the model's timestep must divide the period).
    #[arg(long, default_value_t = 250)]
    control_hz: u32,
    /// Lockstep: run at most this many times real time (1 = real time), still deterministic —
    /// for watching, and for outside tools such as cansend and canplayer.
    #[arg(long)]
    pace: Option<f64>,
    /// Lockstep: how long to wait for the controller's command each cycle, ms.
    #[arg(long, default_value_t = 100)]
    reply_timeout_ms: u64,
    /// IMU gyro white noise, standard deviation, rad/s.
    #[arg(long, default_value_t = 0.0)]
    gyro_noise: f64,
    /// IMU gyro bias on every axis, rad/s.
    #[arg(long, default_value_t = 0.0)]
    gyro_bias: f64,
    /// IMU accelerometer white noise, standard deviation, m/s².
    #[arg(long, default_value_t = 0.0)]
    accel_noise: f64,
    /// Seed of the IMU noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Skip the PNG plots.
    #[arg(long)]
    no_plots: bool,
    /// No progress bar (for logs and scripts).
    #[arg(long)]
    no_progress: bool,
    /// Open the interactive MuJoCo viewer, synced every control cycle; it stays open after the
    /// run until closed, and closing it early ends the run. Needs a display; best with
    /// `--mode realtime` (lockstep plays faster than real time). Build with `--features viewer`.
    #[arg(long)]
    viewer: bool,
    /// Render the model's `chase` camera to <out>/frames/frame_00000.png, … at the start and
    /// every N control cycles (25 at 250 Hz: 10 frames per simulated second). Headless, through
    /// EGL (Mesa: libegl1 libegl-mesa0 libgl1-mesa-dri). Build with `--features renderer`.
    #[arg(long, value_name = "N")]
    render_every: Option<NonZeroU32>,
    /// Break the simulator's bus connection on purpose: `tx.*` faults hit the feedback it
    /// sends, `rx.*` the commands it receives. Comma-separated, e.g.
    /// `tx.drop=0.05,rx.delay=3,tx.flip=0.01,seed=7`; faults: drop, delay, duplicate, reorder,
    /// flip, replay (probabilities 0…1, delay in control cycles), silence=NODE (`feedback`,
    /// `Imu`, `LegDrive_FL`, …). SYNC is never faulted.
    #[arg(long, value_name = "PLAN", default_value = "")]
    faults: Faults,
}

fn parse_step(text: &str) -> Result<PlanStep, String> {
    let (time, mode) = text
        .split_once(':')
        .ok_or_else(|| format!("`{text}`: expected SECONDS:MODE, e.g. 2:W"))?;
    let seconds: f64 = time
        .trim()
        .parse()
        .map_err(|_| format!("`{time}` is not a number of seconds"))?;
    if !(0.0..=1e6).contains(&seconds) {
        return Err(format!("`{time}`: time must be 0…1e6 s"));
    }
    let mode = match mode.trim().to_ascii_lowercase().as_str() {
        "stand" => TeleopMode::Stand,
        "fold" => TeleopMode::Fold,
        key if key.chars().count() == 1 => key
            .chars()
            .next()
            .and_then(TeleopMode::from_key)
            .ok_or_else(|| format!("`{mode}`: use W S A L K X, stand or fold"))?,
        _ => return Err(format!("`{mode}`: use W S A L K X, stand or fold")),
    };
    Ok(PlanStep {
        at_us: (seconds * 1e6).round() as u64,
        mode,
        body_height_m: 0.0,
        speed_scale_pct: 100.0,
    })
}

fn main() -> ExitCode {
    host_can::logging::init("info");
    let cli = Cli::parse();
    match cli.command {
        Command::Faults { model } => faults(&model),
        Command::Run(args) => match run(*args) {
            Ok(()) => ExitCode::SUCCESS,
            Err(message) => {
                eprintln!("sim-host: {message}");
                ExitCode::FAILURE
            }
        },
    }
}

/// A flag that Ctrl-C sets, so that an interrupted run still writes its outputs. If the handler
/// cannot be installed, Ctrl-C keeps its default effect (the process ends) and the run says so.
fn faults(model: &std::path::Path) -> ExitCode {
    eprintln!("running the fault matrix (about a minute in release)…");
    match sim_host::faults::matrix::run(model) {
        Ok(cells) => {
            print!("{}", sim_host::faults::matrix::markdown(&cells));
            let failed = cells.iter().filter(|c| !c.pass).count();
            if failed == 0 {
                ExitCode::SUCCESS
            } else {
                eprintln!("sim-host: {failed} of {} cells failed", cells.len());
                ExitCode::FAILURE
            }
        }
        Err(e) => {
            eprintln!("sim-host: {e}");
            ExitCode::FAILURE
        }
    }
}

fn stop_on_ctrl_c() -> Arc<AtomicBool> {
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    if let Err(e) = ctrlc::set_handler(move || flag.store(true, Ordering::Relaxed)) {
        tracing::warn!("Ctrl-C will end the run without writing its outputs: {e}");
    }
    stop
}

fn run(args: RunArgs) -> Result<(), String> {
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
    let scenario = match &args.scenario {
        Some(path) => Some(Scenario::load(path).map_err(|e| e.to_string())?),
        None => None,
    };
    let duration = args
        .duration
        .or(scenario.as_ref().map(|s| s.duration_s))
        .unwrap_or(10.0);
    if !(duration.is_finite() && duration > 0.0) {
        return Err(format!(
            "--duration {duration} must be a positive number of seconds"
        ));
    }
    let (teleop_plan, segments) = match &scenario {
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
    let model = args.model.unwrap_or_else(|| {
        PathBuf::from(match args.scene {
            Scene::Flat => DEFAULT_MODEL,
            Scene::Obstacles => OBSTACLES_MODEL,
        })
    });
    let bus = match args.bus.as_str() {
        "inproc" => BusChoice::Inproc,
        ifname => BusChoice::SocketCan(ifname.to_owned()),
    };
    let config = SessionConfig {
        model,
        bus,
        clock: match args.mode {
            Mode::Lockstep => Clock::Lockstep,
            Mode::Realtime => Clock::Realtime,
        },
        duration_s: duration,
        control_hz: args.control_hz,
        reply_timeout: Duration::from_millis(args.reply_timeout_ms),
        max_speed: args.pace,
        imu_noise: ImuNoise {
            gyro_std_rad_s: args.gyro_noise,
            gyro_bias_rad_s: [args.gyro_bias; 3],
            accel_std_m_s2: args.accel_noise,
            seed: args.seed,
            ..ImuNoise::default()
        },
        teleop_plan,
        attach: None,
        faults: args.faults.clone(),
        out_dir: Some(args.out.clone()),
        plots: !args.no_plots,
        progress: !args.no_progress,
        frames: args.render_every.map(|every_cycles| FrameSettings {
            dir: args.out.join("frames"),
            every_cycles,
        }),
        viewer: args.viewer,
        stop: Some(stop_on_ctrl_c()),
        segments,
    };
    tracing::info!(model = %config.model.display(), bus = %args.bus, "starting");
    let report = session::run(&config).map_err(|e| e.to_string())?;
    let s = report.stats;
    if report.interrupted {
        println!("interrupted      (Ctrl-C) — outputs cover the simulated part");
    }
    let last = report.rows.last();
    println!(
        "simulated        {:.2} s in {:.2} s wall ({:.1}x real time)",
        s.sim_s,
        s.wall_s,
        s.real_time_factor()
    );
    println!(
        "cycles           {} ({} missed, {} overruns)",
        s.cycles, s.missed_cycles, s.overruns
    );
    println!(
        "frames           {} sent, {} received",
        s.frames_sent, s.frames_received
    );
    println!(
        "rejected         {} by the drives{}",
        report.drives_rejected,
        report
            .firmware_rejected
            .map(|n| format!(", {n} by the firmware"))
            .unwrap_or_default()
    );
    if !args.faults.tx.is_clean() || !args.faults.rx.is_clean() {
        let [tx, rx] = report.fault_stats;
        println!("faults           {}", args.faults);
        println!("  on feedback    {tx:?}");
        println!("  on commands    {rx:?}");
    }
    if let Some(row) = last {
        println!(
            "torso at end     x {:.3} m, y {:.3} m, z {:.3} m, roll {:.1}°, pitch {:.1}°, yaw {:.1}°",
            row.torso_pos_m[0],
            row.torso_pos_m[1],
            row.torso_pos_m[2],
            row.torso_rpy_deg[0],
            row.torso_rpy_deg[1],
            row.torso_rpy_deg[2]
        );
    }
    if let Some(s) = &scenario {
        let path = args.out.join("summary.json");
        let clock = match args.mode {
            Mode::Lockstep => "lockstep",
            Mode::Realtime => "realtime",
        };
        Summary::from_stats(&s.name, &args.bus, clock, &report.stats, &report.segments)
            .write(&path)
            .map_err(|e| e.to_string())?;
        println!("\n{}", summary::table(&report.segments));
        println!("wrote            {}", path.display());
    }
    if let Some(first) = report.frames.first() {
        println!(
            "rendered         {} frames from {}",
            report.frames.len(),
            first.display()
        );
    }
    for file in &report.files {
        println!("wrote            {}", file.display());
    }
    Ok(())
}
