//! The autonomous hybrid mode (`H`, `TeleopMode::Auto`) at a step: it drives on its wheels back
//! first, its wheels stall against a 6 cm riser, and the robot climbs it by itself
//! (`firmware::legs::climb`: front feet down, back feet set on the plateau, the legs lift it,
//! crawl back, set it onto its wheels there) and drives on. Seeded trials over the campaign's
//! robots as built (rated drives, real IMU and estimator, a cycle of delay) and the distance
//! to the step. A manual drive (`S`) into the same step still stops with a stall fault.
//!
//! `cargo test --release -p sim-host --test climb -- --nocapture` prints each robot's figures.

mod common;

use common::climb::{run, StepBehind, Trial, ON_WHEELS_M};
use firmware::control::fsm::{State, WheelMotion};
use protocol::TeleopMode;
use sim_host::campaign::draw::Draw;

/// The step's height, m.
const STEP_M: f64 = 0.06;
/// How long a trial runs, s: every climb has ended by then, and the robot drives on.
const END_S: f64 = 25.0;

/// From the start of `trial`'s climb to the wheels carrying the robot again, s.
fn climb_s(trial: &Trial) -> Option<f64> {
    let start = trial.climb_start_s()?;
    let end = trial
        .states
        .iter()
        .find(|&&(t, s)| t > start && matches!(s, State::Wheels(_)))?
        .0;
    Some(end - start)
}

/// Drives robot `seed` in `mode` toward a riser `height_m` high, `distance_m` behind it, for
/// `end_s`.
fn climb(seed: u64, mode: TeleopMode, height_m: f64, distance_m: f64, end_s: f64) -> Trial {
    let step = StepBehind {
        height_m,
        distance_m,
    };
    run(seed, step, mode, (None, None), end_s)
}

/// The longest a crossing may take from the stall to the wheels on the plateau, s (the
/// issue's figure).
const MAX_CLIMB_S: f64 = 20.0;

/// The largest tilt a crossing of a 6 cm step may show, degrees (the pitch figure).
const MAX_TILT_DEG: f64 = 25.0;

/// Whether `f` is a crossing: driving on in the autonomous mode on the plateau (the torso a
/// step's height above where it rides on flat ground, the axle past the riser), never fallen
/// nor tilted past [`MAX_TILT_DEG`].
fn crossed(f: &Trial) -> bool {
    f.fell_at.is_none()
        && climb_s(f).is_some_and(|s| s <= MAX_CLIMB_S)
        && f.max_tilt_deg <= MAX_TILT_DEG
        && f.last() == Some(State::Wheels(WheelMotion::Auto))
        && f.torso_z_m > ON_WHEELS_M + STEP_M - 0.01
        && f.onto_plateau_m > 0.05
}

/// Seeded trials, the riser 1–2 m behind: at least 23 of 24 robots cross (measured: see
/// docs/obstacles.md).
#[test]
fn in_the_autonomous_mode_the_robot_climbs_a_6cm_step_and_drives_on() {
    const TRIALS: u64 = 24;
    let mut crossings = 0;
    for seed in 0..TRIALS {
        let distance_m = 1.0 + 1.0 * Draw::new(seed ^ 0xc11b_0000).unit();
        let f = climb(seed, TeleopMode::Auto, STEP_M, distance_m, END_S);
        let ok = crossed(&f);
        crossings += u64::from(ok);
        println!(
            "MEASURED seed {seed}, riser {distance_m:.2} m behind, crossed {ok}, climb {:?} s: {f:?}",
            climb_s(&f)
        );
    }
    println!("MEASURED {crossings} of {TRIALS} crossed");
    assert!(crossings >= 23, "{crossings} of {TRIALS} crossed");
}

/// `S` is the operator's drive, not the autonomous mode: into the same step it stops with a
/// stall fault where it met it, and does not climb.
#[test]
fn a_manual_drive_into_the_step_stops_with_a_stall_fault_and_does_not_climb() {
    for seed in 0..4 {
        let f = climb(seed, TeleopMode::WheelBackward, STEP_M, 1.2, 12.0);
        println!("MEASURED S, seed {seed}: {f:?}");
        assert!(f.fell_at.is_none(), "seed {seed}: {f:?}");
        assert!(f.climb_start_s().is_none(), "seed {seed}: {f:?}");
        assert_eq!(f.last(), Some(State::Fault), "seed {seed}: {f:?}");
        assert!(f.torso_z_m < ON_WHEELS_M + 0.03, "seed {seed}: {f:?}");
    }
}

/// Higher steps, measured, not asserted (a long task: `cargo test --release -p sim-host --test
/// climb -- --ignored --nocapture`): how many of 12 robots cross 8 cm, and what happens at
/// 10 cm, where the climb should step down again and report `step_refused`.
#[test]
#[ignore = "measurement: the 8 and 10 cm figures in docs/obstacles.md"]
fn higher_steps_measured() {
    for height_m in [0.08, 0.10] {
        let (mut crossed_on_top, mut refused, mut fell) = (0, 0, 0);
        for seed in 0..12 {
            let distance_m = 1.0 + 1.0 * Draw::new(seed ^ 0xc11b_0000).unit();
            let f = climb(seed, TeleopMode::Auto, height_m, distance_m, END_S);
            let on_top = f.fell_at.is_none() && f.torso_z_m > ON_WHEELS_M + height_m - 0.01;
            crossed_on_top += u32::from(on_top);
            let balancing = f.last() == Some(State::Wheels(WheelMotion::Balance));
            refused += u32::from(balancing && !on_top && f.fell_at.is_none());
            fell += u32::from(f.fell_at.is_some());
            println!("MEASURED {height_m} m, seed {seed}: on top {on_top}: {f:?}");
        }
        println!(
            "MEASURED {height_m} m: {crossed_on_top} of 12 on top, {refused} refused and balancing, {fell} fell"
        );
    }
}
