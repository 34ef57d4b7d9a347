//! `cargo xtask demo [--bus vcan0] [--out DIR] [--scenario FILE] [--no-render]`: the report's
//! demonstration, closed loop. Sets up (MuJoCo, targets, Mesa), builds `sim-host` in release
//! with the headless renderer, and runs `scenarios/report_demo.toml` — STOP, W, S, A, L, K, X —
//! with the firmware's control core on the in-process CAN bus (or over SocketCAN with `--bus`).
//! Leaves `summary.json`, `telemetry.csv`, `bus.log` (candump), `run.mcap` and `robot.urdf`
//! (Foxglove), the plots, a few rendered frames and their animation `run.gif` in `out/` and
//! prints a table of the segments.
//!
//! `cargo xtask demo --course` runs `scenarios/course.toml` instead, into `out/course/`: the
//! autonomous mode over the course (a step up and down, then the 10° ramp), behind the robot.
//!
//! `cargo xtask demo --teleop` instead opens teleop's terminal UI on the simulated robot: the
//! simulator and the firmware run in the teleop process on the in-process bus, so anyone can
//! drive the robot with the report's keys without a CAN interface. The run's telemetry, bus log
//! and plots land in `out/teleop/` when teleop quits.

use crate::util::{cargo, root, run as sh};

pub fn run(args: &[String]) -> Result<(), String> {
    let mut bus = "inproc".to_owned();
    let mut out = root().join("out");
    let mut scenario: Option<std::path::PathBuf> = None;
    let mut render = true;
    let mut teleop = false;
    let mut course = false;
    let mut rest = args.iter();
    while let Some(arg) = rest.next() {
        let mut value = |name: &str| {
            rest.next()
                .cloned()
                .ok_or_else(|| format!("{name} needs a value"))
        };
        match arg.as_str() {
            "--bus" => bus = value("--bus")?,
            "--out" => out = value("--out")?.into(),
            "--scenario" => scenario = Some(value("--scenario")?.into()),
            "--no-render" => render = false,
            "--teleop" => teleop = true,
            "--course" => course = true,
            other => {
                return Err(format!(
                    "unknown option `{other}`: use --bus IFNAME, --out DIR, --scenario FILE, --no-render, --teleop, --course"
                ))
            }
        }
    }
    if course && scenario.is_some() {
        return Err(
            "give --course (scenarios/course.toml) or --scenario FILE, not both".to_owned(),
        );
    }
    let scenario = match scenario {
        Some(file) => file,
        None if course => {
            out = out.join("course");
            root().join("scenarios").join("course.toml")
        }
        None => root().join("scenarios").join("report_demo.toml"),
    };
    crate::setup::run()?;
    if teleop {
        if bus != "inproc" {
            return Err(format!(
                "--teleop drives the in-process robot; for {bus} run firmware-host and sim-host \
                 there and then `cargo run --release -p teleop -- --bus {bus}`"
            ));
        }
        let out = out.join("teleop");
        sh(cargo()
            .args(["run", "--release", "--quiet", "-p", "teleop", "--"])
            .args(["--bus", "inproc", "--out"])
            .arg(&out))?;
        return Ok(());
    }
    let mut cmd = cargo();
    cmd.args(["run", "--release", "--quiet", "-p", "sim-host"]);
    if render {
        cmd.args(["--features", "renderer"]);
    }
    cmd.args(["--", "run", "--scenario"])
        .arg(&scenario)
        .args(["--bus", &bus, "--out"])
        .arg(&out);
    if render {
        // Every 0.5 s of simulated time: a few dozen frames, each ~80 ms on a software renderer.
        cmd.args(["--render-every", "125"]);
    }
    sh(&mut cmd)?;
    eprintln!(
        "demo: outputs in {} (summary.json, telemetry.csv, bus.log, run.mcap, robot.urdf, *.png{})",
        out.display(),
        if render { ", frames/, run.gif" } else { "" }
    );
    Ok(())
}
