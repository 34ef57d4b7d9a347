//! `sim-host run` as a user meets it: outputs in `--out`, and errors that say what to do.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn sim_host() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sim-host"))
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("sim-host-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn a_run_leaves_telemetry_a_candump_log_and_plots() {
    let out = scratch("run");
    let result = sim_host()
        .args(["run", "--duration-s", "2", "--drive", "0:X", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&result.stdout);
    assert!(
        result.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&result.stderr)
    );
    assert!(
        stdout.contains("cycles           500 (0 missed"),
        "{stdout}"
    );
    assert!(
        stdout.contains("0 by the drives, 0 by the firmware"),
        "{stdout}"
    );
    let csv = std::fs::read_to_string(out.join("telemetry.csv")).unwrap();
    assert_eq!(csv.lines().count(), 501, "a header and one row per cycle");
    let log = std::fs::read_to_string(out.join("bus.log")).unwrap();
    // Every cycle: SYNC, wheel feedback, IMU, four leg feedbacks from the simulator, leg targets
    // and the wheel command from the firmware.
    let syncs = log.lines().filter(|l| l.contains(" vcan0 010##")).count();
    let commands = log.lines().filter(|l| l.contains(" vcan0 101##")).count();
    // The controller's first tick (with its announcement) comes in the cycle in which the
    // simulator joins its session, before the first SYNC.
    assert_eq!((syncs, commands), (500, 501));
    for png in [
        "wheel_torque.png",
        "front_left_joints.png",
        "torso_trajectory.png",
        "torso_height.png",
    ] {
        let bytes = std::fs::read(out.join(png)).unwrap();
        assert!(bytes.starts_with(b"\x89PNG"), "{png}");
    }
}

#[test]
fn a_missing_can_interface_names_the_commands_that_create_it() {
    let result = sim_host()
        .args(["run", "--bus", "vcan-absent9", "--duration-s", "1", "--out"])
        .arg(scratch("novcan"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("sudo modprobe vcan && sudo ip link add vcan-absent9 type vcan")
            || stderr.contains("sudo modprobe can can-raw vcan"),
        "{stderr}"
    );
    assert!(stderr.contains("--bus inproc"), "{stderr}");
}

#[test]
fn a_bad_drive_step_is_rejected_with_the_accepted_keys() {
    let result = sim_host().args(["run", "--drive", "2:Q"]).output().unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(teleop_core::scenario::MODE_NAMES),
        "{stderr}"
    );
}

#[test]
fn a_broken_model_names_the_file() {
    let dir = scratch("model");
    std::fs::create_dir_all(&dir).unwrap();
    let model = dir.join("robot.xml");
    std::fs::write(&model, "<mujoco><worldbody><body></mujoco>").unwrap();
    let result = sim_host()
        .args(["run", "--duration-s", "1", "--model"])
        .arg(&model)
        .arg("--out")
        .arg(dir.join("out"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("robot.xml"), "{stderr}");
}

#[test]
fn the_wall_clock_runs_in_real_time_and_reports_it() {
    // The new flags, then the old names they replace (kept as aliases for one release).
    for (name, args) in [
        ("wall", ["--clock", "wall", "--duration-s", "1"]),
        ("realtime", ["--mode", "realtime", "--duration", "1"]),
    ] {
        let started = std::time::Instant::now();
        let result = sim_host()
            .arg("run")
            .args(args)
            .args(["--no-plots", "--out"])
            .arg(scratch(name))
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&result.stdout);
        assert!(result.status.success(), "{name}: {stdout}");
        assert!(stdout.contains("cycles           250 ("), "{stdout}");
        assert!(stdout.contains("x real time"), "{stdout}");
        // One simulated second takes at least one wall second (longer on a busy machine).
        assert!(started.elapsed() >= std::time::Duration::from_millis(990));
    }
}

#[test]
fn the_old_imu_flag_names_still_work_for_one_release() {
    for flags in [
        [
            "--gyro-noise-rad-s",
            "--gyro-bias-rad-s",
            "--accel-noise-m-s2",
        ],
        ["--gyro-noise", "--gyro-bias", "--accel-noise"],
    ] {
        let result = sim_host()
            .args(["run", "--duration-s", "0.2", "--no-plots", "--out"])
            .arg(scratch(flags[0].trim_start_matches('-')))
            .args([flags[0], "0.01", flags[1], "0.001", flags[2], "0.05"])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert!(result.status.success(), "{flags:?}: {stderr}");
    }
}

#[test]
fn out_of_range_pace_and_duration_are_usage_errors_not_panics_or_hangs() {
    for (flag, value, expected) in [
        ("--pace", "1e-30", "factor of real time"),
        ("--pace", "0", "factor of real time"),
        ("--duration-s", "1e300", "simulated seconds"),
        ("--duration-s", "-1", "simulated seconds"),
    ] {
        let result = sim_host()
            .args(["run", &format!("{flag}={value}")])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(2), "{flag} {value}: {stderr}");
        assert!(stderr.contains(expected), "{flag} {value}: {stderr}");
    }
}

/// The complete lines of a file still being written (a kill can leave half a line).
fn complete_lines(path: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let complete = text.rfind('\n').map_or("", |end| &text[..end]);
    complete.lines().map(str::to_owned).collect()
}

/// The time of the last frame in `out`'s `bus.log`, which must be whole (ending in a complete
/// line) and readable, s.
fn bus_log_end_s(out: &Path) -> f64 {
    let log = std::fs::read_to_string(out.join("bus.log")).unwrap();
    assert!(log.ends_with('\n'), "bus.log ends mid-line");
    let frames = host_can::candump::read_log(&log).expect("a readable candump log");
    frames.last().expect("frames on disk").time_s
}

/// The simulated time of a telemetry row (its first field), s.
fn row_time_s(row: &str) -> f64 {
    row.split(',').next().unwrap().parse().unwrap()
}

/// A 60 s trot paced at real time, logging into `out`.
fn paced_run(out: &Path) -> Child {
    sim_host()
        .args([
            "run",
            "--pace",
            "1",
            "--duration-s",
            "60",
            "--drive",
            "0:L",
            "--no-progress",
        ])
        .arg("--out")
        .arg(out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// When `path` appeared, looking every 2 ms for at most `within`.
fn appeared(path: &Path, within: Duration) -> Instant {
    let start = Instant::now();
    while !path.exists() {
        assert!(
            start.elapsed() < within,
            "{} never appeared",
            path.display()
        );
        std::thread::sleep(Duration::from_millis(2));
    }
    Instant::now()
}

#[test]
fn a_run_killed_after_ten_seconds_leaves_its_logs_readable_up_to_a_second_before_the_kill() {
    let out = scratch("killed");
    let spawned = Instant::now();
    let mut child = paced_run(&out);
    // The logs are created as the simulated clock starts, after the model is loaded: paced at
    // real time, the simulated time is from then on the wall time since.
    let created = appeared(&out.join("bus.log"), Duration::from_secs(9));
    std::thread::sleep(
        (spawned + Duration::from_secs(10)).saturating_duration_since(Instant::now()),
    );
    child.kill().unwrap();
    let killed = Instant::now();
    child.wait().unwrap();
    let simulated_at_kill_s = (killed - created).as_secs_f64();
    // What the run had simulated one wall-clock second before the kill must be on disk.
    let least_s = simulated_at_kill_s - 1.0;
    let rows = complete_lines(&out.join("telemetry.csv"));
    assert!(rows.len() > 1, "no telemetry on disk");
    let last_row_s = row_time_s(rows.last().unwrap());
    let log = complete_lines(&out.join("bus.log")).join("\n");
    let frames = host_can::candump::read_log(&(log + "\n")).expect("a readable candump log");
    let last_frame_s = frames.last().expect("frames on disk").time_s;
    println!(
        "MEASURED killed {:.2} s after the start, about {simulated_at_kill_s:.2} s simulated: \
         telemetry.csv ends at {last_row_s} s, bus.log at {last_frame_s} s",
        (killed - spawned).as_secs_f64()
    );
    assert!(
        last_row_s >= least_s,
        "telemetry ends at {last_row_s} s, killed at about {simulated_at_kill_s:.2} s"
    );
    assert!(
        last_frame_s >= least_s,
        "bus.log ends at {last_frame_s} s, killed at about {simulated_at_kill_s:.2} s"
    );
    // The binary log too: its export says the file was cut short and holds as much.
    let exported = out.join("exported");
    let export = sim_host()
        .arg("export")
        .arg(out.join("run.mcap"))
        .arg("--out")
        .arg(&exported)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&export.stderr);
    assert_eq!(export.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("ends early"), "{stderr}");
    let exported_s = bus_log_end_s(&exported);
    println!("MEASURED run.mcap exported up to {exported_s} s");
    assert!(
        exported_s >= least_s,
        "run.mcap exports up to {exported_s} s, killed at about {simulated_at_kill_s:.2} s"
    );
}

/// The figure after `label` in `sim-host run`'s report (`simulated        12.34 s …`).
fn reported(stdout: &str, label: &str) -> f64 {
    let line = stdout
        .lines()
        .find(|l| l.starts_with(label))
        .unwrap_or_else(|| panic!("no `{label}` line in\n{stdout}"));
    line[label.len()..]
        .split_whitespace()
        .next()
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no figure in `{line}`"))
}

#[test]
fn a_run_sent_sigterm_ends_with_its_logs_complete_up_to_the_signal() {
    let out = scratch("sigterm");
    let child = paced_run(&out);
    appeared(&out.join("bus.log"), Duration::from_secs(10));
    std::thread::sleep(Duration::from_secs(2));
    let term = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(term.success());
    let result = child.wait_with_output().unwrap();
    let stdout = String::from_utf8_lossy(&result.stdout);
    let stderr = String::from_utf8_lossy(&result.stderr);
    // Like Ctrl-C: an orderly end, status 0, saying so.
    assert_eq!(result.status.code(), Some(0), "{stdout}\n{stderr}");
    assert!(stdout.contains("interrupted"), "{stdout}");
    let simulated_s = reported(&stdout, "simulated");
    let cycles = reported(&stdout, "cycles") as usize;
    assert!(simulated_s >= 1.0, "{stdout}");
    // telemetry.csv: whole, one row per simulated cycle, up to the last one.
    let csv = std::fs::read_to_string(out.join("telemetry.csv")).unwrap();
    assert!(csv.ends_with('\n'), "telemetry.csv ends mid-row");
    let lines: Vec<&str> = csv.lines().collect();
    let columns = lines[0].split(',').count();
    assert!(lines.iter().all(|l| l.split(',').count() == columns));
    assert_eq!(lines.len(), cycles + 1, "a header and one row per cycle");
    let last_row_s = row_time_s(lines.last().unwrap());
    assert!(
        (last_row_s - simulated_s).abs() < 0.006,
        "{last_row_s} vs {stdout}"
    );
    // bus.log: whole and readable, up to the last cycle (its frames carry the cycle's start).
    let last_frame_s = bus_log_end_s(&out);
    assert!(
        last_frame_s >= last_row_s - 0.004 - 1e-9,
        "bus.log ends at {last_frame_s} s, telemetry at {last_row_s} s"
    );
    assert!(std::fs::read(out.join("wheel_torque.png"))
        .unwrap()
        .starts_with(b"\x89PNG"));
}

#[test]
fn a_run_whose_physics_diverges_leaves_its_logs_up_to_the_failure() {
    let dir = scratch("diverged");
    let out = dir.join("out");
    // MuJoCo logs its warnings to MUJOCO_LOG.TXT in the working directory.
    std::fs::create_dir_all(&dir).unwrap();
    // A weight on a spring too stiff for the time step: the state overflows after ~2 s.
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/models/diverging.xml");
    let result = sim_host()
        .current_dir(&dir)
        .args([
            "run",
            "--duration-s",
            "5",
            "--drive",
            "0:L",
            "--no-plots",
            "--model",
        ])
        .arg(&model)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(1), "{stderr}");
    let failed_s: f64 = stderr
        .split_once("the simulation diverged at t = ")
        .and_then(|(_, rest)| rest.split_whitespace().next())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("no divergence reported: {stderr}"));
    assert!((1.0..4.0).contains(&failed_s), "{stderr}");
    // The failing cycle started one period before the failure: the row that ended the cycle
    // before it, and the frames it sent and heard (logged at its start), are on disk, whole.
    let last_cycle_s = failed_s - 0.004;
    let csv = std::fs::read_to_string(out.join("telemetry.csv")).unwrap();
    assert!(csv.ends_with('\n'), "telemetry.csv ends mid-row");
    let last_row_s = row_time_s(csv.lines().last().unwrap());
    assert!(
        (last_row_s - last_cycle_s).abs() < 1e-6,
        "telemetry ends at {last_row_s} s, the run failed at {failed_s} s"
    );
    let last_frame_s = bus_log_end_s(&out);
    assert!(
        (last_frame_s - last_cycle_s).abs() < 1e-6,
        "bus.log ends at {last_frame_s} s, the run failed at {failed_s} s"
    );
}

#[test]
fn an_autonomous_run_over_a_step_reports_the_crossing_the_climb_and_the_peak_torques() {
    let out = scratch("auto-step");
    let scenario = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenarios/auto_step.toml");
    let status = sim_host()
        .args([
            "run",
            "--scenario",
            scenario,
            "--no-plots",
            "--no-progress",
            "--out",
        ])
        .arg(&out)
        .status()
        .unwrap();
    assert!(status.success());
    let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
    let summary: serde_json::Value = serde_json::from_str(&text).unwrap();
    let auto = &summary["segments"][1];
    assert_eq!(auto["mode"], "auto");
    // One climb, within the 20 s.
    let climbs = auto["climbs_s"].as_array().unwrap();
    assert_eq!(climbs.len(), 1, "{climbs:?}");
    let climb_s = climbs[0].as_f64().unwrap();
    assert!((5.0..=20.0).contains(&climb_s), "{climb_s} s");
    // The step crossed: touched, a foot on it, all four feet past it.
    let crossing = &auto["crossings"][0];
    assert_eq!(crossing["obstacle"], "step");
    assert!(crossing["past_s"].as_f64().is_some(), "{crossing}");
    // The rated drives cap a leg at its 33.5 N·m peak: the climb never asked for it, and its
    // RMS stays inside the 11 N·m continuous rating.
    for joint in ["hip_abduction", "hip_pitch", "knee", "ankle"] {
        let peak = auto["torques"][joint]["peak_nm"].as_f64().unwrap();
        let rms = auto["torques"][joint]["rms_nm"].as_f64().unwrap();
        assert!(peak > 1.0 && peak < 33.0, "{joint}: peak {peak} N·m");
        assert!(rms <= 11.0, "{joint}: RMS {rms} N·m");
    }
    assert_eq!(auto["fell"], false);
}
