//! The course behind the robot, in the autonomous mode (`H`), end to end: a 6 cm step up onto a
//! 1.2 m plateau and down its far edge, 1.5 m of flat ground, the report's 10° ramp up, its 1 m
//! top and down. The robot climbs the step on its legs, rolls off the plateau, sees the ramp
//! with its rangefinder and rolls over it with its legs clear. Seeded trials over the
//! campaign's robots as built (rated drives, real IMU and estimator, each its own rangefinder
//! part, a cycle of delay), as `scenarios/course.toml` (`cargo xtask demo --course`) runs it.
//!
//! `cargo test --release -p sim-host --test course -- --nocapture` prints each robot's figures.

mod common;

use common::climb::{run_scene, Trial, MODE_AT_S, ON_WHEELS_M};
use firmware::control::fsm::{State, WheelMotion};
use protocol::TeleopMode;
use sim_host::scene::{Course, Scene};
use teleop_core::scripted::PlanStep;

/// How long a trial runs, s: the 60 s for the course, from the mode's start.
const END_S: f64 = MODE_AT_S + 60.0;

/// The largest roll a crossing may show, degrees (the figure for its climbs).
const MAX_ROLL_DEG: f64 = 10.0;

/// The course behind the robot.
const COURSE: Course = Course {
    behind: true,
    ..Course::DEFAULT
};

/// Where the course ends along the path, m (behind the start): the ramp's far foot.
fn far_end_x_m() -> f64 {
    Scene::Course(COURSE)
        .features()
        .iter()
        .map(|feature| feature.x_m[0].min(feature.x_m[1]))
        .fold(f64::INFINITY, f64::min)
}

/// Whether `trial` crossed the whole course: beyond its far end, driving on in the autonomous
/// mode on its wheels at the end, never fallen nor rolled past the limit.
fn crossed(trial: &Trial) -> bool {
    trial.fell_at.is_none()
        && trial.max_roll_deg <= MAX_ROLL_DEG
        && trial.last() == Some(State::Wheels(WheelMotion::Auto))
        && trial.torso_z_m < ON_WHEELS_M + 0.01
        && trial.torso_x_m < far_end_x_m() - 0.3
}

/// The course case: at least 90 % of 20 robots cross it end to end within 60 s of the
/// mode's start, and none falls.
#[test]
fn in_the_autonomous_mode_the_robot_crosses_the_course_end_to_end() {
    const TRIALS: u64 = 20;
    let (mut crossings, mut fell) = (0, 0);
    for seed in 0..TRIALS {
        let plan = vec![
            PlanStep::at(0.0, TeleopMode::Fold),
            PlanStep::at(MODE_AT_S, TeleopMode::Auto),
        ];
        let trial = run_scene(seed, &Scene::Course(COURSE), plan, (MODE_AT_S, None), END_S);
        let ok = crossed(&trial);
        crossings += u64::from(ok);
        fell += u64::from(trial.fell_at.is_some());
        println!(
            "MEASURED course, seed {seed}: crossed {ok}, fell {:?}, tilt {:.1}°, roll {:.1}°, faults {:?}, ended at x {:.2} m (the course ends at {:.2}), states {:?}",
            trial.fell_at,
            trial.max_tilt_deg,
            trial.max_roll_deg,
            trial.faults,
            trial.torso_x_m,
            far_end_x_m(),
            trial.states
        );
    }
    println!("MEASURED course: {crossings} of {TRIALS} crossed end to end, {fell} fell");
    assert_eq!(fell, 0);
    assert!(crossings * 100 >= 90 * TRIALS, "{crossings} of {TRIALS}");
}
