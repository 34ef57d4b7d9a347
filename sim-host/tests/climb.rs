//! The autonomous hybrid mode (`H`, `TeleopMode::Auto`) at a step: it drives on its wheels back
//! first, its wheels stall against a 6 cm riser, and the robot climbs it by itself
//! (`firmware::legs::climb`: front feet down, back feet set on the plateau, the legs lift it,
//! crawl back, set it onto its wheels there) and drives on. Seeded trials over the campaign's
//! robots as built (rated drives, real IMU and estimator, a cycle of delay) and the distance
//! to the step. A manual drive (`S`) into the same step still stops with a stall fault.
//!
//! `cargo test --release -p sim-host --test climb -- --nocapture` prints each robot's figures.

use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

use firmware::control::fsm::{State, WheelMotion};
use host_can::fault_plan::Faults;
use protocol::TeleopMode;
use sim_host::campaign::draw::{Draw, Draws};
use sim_host::campaign::Drives;
use sim_host::faults::rig::Rig;
use sim_host::robot::model::DEFAULT_MODEL;
use sim_host::scene::{mjcf, Scene, Step};
use teleop_core::scripted::PlanStep;

/// The step's height, m.
const STEP_M: f64 = 0.06;
/// How deep the plateau is, m: room to drive on after the climb.
const PLATEAU_M: f64 = 6.0;
/// How long a trial runs, s: every climb has ended by then, and the robot drives on.
const END_S: f64 = 25.0;

/// Height of the torso's origin over the ground balancing on the wheels, m.
const ON_WHEELS_M: f64 = 0.27;

/// Runs so far in this process: each writes its scene to a directory of its own (the tests
/// run in parallel, and two writing one file read it half-written).
static RUNS: AtomicU64 = AtomicU64::new(0);

/// What one trial did.
#[derive(Debug)]
struct Figures {
    /// When it first fell (tilt past 45° or the torso on the ground), s, and the controller's
    /// state then.
    fell_at: Option<(f64, Option<State>)>,
    /// The controller's states in order, with when each began, s.
    states: Vec<(f64, State)>,
    /// The state at the end.
    state: Option<State>,
    /// How far past the riser the axle ended, onto the plateau, m.
    onto_plateau_m: f64,
    /// The torso's height at the end, m.
    torso_z_m: f64,
    /// Largest tilt after the drive began, degrees.
    max_tilt_deg: f64,
}

impl Figures {
    /// From the start of the climb to the wheels carrying the robot again, s.
    fn climb_s(&self) -> Option<f64> {
        let start = self
            .states
            .iter()
            .find(|(_, s)| matches!(s, State::Climbing(_)))?
            .0;
        let end = self
            .states
            .iter()
            .find(|&&(t, s)| t > start && matches!(s, State::Wheels(_)))?
            .0;
        Some(end - start)
    }
}

/// Drives robot `seed` in `mode` toward a 6 cm riser `distance_m` behind it and runs for
/// `end_s`.
fn climb(seed: u64, mode: TeleopMode, distance_m: f64, end_s: f64) -> Figures {
    climb_step(seed, mode, STEP_M, distance_m, end_s)
}

/// As [`climb`], the step `height_m` high.
fn climb_step(seed: u64, mode: TeleopMode, height_m: f64, distance_m: f64, end_s: f64) -> Figures {
    let riser_x_m = -distance_m;
    let scene = Scene::Step(Step {
        height_m,
        riser_x_m: riser_x_m - PLATEAU_M,
        depth_m: PLATEAU_M,
    });
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("climb")
        .join(format!("{seed}-{}", RUNS.fetch_add(1, Ordering::Relaxed)));
    let model = mjcf::write(&scene, Path::new(DEFAULT_MODEL), &dir).unwrap();
    let plan = vec![PlanStep::at(0.0, TeleopMode::Fold), PlanStep::at(4.0, mode)];
    let faults = Faults::default();
    let plant = Draws::of(seed).plant(Drives::Rated.ratings());
    let mut rig = Rig::with_plant(&model, plan, &faults, &faults, plant).unwrap();
    let mut max_tilt_deg = 0.0_f64;
    let (mut fell_at, mut states) = (None, Vec::new());
    while rig.time_s() < end_s {
        rig.step().unwrap();
        let record = rig.records().last().unwrap();
        if record.fallen() && fell_at.is_none() {
            fell_at = Some((rig.time_s(), record.state));
        }
        if let Some(state) = record.state {
            if states.last().is_none_or(|&(_, last)| last != state) {
                states.push((rig.time_s(), state));
            }
        }
        if rig.time_s() > 4.0 {
            max_tilt_deg = max_tilt_deg.max(record.tilt_deg);
        }
    }
    let torso = rig.sim().physics().torso();
    Figures {
        fell_at,
        states,
        state: rig.records().last().unwrap().state,
        onto_plateau_m: riser_x_m - torso.pos_m[0],
        torso_z_m: torso.pos_m[2],
        max_tilt_deg,
    }
}

/// The longest a crossing may take from the stall to the wheels on the plateau, s (the
/// issue's figure).
const MAX_CLIMB_S: f64 = 20.0;

/// The largest tilt a crossing of a 6 cm step may show, degrees (the pitch figure).
const MAX_TILT_DEG: f64 = 25.0;

/// Whether `f` is a crossing: driving on in the autonomous mode on the plateau (the torso a
/// step's height above where it rides on flat ground, the axle past the riser), never fallen
/// nor tilted past [`MAX_TILT_DEG`].
fn crossed(f: &Figures) -> bool {
    f.fell_at.is_none()
        && f.climb_s().is_some_and(|s| s <= MAX_CLIMB_S)
        && f.max_tilt_deg <= MAX_TILT_DEG
        && f.state == Some(State::Wheels(WheelMotion::Auto))
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
        let f = climb(seed, TeleopMode::Auto, distance_m, END_S);
        let ok = crossed(&f);
        crossings += u64::from(ok);
        println!(
            "MEASURED seed {seed}, riser {distance_m:.2} m behind, crossed {ok}, climb {:?} s: {f:?}",
            f.climb_s()
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
        let f = climb(seed, TeleopMode::WheelBackward, 1.2, 12.0);
        println!("MEASURED S, seed {seed}: {f:?}");
        assert!(f.fell_at.is_none(), "seed {seed}: {f:?}");
        assert!(
            !f.states
                .iter()
                .any(|(_, s)| matches!(s, State::Climbing(_))),
            "seed {seed}: {f:?}"
        );
        assert_eq!(f.state, Some(State::Fault), "seed {seed}: {f:?}");
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
            let f = climb_step(seed, TeleopMode::Auto, height_m, distance_m, END_S);
            let on_top = f.fell_at.is_none() && f.torso_z_m > ON_WHEELS_M + height_m - 0.01;
            crossed_on_top += u32::from(on_top);
            let balancing = f.state == Some(State::Wheels(WheelMotion::Balance));
            refused += u32::from(balancing && !on_top && f.fell_at.is_none());
            fell += u32::from(f.fell_at.is_some());
            println!("MEASURED {height_m} m, seed {seed}: on top {on_top}: {f:?}");
        }
        println!(
            "MEASURED {height_m} m: {crossed_on_top} of 12 on top, {refused} refused and balancing, {fell} fell"
        );
    }
}
