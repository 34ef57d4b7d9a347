//! `cargo xtask fuzz [--seconds N] [--seeds]`: libFuzzer (cargo fuzz, nightly) on every frame
//! decoder (`decode_frame`), the stateful receive path (`receiver`), the firmware's whole
//! frame handler (`node`, which also asserts every command stays finite and in limits), the
//! E-stop contract on the node (`estop`: scripts of ticks, fresh, forged and replayed frames,
//! latches, releases and restarts against an oracle, see `fuzz/fuzz_targets/estop/oracle.rs`),
//! and the text parsers of the host tools (`candump` lines and logs, `fault_plan`s,
//! `scenario` files), which must never panic.
//!
//! Each target runs `N` seconds (default 60) from its committed seeds (`fuzz/seeds/<target>/`:
//! real frames from the PIL recording of a closed-loop run, so that the fuzzer starts past the
//! CRC; the recording as candump lines; E-stop sessions; the documented fault plans; the
//! shipped scenarios) and its working corpus (`fuzz/corpus/<target>/`, not committed). A crash
//! fails the task and names the input libFuzzer saved in `fuzz/artifacts/`; it becomes a
//! regression test. `--seeds` rewrites the seeds. Installs the nightly toolchain and
//! cargo-fuzz when they are missing. The long run: `cargo xtask fuzz --seconds 3600`, or one
//! target to a number of executions, e.g. `cargo +nightly fuzz run estop -- -runs=10000000`
//! in `fuzz/`.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::util::{root, run as sh};

/// The fuzz targets, in `fuzz/fuzz_targets/`.
pub const TARGETS: [&str; 7] = [
    "decode_frame",
    "receiver",
    "node",
    "estop",
    "candump",
    "fault_plan",
    "scenario",
];

/// Seconds each target runs in `cargo xtask test` (CI), in the order of [`TARGETS`]: 30 s for
/// each frame target, 15 s for each of the other four, so that fuzzing with its build stays
/// near 3 minutes of a CI run kept under 30 (the long runs are in docs/faults.md).
pub const CI_SECONDS: [u32; 7] = [30, 30, 30, 15, 15, 15, 15];

/// The `estop` target's script language and seeds, shared with the target.
#[path = "../../fuzz/fuzz_targets/estop/script.rs"]
mod estop_script;

/// Fault plans as the docs and the tests write them (`host_can::fault_plan`).
const FAULT_PLANS: [&str; 6] = [
    "tx.drop=0.05,rx.delay=3,tx.flip=0.01,seed=7",
    "tx.drop=0.05,rx.delay=3,tx.flip=0.01,rx.replay=0.2,tx.duplicate=0.1,rx.reorder=0.3,\
     tx.flood=40,tx.silence=Imu,rx.drop=0.2,rx.burst=5,seed=7",
    "tx.silence=feedback",
    "rx.drop=0.2,tx.drop=0.2,rx.burst=5",
    "rx.flood=40,seed=3",
    "tx.silence=LegDrive_FL,tx.silence=Controller, rx.duplicate=1",
];

/// candump line forms can-utils writes or reads besides `candump -L`'s own (lower-case hex,
/// dotted bytes, other flags, candump -x extras, a bare timestamp).
const CANDUMP_FORMS: &str = "(1700000000.123456) can0 00A##4\n\
                             (0000000001.5) vcan0 123##1.11.22.33  R\n\
                             (0000000002.000000) vcan0 7ff##f0102030405060708090a0b\n";

pub fn run(args: &[String]) -> Result<(), String> {
    let mut seconds = 60_u32;
    let mut rest = args.iter();
    while let Some(arg) = rest.next() {
        match arg.as_str() {
            "--seconds" => {
                seconds = rest
                    .next()
                    .and_then(|v| v.parse().ok())
                    .filter(|s| *s > 0)
                    .ok_or("--seconds needs a whole number of seconds > 0")?
            }
            "--seeds" => return write_seeds(),
            other => {
                return Err(format!(
                    "unknown option `{other}`: use --seconds N or --seeds"
                ))
            }
        }
    }
    fuzz_all(TARGETS.map(|target| (target, seconds)))
}

/// `cargo xtask test`'s share: every target for its [`CI_SECONDS`].
pub fn ci() -> Result<(), String> {
    let mut plan = TARGETS.map(|target| (target, 0));
    for ((_, seconds), ci) in plan.iter_mut().zip(CI_SECONDS) {
        *seconds = ci;
    }
    fuzz_all(plan)
}

/// Runs each target for its seconds, one after the other; fails on the first crash.
fn fuzz_all(plan: [(&str, u32); TARGETS.len()]) -> Result<(), String> {
    ensure_tools()?;
    let mut total = 0_u64;
    for (target, seconds) in plan {
        let runs = fuzz(target, seconds)?;
        println!("MEASURED fuzz {target}: {runs} executions in {seconds} s, no crash");
        total += runs;
    }
    println!(
        "MEASURED fuzz total: {total} executions over {} targets, no crash",
        TARGETS.len()
    );
    Ok(())
}

fn fuzz_dir() -> PathBuf {
    root().join("fuzz")
}

fn ensure_tools() -> Result<(), String> {
    let has_nightly = Command::new("rustup")
        .args(["run", "nightly", "rustc", "--version"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !has_nightly {
        sh(Command::new("rustup").args([
            "toolchain",
            "install",
            "nightly",
            "--profile",
            "minimal",
        ]))?;
    }
    let has_fuzz = Command::new("cargo")
        .args(["fuzz", "--version"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !has_fuzz {
        sh(Command::new("cargo").args(["install", "cargo-fuzz", "--locked"]))?;
    }
    Ok(())
}

/// Runs one target; the number of executions libFuzzer reports.
fn fuzz(target: &str, seconds: u32) -> Result<u64, String> {
    let corpus = fuzz_dir().join("corpus").join(target);
    let seeds = fuzz_dir().join("seeds").join(target);
    std::fs::create_dir_all(&corpus).map_err(|e| format!("{}: {e}", corpus.display()))?;
    let out = Command::new("cargo")
        .current_dir(fuzz_dir())
        .args(["+nightly", "fuzz", "run", target])
        .arg(&corpus)
        .arg(&seeds)
        .args([
            "--",
            &format!("-max_total_time={seconds}"),
            "-print_final_stats=1",
        ])
        .output()
        .map_err(|e| format!("cannot run cargo fuzz: {e}"))?;
    let log = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        let tail: Vec<&str> = log.lines().rev().take(30).collect();
        let tail: Vec<&str> = tail.into_iter().rev().collect();
        return Err(format!(
            "fuzz target `{target}` failed (a crash saves its input under fuzz/artifacts/{target}/; \
             add it as a regression test):\n{}",
            tail.join("\n")
        ));
    }
    log.lines()
        .find_map(|l| l.strip_prefix("stat::number_of_executed_units:"))
        .and_then(|n| n.trim().parse().ok())
        .ok_or_else(|| format!("fuzz target `{target}`: no execution count in its output"))
}

/// Every target's seeds: frames of the PIL recording for the frame targets and as candump
/// lines, the E-stop sessions of the `estop` script, the fault plans above, the shipped
/// scenarios.
fn write_seeds() -> Result<(), String> {
    let dir = fuzz_dir().join("seeds");
    let _ = std::fs::remove_dir_all(&dir);
    let mut written = write_frame_seeds(&dir)?;
    for (name, script) in estop_script::seeds() {
        save(&dir.join("estop"), name, &script)?;
        written += 1;
    }
    for (n, plan) in FAULT_PLANS.iter().enumerate() {
        save(
            &dir.join("fault_plan"),
            &format!("plan_{n}"),
            plan.as_bytes(),
        )?;
        written += 1;
    }
    written += write_scenario_seeds(&dir.join("scenario"), &root().join("scenarios"))?;
    println!("fuzz: wrote {written} seeds under {}", dir.display());
    Ok(())
}

/// Seeds from the PIL recording: single frames for the decoder, tick sequences for the
/// receiver and the node, candump lines; returns how many.
fn write_frame_seeds(dir: &Path) -> Result<usize, String> {
    let ticks = crate::pil::recorded_ticks()?;
    let mut written = 0;
    // decode_frame: [id u16 LE, data…], the first frame of each id.
    let mut seen = std::collections::BTreeSet::new();
    for (id, data) in ticks.iter().flatten() {
        if seen.insert(*id) {
            let mut input = id.to_le_bytes().to_vec();
            input.extend_from_slice(data);
            save(&dir.join("decode_frame"), &format!("id_{id:03x}"), &input)?;
            written += 1;
        }
    }
    // receiver: [id LE, len, data]…; node: [gap, id LE, len, data]…, one tick's gap before
    // each tick's first frame; candump: `candump -L` lines at 4 ms a tick. Windows of 12 ticks
    // (candump: 2) from several phases of the run.
    for start in (0..ticks.len()).step_by(150) {
        let window = ticks.iter().enumerate().skip(start).take(12);
        let (mut receiver, mut node, mut candump) = (Vec::new(), Vec::new(), String::new());
        for (tick, frames) in window {
            for (n, (id, data)) in frames.iter().enumerate() {
                let len = u8::try_from(data.len()).map_err(|_| "frame longer than 255 bytes")?;
                let head = [id.to_le_bytes()[0], id.to_le_bytes()[1], len];
                receiver.extend_from_slice(&head);
                receiver.extend_from_slice(data);
                node.push(u8::from(n == 0));
                node.extend_from_slice(&head);
                node.extend_from_slice(data);
                // Two ticks of lines: small inputs keep the text fuzzer fast.
                if tick < start + 2 {
                    candump.push_str(&candump_line(tick, *id, data));
                }
            }
        }
        save(
            &dir.join("receiver"),
            &format!("tick_{start:05}"),
            &receiver,
        )?;
        save(&dir.join("node"), &format!("tick_{start:05}"), &node)?;
        save(
            &dir.join("candump"),
            &format!("tick_{start:05}"),
            candump.as_bytes(),
        )?;
        written += 3;
    }
    save(&dir.join("candump"), "forms", CANDUMP_FORMS.as_bytes())?;
    Ok(written + 1)
}

/// One frame of tick `tick` as `candump -L` logs it: `(SECONDS.MICROS) vcan0 ID##4DATA`.
fn candump_line(tick: usize, id: u16, data: &[u8]) -> String {
    let micros = tick as u64 * 4_000;
    let hex: String = data.iter().map(|b| format!("{b:02X}")).collect();
    format!(
        "({:010}.{:06}) vcan0 {id:03X}##4{hex}\n",
        micros / 1_000_000,
        micros % 1_000_000
    )
}

/// Every `*.toml` under `from` (the shipped scenarios) into `to`; returns how many.
fn write_scenario_seeds(to: &Path, from: &Path) -> Result<usize, String> {
    let mut written = 0;
    let entries = std::fs::read_dir(from).map_err(|e| format!("{}: {e}", from.display()))?;
    let mut paths: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    paths.sort();
    for path in paths {
        if path.is_dir() {
            written += write_scenario_seeds(to, &path)?;
        } else if path.extension().is_some_and(|e| e == "toml") {
            let text = std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?;
            let name = path
                .file_stem()
                .map_or_else(String::new, |s| s.to_string_lossy().into());
            save(to, &name, &text)?;
            written += 1;
        }
    }
    Ok(written)
}

fn save(dir: &Path, name: &str, bytes: &[u8]) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let path = dir.join(name);
    std::fs::write(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ci_fuzzes_every_target_within_its_budget() {
        assert!(CI_SECONDS.iter().all(|s| *s > 0));
        // Fuzzing's share of a CI run kept under 30 minutes: at most 3 minutes of running.
        let total: u32 = CI_SECONDS.iter().sum();
        assert!(total <= 180, "{total} s of fuzzing in CI");
    }

    #[test]
    fn every_target_is_a_bin_of_the_fuzz_crate() {
        let manifest = std::fs::read_to_string(root().join("fuzz/Cargo.toml")).unwrap();
        for target in TARGETS {
            assert!(
                manifest.contains(&format!("path = \"fuzz_targets/{target}.rs\"")),
                "{target} is not in fuzz/Cargo.toml"
            );
            assert!(
                root().join("fuzz/seeds").join(target).is_dir(),
                "{target}: no seeds"
            );
        }
    }

    #[test]
    fn estop_seeds_are_written_by_the_script() {
        for (name, script) in estop_script::seeds() {
            let committed = root().join("fuzz/seeds/estop").join(name);
            assert_eq!(
                std::fs::read(&committed).ok(),
                Some(script),
                "{name} is stale"
            );
        }
    }
}
