//! The closed-loop acceptance scenarios with the firmware and the simulator as two processes on
//! one vcan interface, asserting the same figures as the in-process tests.

use hil_tests::{figure, firmware, out_dir, scenario, simulate, Vcan};

#[test]
fn w_over_vcan_drives_1_4_m_in_4_s_on_its_wheels() {
    let bus = Vcan::new();
    let fw = firmware(&bus);
    let out = out_dir("w");
    let summary = simulate(&bus, &out, &["--scenario", &scenario("w.toml")]).expect("summary");
    let _ = fw.terminate();
    let forward = figure(&summary, 1, "forward_m");
    let tilt = figure(&summary, 1, "max_tilt_deg");
    println!("W over vcan: {forward:.3} m, tilt {tilt:.1}°");
    assert!(forward >= 1.4, "{summary}");
    assert!(figure(&summary, 1, "lateral_m").abs() <= 0.15);
    assert!(tilt <= 10.0);
    assert_eq!(figure(&summary, 1, "feet_or_body_on_ground_cycles"), 0.0);
    assert_eq!(summary["missed_cycles"].as_u64(), Some(0), "{summary}");
}

#[test]
fn a_over_vcan_turns_180_degrees_in_2_s() {
    let bus = Vcan::new();
    let fw = firmware(&bus);
    let out = out_dir("a");
    let summary = simulate(&bus, &out, &["--scenario", &scenario("a.toml")]).expect("summary");
    let _ = fw.terminate();
    let yaw = figure(&summary, 1, "dyaw_deg");
    let moved = figure(&summary, 1, "dx_m").hypot(figure(&summary, 1, "dy_m"));
    println!("A over vcan: {yaw:.1}°, centre {moved:.3} m");
    assert!(yaw.abs() >= 180.0 && moved <= 0.10, "{summary}");
}

#[test]
fn l_over_vcan_trots_0_4_m_in_8_s() {
    let bus = Vcan::new();
    let fw = firmware(&bus);
    let out = out_dir("l");
    let summary = simulate(&bus, &out, &["--scenario", &scenario("l.toml")]).expect("summary");
    let _ = fw.terminate();
    let forward = figure(&summary, 1, "forward_m");
    println!("L over vcan: {forward:.3} m");
    assert!(forward >= 0.4, "{summary}");
    assert!(figure(&summary, 1, "max_roll_deg") <= 15.0);
    assert!(figure(&summary, 1, "max_pitch_deg") <= 15.0);
    assert_eq!(figure(&summary, 1, "torso_on_ground_cycles"), 0.0);
}

#[test]
fn all_30_mode_pairs_over_vcan_keep_the_robot_up_and_in_limits() {
    let bus = Vcan::new();
    let fw = firmware(&bus);
    let out = out_dir("pairs");
    let summary =
        simulate(&bus, &out, &["--scenario", &scenario("mode_pairs.toml")]).expect("summary");
    let _ = fw.terminate();
    let segments = summary["segments"].as_array().expect("segments");
    assert_eq!(segments.len(), 31);
    for (i, s) in segments.iter().enumerate() {
        let label = s["label"].as_str().unwrap_or("?");
        assert_eq!(s["fell"].as_bool(), Some(false), "fell in {label}: {s}");
        assert_eq!(
            figure(&summary, i, "joint_limit_violations"),
            0.0,
            "{label}: {s}"
        );
        assert_eq!(
            figure(&summary, i, "torque_limit_violations"),
            0.0,
            "{label}: {s}"
        );
    }
    assert_eq!(summary["missed_cycles"].as_u64(), Some(0), "{summary}");
    println!("30 mode pairs over vcan: no fall, no limit violation");
}

/// The obstacle course in the autonomous mode, the firmware its own process on kernel vcan:
/// the step climbed and left behind, then the ramp rolled over, within the 60 s (the
/// scenario's 56 s of the mode bound it today; the check stays for a longer scenario).
#[test]
fn the_course_over_vcan_is_crossed_end_to_end_in_the_autonomous_mode() {
    let bus = Vcan::new();
    let fw = firmware(&bus);
    let out = out_dir("course");
    let course = hil_tests::workspace().join("scenarios/course.toml");
    let course = course.to_string_lossy();
    let summary = simulate(&bus, &out, &["--scenario", &course]).expect("summary");
    let _ = fw.terminate();
    let auto = &summary["segments"][1];
    assert_eq!(auto["fell"].as_bool(), Some(false), "{auto}");
    let crossings = auto["crossings"].as_array().expect("crossings");
    let past_s = |name: &str| {
        crossings
            .iter()
            .find(|c| c["obstacle"] == name)
            .and_then(|c| c["past_s"].as_f64())
            .unwrap_or_else(|| panic!("{name} not crossed: {auto}"))
    };
    let (step_s, ramp_s) = (past_s("step"), past_s("ramp_down"));
    let climbs = auto["climbs_s"].as_array().expect("climbs_s");
    println!(
        "course over vcan: the step left behind {step_s:.1} s and the ramp {ramp_s:.1} s after the mode began, climbs {climbs:?}"
    );
    assert!(step_s < ramp_s && ramp_s <= 60.0, "{auto}");
    assert_eq!(climbs.len(), 1, "{auto}");
    assert_eq!(summary["missed_cycles"].as_u64(), Some(0), "{summary}");
}
