//! The judge's verdicts on observations built by hand.
use super::*;
use crate::campaign::observe::{Abort, JointExcess, StopFigures};
use firmware::control::fsm::{LegMotion, State, WheelMotion};
use protocol::FaultFlags;

fn stopped(off_after_s: f64, speed_m_s: f64, abort: bool) -> Observation {
    Observation {
        segments: Vec::new(),
        fell_at_s: None,
        abort: abort.then_some(Abort {
            at_s: 5.0,
            flags: FaultFlags::WHEEL_STALL,
        }),
        balancing_at_s: Some(1.0),
        final_state: None,
        stop: Some(StopFigures {
            speed_at_latch_m_s: speed_m_s,
            rest_after_s: Some(0.5),
            off_after_s: Some(off_after_s),
            reported: true,
            held: true,
            ..StopFigures::default()
        }),
        missed_cycles: 0,
        reported: FaultFlags::EMPTY,
        joint_limits: JointExcess::default(),
        joint_limits_torque_free: JointExcess::default(),
    }
}

fn with_segment(mut obs: Observation) -> Observation {
    let sim = crate::session::simulator::Simulator::new(
        std::path::Path::new(crate::robot::model::DEFAULT_MODEL),
        250,
        crate::session::simulator::StartPose::standing(),
        crate::robot::plant::Plant::default(),
    )
    .unwrap();
    let tracker = crate::output::metrics::SegmentTracker::start(
        "E-stop",
        "E-stop",
        &sim,
        Default::default(),
        &[],
    );
    obs.segments.push(tracker.finish());
    obs
}

#[test]
fn a_stand_up_passes_standing_at_rest_in_place_and_a_stop_with_a_cause_is_a_safe_abort() {
    let judged = |state: State, abort: bool, dx_m: f64| {
        let mut obs = with_segment(stopped(1.0, 0.5, abort));
        obs.stop = None;
        obs.final_state = Some(state);
        let segment = &mut obs.segments[0];
        segment.dx_m = dx_m;
        segment.settled_after_s = Some(2.0);
        segment.max_tilt_deg = 5.0;
        judge(Scenario::StandUp, &obs)
    };
    let standing = State::Legs(LegMotion::Stand);
    assert_eq!(judged(standing, false, 0.02).outcome, Outcome::Pass);
    let away = judged(standing, false, 0.2);
    assert_eq!(
        (away.outcome, away.check.as_str()),
        (Outcome::Missed, "moved")
    );
    let wheels = State::Wheels(WheelMotion::Balance);
    let settling = judged(wheels, false, 0.02);
    assert_eq!(settling.check, "standing at the end");
    assert_eq!(settling.outcome, Outcome::Missed);
    assert_eq!(judged(State::Fault, true, 0.02).outcome, Outcome::Aborted);
}

/// A miss the firmware showed a cause for at the end, without stopping the robot, is a
/// failure that says why; the same miss with nothing shown is silent.
#[test]
fn a_miss_the_firmware_reports_without_stopping_is_told_from_a_silent_one() {
    let mut obs = with_segment(stopped(1.0, 0.5, false));
    obs.stop = None;
    obs.final_state = Some(State::Legs(LegMotion::Stand));
    let segment = &mut obs.segments[0];
    segment.dx_m = 0.3;
    segment.settled_after_s = Some(2.0);
    let silent = judge(Scenario::StandUp, &obs);
    assert_eq!(silent.outcome, Outcome::Missed);
    obs.reported = FaultFlags::STAND_TILTED;
    let told = judge(Scenario::StandUp, &obs);
    assert_eq!(
        (told.outcome, told.check.as_str()),
        (Outcome::Reported, "moved")
    );
    assert!(!told.outcome.success());
    assert!(told.detail.contains("stand_tilted"), "{}", told.detail);
}

#[test]
fn an_abort_excuses_the_speed_before_the_latch_but_not_the_stop_itself() {
    let judged = |obs| judge(Scenario::EStop, &with_segment(obs));
    assert_eq!(judged(stopped(1.0, 0.5, false)).outcome, Outcome::Pass);
    let slow = judged(stopped(1.0, 0.1, false));
    assert_eq!(slow.outcome, Outcome::Missed);
    assert_eq!(slow.check, "at top speed at the latch");
    let aborted = judged(stopped(1.0, 0.1, true));
    assert_eq!(aborted.outcome, Outcome::Aborted);
    // Late torque-off after an abort: a miss, and the late torque-off is what decided it.
    let late = judged(stopped(2.008, 0.1, true));
    assert_eq!(late.outcome, Outcome::Missed);
    assert_eq!(late.check, "torque-free by the SS1 deadline");
    assert!(late.detail.contains("wheel_stall"), "{}", late.detail);
}
