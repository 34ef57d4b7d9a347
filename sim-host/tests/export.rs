//! The export step (`output::export`, `sim-host export`): a run's text logs made from its
//! MCAP equal those the run wrote as it went, byte for byte; a run that writes only the MCAP
//! gets them afterwards; a file cut short (a killed run) is exported up to the cut and says so;
//! anything else is refused naming the file.

mod common;

use std::path::{Path, PathBuf};

use common::config;
use protocol::TeleopMode;
use sim_host::output::export::{export, ExportError, ExportTargets};
use sim_host::robot::plant::Plant;
use sim_host::session;
use teleop_core::scripted::PlanStep;

fn dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("export")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Stand, then a steered trot, with every output in `out`.
fn run_into(out: &Path, text_logs: bool) -> session::SessionReport {
    let plan = vec![
        PlanStep::at(0.0, TeleopMode::Stand),
        PlanStep::at(1.0, TeleopMode::TrotForward).with_velocity(0.1, 0.2),
    ];
    let mut cfg = config(Plant::default(), plan, Vec::new(), 5.0);
    cfg.out_dir = Some(out.to_owned());
    cfg.text_logs = text_logs;
    session::run(&cfg).unwrap()
}

fn targets(dir: &Path) -> ExportTargets {
    ExportTargets {
        candump: Some((dir.join("bus.log"), "vcan0".into())),
        csv: Some(dir.join("telemetry.csv")),
    }
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn the_export_of_a_runs_mcap_equals_the_text_logs_the_run_wrote() {
    let live = dir("live");
    let report = run_into(&live, true);
    let exported_dir = dir("exported");
    let exported = export(&live.join("run.mcap"), &targets(&exported_dir)).unwrap();
    let frames = report.stats.frames_sent + report.stats.frames_received;
    assert_eq!(exported.frames, frames);
    assert_eq!(exported.rows, report.stats.cycles);
    for file in ["bus.log", "telemetry.csv"] {
        assert!(
            read(&live.join(file)) == read(&exported_dir.join(file)),
            "{file} differs from the run's"
        );
    }
}

#[test]
fn a_run_without_text_logs_writes_only_the_mcap_and_the_export_makes_them() {
    let out = dir("mcap-only");
    let report = run_into(&out, false);
    assert!(!out.join("bus.log").exists() && !out.join("telemetry.csv").exists());
    assert!(report.files.iter().all(|f| !f.ends_with("bus.log")));
    let exported = export(&out.join("run.mcap"), &targets(&out)).unwrap();
    assert_eq!(exported.rows, report.stats.cycles);
    let csv = read(&out.join("telemetry.csv"));
    assert_eq!(csv.lines().count() as u64, report.stats.cycles + 1);
    let log = read(&out.join("bus.log"));
    assert_eq!(log.lines().count() as u64, exported.frames);
    assert!(log.lines().all(|l| l.contains(" vcan0 ")));
}

#[test]
fn a_file_cut_short_is_exported_up_to_the_cut_and_reported() {
    let live = dir("cut-live");
    run_into(&live, true);
    let whole = std::fs::read(live.join("run.mcap")).unwrap();
    let cut = dir("cut");
    let path = cut.join("run.mcap");
    std::fs::write(&path, &whole[..whole.len() / 2]).unwrap();
    let error = export(&path, &targets(&cut)).unwrap_err();
    let ExportError::CutShort { exported, .. } = &error else {
        panic!("not reported as cut short: {error}");
    };
    assert!(error.to_string().contains("run.mcap ends early"), "{error}");
    assert!(
        exported.rows > 100 && exported.last_time_s > 0.5,
        "{exported:?}"
    );
    // What was exported is the run's logs up to the cut, whole lines.
    for file in ["bus.log", "telemetry.csv"] {
        let part = read(&cut.join(file));
        assert!(!part.is_empty() && part.ends_with('\n'));
        assert!(read(&live.join(file)).starts_with(&part), "{file}");
    }
}

#[test]
fn what_is_not_a_runs_mcap_is_refused_naming_the_file() {
    let out = dir("refused");
    let missing = out.join("missing.mcap");
    let error = export(&missing, &targets(&out)).unwrap_err();
    assert!(matches!(error, ExportError::Read { .. }), "{error}");
    assert!(error.to_string().contains("missing.mcap"));
    let text = out.join("text.mcap");
    std::fs::write(&text, "(0.000000) vcan0 020#00\n").unwrap();
    let error = export(&text, &targets(&out)).unwrap_err();
    assert!(matches!(error, ExportError::NotMcap { .. }), "{error}");
    assert!(error.to_string().contains("text.mcap"));
    // Checked before anything is written: no text log was created.
    assert!(!out.join("bus.log").exists() && !out.join("telemetry.csv").exists());
}

#[test]
fn an_mcap_without_the_topics_the_text_logs_need_is_refused_naming_them() {
    let out = dir("no-topics");
    let path = out.join("empty.mcap");
    let file = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
    mcap::Writer::new(file).unwrap().finish().unwrap();
    let error = export(&path, &targets(&out)).unwrap_err();
    let ExportError::MissingTopic { topic, .. } = &error else {
        panic!("not reported as a missing topic: {error}");
    };
    assert_eq!(*topic, "/can");
    assert!(error.to_string().contains("empty.mcap"), "{error}");
}
