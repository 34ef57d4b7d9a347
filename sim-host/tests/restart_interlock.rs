//! The restart interlock in the closed loop (issue 17, "controller restart while teleop holds
//! W"): the robot drives forward on its wheels at top speed, the controller restarts (a new
//! process: a new session) and the operator's W keeps coming. No motion command may be obeyed —
//! the new controller holds, reports `AWAITING_STOP` and the robot comes to rest — until the
//! operator sends X and then W again, after which it drives forward again. The firmware on the
//! in-process bus in lockstep, the operator a scripted teleop (which arms a controller on its
//! own only at its start), the outcome from the simulator's ground truth.
//!
//! `cargo test -p sim-host --test restart_interlock -- --nocapture` prints the figures.

use std::path::Path;

use firmware::control::fsm::{Direction, State, WheelMotion};
use host_can::fault_plan::Faults;
use host_can::Bus;
use protocol::{AnyMessage, Epoch, FaultFlags, MessageId, RejectCause, TeleopMode};
use sim_host::faults::rig::{CycleRecord, Rig, RIG_EPOCH};
use sim_host::robot::model::DEFAULT_MODEL;
use teleop_core::scripted::PlanStep;

/// The controller restarts here, 4 s into a steady drive at top speed.
const RESTART_S: f64 = 8.0;
/// The operator sends X here, and W again 0.3 s later.
const STOP_S: f64 = RESTART_S + 3.0;
const DRIVE_AGAIN_S: f64 = STOP_S + 0.3;
const END_S: f64 = DRIVE_AGAIN_S + 3.5;

/// The records from `from_s` (exclusive) to `to_s` (inclusive).
fn between(records: &[CycleRecord], from_s: f64, to_s: f64) -> Vec<&CycleRecord> {
    let (from_us, to_us) = ((from_s * 1e6) as u64, (to_s * 1e6) as u64);
    records
        .iter()
        .filter(|r| r.time_us > from_us && r.time_us <= to_us)
        .collect()
}

/// The torso's horizontal speed over each 0.1 s (25 cycles) of `records`, m/s.
fn speeds(records: &[&CycleRecord]) -> Vec<f64> {
    records
        .windows(26)
        .step_by(25)
        .map(|w| {
            let (a, b) = (w[0].torso_pos_m, w[25].torso_pos_m);
            (b[0] - a[0]).hypot(b[1] - a[1]) / 0.1
        })
        .collect()
}

fn driving(record: &CycleRecord) -> bool {
    record.state == Some(State::Wheels(WheelMotion::Drive(Direction::Forward)))
}

/// Frames the firmware refused so far, for any cause.
fn refused(rig: &Rig) -> u64 {
    RejectCause::ALL
        .iter()
        .map(|&c| rig.firmware_rejected(c))
        .sum()
}

#[test]
fn a_controller_restarted_while_w_is_held_obeys_no_motion_until_x_then_w() {
    let plan = vec![
        PlanStep::at(0.0, TeleopMode::Stop),
        PlanStep::at(0.2, TeleopMode::WheelForward),
        PlanStep::at(STOP_S, TeleopMode::Stop),
        PlanStep::at(DRIVE_AGAIN_S, TeleopMode::WheelForward),
    ];
    let clean = Faults::default();
    let mut rig = Rig::new(Path::new(DEFAULT_MODEL), plan, &clean, &clean).unwrap();
    rig.run_until(RESTART_S).unwrap();
    rig.restart_firmware(Epoch::new(RIG_EPOCH.raw() + 1))
        .unwrap();
    // Once the operator has joined the new session (it hears the announcement within a
    // cycle or two), what it sends is authentic: W held, counted from a listener.
    rig.run_until(RESTART_S + 0.2).unwrap();
    let mut listener = rig.tap();
    let refused_before = refused(&rig);
    rig.run_until(STOP_S).unwrap();
    let refused_in_window = refused(&rig) - refused_before;
    let mut w_heard = 0;
    while let Some(frame) = listener.recv(std::time::Duration::ZERO).unwrap() {
        if frame.id() != MessageId::TeleopCommand.raw() {
            continue;
        }
        let decoded = protocol::decode_frame(frame.id(), frame.data()).unwrap();
        if let AnyMessage::TeleopCommand(c) = decoded.message {
            w_heard += u32::from(c.mode == TeleopMode::WheelForward);
        }
    }
    rig.run_until(END_S).unwrap();
    let records = rig.records();

    let before = between(records, RESTART_S - 1.0, RESTART_S);
    let speed_before = speeds(&before).into_iter().fold(f64::INFINITY, f64::min);
    let interlocked = between(records, RESTART_S, STOP_S);
    let held = interlocked.iter().all(|r| r.state == Some(State::Hold));
    // The new controller's status from its first tick on.
    let awaiting = between(records, RESTART_S + 0.1, STOP_S)
        .iter()
        .all(|r| r.faults.contains(FaultFlags::AWAITING_STOP));
    let settled = between(records, RESTART_S + 1.5, STOP_S);
    let speed_settled = speeds(&settled).into_iter().fold(0.0, f64::max);
    let fell = interlocked.iter().any(|r| r.fallen());
    let max_tilt = interlocked.iter().map(|r| r.tilt_deg).fold(0.0, f64::max);
    let again = between(records, DRIVE_AGAIN_S, END_S);
    let drives_again = again.iter().any(|r| driving(r));
    let advance_m = match (again.first(), again.last()) {
        (Some(a), Some(b)) => b.torso_pos_m[0] - a.torso_pos_m[0],
        _ => 0.0,
    };
    let speed_end = speeds(&again).last().copied().unwrap_or(0.0);
    println!(
        "MEASURED restart while W held: {speed_before:.2} m/s before; then {w_heard} W commands \
         heard in {:.1} s, {refused_in_window} frames refused, held throughout: {held}, \
         AWAITING_STOP: {awaiting}, at most {speed_settled:.3} m/s from 1.5 s after the restart, \
         tilt at most {max_tilt:.1}°; after X then W: driving {drives_again}, {advance_m:.2} m \
         forward, {speed_end:.2} m/s at the end",
        STOP_S - RESTART_S - 0.2
    );
    assert!(
        speed_before > 0.4,
        "not driving at speed before the restart"
    );
    // W kept coming (50 Hz), authentic in the new session, and not one was obeyed.
    assert!(w_heard >= 130, "{w_heard} W commands");
    assert_eq!(refused_in_window, 0);
    assert!(held, "a motion command was obeyed before X then W");
    assert!(awaiting, "AWAITING_STOP not reported");
    assert!(speed_settled < 0.02, "not at rest: {speed_settled} m/s");
    assert!(!fell);
    // X then W: the robot drives forward again.
    assert!(drives_again);
    assert!(advance_m > 0.5, "{advance_m} m");
    assert!(speed_end > 0.4, "{speed_end} m/s");
}
