//! The trot's heading hold (`firmware::control::heading`): robots as built that walk circles
//! unheld walk straight once the gyro's bias is measured. Seeded trials on campaign robots the
//! hold was not tuned on (its gains were chosen on robots 0–39): each stands still for 5 s
//! (the estimator measures the gyro's bias), then trots 24 s forward or backward with the
//! operator not steering.
//!
//! `cargo test --release -p sim-host --test heading -- --nocapture` prints the figures.

use std::path::Path;

use host_can::fault_plan::Faults;
use protocol::TeleopMode;
use sim_host::campaign::draw::Draws;
use sim_host::campaign::Drives;
use sim_host::faults::rig::Rig;
use sim_host::robot::model::DEFAULT_MODEL;
use teleop_core::scripted::PlanStep;

/// When the trot starts, s: after the stand-up and a still window.
const TROT_AT_S: f64 = 5.0;

/// How long it trots, s.
const TROT_S: f64 = 24.0;

/// The largest turn allowed, degrees: the obstacle issue's approach within ±15°.
const MAX_TURN_DEG: f64 = 15.0;

/// What one trot did.
#[derive(Debug)]
struct Trial {
    seed: u64,
    turned_deg: f64,
    travelled_m: f64,
    fell: bool,
    calibrated: bool,
}

/// Campaign robot `seed` (drives rated) standing still, then `mode` at [`TROT_AT_S`].
fn stood_then(seed: u64, mode: TeleopMode) -> Rig {
    let plant = Draws::of(seed).plant(Drives::Rated.ratings());
    let plan = vec![
        PlanStep::at(0.0, TeleopMode::Stand),
        PlanStep::at(TROT_AT_S, mode),
    ];
    Rig::with_plant(
        Path::new(DEFAULT_MODEL),
        plan,
        &Faults::default(),
        &Faults::default(),
        plant,
    )
    .unwrap()
}

fn trot(seed: u64, mode: TeleopMode) -> Trial {
    let mut rig = stood_then(seed, mode);
    rig.run_until(TROT_AT_S).unwrap();
    let start = rig.sim().physics().torso();
    let mut fell = false;
    while rig.time_s() < TROT_AT_S + TROT_S {
        rig.step().unwrap();
        fell |= rig.records().last().is_some_and(|r| r.fallen());
    }
    let end = rig.sim().physics().torso();
    let turned_rad = end.rpy_rad()[2] - start.rpy_rad()[2];
    let turned_deg = turned_rad.sin().atan2(turned_rad.cos()).to_degrees();
    let [dx, dy] = [0, 1].map(|i| end.pos_m[i] - start.pos_m[i]);
    let controller = rig.controller().unwrap().node().controller();
    Trial {
        seed,
        turned_deg,
        travelled_m: dx.hypot(dy),
        fell,
        calibrated: controller.sensors().estimator().calibrated(),
    }
}

fn check(mode: TeleopMode) {
    let trials: Vec<Trial> = (100..112).map(|seed| trot(seed, mode)).collect();
    for t in &trials {
        println!(
            "MEASURED {mode:?} robot {}: turned {:+.1}° in {TROT_S} s, travelled {:.2} m, fell {}",
            t.seed, t.turned_deg, t.travelled_m, t.fell
        );
    }
    for t in &trials {
        assert!(t.calibrated, "robot {}: the bias was not measured", t.seed);
        assert!(!t.fell, "robot {} fell", t.seed);
        assert!(
            t.turned_deg.abs() <= MAX_TURN_DEG,
            "robot {} turned {:.1}° trotting {mode:?}",
            t.seed,
            t.turned_deg
        );
        assert!(
            t.travelled_m > 1.5,
            "robot {} travelled {:.2} m",
            t.seed,
            t.travelled_m
        );
    }
}

/// `walk` at no speed and no yaw rate keeps its feet down, held or not: a hold that corrected
/// the body's sway there would march the robot on the spot.
#[test]
fn walk_at_no_speed_keeps_every_foot_down_once_the_bias_is_measured() {
    for seed in [100, 101, 102] {
        let mut rig = stood_then(seed, TeleopMode::Walk);
        // A second for the legs to go from the stand to the trot's stance line.
        rig.run_until(TROT_AT_S + 1.0).unwrap();
        let controller = rig.controller().unwrap().node().controller();
        assert!(controller.sensors().estimator().calibrated());
        let start = rig.sim().physics().torso().pos_m;
        while rig.time_s() < TROT_AT_S + 5.0 {
            rig.step().unwrap();
            let feet = rig.sim().physics().ground_contacts().feet;
            assert!(
                feet.iter().all(|&down| down),
                "robot {seed}: a foot lifted at {:.2} s in walk at no speed",
                rig.time_s()
            );
        }
        let end = rig.sim().physics().torso().pos_m;
        let moved_m = (end[0] - start[0]).hypot(end[1] - start[1]);
        // Planted feet and compliant legs: the body settles a little, it does not walk off.
        assert!(moved_m < 0.05, "robot {seed} moved {moved_m:.3} m");
    }
}

#[test]
fn robots_trotting_forward_hold_their_heading() {
    check(TeleopMode::TrotForward);
}

#[test]
fn robots_trotting_backward_hold_their_heading() {
    check(TeleopMode::TrotBackward);
}
