//! `firmware-host` as a user meets it: the flags shared with `sim-host`, their old names kept for
//! one release, and an error that says what to do when the interface is missing.

use std::process::Command;

fn firmware_host(args: &[&str]) -> (Option<i32>, String) {
    let output = Command::new(env!("CARGO_BIN_EXE_firmware-host"))
        .args(args)
        .output()
        .unwrap();
    (
        output.status.code(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

#[test]
fn new_and_old_clock_and_rate_flags_are_accepted_and_a_missing_bus_is_named() {
    for flags in [
        ["--clock", "wall", "--control-hz", "250"],
        ["--clock", "timer", "--rate-hz", "250"],
        ["--clock", "lockstep", "--control-hz", "1000"],
    ] {
        let (code, stderr) = firmware_host(&[&["--bus", "nosuchcan7"][..], &flags[..]].concat());
        // Past the flags (a flag error is exit 2 from clap): the bus is what fails.
        assert_eq!(code, Some(1), "{flags:?}: {stderr}");
        assert!(stderr.contains("nosuchcan7"), "{flags:?}: {stderr}");
    }
    let (code, stderr) = firmware_host(&["--clock", "sundial"]);
    assert_eq!(code, Some(2), "an unknown clock is a usage error: {stderr}");
    assert!(
        stderr.contains("lockstep") && stderr.contains("wall"),
        "{stderr}"
    );
}

#[test]
fn an_out_of_range_number_is_a_usage_error_not_a_panic() {
    for value in ["1e20", "0", "-3", "nan", "soon"] {
        let (code, stderr) = firmware_host(&[&format!("--idle-timeout-s={value}")]);
        assert_eq!(code, Some(2), "--idle-timeout-s {value}: {stderr}");
        assert!(stderr.contains("0 < s ≤ 86400"), "{stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
}

#[test]
fn a_missing_interface_does_not_suggest_a_bus_this_program_cannot_use() {
    let (code, stderr) = firmware_host(&["--bus", "nosuchcan8"]);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        !stderr.contains("inproc"),
        "firmware-host has no in-process bus: {stderr}"
    );
}
