//! What the closed-loop session tests share: a lockstep in-process session on a given plant,
//! and a plan of operator modes with one measured segment per step.
#![allow(dead_code)] // each test file uses a part

pub mod climb;

use std::path::{Path, PathBuf};
use std::time::Duration;

use sim_host::robot::model::DEFAULT_MODEL;
use sim_host::robot::plant::Plant;
use sim_host::session::{BusChoice, Clock, SegmentSpec, SessionConfig};
use teleop_core::scenario::{mode_name, parse_mode, Scenario};
use teleop_core::scripted::PlanStep;

/// The MCAP file at `path` as the official Python reader (the project venv's `mcap`) reads it:
/// `tests/python/read_mcap.py`'s JSON (channels with schemas and counts, attachments, the
/// `world` → `torso` transforms, the joints' names).
pub fn read_mcap(path: &Path) -> serde_json::Value {
    let python = std::env::var_os("PROTOCOL_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../.venv/bin/python"));
    assert!(
        python.exists(),
        "no Python with mcap at {}: run `cargo xtask setup` (or set PROTOCOL_PYTHON)",
        python.display()
    );
    let output = std::process::Command::new(python)
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/python/read_mcap.py"))
        .arg(path)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "the Python reader failed:\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    serde_json::from_slice(&output.stdout).unwrap()
}

/// An acceptance scenario file by name.
pub fn scenario_file(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenarios/acceptance")
        .join(name)
}

/// A lockstep session on the in-process bus at 250 Hz, no output files.
pub fn config(
    plant: Plant,
    plan: Vec<PlanStep>,
    segments: Vec<SegmentSpec>,
    duration_s: f64,
) -> SessionConfig {
    SessionConfig {
        attach: None,
        faults: Default::default(),
        model: PathBuf::from(DEFAULT_MODEL),
        scene: sim_host::scene::Scene::Flat,
        bus: BusChoice::Inproc,
        clock: Clock::Lockstep,
        duration_s,
        control_hz: 250,
        reply_timeout: Duration::from_millis(100),
        max_speed: None,
        plant,
        teleop_plan: plan,
        out_dir: None,
        plots: false,
        text_logs: true,
        progress: false,
        stop: None,
        segments,
        frames: None,
        viewer: false,
        live_port: None,
    }
}

/// One measured segment per step of `scenario`, labelled as the scenario labels it.
pub fn segments_of(scenario: &Scenario) -> Vec<SegmentSpec> {
    scenario
        .steps
        .iter()
        .map(|s| SegmentSpec {
            start_s: s.plan.at_us as f64 * 1e-6,
            label: s.label.clone(),
            mode: mode_name(s.plan.mode),
        })
        .collect()
}

/// A plan of `(start s, mode key)` steps at full speed and height, and one segment per step
/// labelled with its mode.
pub fn plan(steps: &[(f64, &str)]) -> (Vec<PlanStep>, Vec<SegmentSpec>) {
    let plan = steps
        .iter()
        .map(|(at_s, mode)| PlanStep {
            at_us: (at_s * 1e6) as u64,
            mode: parse_mode(mode).unwrap(),
            body_height_m: 0.0,
            speed_scale_pct: 100.0,
            speed_m_s: 0.0,
            yaw_rate_rad_s: 0.0,
        })
        .collect();
    let segments = steps
        .iter()
        .map(|(at_s, mode)| SegmentSpec {
            start_s: *at_s,
            label: (*mode).to_owned(),
            mode: (*mode).to_owned(),
        })
        .collect();
    (plan, segments)
}
