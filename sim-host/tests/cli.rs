//! `sim-host run` as a user meets it: outputs in `--out`, and errors that say what to do.

use std::path::PathBuf;
use std::process::Command;

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
        stderr.contains("use W S A L K X, stand or fold"),
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
fn complete_lines(path: &std::path::Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let complete = text.rfind('\n').map_or("", |end| &text[..end]);
    complete.lines().map(str::to_owned).collect()
}

#[test]
fn a_killed_run_leaves_its_logs_readable_up_to_a_second_before_the_kill() {
    let out = scratch("killed");
    let mut child = sim_host()
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
        .arg(&out)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let started = std::time::Instant::now();
    std::thread::sleep(std::time::Duration::from_secs(4));
    child.kill().unwrap();
    let killed_after_s = started.elapsed().as_secs_f64();
    child.wait().unwrap();
    // Paced to real time, the simulated clock trails the wall clock by the start-up (model
    // load, under a second); the logs may trail the kill by one flush interval.
    let least_s = killed_after_s - 1.0 - 1.0;
    let rows = complete_lines(&out.join("telemetry.csv"));
    assert!(rows.len() > 1, "no telemetry on disk");
    let last_row_s: f64 = rows
        .last()
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(
        last_row_s >= least_s,
        "telemetry ends at {last_row_s} s, killed at {killed_after_s:.2} s"
    );
    let log = std::fs::read_to_string(out.join("bus.log")).unwrap();
    let frames = host_can::candump::read_log(&log).expect("a readable candump log");
    let last_frame_s = frames.last().expect("frames on disk").time_s;
    assert!(last_frame_s >= least_s, "bus.log ends at {last_frame_s} s");
}
