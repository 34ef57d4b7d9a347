//! `firmware-host`: the robot's firmware (the same control core as the MCU image) as a host
//! process on a SocketCAN interface.
// Functions stay short enough to read whole (clippy.toml: 80 lines); tests may run longer.
#![cfg_attr(not(test), warn(clippy::too_many_lines))]

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use clap::{Parser, ValueEnum};
use firmware_host::runner::{self, Clock, RunnerConfig};
use firmware_host::state::{self, StateFile};
use host_can::fault_plan::Faults;
use host_can::faulty_bus::FaultyBus;
use host_can::socketcan_bus::SocketCanBus;
use protocol::{Epoch, Session};

/// The hybrid robot's firmware as a host process on a CAN interface.
///
/// In lockstep mode it computes one control tick per SYNC frame from the simulator
/// (`sim-host run --bus vcan0`); on the wall clock it keeps its own time at the control rate, as
/// on the microcontroller. Ctrl-C or SIGTERM stops it after sending the drives a stop (legs
/// torque-free, zero wheel torque).
///
/// Example: firmware-host --bus vcan0 --clock lockstep
#[derive(Debug, Parser)]
#[command(version, about, long_about)]
struct Cli {
    /// The SocketCAN interface (vcan0, can0).
    #[arg(long, default_value = "vcan0")]
    bus: String,
    /// What paces the control loop; the same names as `sim-host run --clock` (`timer` is the
    /// old name of `wall`, kept for one release).
    #[arg(long, value_enum, default_value = "lockstep")]
    clock: ClockArg,
    /// Control rate, Hz (on the wall clock; in lockstep it sets the firmware's tick length).
    /// `--rate-hz` is the old name.
    #[arg(long, default_value_t = 250, alias = "rate-hz")]
    control_hz: u32,
    /// Stop after this many control ticks.
    #[arg(long)]
    ticks: Option<u64>,
    /// Lockstep: exit with an error when no SYNC arrives for this many seconds (0 < s ≤ 86400).
    #[arg(long, value_parser = parse_idle_timeout)]
    idle_timeout_s: Option<Duration>,
    /// Break the firmware's own bus connection on purpose: `rx.*` faults hit the feedback it
    /// receives, `tx.*` the commands it sends, e.g. `rx.drop=0.05,tx.flip=0.01,seed=3`
    /// (faults: drop, delay, duplicate, reorder, flip, replay, silence=NODE; delays count
    /// SYNC-delimited cycles). SYNC is never faulted.
    #[arg(long, value_name = "PLAN", default_value = "")]
    faults: Faults,
    /// The bus key: a file holding 32 hexadecimal digits, readable by this account only.
    /// Without it, the public test key of simulation and CI.
    #[arg(long, value_name = "PATH")]
    key_file: Option<PathBuf>,
    /// Where the controller keeps its session epoch and E-stop latch across restarts
    /// (default: $XDG_STATE_HOME/hybrid-robot/firmware-host.toml, or under ~/.local/state).
    #[arg(long, value_name = "PATH")]
    state_file: Option<PathBuf>,
    /// Open a session with at least this epoch (after a lost state file: above the last one
    /// the controller announced).
    #[arg(long)]
    epoch: Option<u32>,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum ClockArg {
    /// One tick per SYNC frame from the simulator.
    Lockstep,
    /// The wall clock at --control-hz, as on the microcontroller.
    #[value(alias = "timer")]
    Wall,
}

/// `--idle-timeout-s`: a number of seconds, 0 < s ≤ 86400 (a day).
fn parse_idle_timeout(text: &str) -> Result<Duration, String> {
    text.trim()
        .parse::<f64>()
        .ok()
        .filter(|s| *s > 0.0 && *s <= 86_400.0)
        .map(Duration::from_secs_f64)
        .ok_or_else(|| format!("`{text}`: give a number of seconds, 0 < s ≤ 86400"))
}

fn main() -> ExitCode {
    host_can::logging::init("info");
    let cli = Cli::parse();
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    if let Err(e) = ctrlc::set_handler(move || flag.store(true, Ordering::Relaxed)) {
        tracing::warn!("Ctrl-C/SIGTERM will not stop the drives first: {e}");
    }
    let mut bus = match SocketCanBus::open(&cli.bus) {
        Ok(bus) => FaultyBus::new(bus, &cli.faults),
        Err(e) => {
            eprintln!("firmware-host: {e}");
            return ExitCode::FAILURE;
        }
    };
    let key = match host_can::key_file::load(cli.key_file.as_deref()) {
        Ok(key) => key,
        Err(e) => {
            eprintln!("firmware-host: {e}");
            return ExitCode::FAILURE;
        }
    };
    let Some(state_path) = cli.state_file.clone().or_else(state::default_path) else {
        eprintln!("firmware-host: no HOME or XDG_STATE_HOME: give --state-file PATH");
        return ExitCode::FAILURE;
    };
    let (mut state, epoch, latched) = match StateFile::start(&state_path, cli.epoch.map(Epoch::new))
    {
        Ok(started) => started,
        Err(e) => {
            eprintln!("firmware-host: {e}");
            return ExitCode::FAILURE;
        }
    };
    if latched {
        tracing::warn!(
            "the E-stop was latched when the last run ended: it stays latched until released"
        );
    }
    let config = RunnerConfig {
        session: Session::owned(key, epoch),
        latched,
        clock: match cli.clock {
            ClockArg::Lockstep => Clock::Lockstep,
            ClockArg::Wall => Clock::Wall,
        },
        control_hz: cli.control_hz,
        max_ticks: cli.ticks,
        idle_timeout: cli.idle_timeout_s,
    };
    tracing::info!(
        bus = %cli.bus,
        clock = ?cli.clock,
        control_hz = cli.control_hz,
        epoch = epoch.raw(),
        state = %state_path.display(),
        "firmware running"
    );
    match runner::run(&mut bus, config, &stop, Some(&mut state)) {
        Ok(stats) => {
            println!(
                "ticks {} | frames in {} out {} | rejected {:?} | overruns {}",
                stats.ticks, stats.frames_in, stats.frames_out, stats.rejected, stats.overruns
            );
            if !cli.faults.tx.is_clean() || !cli.faults.rx.is_clean() {
                println!(
                    "faults {} | on received {:?} | on sent {:?}",
                    cli.faults,
                    bus.rx_stats(),
                    bus.tx_stats()
                );
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("firmware-host: {e}");
            ExitCode::FAILURE
        }
    }
}
