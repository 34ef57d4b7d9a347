//! `sim-host`: the hybrid wheel–leg robot in MuJoCo, playing its leg drives, wheel drive and IMU
//! on a CAN bus.
// Functions stay short enough to read whole (clippy.toml: 80 lines); tests may run longer.
#![cfg_attr(not(test), warn(clippy::too_many_lines))]

mod campaign;
mod export;
mod report;
mod run;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use sim_host::robot::model::DEFAULT_MODEL;

use crate::campaign::CampaignArgs;
use crate::export::ExportArgs;
use crate::run::RunArgs;

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
    /// Example: sim-host run --duration-s 10 --drive 0:stand --drive 2:W --out out/sim
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
    /// Run the robustness campaign: N seeded trials, each a robot as built (masses, centre of
    /// mass, friction, wheel damping, transport delay, drive ratings, its BMI088 chip and its
    /// drive sensors drawn from its seed), through every acceptance scenario on all cores; judged by the
    /// acceptance figures. Prints a Markdown table, writes the results as JSON. A run that
    /// fails is a result: the exit code is 0 unless the campaign itself could not run.
    ///
    /// Examples: sim-host campaign --trials 100;  sim-host campaign --seed 17 --scenario W;
    /// sim-host campaign --shard 0/4 --results a.json;  sim-host campaign --merge a.json b.json
    Campaign(Box<CampaignArgs>),
    /// Write a run's text logs — bus.log (candump `-L`) and telemetry.csv — from its run.mcap:
    /// the same files the run writes itself, byte for byte. A file cut short (a killed run) is
    /// exported up to the cut, and the exit code is 1. Existing text logs are kept unless
    /// `--force`.
    ///
    /// Example: sim-host export out/sim/run.mcap --out out/text
    Export(ExportArgs),
}

fn main() -> ExitCode {
    host_can::logging::init("info");
    let cli = Cli::parse();
    match cli.command {
        Command::Faults { model } => faults(&model),
        Command::Campaign(args) => match campaign::run(*args) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("sim-host campaign: {e}");
                ExitCode::FAILURE
            }
        },
        Command::Export(args) => match export::run(&args) {
            Ok(()) => ExitCode::SUCCESS,
            Err(message) => {
                eprintln!("sim-host export: {message}");
                ExitCode::FAILURE
            }
        },
        Command::Run(args) => match run::run(*args) {
            Ok(()) => ExitCode::SUCCESS,
            Err(message) => {
                eprintln!("sim-host: {message}");
                ExitCode::FAILURE
            }
        },
    }
}

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
