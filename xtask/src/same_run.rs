//! `cargo xtask same-run REV`: proof that a change left the robot's behaviour alone.
//!
//! Builds `sim-host` from git revision `REV` (extracted with `git archive` under
//! `target/same-run/`, built with its own target folder) and from the working tree, runs every
//! shipped scenario (`scenarios/*.toml`, `scenarios/acceptance/*.toml`) with both in lockstep
//! on the in-process bus, and compares what each leaves: every field of `summary.json` except
//! the wall-clock ones ([`WALL_CLOCK_FIELDS`]), and the bytes of `bus.log` and
//! `telemetry.csv`. Lockstep runs are deterministic, so any difference is a change of
//! behaviour; the first one is named (scenario, file, field path).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use serde_json::Value;

use crate::util::{cargo, root, run as sh};

/// Fields of `summary.json` that measure the machine, not the robot.
const WALL_CLOCK_FIELDS: [&str; 3] = ["wall_s", "real_time_factor", "steps_per_s"];

pub fn run(args: &[String]) -> Result<(), String> {
    let [rev] = args else {
        return Err("usage: cargo xtask same-run REV (a git revision, e.g. HEAD~3)".into());
    };
    crate::setup::run()?;
    let work = root().join("target").join("same-run");
    let old_bin = build_old(rev, &work)?;
    sh(cargo().args(["build", "--quiet", "-p", "sim-host"]))?;
    let new_bin = std::env::var_os("CARGO_TARGET_DIR")
        .map_or_else(|| root().join("target"), PathBuf::from)
        .join("debug")
        .join("sim-host");
    let scenarios = scenarios()?;
    let mut differences = Vec::new();
    for scenario in &scenarios {
        let name = scenario_name(scenario);
        let old_out = work.join("out").join("old").join(&name);
        let new_out = work.join("out").join("new").join(&name);
        simulate(&old_bin, scenario, &old_out)?;
        simulate(&new_bin, scenario, &new_out)?;
        let verdict = compare(&old_out, &new_out)?;
        println!(
            "{name:<28} {}",
            verdict
                .as_deref()
                .unwrap_or("same (summary, bus.log, telemetry.csv)")
        );
        if let Some(what) = verdict {
            differences.push(format!("{name}: {what}"));
        }
    }
    if differences.is_empty() {
        println!(
            "same-run: {} scenarios behave the same at {rev} and in the working tree",
            scenarios.len()
        );
        Ok(())
    } else {
        Err(format!(
            "behaviour changed since {rev}:\n  {}",
            differences.join("\n  ")
        ))
    }
}

/// `sim-host` built from `rev`, in a folder of its own.
fn build_old(rev: &str, work: &Path) -> Result<PathBuf, String> {
    let src = work.join("src");
    if src.exists() {
        std::fs::remove_dir_all(&src).map_err(|e| format!("{}: {e}", src.display()))?;
    }
    std::fs::create_dir_all(&src).map_err(|e| format!("{}: {e}", src.display()))?;
    let mut archive = Command::new("git")
        .args(["archive", "--format=tar", rev])
        .current_dir(root())
        .stdout(Stdio::piped())
        .spawn()
        .map_err(|e| format!("could not run git archive: {e}"))?;
    let Some(tar_input) = archive.stdout.take() else {
        return Err("git archive gave no output".into());
    };
    let extracted = Command::new("tar")
        .args(["-x", "-C"])
        .arg(&src)
        .stdin(tar_input)
        .status()
        .map_err(|e| format!("could not run tar: {e}"))?;
    let archived = archive
        .wait()
        .map_err(|e| format!("git archive did not finish: {e}"))?;
    if !archived.success() || !extracted.success() {
        return Err(format!(
            "could not extract `{rev}`: is it a revision of this repository? (git archive: \
             {archived}, tar: {extracted})"
        ));
    }
    let target = work.join("target");
    sh(cargo()
        .args(["build", "--quiet", "-p", "sim-host"])
        .current_dir(&src)
        .env("CARGO_TARGET_DIR", &target)
        .env(
            "MUJOCO_DYNAMIC_LINK_DIR",
            root().join(".cache").join("mujoco").join("lib"),
        ))?;
    Ok(target.join("debug").join("sim-host"))
}

/// The shipped scenarios, sorted.
fn scenarios() -> Result<Vec<PathBuf>, String> {
    let mut found = Vec::new();
    for dir in ["scenarios", "scenarios/acceptance"] {
        let dir = root().join(dir);
        let entries = std::fs::read_dir(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        for entry in entries {
            let path = entry.map_err(|e| format!("{}: {e}", dir.display()))?.path();
            if path.extension().is_some_and(|ext| ext == "toml") {
                found.push(path);
            }
        }
    }
    found.sort();
    Ok(found)
}

fn scenario_name(path: &Path) -> String {
    let relative = path.strip_prefix(root().join("scenarios")).unwrap_or(path);
    relative
        .with_extension("")
        .to_string_lossy()
        .replace(std::path::MAIN_SEPARATOR, "_")
}

fn simulate(bin: &Path, scenario: &Path, out: &Path) -> Result<(), String> {
    let output = Command::new(bin)
        .arg("run")
        .arg("--scenario")
        .arg(scenario)
        .args(["--no-plots", "--no-progress", "--out"])
        .arg(out)
        .current_dir(root())
        .output()
        .map_err(|e| format!("could not start {}: {e}", bin.display()))?;
    if output.status.success() {
        Ok(())
    } else {
        Err(format!(
            "{} on {} failed ({}):\n{}",
            bin.display(),
            scenario.display(),
            output.status,
            String::from_utf8_lossy(&output.stderr)
        ))
    }
}

/// `None` when the two runs left the same outputs, else what differs first.
fn compare(old: &Path, new: &Path) -> Result<Option<String>, String> {
    let summary = |dir: &Path| -> Result<Value, String> {
        let path = dir.join("summary.json");
        let text =
            std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut value: Value =
            serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
        if let Some(fields) = value.as_object_mut() {
            for field in WALL_CLOCK_FIELDS {
                fields.remove(field);
            }
        }
        Ok(value)
    };
    if let Some(path) = first_difference(&summary(old)?, &summary(new)?, "") {
        return Ok(Some(format!("summary.json differs at {path}")));
    }
    for file in ["bus.log", "telemetry.csv"] {
        let read = |dir: &Path| {
            let path = dir.join(file);
            std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))
        };
        if read(old)? != read(new)? {
            return Ok(Some(format!("{file} differs")));
        }
    }
    Ok(None)
}

/// The path of the first value that differs between `a` and `b` (`None`: equal).
fn first_difference(a: &Value, b: &Value, path: &str) -> Option<String> {
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            let mut keys: Vec<&String> = x.keys().chain(y.keys()).collect();
            keys.sort();
            keys.dedup();
            keys.into_iter().find_map(|key| {
                let here = format!("{path}.{key}");
                match (x.get(key), y.get(key)) {
                    (Some(a), Some(b)) => first_difference(a, b, &here),
                    _ => Some(here),
                }
            })
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => x
            .iter()
            .zip(y)
            .enumerate()
            .find_map(|(i, (a, b))| first_difference(a, b, &format!("{path}[{i}]"))),
        _ if a == b => None,
        _ => Some(if path.is_empty() {
            ".".into()
        } else {
            path.into()
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_difference_is_named_by_its_path() {
        let a: Value = serde_json::json!({"segments": [{"dx_m": 1.0, "fell": false}], "x": 1});
        let b: Value = serde_json::json!({"segments": [{"dx_m": 1.5, "fell": false}], "x": 1});
        assert_eq!(first_difference(&a, &a, ""), None);
        assert_eq!(
            first_difference(&a, &b, ""),
            Some(".segments[0].dx_m".into())
        );
        let c: Value = serde_json::json!({"segments": [], "x": 1});
        assert_eq!(first_difference(&a, &c, ""), Some(".segments".into()));
        let d: Value = serde_json::json!({"x": 1});
        assert_eq!(first_difference(&d, &a, ""), Some(".segments".into()));
    }
}
