//! The control step against an ideal plant (every drive reaches its target, the torso stays
//! level): transitions, watchdogs, the E-stop latch, and the safety clamp under arbitrary input.

mod common;

use common::{command, imu, leg_feedback, Ticks};

use firmware::control::controller::Output;
use firmware::control::fsm::{LegMotion, State, WheelMotion};
use firmware::control::safety::SS1_DEADLINE_MS;
use firmware::{Config, Controller, Tick};
use proptest::prelude::*;
use protocol::{
    Acceleration, Angle, AngularRate, AnyMessage, BodyHeight, EStop, EStopAction, FaultFlags, Imu,
    JointVelocity, Joints, Leg, LegFeedback, NodeId, ReleaseToken, SpeedScale, TeleopCommand,
    TeleopHeartbeat, TeleopMode, Torque, WheelFeedback, WheelVelocity,
};

const CONFIG: Config = Config::ROBOT;

/// A plant whose drives reach their targets at once and whose torso stays level.
struct Bench {
    controller: Controller,
    now: u32,
    joints_rad: Joints<f32>,
    drives_alive: bool,
    imu_alive: bool,
    teleop_alive: bool,
    pitch_rad: f32,
}

/// A latch, or a release (the controller takes any token: the node checks it).
fn estop(action: EStopAction) -> AnyMessage {
    AnyMessage::EStop(match action {
        EStopAction::Latch => EStop::latch(NodeId::Tool),
        EStopAction::Clear => EStop::release(NodeId::Tool, ReleaseToken::new(0)),
    })
}

impl Bench {
    fn new() -> Self {
        // Start on the legs, roughly standing.
        let joints = common::standing_joints_rad(&CONFIG);
        Self {
            controller: Controller::new(CONFIG).unwrap(),
            now: 0,
            joints_rad: joints,
            drives_alive: true,
            imu_alive: true,
            teleop_alive: true,
            pitch_rad: 0.0,
        }
    }

    /// A bench run for 5 ticks whose operator has pressed X (STOP): the restart interlock is
    /// released and the next new key acts.
    fn ready() -> Self {
        let mut bench = Self::new();
        bench.run(5);
        bench.send(command(TeleopMode::Stop));
        bench
    }

    fn send(&mut self, message: AnyMessage) {
        self.controller.on_message(Tick(self.now), &message);
    }

    fn tick(&mut self) -> Output {
        let now = Tick(self.now);
        if self.drives_alive {
            for (leg, angles_rad) in self.joints_rad.iter_legs() {
                self.controller
                    .on_message(now, &AnyMessage::LegFeedback(leg, leg_feedback(angles_rad)));
            }
            let wheels_rad_s = common::following_wheels_rad_s(&self.controller);
            self.controller
                .on_message(now, &common::wheels_at(wheels_rad_s));
        }
        if self.imu_alive {
            self.controller
                .on_message(now, &AnyMessage::Imu(imu(self.pitch_rad)));
        }
        if self.teleop_alive && self.now % 5 == 0 {
            self.controller.on_message(
                now,
                &AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
                    uptime: protocol::Millis::from_raw(self.now * 4).unwrap(),
                }),
            );
        }
        let output = self.controller.step(now);
        if output.legs_enabled {
            self.joints_rad = output.leg_targets_rad;
        }
        self.now += 1;
        output
    }

    fn state(&self) -> State {
        self.controller.state()
    }
}

impl Ticks for Bench {
    fn tick(&mut self) -> Output {
        Bench::tick(self)
    }
}

fn ms(ms: u32) -> u32 {
    CONFIG.rate.ticks_from_ms(ms)
}

#[test]
fn drives_stay_torque_free_until_every_drive_has_reported() {
    let mut bench = Bench::new();
    bench.drives_alive = false;
    let output = bench.run(10);
    assert!(!output.legs_enabled);
    assert!(output.status.faults.contains(FaultFlags::FEEDBACK_TIMEOUT));
    assert_eq!(bench.state(), State::Hold);
    bench.drives_alive = true;
    let output = bench.run(2);
    assert!(output.legs_enabled);
    // Holding exactly where the legs are: no jump on power-up.
    assert_eq!(output.leg_targets_rad, bench.joints_rad);
}

#[test]
fn w_folds_the_legs_through_the_touchdown_pose_then_drives_on_the_wheels() {
    let mut bench = Bench::ready();
    bench.send(command(TeleopMode::WheelForward));
    let output = bench.tick();
    let folding = State::Folding(WheelMotion::Drive(
        firmware::control::fsm::Direction::Forward,
    ));
    assert_eq!(bench.state(), folding);
    assert_eq!(output.status.mode, protocol::ControllerMode::Folding);
    // The legs carry the torso down into the touchdown pose, then tuck into the fold: the
    // touchdown pose is passed on the way (see `legs::transfer`).
    let touchdown = CONFIG.transfer.touchdown.to_array();
    let mut closest_rad = f32::MAX;
    let mut ticks = 1;
    while matches!(bench.state(), State::Folding(_)) {
        bench.tick();
        ticks += 1;
        let off = bench.joints_rad.leg(Leg::Fl).iter().zip(&touchdown);
        closest_rad = closest_rad.min(off.map(|(a, b)| (a - b).abs()).fold(0.0, f32::max));
        assert!(ticks < 2_000, "folding never finished");
    }
    assert!(
        closest_rad < 1e-3,
        "never in the touchdown pose: {closest_rad} rad off"
    );
    // Carried at 0.6 rad/s and tucked at 1.5 rad/s (peaks): a few seconds, not the report's
    // lunge of 0.85 s.
    let seconds = ticks as f32 / 250.0;
    assert!((1.5..4.0).contains(&seconds), "folded in {seconds} s");
    assert_eq!(
        bench.state(),
        State::Wheels(WheelMotion::Drive(
            firmware::control::fsm::Direction::Forward
        ))
    );
    // The fold: front hips at +50°, back hips at −45° (see `Posture::ROBOT`).
    let front_hip = bench.joints_rad.leg(Leg::Fl)[1];
    let back_hip = bench.joints_rad.leg(Leg::Bl)[1];
    assert!(
        (front_hip - 50f32.to_radians()).abs() < 0.011,
        "front hip {front_hip}"
    );
    assert!(
        (back_hip - (-45f32).to_radians()).abs() < 0.011,
        "back hip {back_hip}"
    );
}

#[test]
fn trot_from_the_wheels_stands_up_first() {
    let mut bench = Bench::ready();
    bench.send(command(TeleopMode::Fold));
    bench.run(1_000);
    assert_eq!(bench.state(), State::Wheels(WheelMotion::Balance));
    bench.send(command(TeleopMode::TrotForward));
    bench.tick();
    assert_eq!(
        bench.state(),
        State::Standing(LegMotion::Trot(firmware::control::fsm::Direction::Forward))
    );
    bench.run(400);
    assert_eq!(
        bench.state(),
        State::Legs(LegMotion::Trot(firmware::control::fsm::Direction::Forward))
    );
    // And the legs now move: the gait, not a frozen pose.
    let a = bench.tick().leg_targets_rad;
    let b = bench.run(60).leg_targets_rad;
    assert!(a.iter().zip(b).any(|(x, y)| (x - y).abs() > 0.02));
}

#[test]
fn silent_feedback_safe_stops_within_fifty_milliseconds() {
    let mut bench = Bench::ready();
    bench.send(command(TeleopMode::TrotForward));
    bench.run(300);
    assert!(matches!(bench.state(), State::Legs(LegMotion::Trot(_))));
    bench.drives_alive = false;
    let mut ticks = 0;
    while bench.state() != State::Fault {
        bench.tick();
        ticks += 1;
        assert!(ticks <= ms(50) + 1, "no fault after {ticks} ticks");
    }
    assert!(ticks * 4 <= 56, "fault after {} ms", ticks * 4);
    let output = bench.tick();
    assert!(output.status.faults.contains(FaultFlags::FEEDBACK_TIMEOUT));
    assert_eq!(output.wheel_torque_nm, [0.0, 0.0]);
    // Holds its legs where they were, and stays faulted while feedback is missing.
    let held = output.leg_targets_rad;
    assert_eq!(bench.run(50).leg_targets_rad, held);
    bench.send(command(TeleopMode::Stop));
    assert_eq!(bench.state(), State::Fault);
    // Feedback back and the operator asks to stop: reset to Hold.
    bench.drives_alive = true;
    bench.tick();
    bench.send(command(TeleopMode::Stand));
    bench.send(command(TeleopMode::Stop));
    assert_eq!(bench.state(), State::Hold);
}

#[test]
fn a_silent_operator_stops_the_robot_within_half_a_second_of_teleop_dying() {
    let mut bench = Bench::ready();
    bench.send(command(TeleopMode::TrotForward));
    bench.run(300);
    while bench.now % 5 != 1 {
        bench.tick();
    }
    // The last heartbeat went out on the previous tick.
    bench.teleop_alive = false;
    let mut ticks = 1;
    while matches!(bench.state(), State::Legs(LegMotion::Trot(_))) {
        bench.tick();
        ticks += 1;
        assert!(ticks < 200, "still trotting");
    }
    let silent_ms = ticks * 4;
    assert!(
        (460..=468).contains(&silent_ms),
        "stopped {silent_ms} ms after the last heartbeat"
    );
    assert_eq!(bench.state(), State::Legs(LegMotion::Stand));
    assert!(bench
        .tick()
        .status
        .faults
        .contains(FaultFlags::TELEOP_TIMEOUT));
    // The operator comes back still holding L: no restart without a new key, and the lost
    // operator engaged the restart interlock, so not even a new key acts before X.
    bench.teleop_alive = true;
    bench.send(command(TeleopMode::TrotForward));
    bench.run(20);
    assert_eq!(bench.state(), State::Legs(LegMotion::Stand));
    bench.send(command(TeleopMode::TrotBackward));
    let output = bench.run(20);
    assert_eq!(bench.state(), State::Legs(LegMotion::Stand));
    assert!(output.status.faults.contains(FaultFlags::AWAITING_STOP));
    bench.send(command(TeleopMode::Stop));
    bench.send(command(TeleopMode::TrotForward));
    let output = bench.tick();
    assert!(matches!(bench.state(), State::Legs(LegMotion::Trot(_))));
    assert!(!output.status.faults.contains(FaultFlags::AWAITING_STOP));
}

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
    // An E-stop released: the robot holds, interlocked again.
    bench.send(estop(EStopAction::Latch));
    bench.tick();
    bench.send(estop(EStopAction::Clear));
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

fn torque_free(output: &Output) -> bool {
    !output.legs_enabled && output.wheel_torque_nm == [0.0, 0.0]
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
    bench.run(2);
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

fn any_message() -> impl Strategy<Value = AnyMessage> {
    let angle = (-3.3f32..3.3).prop_map(Angle::saturating_from_si);
    let leg = prop::sample::select(Leg::ALL.to_vec());
    let mode = (0u8..8).prop_map(|raw| TeleopMode::from_raw(raw).unwrap());
    prop_oneof![
        (leg, prop::array::uniform4(angle.clone())).prop_map(|(leg, position)| {
            AnyMessage::LegFeedback(
                leg,
                LegFeedback {
                    position,
                    velocity: [JointVelocity::saturating_from_si(1.0); 4],
                    effort: [Torque::saturating_from_si(0.0); 4],
                },
            )
        }),
        (
            prop::array::uniform4(-1.0f32..1.0),
            prop::array::uniform3(-30.0f32..30.0)
        )
            .prop_map(|(q, w)| AnyMessage::Imu(Imu {
                orientation: Imu::orientation_of(q),
                angular_rate: w.map(AngularRate::saturating_from_si),
                acceleration: [Acceleration::saturating_from_si(0.0); 3],
            })),
        prop::array::uniform2(-300.0f32..300.0).prop_map(|v| AnyMessage::WheelFeedback(
            WheelFeedback {
                velocity: v.map(WheelVelocity::saturating_from_si),
                effort: [Torque::saturating_from_si(0.0); 2],
            }
        )),
        (mode, -0.2f32..0.2, 0u8..=100).prop_map(|(mode, h, s)| AnyMessage::TeleopCommand(
            TeleopCommand {
                mode,
                body_height: BodyHeight::saturating_from_si(h),
                speed_scale: SpeedScale::from_raw(s).unwrap(),
            }
        )),
        Just(AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
            uptime: protocol::Millis::from_raw(0).unwrap()
        })),
        prop::bool::ANY.prop_map(|latch| estop(if latch {
            EStopAction::Latch
        } else {
            EStopAction::Clear
        })),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Whatever arrives, in whatever order, with whatever gaps between ticks: every output is
    /// finite and inside the joint and torque limits.
    #[test]
    fn no_input_sequence_produces_an_out_of_limit_or_non_finite_command(
        script in prop::collection::vec((prop::collection::vec(any_message(), 0..6), 1u32..40), 1..120)
    ) {
        let mut controller = Controller::new(CONFIG).unwrap();
        let mut now = 0u32;
        for (messages, gap) in script {
            for message in &messages {
                controller.on_message(Tick(now), message);
            }
            now = now.wrapping_add(gap);
            let output = controller.step(Tick(now));
            for (leg, angles) in output.leg_targets_rad.iter_legs() {
                for (joint, angle) in firmware::limits::Joint::ALL.into_iter().zip(angles) {
                    prop_assert!(
                        angle.is_finite() && CONFIG.limits.range(joint).contains(*angle),
                        "leg {leg:?} {joint:?} = {angle}"
                    );
                }
            }
            for torque in output.wheel_torque_nm {
                prop_assert!(torque.is_finite() && torque.abs() <= CONFIG.wheel_torque_limit_nm);
            }
        }
    }
}
