//! What a shell user gets from `teleop` when something is wrong: a message saying what to do
//! and an exit code a script can act on (1 bus, 2 arguments or file, 3 no controller).

use std::process::{Command, Output};

fn teleop(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_teleop"))
        .args(args)
        .output()
        .unwrap()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn a_bad_scenario_file_names_its_line_and_exits_2() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"));
    let file = dir.join("bad_teleop_script.toml");
    std::fs::write(&file, "duration_s = 4\n[[step]]\nat_s = 0\nmode = \"Q\"\n").unwrap();
    let out = teleop(&["--bus", "vcan0", "script", &file.to_string_lossy()]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let text = stderr(&out);
    assert!(text.contains("bad_teleop_script.toml:4:"), "{text}");
    assert!(text.contains(teleop_core::scenario::MODE_NAMES), "{text}");

    let out = teleop(&["script", "no/such/file.toml"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("cannot read the scenario no/such/file.toml"));
}

#[test]
fn wrong_keys_and_options_exit_2_with_what_to_give() {
    let out = teleop(&["send", "Z"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("give one key: W S A L K X T F, or `space`"));
    let out = teleop(&["send", "W", "--for", "-3"]);
    assert_eq!(out.status.code(), Some(2));
    let out = teleop(&["--bus", "vcan0", "--out", "x", "send", "W"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("belong to --bus inproc"));
}

#[test]
fn a_missing_can_interface_exits_1_and_says_how_to_make_one() {
    let out = teleop(&["--bus", "nosuchcan7", "send", "W", "--for", "0.1"]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let text = stderr(&out);
    // Without CAN in the kernel the message says how to load it; with CAN, how to add vcan.
    assert!(
        text.contains("sudo ip link add nosuchcan7 type vcan")
            || text.contains("sudo modprobe can can-raw vcan"),
        "{text}"
    );
    assert!(text.contains("--bus inproc"), "{text}");
}

#[cfg(feature = "sim")]
#[test]
fn inproc_send_drives_the_simulated_robot_without_any_can() {
    let out = teleop(&["--bus", "inproc", "send", "L", "--for", "4"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}{stdout}", stderr(&out));
    assert!(
        stdout.contains("the controller's last mode: TrotForward"),
        "{stdout}"
    );
    let x: f64 = stdout
        .split("ended at x ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!(x > 0.15, "trotted {x} m in 4 s: {stdout}");
}

#[test]
fn a_key_file_that_is_missing_or_malformed_exits_2_naming_it() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"));
    let out = teleop(&["--key-file", "no/such/robot.key", "send", "X"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("key file no/such/robot.key"));
    let file = dir.join("short.key");
    std::fs::write(&file, "0011\n").unwrap();
    let out = teleop(&["--key-file", &file.to_string_lossy(), "send", "X"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("32 hexadecimal digits"),
        "{}",
        stderr(&out)
    );
    let out = teleop(&["--bus", "inproc", "--key-file", &file.to_string_lossy()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("--key-file belongs to a CAN bus"));
}
