//! The transition table of `firmware::control::fsm`, checked cell by cell, and the sequences a robot
//! goes through.

use firmware::control::fsm::{Direction, Event, LegMotion, State, WheelMotion};
use protocol::{ControllerMode, TeleopMode};

use Direction::{Backward, Forward};

const TROT_F: LegMotion = LegMotion::Trot(Forward);
const DRIVE_F: WheelMotion = WheelMotion::Drive(Forward);

fn all_states() -> Vec<State> {
    let legs = [LegMotion::Stand, TROT_F, LegMotion::Trot(Backward)];
    let wheels = [
        WheelMotion::Balance,
        DRIVE_F,
        WheelMotion::Drive(Backward),
        WheelMotion::Rotate,
        WheelMotion::Velocity,
        WheelMotion::Auto,
    ];
    let mut states = vec![State::Hold, State::EStop, State::Fault];
    for m in legs {
        states.push(State::Legs(m));
        states.push(State::Standing(m));
    }
    for m in wheels {
        states.push(State::Folding(m));
        states.push(State::Wheels(m));
        states.push(State::Climbing(m));
    }
    states
}

fn all_events() -> Vec<Event> {
    let mut events: Vec<Event> = [
        TeleopMode::Stop,
        TeleopMode::WheelForward,
        TeleopMode::WheelBackward,
        TeleopMode::WheelRotate,
        TeleopMode::TrotForward,
        TeleopMode::TrotBackward,
        TeleopMode::Stand,
        TeleopMode::Fold,
        TeleopMode::Drive,
        TeleopMode::Walk,
        TeleopMode::Auto,
    ]
    .into_iter()
    .map(Event::Request)
    .collect();
    events.extend([
        Event::TeleopLost,
        Event::LinkDegraded,
        Event::LegBlocked,
        Event::StepStall,
        Event::StepRefused,
        Event::RangeLost,
        Event::PoseReached,
        Event::EStopLatch,
        Event::EStopClear,
        Event::Fault,
        Event::Reset,
    ]);
    events
}

#[test]
fn the_documented_table_row_by_row() {
    use State::*;
    let req = Event::Request;
    let cases = [
        // Hold
        (Hold, req(TeleopMode::Stop), Hold),
        (Hold, req(TeleopMode::Stand), Standing(LegMotion::Stand)),
        (Hold, req(TeleopMode::TrotForward), Standing(TROT_F)),
        (Hold, req(TeleopMode::Fold), Folding(WheelMotion::Balance)),
        (Hold, req(TeleopMode::WheelForward), Folding(DRIVE_F)),
        (Hold, Event::PoseReached, Hold),
        // Legs
        (Legs(TROT_F), req(TeleopMode::Stop), Legs(LegMotion::Stand)),
        (Legs(TROT_F), Event::TeleopLost, Legs(LegMotion::Stand)),
        (Legs(TROT_F), Event::LinkDegraded, Legs(LegMotion::Stand)),
        (Legs(TROT_F), Event::LegBlocked, Legs(LegMotion::Stand)),
        (
            Legs(LegMotion::Stand),
            req(TeleopMode::TrotBackward),
            Legs(LegMotion::Trot(Backward)),
        ),
        (
            Legs(TROT_F),
            req(TeleopMode::WheelRotate),
            Folding(WheelMotion::Rotate),
        ),
        (
            Legs(TROT_F),
            req(TeleopMode::Fold),
            Folding(WheelMotion::Balance),
        ),
        // Standing
        (Standing(TROT_F), Event::PoseReached, Legs(TROT_F)),
        (
            Standing(TROT_F),
            req(TeleopMode::Stop),
            Standing(LegMotion::Stand),
        ),
        (
            Standing(TROT_F),
            req(TeleopMode::WheelForward),
            Folding(DRIVE_F),
        ),
        // Folding
        (Folding(DRIVE_F), Event::PoseReached, Wheels(DRIVE_F)),
        (
            Folding(DRIVE_F),
            req(TeleopMode::Stop),
            Folding(WheelMotion::Balance),
        ),
        (
            Folding(DRIVE_F),
            req(TeleopMode::TrotForward),
            Standing(TROT_F),
        ),
        (
            Folding(DRIVE_F),
            req(TeleopMode::WheelRotate),
            Folding(WheelMotion::Rotate),
        ),
        // Wheels
        (
            Wheels(DRIVE_F),
            req(TeleopMode::Stop),
            Wheels(WheelMotion::Balance),
        ),
        (
            Wheels(DRIVE_F),
            Event::TeleopLost,
            Wheels(WheelMotion::Balance),
        ),
        (
            Wheels(DRIVE_F),
            Event::LinkDegraded,
            Wheels(WheelMotion::Balance),
        ),
        (Hold, Event::LinkDegraded, Hold),
        (Fault, Event::LinkDegraded, Fault),
        (
            Wheels(DRIVE_F),
            req(TeleopMode::WheelRotate),
            Wheels(WheelMotion::Rotate),
        ),
        (Wheels(DRIVE_F), req(TeleopMode::Fold), Wheels(DRIVE_F)),
        (
            Wheels(DRIVE_F),
            req(TeleopMode::TrotForward),
            Standing(TROT_F),
        ),
        (
            Wheels(DRIVE_F),
            req(TeleopMode::Stand),
            Standing(LegMotion::Stand),
        ),
        (Wheels(DRIVE_F), Event::PoseReached, Wheels(DRIVE_F)),
        // Stops
        (EStop, req(TeleopMode::WheelForward), EStop),
        (EStop, Event::Reset, EStop),
        (EStop, Event::Fault, EStop),
        (EStop, Event::EStopClear, Hold),
        (Fault, req(TeleopMode::WheelForward), Fault),
        (Fault, Event::EStopClear, Fault),
        (Fault, Event::Reset, Hold),
        (Fault, Event::EStopLatch, EStop),
        (Legs(TROT_F), Event::Reset, Legs(TROT_F)),
        (Legs(TROT_F), Event::EStopClear, Legs(TROT_F)),
    ];
    for (from, event, to) in cases {
        assert_eq!(from.next(event), to, "{from:?} on {event:?}");
    }
}

#[test]
fn every_request_in_every_state_has_a_defined_safe_result() {
    for state in all_states() {
        for event in all_events() {
            let next = state.next(event);
            // E-stop outranks everything, and only a clear leaves it.
            if event == Event::EStopLatch {
                assert_eq!(next, State::EStop);
            }
            if state == State::EStop && event != Event::EStopClear {
                assert_eq!(next, State::EStop, "{event:?} must not leave EStop");
            }
            if state == State::Fault && !matches!(event, Event::Reset | Event::EStopLatch) {
                assert_eq!(next, State::Fault, "{event:?} must not leave Fault");
            }
            // A stop request never starts a motion. A climb under way ends (back to the fold, or
            // over the step) and then balances: it does not drive on.
            if matches!(
                event,
                Event::Request(TeleopMode::Stop)
                    | Event::TeleopLost
                    | Event::LinkDegraded
                    | Event::LegBlocked
                    | Event::StepRefused
                    | Event::RangeLost
            ) {
                let climbing = matches!(state, State::Climbing(_));
                assert!(
                    matches!(
                        next.mode(),
                        ControllerMode::Stop
                            | ControllerMode::Standing
                            | ControllerMode::Folding
                            | ControllerMode::EStop
                            | ControllerMode::Fault
                    ) || (climbing && next == State::Climbing(WheelMotion::Balance)),
                    "{state:?} on {event:?} → {next:?}"
                );
                assert_ne!(
                    next.next(Event::PoseReached).mode(),
                    ControllerMode::Auto,
                    "{state:?} on {event:?} then its end drives on"
                );
            }
            // Only the autonomous mode's stall starts a climb.
            if matches!(next, State::Climbing(_)) && !matches!(state, State::Climbing(_)) {
                assert_eq!(
                    (state, event),
                    (State::Wheels(WheelMotion::Auto), Event::StepStall)
                );
            }
        }
    }
}

#[test]
fn trot_while_folded_stands_up_first_then_trots() {
    let mut state = State::Wheels(WheelMotion::Balance);
    state = state.next(Event::Request(TeleopMode::TrotForward));
    assert_eq!(state.mode(), ControllerMode::Standing);
    state = state.next(Event::PoseReached);
    assert_eq!(state.mode(), ControllerMode::TrotForward);
}

#[test]
fn wheels_while_trotting_fold_first_then_drive() {
    let mut state = State::Legs(TROT_F);
    state = state.next(Event::Request(TeleopMode::WheelBackward));
    assert_eq!(state.mode(), ControllerMode::Folding);
    state = state.next(Event::PoseReached);
    assert_eq!(state.mode(), ControllerMode::WheelBackward);
}

#[test]
fn the_balance_law_runs_exactly_when_the_wheels_may_carry_the_robot() {
    for state in all_states() {
        let expected = matches!(
            state,
            State::Folding(_) | State::Wheels(_) | State::Standing(_) | State::Climbing(_)
        );
        assert_eq!(state.balancing(), expected, "{state:?}");
    }
}
