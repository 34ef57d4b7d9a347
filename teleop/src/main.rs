//! `teleop`: drive the robot over CAN from a terminal or a script.
// Functions stay short enough to read whole (clippy.toml: 80 lines); tests may run longer.
#![cfg_attr(not(test), warn(clippy::too_many_lines))]

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use clap::{Parser, Subcommand};
use host_can::bus::Bus;
use host_can::socketcan_bus::SocketCanBus;
use teleop::script::{self, ScriptReport};
use teleop_core::keys::{action, Action, Key};
use teleop_core::scenario::{mode_name, Scenario};

/// Drive the hybrid wheel–leg robot over CAN with the report's keys.
///
/// Without a subcommand teleop opens its terminal UI: W/S wheels forward/backward, A rotate,
/// L/K trot forward/backward, X stop, T stand, F fold, H autonomous (drive back first and
/// climb steps), ↑/↓ body height, ]/[ speed, space
/// E-stop (R twice releases it), Q quit. It sends the operator's heartbeat at 50 Hz; when
/// teleop quits or dies the controller stops the robot within 500 ms.
///
/// Examples:
///   teleop --bus inproc                 drive the simulated robot (no CAN needed)
///   teleop --bus vcan0                  drive whatever controller is on vcan0
///   teleop --bus vcan0 send W --for 5   hold W for 5 s (for scripts)
///   teleop --bus vcan0 script scenarios/acceptance/w.toml
///
/// Exit codes: 0 done, 1 the bus or the simulator failed, 2 bad arguments or scenario file,
/// 3 no controller answered on the bus.
#[derive(Debug, Parser)]
#[command(version, about, long_about, verbatim_doc_comment)]
struct Cli {
    /// The bus: a SocketCAN interface (vcan0, can0) or `inproc` (the simulator and the
    /// firmware in this process, on the wall clock).
    #[arg(long, default_value = "vcan0")]
    bus: String,
    /// With `--bus inproc`: the MJCF model (default: the report's robot on flat ground).
    #[arg(long)]
    model: Option<PathBuf>,
    /// With `--bus inproc`: write telemetry.csv, bus.log and plots here when teleop ends.
    #[arg(long)]
    out: Option<PathBuf>,
    /// With `--bus inproc`: serve the simulated robot live to the Foxglove app on this
    /// WebSocket port of 127.0.0.1 (as `sim-host run --foxglove-port`).
    #[arg(long, value_name = "PORT")]
    foxglove_port: Option<u16>,
    /// The bus key: a file holding 32 hexadecimal digits, readable by this account only (as
    /// firmware-host's). Without it, the public test key of simulation and CI.
    #[arg(long, value_name = "PATH")]
    key_file: Option<PathBuf>,
    /// Also drive with a gamepad (sticks: speed and yaw rate; A drive, right shoulder walk, X
    /// or Y stop, B E-stop, Start twice release, left shoulder stand, Select fold, D-pad
    /// height): the first one found, or the evdev device named (/dev/input/eventN). `teleop
    /// pad` uses it without a screen.
    #[arg(long, value_name = "DEVICE", num_args = 0..=1, default_missing_value = "auto")]
    gamepad: Option<String>,
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Send one key and keep the operator's heartbeat going for a while.
    Send {
        /// W S A L K X (the report's keys), T (stand), F (fold), or `space` for the E-stop.
        #[arg(value_parser = parse_key)]
        key: Action,
        /// Seconds to keep sending the command and heartbeat.
        #[arg(long = "for", default_value_t = 1.0)]
        seconds: f64,
    },
    /// Drive with a gamepad without a screen (for scripts and tests), for a while.
    Pad {
        /// Seconds to keep reading the pad and sending.
        #[arg(long = "for", default_value_t = 60.0)]
        seconds: f64,
    },
    /// Follow a scenario file (TOML: steps of `at_s` and `mode`, as sim-host reads) on the
    /// wall clock.
    Script {
        /// The scenario file, e.g. scenarios/report_demo.toml.
        file: PathBuf,
    },
}

fn parse_key(text: &str) -> Result<Action, String> {
    let wrong = || format!("`{text}`: give one key: W S A L K X T F, or `space`");
    let mut chars = text.chars();
    let key = match (text, chars.next(), chars.next()) {
        ("space", _, _) => ' ',
        (_, Some(c), None) => c,
        _ => return Err(wrong()),
    };
    match action(Key::Char(key)) {
        Some(a @ (Action::Mode(_) | Action::EStop)) => Ok(a),
        _ => Err(wrong()),
    }
}

/// A failure, with the exit code a shell can act on.
struct Failure {
    code: u8,
    message: String,
}

impl Failure {
    fn bus(e: impl std::fmt::Display) -> Self {
        Self {
            code: 1,
            message: e.to_string(),
        }
    }

    fn usage(message: String) -> Self {
        Self { code: 2, message }
    }
}

fn main() -> ExitCode {
    host_can::logging::init("warn");
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(failure) => {
            eprintln!("teleop: {}", failure.message);
            ExitCode::from(failure.code)
        }
    }
}

fn run(cli: Cli) -> Result<(), Failure> {
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = Arc::clone(&stop);
        ctrlc::set_handler(move || stop.store(true, Ordering::Relaxed))
            .map_err(|e| Failure::bus(format!("cannot install the Ctrl-C handler: {e}")))?;
    }
    // Check what can be checked before the bus or the simulator starts.
    let scenario = match &cli.command {
        Some(Command::Script { file }) => {
            Some(Scenario::load(file).map_err(|e| Failure::usage(e.to_string()))?)
        }
        Some(Command::Send { seconds, .. } | Command::Pad { seconds })
            if !(seconds.is_finite() && (0.0..=86_400.0).contains(seconds)) =>
        {
            return Err(Failure::usage(format!(
                "--for {seconds}: give 0…86400 seconds"
            )))
        }
        _ => None,
    };
    if cli.bus == "inproc" {
        if cli.key_file.is_some() {
            return Err(Failure::usage(
                "--key-file belongs to a CAN bus (the in-process robot uses the test key)".into(),
            ));
        }
        return inproc(&cli, scenario.as_ref(), &stop);
    }
    if cli.model.is_some() || cli.out.is_some() || cli.foxglove_port.is_some() {
        return Err(Failure::usage(
            "--model, --out and --foxglove-port belong to --bus inproc (on a CAN bus the robot is \
             elsewhere)"
                .into(),
        ));
    }
    let key = host_can::key_file::load(cli.key_file.as_deref())
        .map_err(|e| Failure::usage(e.to_string()))?;
    let mut bus = SocketCanBus::open(&cli.bus).map_err(|e| {
        let hint = if e.is_missing_interface() {
            "\n(or drive the simulated robot without CAN: `--bus inproc`)"
        } else {
            ""
        };
        Failure::bus(format!("{e}{hint}"))
    })?;
    operate(&mut bus, &cli, key, scenario.as_ref(), &stop, &mut || None)
}

/// Runs the chosen mode on `bus`; `live` gives ground truth when the robot is simulated here.
fn operate(
    bus: &mut dyn Bus,
    cli: &Cli,
    key: protocol::Key,
    scenario: Option<&Scenario>,
    stop: &AtomicBool,
    live: &mut dyn FnMut() -> Option<teleop::app::SimView>,
) -> Result<(), Failure> {
    let mut pad = open_pad(cli)?;
    let report = match (&cli.command, scenario) {
        (None, _) => {
            let report = teleop::terminal::run(bus, &cli.bus, key, live, pad.as_mut(), stop)
                .map_err(|e| Failure::bus(e.to_string()))?;
            println!(
                "teleop: sent {} frames on {}; the robot was told to stop{}",
                report.frames_sent,
                cli.bus,
                if report.estop_latched {
                    " (the E-stop is still latched)"
                } else {
                    ""
                }
            );
            return Ok(());
        }
        (
            Some(Command::Send {
                key: action,
                seconds,
            }),
            _,
        ) => script::send(bus, key, *action, Duration::from_secs_f64(*seconds), stop),
        (Some(Command::Pad { seconds }), _) => {
            let Some(reader) = pad.as_mut() else {
                return Err(Failure::usage("no gamepad was opened".into()));
            };
            println!(
                "teleop: gamepad {} on {} for {seconds:.1} s",
                reader
                    .device()
                    .map_or("?".into(), |p| p.display().to_string()),
                cli.bus
            );
            script::pad(
                bus,
                key,
                reader,
                Duration::from_secs_f64(*seconds),
                stop,
                |now_ms, action| println!("  t = {:6.3} s  {action:?}", now_ms as f64 / 1e3),
            )
        }
        (Some(Command::Script { .. }), Some(scenario)) => {
            println!(
                "teleop: script `{}`, {} steps over {:.1} s on {}",
                scenario.name,
                scenario.steps.len(),
                scenario.duration_s,
                cli.bus
            );
            script::run(bus, key, scenario, stop, |index| {
                if let Some(step) = scenario.steps.get(index) {
                    println!(
                        "  t = {:6.2} s  {:<5} {}",
                        step.plan.at_us as f64 / 1e6,
                        mode_name(step.plan.mode),
                        step.label
                    );
                }
            })
        }
        (Some(Command::Script { .. }), None) => {
            return Err(Failure::usage("the scenario was not loaded".into()))
        }
    }
    .map_err(Failure::bus)?;
    conclude(&report, &cli.bus)
}

/// The gamepad `--gamepad` names (or `teleop pad` wants), opened; `None` without one.
fn open_pad(cli: &Cli) -> Result<Option<teleop::gamepad::PadReader>, Failure> {
    let wanted = match (&cli.gamepad, &cli.command) {
        (Some(_), Some(Command::Send { .. } | Command::Script { .. })) => {
            return Err(Failure::usage(
                "--gamepad drives the interactive operator or `teleop pad`, not `send` or `script`"
                    .into(),
            ))
        }
        (Some(device), _) => Some(device.as_str()),
        (None, Some(Command::Pad { .. })) => Some("auto"),
        (None, _) => None,
    };
    let Some(wanted) = wanted else {
        return Ok(None);
    };
    let path = (wanted != "auto").then(|| PathBuf::from(wanted));
    teleop::gamepad::PadReader::open(path.as_deref())
        .map(Some)
        .map_err(|e| Failure::bus(e.to_string()))
}

fn conclude(report: &ScriptReport, bus: &str) -> Result<(), Failure> {
    println!(
        "teleop: sent {} frames on {bus}, heard {}{}",
        report.frames_sent,
        report.frames_heard,
        if report.interrupted {
            " (interrupted)"
        } else {
            ""
        }
    );
    match report.last_mode {
        Some(mode) => {
            println!("teleop: the controller's last mode: {}", mode.label());
            Ok(())
        }
        None => Err(Failure {
            code: 3,
            message: format!(
                "no controller status was heard on {bus}: is the firmware running there \
                 (firmware-host --bus {bus})? Or use --bus inproc for the simulated robot."
            ),
        }),
    }
}

#[cfg(feature = "sim")]
fn inproc(cli: &Cli, scenario: Option<&Scenario>, stop: &AtomicBool) -> Result<(), Failure> {
    use teleop::inproc::{InprocOptions, InprocRobot};
    let mut options = InprocOptions::wall_clock();
    if let Some(model) = &cli.model {
        options.model = model.clone();
    }
    options.out_dir = cli.out.clone();
    options.foxglove_port = cli.foxglove_port;
    let (robot, mut endpoint) = InprocRobot::start(options);
    // A simulator that fails (a bad model, say) ends the session; its error is shown below.
    let mut live = || {
        if robot.finished() {
            stop.store(true, Ordering::Relaxed);
        }
        robot.view()
    };
    let result = operate(
        &mut endpoint,
        cli,
        protocol::TEST_KEY,
        scenario,
        stop,
        &mut live,
    );
    let last = robot.view();
    let finished = robot.finish();
    result?;
    let report = finished.map_err(|e| Failure::bus(sim_host::error_chain::chain(&e)))?;
    if let Some(v) = last {
        println!(
            "teleop: the simulated robot ended at x {:+.2} m, y {:+.2} m, heading {:+.0}°",
            v.position_m[0], v.position_m[1], v.yaw_deg
        );
    }
    for file in &report.files {
        println!("teleop: wrote {}", file.display());
    }
    Ok(())
}

#[cfg(not(feature = "sim"))]
fn inproc(_: &Cli, _: Option<&Scenario>, _: &AtomicBool) -> Result<(), Failure> {
    Err(Failure::usage(
        "--bus inproc needs teleop built with its `sim` feature (the default)".into(),
    ))
}
