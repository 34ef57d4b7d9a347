//! `sim-host run` as a user runs it — bare and with every output — beside the report's control
//! program in Python with the official MuJoCo bindings (`xtask/python/report_loop.py`, in the
//! project venv: as the report wrote it, and with its name lookups hoisted), on the same model
//! and schedule: 120 simulated seconds, STOP for a second and then the trot. Each is run
//! [`RUNS`] times, interleaved, and the medians compared within this run. Then one hour of the
//! same with every output, for the resident memory at the 5th and the 60th minute.

use std::path::Path;
use std::process::Command;
use std::time::Instant;

use crate::util::{cargo, root, run, target_dir};

/// Runs of each program; their medians are reported.
const RUNS: usize = 5;

/// Simulated seconds of each timed run.
const SECONDS: u32 = 120;

/// Simulated seconds of the memory run.
const SOAK_SECONDS: u32 = 3600;

/// One program's medians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Timing {
    /// Whole process, s.
    pub process_s: f64,
    /// Its loop's steps per second.
    pub loop_steps_per_s: f64,
}

/// What the side-by-side runs measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct WholeRun {
    /// `sim-host run --no-out`.
    pub bare: Timing,
    /// `sim-host run` with every output.
    pub outputs: Timing,
    /// `sim-host run --no-text-logs`: the MCAP, URDF and plots.
    pub mcap_only: Timing,
    /// `sim-host export` of that run's MCAP, whole process, s.
    pub export_s: f64,
    /// The report's program as written.
    pub python: Timing,
    /// The report's program with its lookups hoisted out of the loop.
    pub python_hoisted: Timing,
    /// Resident size at the 5th and the last (60th) simulated minute of an hour's run, bytes.
    pub resident: (f64, f64),
}

/// Builds `sim-host` and runs every program.
pub(super) fn measure() -> Result<WholeRun, String> {
    run(cargo().args(["build", "--release", "-p", "sim-host"]))?;
    let sim_host = target_dir().join("release").join("sim-host");
    let out = target_dir().join("bench-run");
    let mcap_out = target_dir().join("bench-run-mcap");
    let python_out = target_dir().join("bench-run-python");
    let steps = f64::from(SECONDS) / 0.004;
    let mut samples: [Vec<Timing>; 5] = Default::default();
    let mut exports = Vec::new();
    for _ in 0..RUNS {
        let mut bare = sim_run(&sim_host, SECONDS);
        bare.arg("--no-out");
        let mut outputs = sim_run(&sim_host, SECONDS);
        outputs.arg("--out").arg(&out);
        let mut mcap_only = sim_run(&sim_host, SECONDS);
        mcap_only.arg("--no-text-logs").arg("--out").arg(&mcap_out);
        for (k, mut command) in [bare, outputs, mcap_only].into_iter().enumerate() {
            let (process_s, stdout) = timed(&mut command)?;
            samples[k].push(Timing {
                process_s,
                loop_steps_per_s: steps / sim_loop_s(&stdout)?,
            });
        }
        let mut export = Command::new(&sim_host);
        export.arg("export").arg(mcap_out.join("run.mcap"));
        exports.push(timed(&mut export)?.0);
        for (k, hoisted) in [(3, false), (4, true)] {
            let mut command = python_run(&python_out, hoisted);
            let (process_s, stdout) = timed(&mut command)?;
            samples[k].push(Timing {
                process_s,
                loop_steps_per_s: python_steps_per_s(&stdout)?,
            });
        }
    }
    let [bare, outputs, mcap_only, python, python_hoisted] = samples.map(|runs| Timing {
        process_s: median(runs.iter().map(|t| t.process_s)),
        loop_steps_per_s: median(runs.iter().map(|t| t.loop_steps_per_s)),
    });
    let soak_out = target_dir().join("bench-soak");
    let mut soak = sim_run(&sim_host, SOAK_SECONDS);
    soak.arg("--out").arg(&soak_out);
    let (_, stdout) = timed(&mut soak)?;
    // An hour of logs is about 2 GB.
    let _ = std::fs::remove_dir_all(&soak_out);
    Ok(WholeRun {
        bare,
        outputs,
        mcap_only,
        export_s: median(exports.into_iter()),
        python,
        python_hoisted,
        resident: resident_mb(&stdout)?,
    })
}

/// `sim-host run` of `seconds`: a second of STOP-and-stand, then the trot.
fn sim_run(sim_host: &Path, seconds: u32) -> Command {
    let mut command = Command::new(sim_host);
    command
        .args([
            "run",
            "--drive",
            "0:stand",
            "--drive",
            "1:L",
            "--no-progress",
        ])
        .args(["--duration-s", &seconds.to_string()]);
    command
}

/// The report's program in the venv, writing its figures to `out`.
fn python_run(out: &Path, hoisted: bool) -> Command {
    let mut command = Command::new(crate::setup::venv_python());
    command
        .arg(root().join("xtask/python/report_loop.py"))
        .arg(root().join("sim-host/models/hybrid_robot.xml"))
        .arg(SECONDS.to_string())
        .arg(out);
    if hoisted {
        command.arg("--hoisted");
    }
    command
}

/// The comparison as Markdown, with `raw_steps_per_s` (one MuJoCo step) and
/// `closed_steps_per_s` (the closed-loop cycle), criterion's medians.
pub(super) fn markdown(run: &WholeRun, raw_steps_per_s: f64, closed_steps_per_s: f64) -> String {
    let of_raw = |steps_per_s: f64| 100.0 * steps_per_s / raw_steps_per_s;
    let row = |what: &str, t: &Timing| {
        format!(
            "| {what} | {:.2} s | {:.0} | {:.0} % |\n",
            t.process_s,
            t.loop_steps_per_s,
            of_raw(t.loop_steps_per_s)
        )
    };
    let (early, late) = run.resident;
    format!(
        "| 120 s of trot | whole process | loop steps/s | of raw MuJoCo |\n|---|---|---|---|\n\
         | raw MuJoCo, one step (criterion) | — | {raw_steps_per_s:.0} | 100 % |\n\
         | closed loop, one cycle on the wheels (criterion) | — | {closed_steps_per_s:.0} | {:.0} % |\n\
         {}{}{}{}{}\n\
         - With every output the loop runs at **{:.0} %** of raw MuJoCo (issue 21: ≥ 80 %); the \
         outputs cost **{:+.1} %** of the bare loop's time (≤ 10 %).\n\
         - Whole process: `sim-host run` with every output takes **{:.2}×** the report's program \
         (issue 21: ≤ 0.5×), {:.2}× the same with its lookups hoisted.\n\
         - `sim-host export` makes that run's bus.log and telemetry.csv from its MCAP in \
         {:.2} s (the same files the run with every output writes).\n\
         - Resident memory of an hour's run with every output: {:.1} MB at the 5th simulated \
         minute, {:.1} MB at the 60th: **{:+.1} MB** (≤ 5 MB).\n\n\
         Medians of {RUNS} runs each, interleaved; `sim-host run --drive 0:stand --drive 1:L \
         --duration-s {SECONDS}` with `--no-out` (bare) or `--out DIR` (CSV, candump log, MCAP, \
         URDF, plots); `xtask/python/report_loop.py` draws the report's two figures after its \
         loop.\n",
        of_raw(closed_steps_per_s),
        row("`sim-host run --no-out`, bare", &run.bare),
        row(
            "`sim-host run`, every output (CSV, candump, MCAP, plots)",
            &run.outputs
        ),
        row(
            "`sim-host run --no-text-logs`, the MCAP alone (and plots)",
            &run.mcap_only
        ),
        row("the report's program, Python bindings", &run.python),
        row("the same, name lookups hoisted", &run.python_hoisted),
        of_raw(run.outputs.loop_steps_per_s),
        100.0 * (run.bare.loop_steps_per_s / run.outputs.loop_steps_per_s - 1.0),
        run.outputs.process_s / run.python.process_s,
        run.outputs.process_s / run.python_hoisted.process_s,
        run.export_s,
        early / 1e6,
        late / 1e6,
        (late - early) / 1e6,
    )
}

/// Runs `command`, returning its wall time, s, and its standard output.
fn timed(command: &mut Command) -> Result<(f64, String), String> {
    let started = Instant::now();
    let output = command.output().map_err(|e| format!("{command:?}: {e}"))?;
    let elapsed = started.elapsed().as_secs_f64();
    if !output.status.success() {
        return Err(format!(
            "{command:?} failed: {}",
            String::from_utf8_lossy(&output.stderr)
        ));
    }
    Ok((
        elapsed,
        String::from_utf8_lossy(&output.stdout).into_owned(),
    ))
}

/// The loop's wall time from `sim-host run`'s report line `simulated 120.00 s in 1.07 s wall …`.
fn sim_loop_s(stdout: &str) -> Result<f64, String> {
    stdout
        .lines()
        .find_map(|line| {
            let rest = line.strip_prefix("simulated")?;
            let (_, after) = rest.split_once(" in ")?;
            after.split_whitespace().next()?.parse().ok()
        })
        .ok_or_else(|| format!("no `simulated … in … s wall` line in sim-host's output:\n{stdout}"))
}

/// The resident sizes, bytes, from `sim-host run`'s line
/// `memory resident 48.1 MB at 5.0 min, 48.3 MB at 60.0 min (+0.2 MB)`.
fn resident_mb(stdout: &str) -> Result<(f64, f64), String> {
    let line = stdout
        .lines()
        .find_map(|line| line.strip_prefix("memory"))
        .ok_or_else(|| format!("no `memory` line in sim-host's output:\n{stdout}"))?;
    let sizes: Vec<f64> = line
        .split(" MB")
        .filter_map(|part| part.split_whitespace().last()?.parse().ok())
        .collect();
    match sizes[..] {
        [early, late, ..] => Ok((early * 1e6, late * 1e6)),
        _ => Err(format!("no two sizes in sim-host's memory line: {line}")),
    }
}

/// `steps_per_s` from the Python loop's JSON.
fn python_steps_per_s(stdout: &str) -> Result<f64, String> {
    let key = "\"steps_per_s\":";
    let start = stdout
        .find(key)
        .ok_or_else(|| format!("no steps_per_s in the Python loop's output: {stdout}"))?
        + key.len();
    stdout[start..]
        .trim_start()
        .chars()
        .take_while(|c| c.is_ascii_digit() || matches!(c, '.' | 'e' | 'E' | '-' | '+'))
        .collect::<String>()
        .parse()
        .map_err(|e| format!("steps_per_s in {stdout}: {e}"))
}

fn median(values: impl Iterator<Item = f64>) -> f64 {
    let mut sorted: Vec<f64> = values.collect();
    sorted.sort_by(f64::total_cmp);
    sorted.get(sorted.len() / 2).copied().unwrap_or(f64::NAN)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_both_programs_figures() {
        let sim = "model …\nsimulated        120.00 s in 1.07 s wall (112.1x real time)\n";
        assert_eq!(sim_loop_s(sim), Ok(1.07));
        assert!(sim_loop_s("nothing").is_err());
        let py = r#"{"steps": 30000, "loop_s": 0.79, "steps_per_s": 37808.2}"#;
        assert_eq!(python_steps_per_s(py), Ok(37808.2));
        assert_eq!(median([3.0, 1.0, 2.0].into_iter()), 2.0);
        let memory = "cycles 3\nmemory           resident 48.1 MB at 5.0 min, 48.3 MB at 60.0 min (+0.2 MB)\n";
        let (early, late) = resident_mb(memory).unwrap();
        assert!((early - 48.1e6).abs() < 1.0 && (late - 48.3e6).abs() < 1.0);
        assert!(resident_mb("memory           resident 48.1 MB at 0.5 min").is_err());
    }
}
