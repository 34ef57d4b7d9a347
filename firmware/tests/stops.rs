//! The stops on an ideal plant: the E-stop's latch and release, faults and what resets them,
//! and the restart interlock (nothing moves after a start or a release until the operator's
//! STOP).

mod common;

use common::bench::{estop, ms, torque_free, Bench, CONFIG};
use common::{command, Ticks};

use firmware::control::controller::Output;
use firmware::control::fsm::{State, WheelMotion};
use firmware::control::safety::SS1_DEADLINE_MS;
use protocol::{AnyMessage, EStopAction, FaultFlags, TeleopMode};

#[test]
fn no_request_but_stop_acts_after_start_or_a_release_until_a_stop_arrives() {
    let mut bench = Bench::new();
    let output = bench.run(5);
    assert!(output.status.faults.contains(FaultFlags::AWAITING_STOP));
    // A teleop that holds W from before the controller started moves nothing, nor does any
    // other key.
    for mode in [
        TeleopMode::WheelForward,
        TeleopMode::Stand,
        TeleopMode::Fold,
    ] {
        bench.send(command(mode));
        bench.run(5);
        assert_eq!(bench.state(), State::Hold, "{mode:?} before a STOP");
    }
    // X, then W: the next new request acts.
    bench.send(command(TeleopMode::Stop));
    assert!(!bench
        .tick()
        .status
        .faults
        .contains(FaultFlags::AWAITING_STOP));
    bench.send(command(TeleopMode::WheelForward));
    bench.tick();
    assert!(matches!(bench.state(), State::Folding(_)));
    // An E-stop released (once its stop is over): the robot holds, interlocked again.
    bench.send(estop(EStopAction::Latch));
    bench.tick();
    bench.send(estop(EStopAction::Clear));
    bench.run(ms(SS1_DEADLINE_MS));
    let output = bench.tick();
    assert_eq!(bench.state(), State::Hold);
    assert!(output.status.faults.contains(FaultFlags::AWAITING_STOP));
    bench.send(command(TeleopMode::Fold));
    bench.run(5);
    assert_eq!(bench.state(), State::Hold, "a new key before X");
    bench.send(command(TeleopMode::Stop));
    bench.send(command(TeleopMode::Fold));
    bench.tick();
    assert_eq!(bench.state(), State::Folding(WheelMotion::Balance));
}

/// Latches an E-stop and runs until the SS1 deadline; returns the output of the latch tick and
/// the tick (from the latch) from which every drive was torque-free.
fn latch_and_stop(bench: &mut Bench) -> (Output, Option<u32>) {
    bench.send(estop(EStopAction::Latch));
    let first = bench.tick();
    let mut off_from = torque_free(&first).then_some(0);
    for n in 1..=ms(SS1_DEADLINE_MS) {
        let output = bench.tick();
        assert_eq!(output.status.mode, protocol::ControllerMode::EStop);
        assert!(output.status.faults.contains(FaultFlags::ESTOP_LATCHED));
        match off_from {
            None if torque_free(&output) => off_from = Some(n),
            Some(_) => assert!(torque_free(&output), "tick {n}: a drive came back on"),
            None => {}
        }
    }
    (first, off_from)
}

#[test]
fn an_estop_on_the_wheels_is_a_controlled_stop_that_ends_torque_free_by_the_deadline() {
    let mut bench = Bench::ready();
    bench.send(command(TeleopMode::WheelForward));
    bench.run(1_000);
    assert!(matches!(bench.state(), State::Wheels(_)));
    let (first, off_from) = latch_and_stop(&mut bench);
    // EStop from the latch tick on, but the drives stay powered for the controlled stop.
    assert_eq!(first.status.mode, protocol::ControllerMode::EStop);
    assert!(first.status.faults.contains(FaultFlags::ESTOP_LATCHED));
    assert!(first.legs_enabled);
    let off_from = off_from.expect("torque-free by the deadline");
    assert!(off_from > 0 && off_from < ms(SS1_DEADLINE_MS), "{off_from}");
    // The legs went to the kickstand pose before the cut.
    let kickstand = CONFIG.stop.kickstand();
    for (measured, pose) in bench.joints_rad.iter().zip(kickstand.iter()) {
        assert!((measured - pose).abs() < 1e-4, "{measured} vs {pose}");
    }
}

#[test]
fn an_estop_ignores_every_request_and_only_a_clear_leaves_it() {
    let mut bench = Bench::ready();
    bench.send(command(TeleopMode::Stand));
    bench.run(300);
    bench.send(estop(EStopAction::Latch));
    bench.tick();
    for mode in [
        TeleopMode::Stop,
        TeleopMode::TrotForward,
        TeleopMode::WheelRotate,
        TeleopMode::Stand,
        TeleopMode::Fold,
    ] {
        bench.send(command(mode));
        let output = bench.run(25);
        assert_eq!(bench.state(), State::EStop);
        assert_eq!(output.status.mode, protocol::ControllerMode::EStop);
    }
    // Past the deadline, torque-free until the clear; the clear holds where the legs lie.
    let output = bench.run(ms(SS1_DEADLINE_MS));
    assert!(torque_free(&output));
    bench.send(estop(EStopAction::Clear));
    let output = bench.tick();
    assert_eq!(bench.state(), State::Hold);
    assert!(output.legs_enabled);
    assert_eq!(output.leg_targets_rad, bench.joints_rad);
}

#[test]
fn an_estop_on_the_legs_sits_the_robot_down_then_cuts_by_the_deadline() {
    let mut bench = Bench::ready();
    bench.send(command(TeleopMode::TrotForward));
    bench.run(300);
    let before = bench.joints_rad;
    let (first, off_from) = latch_and_stop(&mut bench);
    assert!(first.legs_enabled);
    // The first tick of the ramp barely moves a joint (smoothstep starts at rest).
    let step = first
        .leg_targets_rad
        .iter()
        .zip(before.iter())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f32::max);
    assert!(step < 0.01, "{step}");
    let off_from = off_from.expect("torque-free by the deadline");
    assert!(off_from > ms(SS1_DEADLINE_MS) / 2, "{off_from}");
    assert!(off_from < ms(SS1_DEADLINE_MS));
}

#[test]
fn an_estop_in_hold_cuts_every_drive_at_once() {
    let mut bench = Bench::new();
    let output = bench.run(5);
    assert!(output.legs_enabled);
    let (first, off_from) = latch_and_stop(&mut bench);
    assert!(torque_free(&first));
    assert_eq!(off_from, Some(0));
}

#[test]
fn a_fault_during_the_controlled_stop_cuts_every_drive_at_once() {
    let mut bench = Bench::ready();
    bench.send(command(TeleopMode::Stand));
    bench.run(300);
    bench.send(estop(EStopAction::Latch));
    let output = bench.run(50);
    assert!(output.legs_enabled);
    // The drives fall silent: the feedback watchdog trips and the stop cuts then, not at the
    // deadline; the state stays EStop (an E-stop outranks a fault).
    bench.drives_alive = false;
    let output = bench.run(ms(CONFIG.feedback_timeout_ms) + 1);
    assert!(torque_free(&output));
    assert_eq!(bench.state(), State::EStop);
    assert!(output.status.faults.contains(FaultFlags::FEEDBACK_TIMEOUT));
    bench.drives_alive = true;
    let output = bench.run(25);
    assert!(torque_free(&output), "a fault's cut holds until the clear");
}

#[test]
fn a_fall_is_a_fault() {
    let mut bench = Bench::ready();
    bench.send(command(TeleopMode::WheelForward));
    bench.run(100);
    bench.pitch_rad = 1.0;
    // 45° at 10 rad/s: 79 ms, and the tick after.
    bench.run(ms(84));
    assert_eq!(bench.state(), State::Fault);
    assert!(bench.tick().status.faults.contains(FaultFlags::TILT_LIMIT));
}

#[test]
fn a_drive_fault_stops_the_robot_until_the_drive_recovers_and_the_operator_resets() {
    use protocol::{Count, Drive, DriveFlags, DriveStatus};
    let status = |flags: DriveFlags| {
        AnyMessage::DriveStatus(
            Drive::LegFl,
            DriveStatus {
                flags,
                rejected: Count::ZERO,
                commands: Count::ZERO,
            },
        )
    };
    let mut bench = Bench::ready();
    bench.send(command(TeleopMode::TrotForward));
    bench.run(300);
    bench.send(status(DriveFlags::ENABLED.with(DriveFlags::FAULT)));
    assert_eq!(bench.state(), State::Fault);
    assert!(bench.tick().status.faults.contains(FaultFlags::DRIVE_FAULT));
    bench.send(command(TeleopMode::Stop));
    assert_eq!(
        bench.state(),
        State::Fault,
        "the drive still reports its fault"
    );
    bench.send(status(DriveFlags::ENABLED));
    // An idle operator repeating STOP resets nothing: the fault needs a new STOP.
    for _ in 0..5 {
        bench.send(command(TeleopMode::Stop));
        bench.tick();
    }
    assert_eq!(bench.state(), State::Fault, "a repeated STOP is no reset");
    bench.send(command(TeleopMode::Stand));
    bench.send(command(TeleopMode::Stop));
    assert_eq!(bench.state(), State::Hold);
    assert!(!bench.tick().status.faults.contains(FaultFlags::DRIVE_FAULT));
}
/// A drive's status frame reporting `flags` for the front-left leg.
fn leg_fl_status(flags: protocol::DriveFlags) -> AnyMessage {
    use protocol::{Count, Drive, DriveStatus};
    AnyMessage::DriveStatus(
        Drive::LegFl,
        DriveStatus {
            flags,
            rejected: Count::ZERO,
            commands: Count::ZERO,
        },
    )
}

/// After a release with `cause` still there, STOP and a new key must start nothing: the
/// release leads to `Fault`, which only a STOP with no cause left resets.
fn assert_release_keeps_the_fault(bench: &mut Bench, cause: FaultFlags) {
    bench.send(estop(EStopAction::Clear));
    let output = bench.tick();
    assert_eq!(bench.state(), State::Fault, "released with {cause:?} held");
    assert!(output.status.faults.contains(cause));
    for mode in [TeleopMode::Stop, TeleopMode::WheelForward] {
        bench.send(command(mode));
        let output = bench.run(25);
        assert_eq!(bench.state(), State::Fault, "{mode:?} after the release");
        assert_eq!(output.wheel_torque_nm, [0.0, 0.0]);
    }
}

#[test]
fn a_release_resets_no_drive_fault_reported_while_latched() {
    use protocol::DriveFlags;
    let mut bench = Bench::ready();
    bench.send(command(TeleopMode::Stand));
    bench.run(300);
    bench.send(estop(EStopAction::Latch));
    bench.run(10);
    bench.send(leg_fl_status(DriveFlags::ENABLED.with(DriveFlags::FAULT)));
    bench.run(ms(SS1_DEADLINE_MS));
    assert_eq!(bench.state(), State::EStop, "an E-stop outranks a fault");
    assert_release_keeps_the_fault(&mut bench, FaultFlags::DRIVE_FAULT);
    // Once the drive recovers, a new STOP resets and the robot holds.
    bench.send(leg_fl_status(DriveFlags::ENABLED));
    bench.send(command(TeleopMode::Stand));
    bench.send(command(TeleopMode::Stop));
    bench.tick();
    assert_eq!(bench.state(), State::Hold);
}

#[test]
fn a_release_resets_no_frozen_sync() {
    let mut bench = Bench::ready();
    bench.send(command(TeleopMode::Stand));
    bench.run(300);
    bench.controller.set_clock_stalled(true);
    bench.send(estop(EStopAction::Latch));
    bench.run(ms(SS1_DEADLINE_MS));
    assert_eq!(bench.state(), State::EStop);
    assert_release_keeps_the_fault(&mut bench, FaultFlags::SYNC_LOST);
}

#[test]
fn a_release_during_the_controlled_stop_waits_for_its_end() {
    let mut bench = Bench::ready();
    bench.send(command(TeleopMode::WheelForward));
    bench.run(ms(6_000));
    assert!(matches!(bench.state(), State::Wheels(_)));
    bench.send(estop(EStopAction::Latch));
    bench.run(50);
    // Released mid-stop: the stop goes on, the robot stays latched.
    bench.send(estop(EStopAction::Clear));
    let mut released_at = None;
    let mut off_seen = false;
    for n in 0..ms(SS1_DEADLINE_MS) {
        let output = bench.tick();
        off_seen |= torque_free(&output);
        if bench.state() != State::EStop {
            released_at = Some(n);
            break;
        }
        assert!(
            !off_seen || torque_free(&output),
            "tick {n}: a drive came back on"
        );
    }
    let released_at = released_at.expect("released once the stop ended");
    assert!(off_seen, "released before the stop was torque-free");
    assert!(released_at > 10, "released at once: {released_at}");
    assert_eq!(bench.state(), State::Hold);
    // A new latch while a release waits cancels it.
    let mut bench = Bench::ready();
    bench.send(command(TeleopMode::WheelForward));
    bench.run(ms(6_000));
    bench.send(estop(EStopAction::Latch));
    bench.run(50);
    bench.send(estop(EStopAction::Clear));
    bench.send(estop(EStopAction::Latch));
    bench.run(ms(SS1_DEADLINE_MS) + 10);
    assert_eq!(bench.state(), State::EStop, "the later latch holds");
}
