//! `sim-host run` as a user runs it, beside the report's control loop in Python with the official
//! MuJoCo bindings (`xtask/python/report_loop.py`, in the project venv), on the same model and
//! schedule: 120 simulated seconds, STOP for a second and then the trot. Each is run
//! [`RUNS`] times, one after the other, and the medians compared within this run.

use std::process::Command;
use std::time::Instant;

use crate::util::{cargo, root, run, target_dir};

/// Runs of each program; their medians are reported.
const RUNS: usize = 5;

/// Simulated seconds of each run.
const SECONDS: u32 = 120;

/// What the side-by-side runs measured, medians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct WholeRun {
    /// `sim-host run`, whole process, s.
    pub sim_process_s: f64,
    /// `sim-host run`, its loop's steps per second.
    pub sim_loop_steps_per_s: f64,
    /// The report's loop in Python, whole process, s.
    pub python_process_s: f64,
    /// The report's loop in Python, its loop's steps per second.
    pub python_loop_steps_per_s: f64,
}

/// Builds `sim-host` and runs both programs.
pub(super) fn measure() -> Result<WholeRun, String> {
    run(cargo().args(["build", "--release", "-p", "sim-host"]))?;
    let sim_host = target_dir().join("release").join("sim-host");
    let out = target_dir().join("bench-run");
    let model = root().join("sim-host/models/hybrid_robot.xml");
    let script = root().join("xtask/python/report_loop.py");
    let python = crate::setup::venv_python();
    let steps = f64::from(SECONDS) / 0.004;
    let (mut sim, mut py) = (Vec::new(), Vec::new());
    for _ in 0..RUNS {
        let mut command = Command::new(&sim_host);
        command
            .args([
                "run",
                "--drive",
                "0:stand",
                "--drive",
                "1:L",
                "--no-progress",
            ])
            .args(["--duration-s", &SECONDS.to_string(), "--out"])
            .arg(&out);
        let (process_s, stdout) = timed(&mut command)?;
        sim.push((process_s, steps / sim_loop_s(&stdout)?));
        let mut command = Command::new(&python);
        command.arg(&script).arg(&model).arg(SECONDS.to_string());
        let (process_s, stdout) = timed(&mut command)?;
        py.push((process_s, python_steps_per_s(&stdout)?));
    }
    Ok(WholeRun {
        sim_process_s: median(sim.iter().map(|r| r.0)),
        sim_loop_steps_per_s: median(sim.iter().map(|r| r.1)),
        python_process_s: median(py.iter().map(|r| r.0)),
        python_loop_steps_per_s: median(py.iter().map(|r| r.1)),
    })
}

/// The comparison as Markdown, with `raw_steps_per_s` (one MuJoCo step, criterion's median).
pub(super) fn markdown(run: &WholeRun, raw_steps_per_s: f64) -> String {
    format!(
        "| 120 s of trot | whole process | loop steps/s | of raw MuJoCo |\n|---|---|---|---|\n\
         | `sim-host run`, every output (CSV, candump, MCAP, plots) | {:.2} s | {:.0} | {:.0} % |\n\
         | the report's loop, Python bindings | {:.2} s | {:.0} | {:.0} % |\n\n\
         `sim-host run` takes {:.2}× the Python loop's whole-process time (issue 21's goal: at most \
         0.5×); raw MuJoCo steps this model at {:.0} steps/s. Medians of {RUNS} runs each, one \
         after the other.\n",
        run.sim_process_s,
        run.sim_loop_steps_per_s,
        100.0 * run.sim_loop_steps_per_s / raw_steps_per_s,
        run.python_process_s,
        run.python_loop_steps_per_s,
        100.0 * run.python_loop_steps_per_s / raw_steps_per_s,
        run.sim_process_s / run.python_process_s,
        raw_steps_per_s,
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
    }
}
