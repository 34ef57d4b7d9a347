//! `cargo xtask test`: everything CI checks, in the order that fails fastest.

use std::process::Command;

use crate::setup::{venv_python, MCU_TARGET};
use crate::util::{cargo, root, run as sh};

/// Crates that must stay `no_std` and free of `f64`.
const NO_STD_CRATES: [&str; 2] = ["protocol", "firmware"];

/// Prints how long each step took, so that a slow CI run says where its time went.
struct Steps {
    started: std::time::Instant,
    step: std::time::Instant,
}

impl Steps {
    fn new() -> Self {
        let now = std::time::Instant::now();
        Self {
            started: now,
            step: now,
        }
    }

    fn done(&mut self, what: &str) {
        eprintln!(
            "test: {what} took {:.0} s ({:.1} min in all)",
            self.step.elapsed().as_secs_f64(),
            self.started.elapsed().as_secs_f64() / 60.0
        );
        self.step = std::time::Instant::now();
    }
}

pub fn run() -> Result<(), String> {
    let mut steps = Steps::new();
    crate::setup::run()?;
    steps.done("setup");
    sh(cargo().args(["fmt", "--all", "--check"]))
        .map_err(|e| format!("{e}\nformatting differs: run `cargo fmt --all`"))?;
    sh(cargo().args([
        "clippy",
        "--workspace",
        "--all-targets",
        "--all-features",
        "--",
        "-D",
        "warnings",
    ]))?;
    crate::dbc::run(&["--check".to_string()])?;
    check_no_f64()?;
    check_file_lengths()?;
    steps.done("fmt, clippy, dbc and source checks");
    // The vcan suite needs a kernel with vcan and root; `cargo xtask hil` provides both (here
    // or in a VM), below.
    sh(cargo()
        .args(["test", "--workspace", "--exclude", "hil-tests"])
        .env("PROTOCOL_PYTHON", venv_python()))?;
    steps.done("workspace tests");
    // Headless rendering through Mesa EGL (the feature is off by default).
    sh(cargo().args([
        "test",
        "-p",
        "sim-host",
        "--features",
        "renderer",
        "--test",
        "render",
    ]))?;
    steps.done("render test");
    let mut build = cargo();
    build.args(["build", "--target", MCU_TARGET]);
    for krate in NO_STD_CRATES {
        build.args(["-p", krate]);
    }
    sh(&mut build)?;
    // The no_std crates' docs are their contract (units, ranges, tables): broken links fail.
    let mut doc = cargo();
    doc.args(["doc", "--no-deps"])
        .env("RUSTDOCFLAGS", "-D warnings");
    for krate in NO_STD_CRATES {
        doc.args(["-p", krate]);
    }
    sh(&mut doc)?;
    steps.done("MCU build and docs");
    // The MCU images: clippy for their target (on the host they are stubs), the STM32 image
    // built and sized, and processor-in-the-loop in QEMU against the host build.
    let mut clippy = cargo();
    clippy
        .args([
            "clippy",
            "-p",
            "firmware-stm32",
            "-p",
            "firmware-pil",
            "--target",
            MCU_TARGET,
            "--",
            "-D",
            "warnings",
        ])
        .envs(crate::pil::prepare_build_env()?);
    sh(&mut clippy)?;
    crate::firmware::run()?;
    crate::pil::run(&[])?;
    steps.done("MCU clippy, image and PIL");
    // libFuzzer from the committed seeds: 30 s per frame target, 15 s per other target
    // (the long runs are documented).
    crate::fuzz::ci()?;
    steps.done("fuzzing");
    // Ten simulated minutes of the soak (the day is `cargo xtask soak`).
    crate::soak::run(&["--minutes".to_string(), "10".to_string()])?;
    steps.done("soak");
    // A hundred trials of the robustness campaign; the table in docs/campaign.md must be the
    // one they give (the 500-trial run is `cargo xtask campaign`).
    crate::campaign::run(&[
        "--trials".to_string(),
        "100".to_string(),
        "--check".to_string(),
    ])?;
    steps.done("campaign");
    crate::hil::run(&[])?;
    steps.done("vcan suite");
    eprintln!("test: all checks passed");
    Ok(())
}

/// The no_std crates use only `f32` (the MCU's FPU is single precision): any `f64` in their
/// sources is an error.
fn check_no_f64() -> Result<(), String> {
    let mut offenders = Vec::new();
    for krate in NO_STD_CRATES {
        let out = Command::new("git")
            .args(["grep", "-n", "-w", "f64", "--", &format!("{krate}/src")])
            .current_dir(root())
            .output()
            .map_err(|e| format!("could not run git grep: {e}"))?;
        offenders.extend(
            String::from_utf8_lossy(&out.stdout)
                .lines()
                .map(str::to_owned),
        );
    }
    if offenders.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "f64 in a no_std crate (use f32):\n{}",
            offenders.join("\n")
        ))
    }
}

/// Longest non-test source file, lines: a file longer than this holds more than one concept.
const MAX_SOURCE_LINES: usize = 500;

/// No non-test Rust source over [`MAX_SOURCE_LINES`] lines. Integration tests, benches,
/// examples and fuzz targets are test code; in other files the unit-test module (the last
/// `#[cfg(test)]` followed by `mod`) and what follows it do not count.
fn check_file_lengths() -> Result<(), String> {
    let out = Command::new("git")
        .args(["ls-files", "*.rs"])
        .current_dir(root())
        .output()
        .map_err(|e| format!("could not run git ls-files: {e}"))?;
    let mut offenders = Vec::new();
    for path in String::from_utf8_lossy(&out.stdout).lines() {
        let test_code = path.starts_with("fuzz/")
            || ["tests", "benches", "examples"]
                .iter()
                .any(|dir| path.split('/').any(|part| part == *dir));
        if test_code {
            continue;
        }
        let text = std::fs::read_to_string(root().join(path))
            .map_err(|e| format!("cannot read {path}: {e}"))?;
        let all: Vec<&str> = text.lines().collect();
        let lines = all
            .windows(2)
            .rposition(|w| w[0].trim() == "#[cfg(test)]" && w[1].trim_start().starts_with("mod "))
            .unwrap_or(all.len());
        if lines > MAX_SOURCE_LINES {
            offenders.push(format!("{path}: {lines} lines"));
        }
    }
    if offenders.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "source files over {MAX_SOURCE_LINES} lines (split them by concept):\n{}",
            offenders.join("\n")
        ))
    }
}
