//! `cargo xtask fuzz [--seconds N] [--seeds]`: libFuzzer (cargo fuzz, nightly) on every frame
//! decoder (`decode_frame`), the stateful receive path (`receiver`) and the firmware's whole
//! frame handler (`node`, which also asserts every command stays finite and in limits).
//!
//! Each target runs `N` seconds (default 60) from its committed seeds (`fuzz/seeds/<target>/`,
//! real frames from the PIL recording of a closed-loop run, so that the fuzzer starts past the
//! CRC) and its working corpus (`fuzz/corpus/<target>/`, not committed). A crash fails the task
//! and names the input libFuzzer saved in `fuzz/artifacts/`; it becomes a regression test.
//! `--seeds` rewrites the seeds from the recording. Installs the nightly toolchain and
//! cargo-fuzz when they are missing. The long run: `cargo xtask fuzz --seconds 3600`.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::util::{root, run as sh};

/// The fuzz targets, in `fuzz/fuzz_targets/`.
pub const TARGETS: [&str; 3] = ["decode_frame", "receiver", "node"];

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
    ensure_tools()?;
    let mut total = 0_u64;
    for target in TARGETS {
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

/// Seeds from the PIL recording: single frames for the decoder, tick sequences for the
/// receiver and the node, in each target's input format.
fn write_seeds() -> Result<(), String> {
    let ticks = crate::pil::recorded_ticks()?;
    let dir = fuzz_dir().join("seeds");
    let _ = std::fs::remove_dir_all(&dir);
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
    // each tick's first frame. Windows of 12 ticks from several phases of the run.
    for start in (0..ticks.len()).step_by(150) {
        let window = ticks.iter().skip(start).take(12);
        let (mut receiver, mut node) = (Vec::new(), Vec::new());
        for frames in window {
            for (n, (id, data)) in frames.iter().enumerate() {
                let len = u8::try_from(data.len()).map_err(|_| "frame longer than 255 bytes")?;
                let head = [id.to_le_bytes()[0], id.to_le_bytes()[1], len];
                receiver.extend_from_slice(&head);
                receiver.extend_from_slice(data);
                node.push(u8::from(n == 0));
                node.extend_from_slice(&head);
                node.extend_from_slice(data);
            }
        }
        save(
            &dir.join("receiver"),
            &format!("tick_{start:05}"),
            &receiver,
        )?;
        save(&dir.join("node"), &format!("tick_{start:05}"), &node)?;
        written += 2;
    }
    println!("fuzz: wrote {written} seeds under {}", dir.display());
    Ok(())
}

fn save(dir: &Path, name: &str, bytes: &[u8]) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let path = dir.join(name);
    std::fs::write(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))
}
