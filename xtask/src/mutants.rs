//! `cargo xtask mutants [FILE…]`: mutation testing of the safety-critical modules with
//! `cargo-mutants` (installed if missing). Each mutant of these files — a function that returns
//! a constant, an operator swapped, a condition negated — must make some test of its own crate
//! fail; a mutant that survives is a behaviour no test looks at. The task fails on any survivor
//! not listed in [`EQUIVALENT`] with the reason it cannot be told apart.
//!
//! A long task (minutes per file on two cores), documented in docs/faults.md and not part of
//! `cargo xtask test`. With FILE arguments it tests only those files; `--iterate` first tests
//! only the mutants the previous run did not catch.

use std::process::Command;

use crate::util::{cargo, root, run as sh};

/// The safety-critical modules: the receive checks, the session and the sealing of frames, the
/// CMAC, the watchdogs and clamps, the link monitor, the operator-command budget, the operator
/// requests and the restart interlock, the mode machine, the controlled stop, the node with its
/// acceptance filter and release token, its memory across restarts, the service loop, and the
/// stall and runaway detector.
const FILES: [&str; 15] = [
    "protocol/src/e2e.rs",
    "protocol/src/receiver.rs",
    "protocol/src/session.rs",
    "protocol/src/sender.rs",
    "protocol/src/cmac.rs",
    "firmware/src/control/safety.rs",
    "firmware/src/node/link.rs",
    "firmware/src/node/rate_limit.rs",
    "firmware/src/control/teleop.rs",
    "firmware/src/control/fsm.rs",
    "firmware/src/control/stop.rs",
    "firmware/src/node/mod.rs",
    "firmware/src/node/persist.rs",
    "firmware/src/node/service.rs",
    "firmware/src/wheels/runaway.rs",
];

/// Mutants that survive because no behaviour tells them apart, with the reason. Each entry is
/// the start of the line cargo-mutants prints in `missed.txt`.
const EQUIVALENT: [(&str, &str); 11] = [
    (
        "firmware/src/node/mod.rs:144:9: replace Node::encode_failures -> u32 with 0",
        "no message can fail to encode (their sizes are checked at compile time), so the count \
         is always 0",
    ),
    (
        "firmware/src/node/mod.rs:201:31: replace match guard previous == now with false",
        "the same tick again then adds its 0 ticks to the session time: the same time",
    ),
    (
        "firmware/src/wheels/runaway.rs:79:62: replace * with / in RunawayInput::cause",
        "the speed times the reference's sign (±1: f32::signum is never 0) is the speed \
         divided by it",
    ),
    (
        "firmware/src/wheels/runaway.rs:80:54: replace * with / in RunawayInput::cause",
        "as above: ±1 multiplies and divides alike",
    ),
    (
        "firmware/src/wheels/runaway.rs:154:37: replace * with / in Runaway::update",
        "the error's rate times the reference's sign (±1: f32::signum is never 0) is the rate \
         divided by it",
    ),
    (
        "firmware/src/wheels/runaway.rs:154:71: replace < with <= in Runaway::update",
        "they differ only at a rate of exactly 0, which is never a collision (the rate must \
         also be past the collision bound)",
    ),
    (
        "protocol/src/e2e.rs:241:45: replace | with ^ in Search::candidates",
        "the reference with its low 16 bits cleared and a 16-bit low counter share no bit: or \
         and exclusive or give the same counter",
    ),
    (
        "protocol/src/e2e.rs:328:57: replace > with >= in E2eChecker::check",
        "a candidate equal to the last accepted counter has the same low half, which the \
         repeat check before the search already verified and found failing; the check is \
         deterministic, so it fails again",
    ),
    (
        "protocol/src/receiver.rs:171:41: replace > with >= in Receiver::on_announce",
        "an announcement at the session's present time is taken by the branch before, so the \
         two comparisons never see an equal time",
    ),
    (
        "protocol/src/session.rs:115:40: replace | with ^ in Key::from_hex",
        "the high digit shifted left by 4 has its low four bits clear and the low digit is \
         below 16: or and exclusive or give the same byte",
    ),
    (
        "protocol/src/sender.rs:57:38: replace match guard key == session.key() with false",
        "the sender then prepares the CMAC key for every frame instead of once per key: the same \
     frames, only slower (the guard is a cache check)",
    ),
];

pub fn run(args: &[String]) -> Result<(), String> {
    // `--iterate`: test only what the last run did not catch (and what changed since), after
    // adding tests for its survivors.
    let (iterate, args) = match args.split_first() {
        Some((first, rest)) if first == "--iterate" => (true, rest),
        _ => (false, args),
    };
    let files: Vec<&str> = if args.is_empty() {
        FILES.to_vec()
    } else {
        args.iter().map(String::as_str).collect()
    };
    ensure_cargo_mutants()?;
    let out = root().join("target").join("mutants");
    if !iterate {
        // A list left by an earlier run must not stand in for this one's.
        let _ = std::fs::remove_dir_all(&out);
    }
    let mut cmd = cargo();
    if iterate {
        cmd.arg("mutants").arg("--iterate");
    } else {
        cmd.arg("mutants");
    }
    // Ignored files (the fuzz corpus, caches) stay out of the copies the mutants build in.
    cmd.args([
        "--no-shuffle",
        "--test-workspace=false",
        "--gitignore=true",
        "--output",
    ])
    .arg(&out)
    // The copies hold no `.venv`: the DBC's cantools test finds Python here.
    .env("PROTOCOL_PYTHON", crate::setup::venv_python());
    for package in ["protocol", "firmware"] {
        cmd.args(["--package", package]);
    }
    for file in &files {
        cmd.args(["--file", file]);
    }
    // cargo-mutants exits 0 when every mutant was caught, 2 when some survived (the list below
    // says which) and 3 when some made a test hang until its timeout (caught: the tests did not
    // pass); anything else (a usage error, a failing unmutated tree) ends the task.
    let status = cmd
        .status()
        .map_err(|e| format!("cannot run cargo mutants: {e}"))?;
    match status.code() {
        Some(0 | 2 | 3) => {}
        other => {
            return Err(format!(
                "cargo mutants failed (exit {other:?}): see its output above"
            ))
        }
    }
    let missed_path = out.join("mutants.out").join("missed.txt");
    let missed = std::fs::read_to_string(&missed_path).map_err(|e| {
        format!(
            "{}: {e} (did cargo-mutants run? see its output above)",
            missed_path.display()
        )
    })?;
    let survivors: Vec<&str> = missed
        .lines()
        .filter(|line| !line.trim().is_empty())
        .filter(|line| !EQUIVALENT.iter().any(|(start, _)| line.starts_with(start)))
        .collect();
    println!(
        "MEASURED mutants: {} files, {} surviving mutants outside the documented equivalents",
        files.len(),
        survivors.len()
    );
    if survivors.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "mutants no test kills (add a test that tells each apart, or name it in \
             xtask/src/mutants.rs EQUIVALENT with the reason):\n  {}",
            survivors.join("\n  ")
        ))
    }
}

fn ensure_cargo_mutants() -> Result<(), String> {
    let installed = Command::new("cargo")
        .args(["mutants", "--version"])
        .output()
        .is_ok_and(|out| out.status.success());
    if installed {
        Ok(())
    } else {
        sh(Command::new("cargo").args(["install", "cargo-mutants", "--locked"]))
    }
}
