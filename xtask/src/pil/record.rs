//! `cargo xtask pil --record`: reruns the closed loop and rewrites the committed recording.

use pil_format::Recording;

use super::RECORDING;
use crate::util::{cargo, root, run as sh};

/// Seconds of closed loop `--record` captures.
const RECORD_SECONDS: &str = "6";

/// Runs `sim-host`'s example `pil_record` (it writes the raw format) and keeps its recording in
/// the compact format.
pub(super) fn run() -> Result<(), String> {
    crate::setup::run()?;
    let raw_path = super::image::work_dir()?.join("recorded.raw");
    sh(cargo()
        .args([
            "run",
            "--release",
            "-p",
            "sim-host",
            "--example",
            "pil_record",
            "--",
        ])
        .arg(&raw_path)
        .arg(RECORD_SECONDS))?;
    let raw =
        std::fs::read(&raw_path).map_err(|e| format!("cannot read {}: {e}", raw_path.display()))?;
    let recording =
        Recording::from_raw(&raw).map_err(|e| format!("{}: {e}", raw_path.display()))?;
    let compact = recording
        .to_compact()
        .map_err(|e| format!("cannot compress the recording: {e}"))?;
    let out = root().join(RECORDING);
    std::fs::write(&out, &compact).map_err(|e| format!("cannot write {}: {e}", out.display()))?;
    eprintln!(
        "pil: recorded {} ticks ({} bytes raw) → {} ({} bytes)",
        recording.ticks.len(),
        raw.len(),
        RECORDING,
        compact.len()
    );
    Ok(())
}
