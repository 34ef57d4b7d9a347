//! Stops during a climb of the autonomous mode (`firmware::legs::climb`): the operator's STOP
//! before the legs lift the robot takes them back to the fold and it balances where it is;
//! a STOP during the crawl lets the climb end over the step, and the robot balances there;
//! neither drives on. An E-stop latched during the climb stops it at once, and the robot does
//! not fall. Seeded trials over the campaign's robots as built, a 6 cm step 1.2 m behind.
//!
//! `cargo test --release -p sim-host --test climb_stops -- --nocapture` prints the figures.

use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

use firmware::control::fsm::{State, WheelMotion};
use host_can::fault_plan::Faults;
use protocol::{AnyMessage, EStop, NodeId, Session, TeleopMode, TEST_KEY};
use sim_host::campaign::draw::Draws;
use sim_host::campaign::Drives;
use sim_host::faults::rig::Rig;
use sim_host::robot::model::DEFAULT_MODEL;
use sim_host::scene::{mjcf, Scene, Step};
use teleop_core::scripted::PlanStep;

/// The step, m high, and where its riser stands behind the start, m.
const STEP_M: f64 = 0.06;
const RISER_M: f64 = 1.2;
/// Height of the torso's origin over the ground balancing on the wheels, m.
const ON_WHEELS_M: f64 = 0.27;
/// How long after the stop the robot has to end balancing, s.
const SETTLE_S: f64 = 20.0;

/// Runs so far in this process: each writes its scene to a directory of its own (the tests
/// run in parallel, and two writing one file read it half-written).
static RUNS: AtomicU64 = AtomicU64::new(0);

/// What a run did.
#[derive(Debug)]
struct Run {
    /// The controller's states in order, with when each began, s.
    states: Vec<(f64, State)>,
    /// Whether the robot fell (tilt past 45° or the torso on the ground).
    fell: bool,
    /// The torso's height at the end, m.
    torso_z_m: f64,
}

/// Robot `seed` in the autonomous mode toward the step; the operator's `stop` at `stop_s` if
/// any, an E-stop latched at `latch_s` if any; until `end_s`.
fn run(seed: u64, stop_s: Option<f64>, latch_s: Option<f64>, end_s: f64) -> Run {
    let scene = Scene::Step(Step {
        height_m: STEP_M,
        riser_x_m: -RISER_M - 6.0,
        depth_m: 6.0,
    });
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("climb_stops")
        .join(format!("{seed}-{}", RUNS.fetch_add(1, Ordering::Relaxed)));
    let model = mjcf::write(&scene, Path::new(DEFAULT_MODEL), &dir).unwrap();
    let mut plan = vec![
        PlanStep::at(0.0, TeleopMode::Fold),
        PlanStep::at(4.0, TeleopMode::Auto),
    ];
    plan.extend(stop_s.map(|at_s| PlanStep::at(at_s, TeleopMode::Stop)));
    let faults = Faults::default();
    let plant = Draws::of(seed).plant(Drives::Rated.ratings());
    let mut rig = Rig::with_plant(&model, plan, &faults, &faults, plant).unwrap();
    let (mut states, mut fell) = (Vec::new(), false);
    let mut latch_s = latch_s;
    while rig.time_s() < end_s {
        if latch_s.is_some_and(|at_s| rig.time_s() >= at_s) {
            latch_s = None;
            let latch = AnyMessage::EStop(EStop::latch(NodeId::Tool))
                .encode(&Session::unjoined(TEST_KEY), 0)
                .unwrap();
            rig.tool_send(&latch).unwrap();
        }
        rig.step().unwrap();
        let record = rig.records().last().unwrap();
        fell |= record.fallen();
        if let Some(state) = record.state {
            if states.last().is_none_or(|&(_, last)| last != state) {
                states.push((rig.time_s(), state));
            }
        }
    }
    Run {
        states,
        fell,
        torso_z_m: rig.sim().physics().torso().pos_m[2],
    }
}

/// When robot `seed`'s climb begins, s.
fn climb_start_s(seed: u64) -> f64 {
    let free = run(seed, None, None, 12.0);
    free.states
        .iter()
        .find(|(_, s)| matches!(s, State::Climbing(_)))
        .map(|&(t, _)| t)
        .expect("the wheels stall and a climb begins")
}

impl Run {
    /// Whether the robot drove on in the autonomous mode after its climb began.
    fn drove_on(&self) -> bool {
        let start = self
            .states
            .iter()
            .position(|(_, s)| matches!(s, State::Climbing(_)));
        start.is_some_and(|i| {
            self.states[i..]
                .iter()
                .any(|(_, s)| *s == State::Wheels(WheelMotion::Auto))
        })
    }

    fn last(&self) -> Option<State> {
        self.states.last().map(|&(_, s)| s)
    }
}

#[test]
fn a_stop_before_the_rise_folds_back_and_balances_where_the_robot_is() {
    for seed in 0..4 {
        let stop_s = climb_start_s(seed) + 1.0;
        let r = run(seed, Some(stop_s), None, stop_s + SETTLE_S);
        println!("MEASURED stop 1 s into the climb, seed {seed}: {r:?}");
        assert!(!r.fell, "seed {seed}: {r:?}");
        assert!(!r.drove_on(), "seed {seed}: {r:?}");
        assert_eq!(r.last(), Some(State::Wheels(WheelMotion::Balance)), "{r:?}");
        assert!(r.torso_z_m < ON_WHEELS_M + 0.02, "seed {seed}: {r:?}");
    }
}

#[test]
fn a_stop_during_the_crawl_ends_the_climb_over_the_step_and_balances_there() {
    for seed in 0..4 {
        let stop_s = climb_start_s(seed) + 8.0;
        let r = run(seed, Some(stop_s), None, stop_s + SETTLE_S);
        println!("MEASURED stop 8 s into the climb, seed {seed}: {r:?}");
        assert!(!r.fell, "seed {seed}: {r:?}");
        assert!(!r.drove_on(), "seed {seed}: {r:?}");
        assert_eq!(r.last(), Some(State::Wheels(WheelMotion::Balance)), "{r:?}");
        assert!(
            r.torso_z_m > ON_WHEELS_M + STEP_M - 0.01,
            "seed {seed}: {r:?}"
        );
    }
}

#[test]
fn an_estop_during_the_climb_stops_it_and_the_robot_does_not_fall() {
    for seed in 0..4 {
        for into_s in [1.0, 5.0, 9.0] {
            let latch_s = climb_start_s(seed) + into_s;
            let r = run(seed, None, Some(latch_s), latch_s + 6.0);
            println!("MEASURED E-stop {into_s} s into the climb, seed {seed}: {r:?}");
            assert_eq!(r.last(), Some(State::EStop), "{r:?}");
            assert!(!r.fell, "seed {seed}, {into_s} s: {r:?}");
        }
    }
}
