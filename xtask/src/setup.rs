//! `cargo xtask setup`: installs what the project needs, idempotently.
//!
//! - the `thumbv7em-none-eabihf` rustup target (the MCU build);
//! - a project-local Python venv (`.venv/`) with the pinned `cantools`, used by the tests that
//!   read the bus with standard tools, and pip's `download` for MuJoCo;
//! - the MuJoCo library in `.cache/mujoco/` ([`crate::mujoco`]);
//! - Mesa's EGL for headless rendering and tmux for the teleop terminal test, from apt
//!   ([`crate::apt`]).
//!
//! Nothing is installed system-wide.

use std::path::PathBuf;
use std::process::Command;

use crate::util::{output, root, run as sh};

/// The MCU target.
pub const MCU_TARGET: &str = "thumbv7em-none-eabihf";

/// The venv's Python, which the tests use (through `PROTOCOL_PYTHON`).
pub fn venv_python() -> PathBuf {
    root().join(".venv").join("bin").join("python")
}

pub fn run() -> Result<(), String> {
    ensure_target()?;
    ensure_venv()?;
    crate::mujoco::ensure()?;
    crate::apt::ensure(
        &crate::apt::RENDERING,
        "headless rendering (sim-host --features renderer)",
    )?;
    crate::apt::ensure(&["tmux"], "the teleop terminal test (teleop/tests/tmux.rs)")?;
    eprintln!("setup: done");
    Ok(())
}

pub fn ensure_target() -> Result<(), String> {
    let installed = output(Command::new("rustup").args(["target", "list", "--installed"])).ok_or(
        "`rustup` is not available: install Rust with rustup (https://rustup.rs), then rerun `cargo xtask setup`",
    )?;
    if installed.lines().any(|line| line.trim() == MCU_TARGET) {
        return Ok(());
    }
    sh(Command::new("rustup").args(["target", "add", MCU_TARGET]))
}

fn ensure_venv() -> Result<(), String> {
    let requirements = root().join("xtask").join("python-requirements.txt");
    let wanted = std::fs::read_to_string(&requirements)
        .map_err(|e| format!("cannot read {}: {e}", requirements.display()))?;
    let stamp = root().join(".venv").join("requirements.installed");
    let python = venv_python();
    if python.exists() && std::fs::read_to_string(&stamp).ok().as_deref() == Some(wanted.as_str()) {
        return Ok(());
    }
    if !python.exists() {
        sh(Command::new("python3")
            .args(["-m", "venv"])
            .arg(root().join(".venv")))
        .map_err(|e| {
            format!(
                "{e}\nPython 3 with the venv module is needed: install python3 and python3-venv"
            )
        })?;
    }
    sh(Command::new(&python)
        .args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "--disable-pip-version-check",
            "-r",
        ])
        .arg(&requirements))?;
    std::fs::write(&stamp, wanted).map_err(|e| format!("cannot write {}: {e}", stamp.display()))
}
