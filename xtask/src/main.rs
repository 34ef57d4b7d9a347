//! `cargo xtask <task>`: every project task. This file only dispatches; each task is a module.
// Functions stay short enough to read whole (clippy.toml: 80 lines); tests may run longer.
#![cfg_attr(not(test), warn(clippy::too_many_lines))]

mod apt;
mod bench;
mod busload;
mod campaign;
mod dbc;
mod demo;
mod elf;
mod faults;
mod firmware;
mod frame;
mod fuzz;
mod hil;
mod mujoco;
mod mutants;
mod pil;
mod same_run;
mod setup;
mod soak;
mod test;
mod util;

use std::process::ExitCode;

const HELP: &str = "\
cargo xtask <task> [options]

Tasks:
  setup              install what the project needs (rustup target, Python venv with cantools,
                     the MuJoCo library in .cache/mujoco, Mesa EGL from apt); idempotent, fast
                     when already done
  test               everything CI checks: fmt, clippy -D warnings (all features), DBC
                     freshness, no f64 in the no_std crates, all tests (the headless renderer's
                     too), a thumbv7em-none-eabihf build of the no_std crates, the MCU
                     images (`firmware`, `pil`), fuzzing (`fuzz`: a minute per frame target,
                     20 s per other), and the vcan suite (`hil`)
  dbc [--check]      regenerate protocol/hybrid_robot.dbc (--check: fail if the committed file is stale)
  busload            print the per-cycle frame schedule and the bus load at 250 Hz and 1 kHz
  frame KIND [opts]  a valid frame as a `cansend` line: `latch` (the constant E-stop latch),
                     `release --epoch N --time-ms T --token N`, `command MODE --epoch N
                     --time-ms T` (sealed with --key-file FILE, or the simulation's test key);
                     epoch and time from the controller's latest Announce, the token from its
                     status (`cargo xtask frame` alone prints the options)
  bench [args]       criterion benchmarks (control step, raw MuJoCo step, closed-loop cycle), then a
                     table of medians and steps per second, also written into docs/measurements.md
                     (args go to criterion, e.g. `--measurement-time 3`)
  hil [--vm] [NAME]  the vcan hardware-in-the-loop suite: firmware and simulator as two processes
                     on a kernel vcan; natively where this kernel has vcan and you are root,
                     otherwise (or with --vm) in a QEMU VM booting a stock Debian kernel
                     (NAME: only the tests whose name contains it, e.g. `flood`)
  firmware           build the STM32G474 image (firmware/stm32, release + LTO) and print its flash
                     and static RAM use (fails over 64 KiB flash or 16 KiB RAM)
  pil [--record]     processor-in-the-loop: the control core on QEMU's mps2-an386 (Cortex-M4F)
                     against recorded bus traffic; fails unless its frames equal the host
                     build's; prints instructions per control step and peak stack
                     (--record: rerun the closed loop and rewrite firmware/pil/recording.pil)
  fuzz [--seconds N] libFuzzer (cargo fuzz, nightly; installed if missing) on the frame decoders,
                     the receive path, the firmware's frame handler, its E-stop contract and
                     the host tools' text parsers (candump logs, fault plans, scenarios), N s
                     each (default 60) from the committed seeds; fails on a crash (--seeds:
                     rewrite the seeds)
  faults [--check]   the fault matrix (lost, late, corrupted, replayed frames, a teleop flood,
                     silent feedback, a killed firmware, a restarted simulator, E-stops) on the
                     closed loop in-process; writes its table into docs/faults.md (--check: fail
                     if the table there is stale)
  campaign [opts]    the robustness campaign: N seeded trials (default 500), each a robot as
                     built (masses, centre of mass, friction, wheel damping, transport delay,
                     drive ratings, its IMU chip and drive sensors drawn from its seed) through every
                     acceptance scenario on all cores; writes its table into
                     docs/campaign.md (--check: fail if the table there is stale; `test` runs
                     --trials 100 --check). --jobs N, --drives rated|ideal, --shard I/N with
                     --results FILE (a part, for --merge FILE…), --seed S [--scenario NAME]
                     (rerun one trial, every figure), --scaling N (runs/s on 1 and 2 workers),
                     --sweep (one parameter at a time at each end of its range)
  mutants [--iterate] [FILE…]
                     mutation testing (cargo-mutants, installed if missing) of the
                     safety-critical modules: fails on a mutant no test kills (long: minutes per
                     file; not part of `test`); --iterate: only what the last run missed
  soak [--minutes N] sim-host in-process for N simulated minutes (default 1440: a day), every
                     output on (streamed to /dev/null), turning in place; fails if its resident
                     memory grows more than 5 MB after minute 5 (`test` runs 10 minutes)
  same-run REV       proof that behaviour did not change: builds sim-host at git revision REV
                     and from the working tree, runs every shipped scenario with both, and
                     compares summary.json (all but the wall-clock fields), bus.log and
                     telemetry.csv
  demo [options]     the report's demonstration, closed loop (STOP, W, S, A, L, K, X): sets up,
                     builds, runs scenarios/report_demo.toml with the firmware on the in-process
                     CAN bus; writes out/ (summary.json, telemetry.csv, bus.log, plots, frames)
                     --bus vcan0   over SocketCAN instead (the controller runs elsewhere)
                     --out DIR     --scenario FILE     --no-render (skip the rendered frames)
                     --teleop      drive it yourself instead: teleop's terminal UI on the
                                   simulated robot (keys W S A L K X, T, F, space, Q)
                     --course      the autonomous mode over the course (step, then 10° ramp)
                                   instead: scenarios/course.toml into out/course/
";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (task, rest) = match args.split_first() {
        Some((task, rest)) => (task.as_str(), rest),
        None => {
            eprint!("{HELP}");
            return ExitCode::from(2);
        }
    };
    let result = match task {
        "setup" => setup::run(),
        "test" => test::run(),
        "dbc" => dbc::run(rest),
        "busload" => busload::run(),
        "bench" => bench::run_task(rest),
        "demo" => demo::run(rest),
        "hil" => hil::run(rest),
        "firmware" => firmware::run(),
        "frame" => frame::run(rest),
        "pil" => pil::run(rest),
        "fuzz" => fuzz::run(rest),
        "faults" => faults::run(rest),
        "campaign" => campaign::run(rest),
        "same-run" => same_run::run(rest),
        "mutants" => mutants::run(rest),
        "soak" => soak::run(rest),
        "help" | "-h" | "--help" => {
            print!("{HELP}");
            Ok(())
        }
        other => Err(format!("unknown task `{other}`\n\n{HELP}")),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("xtask {task}: {message}");
            ExitCode::FAILURE
        }
    }
}
