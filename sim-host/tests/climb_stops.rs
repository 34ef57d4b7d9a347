//! Stops during a climb of the autonomous mode (`firmware::legs::climb`): the operator's STOP
//! before the legs lift the robot takes them back to the fold and it balances where it is;
//! a STOP during the crawl lets the climb end over the step, and the robot balances there;
//! neither drives on. An E-stop latched during the climb stops it at once, and the robot does
//! not fall. Seeded trials over the campaign's robots as built, a 6 cm step 1.2 m behind.
//!
//! `cargo test --release -p sim-host --test climb_stops -- --nocapture` prints the figures.

mod common;

use common::climb::{run, StepBehind, Trial, LONG_PLATEAU_M, ON_WHEELS_M};
use firmware::control::fsm::{State, WheelMotion};
use protocol::TeleopMode;

/// The step: 6 cm high, 1.2 m behind the start.
const STEP: StepBehind = StepBehind {
    height_m: 0.06,
    distance_m: 1.2,
    plateau_m: LONG_PLATEAU_M,
    heading_rad: 0.0,
};
/// How long after the stop the robot has to end balancing, s.
const SETTLE_S: f64 = 20.0;

/// When robot `seed`'s climb begins, s.
fn climb_start_s(seed: u64) -> f64 {
    run(seed, STEP, TeleopMode::Auto, (None, None), 12.0)
        .climb_start_s()
        .expect("the wheels stall and a climb begins")
}

/// Whether the robot drove on in the autonomous mode after its climb began.
fn drove_on(trial: &Trial) -> bool {
    let start = trial
        .states
        .iter()
        .position(|(_, s)| matches!(s, State::Climbing(_)));
    start.is_some_and(|i| {
        trial.states[i..]
            .iter()
            .any(|(_, s)| *s == State::Wheels(WheelMotion::Auto))
    })
}

/// The operator's STOP `into_s` into each robot's climb: it does not fall, does not drive on,
/// and ends balancing, on the plateau if `over_the_step`, at the foot of the step if not.
fn stop_during_the_climb(into_s: f64, over_the_step: bool) {
    for seed in 0..4 {
        let stop_s = climb_start_s(seed) + into_s;
        let r = run(
            seed,
            STEP,
            TeleopMode::Auto,
            (Some(stop_s), None),
            stop_s + SETTLE_S,
        );
        println!("MEASURED stop {into_s} s into the climb, seed {seed}: {r:?}");
        assert!(r.fell_at.is_none(), "seed {seed}: {r:?}");
        assert!(!drove_on(&r), "seed {seed}: {r:?}");
        assert_eq!(r.last(), Some(State::Wheels(WheelMotion::Balance)), "{r:?}");
        if over_the_step {
            assert!(
                r.torso_z_m > ON_WHEELS_M + STEP.height_m - 0.01,
                "seed {seed}: {r:?}"
            );
        } else {
            assert!(r.torso_z_m < ON_WHEELS_M + 0.02, "seed {seed}: {r:?}");
        }
    }
}

#[test]
fn a_stop_before_the_rise_folds_back_and_balances_where_the_robot_is() {
    stop_during_the_climb(1.0, false);
}

#[test]
fn a_stop_during_the_crawl_ends_the_climb_over_the_step_and_balances_there() {
    stop_during_the_climb(8.0, true);
}

#[test]
fn an_estop_during_the_climb_stops_it_and_the_robot_does_not_fall() {
    for seed in 0..4 {
        for into_s in [1.0, 5.0, 9.0] {
            let latch_s = climb_start_s(seed) + into_s;
            let r = run(
                seed,
                STEP,
                TeleopMode::Auto,
                (None, Some(latch_s)),
                latch_s + 6.0,
            );
            println!("MEASURED E-stop {into_s} s into the climb, seed {seed}: {r:?}");
            assert_eq!(r.last(), Some(State::EStop), "{r:?}");
            assert!(r.fell_at.is_none(), "seed {seed}, {into_s} s: {r:?}");
        }
    }
}
