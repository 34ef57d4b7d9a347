//! The closed loop — the firmware's control core driving the simulated robot only through CAN
//! frames on the in-process bus, in lockstep — does every mode of the report, measured from the
//! simulator's ground truth. Lockstep is deterministic, so these figures repeat exactly.

mod common;

use common::{config, plan, scenario_file, segments_of};
use sim_host::output::metrics::SegmentSummary;
use sim_host::robot::plant::Plant;
use sim_host::session::{self, SegmentSpec};
use teleop_core::scenario::Scenario;
use teleop_core::scripted::PlanStep;

/// Runs an acceptance scenario; returns its segments, checking the bus stayed clean.
fn run(name: &str) -> Vec<SegmentSummary> {
    let scenario = Scenario::load(&scenario_file(name)).unwrap();
    let report = session::run(&config(
        Plant::default(),
        scenario.plan(),
        segments_of(&scenario),
        scenario.duration_s,
    ))
    .unwrap();
    assert_eq!(report.stats.missed_cycles, 0);
    assert_eq!(report.firmware_rejected, Some(0));
    assert_eq!(report.drives_rejected, 0);
    report.segments
}

fn assert_wheels_only(s: &SegmentSummary) {
    assert!(!s.fell, "{s:#?}");
    assert!(s.max_tilt_deg <= 10.0, "tilt {:.1}°", s.max_tilt_deg);
    assert_eq!(
        s.feet_or_body_on_ground_cycles, 0,
        "only the wheels touch: {s:#?}"
    );
    assert_eq!(
        s.joint_limit_violations + s.torque_limit_violations,
        0,
        "{s:#?}"
    );
}

#[test]
fn w_drives_forward_at_least_1_4_m_in_4_s_balancing_on_its_wheels() {
    let segments = run("w.toml");
    let w = &segments[1];
    println!("W: {w:#?}");
    assert!(w.forward_m >= 1.4, "forward {:.3} m", w.forward_m);
    assert!(w.lateral_m.abs() <= 0.15, "drift {:.3} m", w.lateral_m);
    assert_wheels_only(w);
}

#[test]
fn s_drives_backward_at_least_1_4_m_in_4_s_balancing_on_its_wheels() {
    let segments = run("s.toml");
    let s = &segments[1];
    println!("S: {s:#?}");
    assert!(s.forward_m <= -1.4, "backward {:.3} m", s.forward_m);
    assert!(s.lateral_m.abs() <= 0.15, "drift {:.3} m", s.lateral_m);
    assert_wheels_only(s);
}

#[test]
fn a_turns_at_least_180_degrees_in_2_s_on_the_spot() {
    let segments = run("a.toml");
    let a = &segments[1];
    println!("A: {a:#?}");
    assert!(a.dyaw_deg.abs() >= 180.0, "yaw {:.1}°", a.dyaw_deg);
    assert!(
        a.dx_m.hypot(a.dy_m) <= 0.10,
        "centre moved {:.3} m",
        a.dx_m.hypot(a.dy_m)
    );
    assert_wheels_only(a);
}

fn assert_trot(s: &SegmentSummary) {
    assert!(!s.fell, "{s:#?}");
    assert!(s.max_roll_deg <= 15.0 && s.max_pitch_deg <= 15.0, "{s:#?}");
    assert_eq!(s.torso_on_ground_cycles, 0, "{s:#?}");
    assert_eq!(s.body_on_ground_cycles, 0, "only feet touch: {s:#?}");
    // A trot stands on diagonal pairs: two feet of one side or one end alone carry the robot
    // only in brief hand-overs.
    assert!(
        (s.non_diagonal_support_cycles as f64) < 0.05 * s.cycles as f64,
        "non-diagonal support in {} of {} cycles",
        s.non_diagonal_support_cycles,
        s.cycles
    );
    assert_eq!(
        s.joint_limit_violations + s.torque_limit_violations,
        0,
        "{s:#?}"
    );
}

#[test]
fn l_trots_forward_at_least_0_4_m_in_8_s() {
    let segments = run("l.toml");
    let l = &segments[1];
    println!("L: {l:#?}");
    assert!(l.forward_m >= 0.4, "forward {:.3} m", l.forward_m);
    assert_trot(l);
}

#[test]
fn k_trots_backward_at_least_0_4_m_in_8_s() {
    let segments = run("k.toml");
    let k = &segments[1];
    println!("K: {k:#?}");
    assert!(k.forward_m <= -0.4, "backward {:.3} m", k.forward_m);
    assert_trot(k);
}

#[test]
fn x_from_every_mode_stops_within_1_s_and_stays_upright() {
    for mode in ["W", "S", "A", "L", "K"] {
        let start = if matches!(mode, "L" | "K") {
            "stand"
        } else {
            "fold"
        };
        let (plan, segments) = plan(&[(0.0, start), (3.0, mode), (6.0, "X")]);
        let report = session::run(&config(Plant::default(), plan, segments, 9.0)).unwrap();
        let x = &report.segments[2];
        println!(
            "{mode} → X: moved {:.3} m after the first second, within 3 cm after {:?} s, tilt {:.1}°",
            x.moved_after_1s_m, x.settled_after_s, x.max_tilt_deg
        );
        assert!(!x.fell, "{mode} → X: {x:#?}");
        assert!(
            x.max_tilt_deg < 20.0,
            "{mode} → X: tilt {:.1}°",
            x.max_tilt_deg
        );
        // Stopped within 1 s: from then on the torso stays within 5 cm — a balancing robot
        // rocks on its wheels and a standing one sways on its servos, neither drives on.
        assert!(
            x.moved_after_1s_m <= 0.05,
            "{mode} → X: moved {:.3} m after the first second",
            x.moved_after_1s_m
        );
    }
}

#[test]
fn every_ordered_pair_of_modes_switched_mid_motion_keeps_the_robot_up_and_in_limits() {
    let modes = ["W", "S", "A", "L", "K", "X"];
    let mut failures = Vec::new();
    for first in modes {
        for second in modes {
            if first == second {
                continue;
            }
            let (plan, segments) = plan(&[(0.0, "X"), (0.5, first), (3.5, second)]);
            let report = session::run(&config(Plant::default(), plan, segments, 7.0)).unwrap();
            for s in &report.segments {
                let bad = s.fell
                    || s.joint_limit_violations > 0
                    || s.torque_limit_violations > 0
                    || s.torso_on_ground_cycles > 0;
                println!(
                    "{first} → {second} [{}]: tilt {:.1}°, joint excess {:.2}°, torque {:.1} N·m{}",
                    s.label,
                    s.max_tilt_deg,
                    s.max_joint_excess_deg,
                    s.max_wheel_torque_nm,
                    if bad { "  ← FAIL" } else { "" }
                );
                if bad {
                    failures.push(format!("{first} → {second} in {}: {s:?}", s.label));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn ten_minutes_of_trotting_behave_like_the_first_ten_seconds() {
    let (plan, _) = plan(&[(0.0, "stand"), (1.0, "L")]);
    let segment = |start_s: f64, label: &str| SegmentSpec {
        start_s,
        label: label.to_owned(),
        mode: "L".to_owned(),
    };
    let segments = vec![
        SegmentSpec {
            start_s: 0.0,
            label: "stand".into(),
            mode: "stand".into(),
        },
        segment(3.0, "first 10 s"),
        segment(13.0, "middle"),
        segment(591.0, "last 10 s"),
    ];
    let report = session::run(&config(Plant::default(), plan, segments, 601.0)).unwrap();
    assert_eq!(report.stats.missed_cycles, 0);
    let (first, middle, last) = (
        &report.segments[1],
        &report.segments[2],
        &report.segments[3],
    );
    println!(
        "first 10 s: {:.3} m, tilt {:.1}°; last 10 s: {:.3} m, tilt {:.1}°",
        first.forward_m, first.max_tilt_deg, last.forward_m, last.max_tilt_deg
    );
    for s in [first, middle, last] {
        assert!(!s.fell, "{s:#?}");
        assert_eq!(
            s.joint_limit_violations + s.torque_limit_violations,
            0,
            "{s:#?}"
        );
        assert_eq!(s.body_on_ground_cycles, 0, "{s:#?}");
    }
    // The same gait: the same speed along the heading within 20 %, the same tilt within 3°.
    assert!(first.forward_m > 0.4, "{first:#?}");
    let ratio = last.forward_m / first.forward_m;
    assert!((0.8..1.25).contains(&ratio), "speed ratio {ratio:.2}");
    assert!((last.max_tilt_deg - first.max_tilt_deg).abs() < 3.0);
}

#[test]
fn body_height_commands_are_held_within_1_cm_where_the_legs_reach() {
    let posture = firmware::config::Config::ROBOT.posture;
    let (lowest, highest) = posture.body_height_range_m();
    let stand_at = |offset_m: f32| {
        let plan = vec![PlanStep {
            at_us: 0,
            mode: protocol::TeleopMode::Stand,
            body_height_m: offset_m,
            speed_scale_pct: 100.0,
            speed_m_s: 0.0,
            yaw_rate_rad_s: 0.0,
        }];
        let report = session::run(&config(Plant::default(), plan, Vec::new(), 3.0)).unwrap();
        let s = &report.segments[0];
        assert!(!s.fell && s.joint_limit_violations == 0, "{s:#?}");
        s.end_height_m
    };
    let nominal = stand_at(0.0);
    for offset in [-0.10_f32, lowest, -0.02, 0.01, highest, 0.12] {
        let height = stand_at(offset);
        let realised = offset.clamp(lowest, highest);
        let change = height - nominal;
        println!("offset {offset:+.3} m (legs realise {realised:+.3}): torso {height:.4} m, change {change:+.4} m");
        assert!(
            (change - f64::from(realised)).abs() <= 0.01,
            "offset {offset}: the torso moved {change:.4} m for {realised:.4} m"
        );
    }
}

#[test]
fn the_30_mode_pairs_in_one_run_keep_the_robot_up_and_in_limits() {
    let segments = run("mode_pairs.toml");
    assert_eq!(segments.len(), 31);
    for s in &segments {
        assert!(!s.fell, "{s:#?}");
        assert_eq!(
            s.joint_limit_violations + s.torque_limit_violations,
            0,
            "{s:#?}"
        );
    }
}
