//! The PIL image: the input file it embeds (the recording in `pil-format`'s raw format, given
//! to its build as `PIL_INPUTS`) and its build. The linker script is `firmware/pil/an386.x`,
//! which the package's build script passes to the linker itself.

use std::path::{Path, PathBuf};

use pil_format::Recording;

use crate::setup::MCU_TARGET;
use crate::util::{cargo, root, run as sh};

/// Environment for building the PIL image outside this task (e.g. clippy): the input file.
pub fn prepare_build_env() -> Result<Vec<(&'static str, PathBuf)>, String> {
    let recording = super::load_recording()?;
    Ok(vec![("PIL_INPUTS", write_inputs(&recording)?)])
}

/// Builds the image (profile `mcu`) on `recording`'s frames; returns the ELF's path.
pub(super) fn build(recording: &Recording) -> Result<PathBuf, String> {
    let inputs = write_inputs(recording)?;
    sh(cargo()
        .args([
            "build",
            "--profile",
            crate::firmware::PROFILE,
            "-p",
            "firmware-pil",
            "--target",
            MCU_TARGET,
        ])
        .env("PIL_INPUTS", &inputs))?;
    Ok(crate::firmware::image("firmware-pil"))
}

/// Writes the input file and returns its path.
fn write_inputs(recording: &Recording) -> Result<PathBuf, String> {
    let path = work_dir()?.join("inputs.raw");
    let raw = recording
        .to_raw()
        .map_err(|e| format!("cannot write the recording for the image: {e}"))?;
    write(&path, &raw)?;
    Ok(path)
}

/// This task's files: `target/pil`.
pub(super) fn work_dir() -> Result<PathBuf, String> {
    let dir = root().join("target").join("pil");
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    Ok(dir)
}

fn write(path: &Path, bytes: &[u8]) -> Result<(), String> {
    // Unchanged files keep their time stamps, so cargo does not rebuild for nothing.
    if std::fs::read(path).ok().as_deref() == Some(bytes) {
        return Ok(());
    }
    std::fs::write(path, bytes).map_err(|e| format!("cannot write {}: {e}", path.display()))
}
