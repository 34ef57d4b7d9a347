//! The E-stop as a stop of category 1 (IEC 60204-1 "SS1") in the closed loop: the firmware on
//! the in-process bus in lockstep, the emulated drives with their 2 s SS1 timer, an E-stop frame
//! put on the bus mid-motion as `cansend` would, and the outcome measured from the simulator's
//! ground truth (MuJoCo's torso state). Lockstep is deterministic, so the figures repeat exactly.
//!
//! `cargo test -p sim-host --test estop_ss1 -- --nocapture` prints them.

use std::path::Path;

use firmware::control::safety::SS1_DEADLINE_MS;
use host_can::fault_plan::Faults;
use protocol::{AnyMessage, EStop, NodeId, Session, TeleopMode, TEST_KEY};
use sim_host::campaign::estop::{StopFigures, StopTracker};
use sim_host::faults::rig::{Rig, PERIOD_US};
use sim_host::robot::model::DEFAULT_MODEL;
use teleop_core::scripted::PlanStep;

/// What one E-stop did, from the latch on, and whether the robot fell (tilt past 45° or the
/// torso on the ground).
#[derive(Debug)]
struct Figures {
    stop: StopFigures,
    fell: bool,
}

/// Runs `plan`, latches the E-stop at `latch_s` and runs until `end_s`.
fn estop(plan: Vec<PlanStep>, latch_s: f64, end_s: f64) -> Figures {
    let model = Path::new(DEFAULT_MODEL);
    let mut rig = Rig::new(model, plan, &Faults::default(), &Faults::default()).unwrap();
    rig.run_until(latch_s).unwrap();
    let mut tracker = StopTracker::start(&rig);
    // Bound to no session, as an E-stop panel's constant frame.
    let latch = AnyMessage::EStop(EStop::latch(NodeId::Tool))
        .encode(&Session::unjoined(TEST_KEY), 0)
        .unwrap();
    rig.tool_send(&latch).unwrap();
    let end_us = (end_s * 1e6).round() as u64;
    let mut fell = false;
    while rig.stats().cycles * PERIOD_US < end_us {
        rig.step().unwrap();
        let record = rig.records().last().unwrap().clone();
        fell |= record.fallen();
        tracker.observe(&rig, &record);
    }
    Figures {
        stop: tracker.finish(),
        fell,
    }
}

fn deadline_s() -> f64 {
    f64::from(SS1_DEADLINE_MS) * 1e-3
}

/// Every drive torque-free by the SS1 deadline and ever after, `EStop` reported throughout, no
/// fall.
fn assert_stopped_within_the_deadline(what: &str, f: &Figures) {
    assert!(
        f.stop.reported,
        "{what}: EStop not reported from the latch on: {f:#?}"
    );
    let off = f.stop.off_after_s.unwrap_or(f64::INFINITY);
    assert!(
        off <= deadline_s() + 1e-9,
        "{what}: torque-free after {off} s: {f:#?}"
    );
    assert!(f.stop.held, "{what}: a drive came back on: {f:#?}");
    assert!(!f.fell, "{what}: fell: {f:#?}");
}

#[test]
fn an_e_stop_at_top_speed_on_the_wheels_brakes_to_rest_and_sets_the_robot_down() {
    // Fold, W at full speed scale (4 rad/s: 0.48 m/s), steady from about 3 s; latch at 6 s.
    let plan = vec![
        PlanStep::at(0.0, TeleopMode::Fold),
        PlanStep::at(1.5, TeleopMode::WheelForward),
    ];
    let f = estop(plan, 6.0, 6.0 + deadline_s() + 2.5);
    println!("MEASURED E-stop on the wheels at top speed: {f:#?}");
    assert!(f.stop.speed_at_latch_m_s > 0.45, "not at top speed: {f:#?}");
    assert_stopped_within_the_deadline("wheels", &f);
    let rest = f.stop.rest_after_s.unwrap_or(f64::INFINITY);
    assert!(rest <= 1.0, "at rest after {rest} s: {f:#?}");
    assert!(f.stop.max_tilt_to_rest_deg <= 15.0, "{f:#?}");
    assert!(f.stop.max_drop_after_off_m_s <= 0.3, "{f:#?}");
    assert!(f.stop.final_tilt_deg <= 20.0, "{f:#?}");
    // Under power, the front legs swing out on their way into the kickstand so that their
    // sweep does not lift the robot off its wheels (1.17 m/s of descent without; 0.30 with).
    assert!(f.stop.max_drop_before_off_m_s <= 0.35, "{f:#?}");
}

/// The sit-down from the legs: torque-free by the deadline, no fall, resting on the kickstand
/// (the torso does not move when the torque goes), and the torso lowered at no more than
/// 0.3 m/s under power.
fn assert_sat_down(what: &str, f: &Figures) {
    assert_stopped_within_the_deadline(what, f);
    assert!(f.stop.max_drop_before_off_m_s <= 0.3, "{what}: {f:#?}");
    assert!(f.stop.max_drop_after_off_m_s <= 0.3, "{what}: {f:#?}");
    assert!(f.stop.final_tilt_deg <= 20.0, "{what}: {f:#?}");
}

#[test]
fn an_e_stop_while_trotting_sits_the_robot_down() {
    let plan = vec![PlanStep::at(0.0, TeleopMode::TrotForward)];
    let f = estop(plan, 4.0, 4.0 + deadline_s() + 2.5);
    println!("MEASURED E-stop while trotting: {f:#?}");
    assert_sat_down("trot", &f);
}

#[test]
fn an_e_stop_while_standing_sits_the_robot_down() {
    let plan = vec![PlanStep::at(0.0, TeleopMode::Stand)];
    let f = estop(plan, 2.0, 2.0 + deadline_s() + 2.5);
    println!("MEASURED E-stop while standing: {f:#?}");
    assert_sat_down("stand", &f);
}
