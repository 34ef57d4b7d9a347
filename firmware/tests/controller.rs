//! The control step against an ideal plant (every drive reaches its target, the torso stays
//! level): transitions, watchdogs, and the safety clamp under arbitrary input. The stops are in
//! `stops.rs`.

mod common;

use common::bench::{estop, ms, Bench, CONFIG};
use common::{command, Ticks};

use firmware::control::fsm::{LegMotion, State, WheelMotion};
use firmware::{Controller, Tick};
use proptest::prelude::*;
use protocol::{
    Acceleration, Angle, AngularRate, AnyMessage, BodyHeight, EStopAction, FaultFlags, Imu,
    JointVelocity, Leg, LegFeedback, SpeedScale, TeleopCommand, TeleopHeartbeat, TeleopMode,
    Torque, WheelFeedback, WheelVelocity,
};

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
    // The legs carry the torso down toward the touchdown pose until the wheels take it, then
    // tuck into the fold (see `legs::transfer`): the planted feet let the torso down onto its
    // wheels on the way, and the tuck starts only then.
    let support = CONFIG.support;
    let mut at_tuck = None;
    let mut last = support.stance_of(&CONFIG.geometry, &bench.joints_rad);
    let mut back_hip_rad = bench.joints_rad.leg(Leg::Bl)[1];
    let mut ticks = 1;
    while matches!(bench.state(), State::Folding(_)) {
        bench.tick();
        ticks += 1;
        // The back hips swing forward over the carry and back in the tuck.
        let now_rad = bench.joints_rad.leg(Leg::Bl)[1];
        if at_tuck.is_none() && now_rad < back_hip_rad - 1e-6 {
            at_tuck = Some(last);
        }
        back_hip_rad = now_rad;
        last = support.stance_of(&CONFIG.geometry, &bench.joints_rad);
        assert!(ticks < 2_000, "folding never finished");
    }
    let at_tuck = at_tuck.expect("the legs never tucked");
    assert!(
        support.lowered_onto_wheels(&at_tuck),
        "the tuck began before the wheels took the robot: {at_tuck:?}"
    );
    let touchdown = CONFIG.transfer.touchdown.to_array();
    assert!(
        at_tuck.shallowest_height_m
            > support
                .stance_of(
                    &CONFIG.geometry,
                    &protocol::Joints::from_leg_fn(|_| touchdown)
                )
                .height_m,
        "the carry went on past the wheels' touchdown: {at_tuck:?}"
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
    // The fold at the levelling's shift (see `legs::levelling`): the bench's torso is level,
    // so the legs are where a robot that balances upright keeps them, once the smoothing has
    // followed the last of the levelling.
    bench.run(250);
    let levelling = bench.controller.levelling();
    let fold = levelling.pose(&CONFIG.levelling);
    for leg in Leg::ALL {
        for (joint, goal) in bench.joints_rad.leg(leg).iter().zip(fold.leg(leg)) {
            assert!(
                (joint - goal).abs() < 0.011,
                "{leg:?} at {joint}, fold {goal}"
            );
        }
    }
    assert!(
        levelling.shift() > 0.0,
        "the fold with the back legs under the torso"
    );
}

#[test]
fn trot_from_the_wheels_stands_up_first() {
    let mut bench = Bench::on_the_wheels();
    bench.send(command(TeleopMode::TrotForward));
    bench.tick();
    assert_eq!(
        bench.state(),
        State::Standing(LegMotion::Trot(firmware::control::fsm::Direction::Forward))
    );
    // The roll ahead (1.5 s), then the unfold.
    bench.run(800);
    assert_eq!(
        bench.state(),
        State::Legs(LegMotion::Trot(firmware::control::fsm::Direction::Forward))
    );
    // And the legs now move: the gait, not a frozen pose.
    let a = bench.tick().leg_targets_rad;
    let b = bench.run(60).leg_targets_rad;
    assert!(a.iter().zip(b).any(|(x, y)| (x - y).abs() > 0.02));
}

/// A stand-up from the wheels rolls the robot ahead once: a change of what follows it (`X`
/// during the stand-up for a trot) does not roll it again.
#[test]
fn a_stand_up_rolls_ahead_once() {
    let mut bench = Bench::on_the_wheels();
    bench.send(command(TeleopMode::TrotForward));
    // Until the roll ahead is over: the reference up past 0.1 m/s and back to zero.
    let mut peak_m_s = 0.0_f32;
    for _ in 0..ms(3_000) {
        bench.tick();
        let reference_m_s = bench.controller.balance().velocity_ref_m_s();
        peak_m_s = peak_m_s.max(reference_m_s);
        if peak_m_s > 0.1 && reference_m_s.abs() < 1e-6 {
            break;
        }
    }
    assert!(peak_m_s > 0.1, "no roll ahead: {peak_m_s} m/s");
    assert!(
        matches!(bench.state(), State::Standing(_)),
        "{:?}",
        bench.state()
    );
    bench.send(command(TeleopMode::Stop));
    bench.tick();
    assert!(
        matches!(bench.state(), State::Standing(_)),
        "{:?}",
        bench.state()
    );
    for tick in 0..ms(2_000) {
        bench.tick();
        let reference_m_s = bench.controller.balance().velocity_ref_m_s();
        assert!(
            reference_m_s.abs() < 1e-6,
            "tick {tick}: {reference_m_s} m/s"
        );
    }
}

/// The depth of `leg`'s foot below its hip where the bench's legs are, m.
fn foot_depth_m(bench: &Bench, leg: Leg) -> f32 {
    use firmware::legs::kinematics::{leg_fk, LegJoints};
    let joints = LegJoints::from_array(*bench.joints_rad.leg(leg));
    -leg_fk(&CONFIG.geometry, &joints).z_m
}

/// Standing after a stand-up from the wheels, a torso pitched 8.6° nose down (front legs giving
/// way) is lowered at its high end: the back feet come up under their hips. After a stand-up
/// from the legs, or once the robot has trotted since, the stand keeps every foot at its depth.
#[test]
fn a_stand_after_a_stand_up_from_the_wheels_levels_the_torso_in_pitch() {
    let until_standing = |bench: &mut Bench| {
        for _ in 0..ms(8_000) {
            bench.tick();
            if bench.state() == State::Legs(LegMotion::Stand) {
                break;
            }
        }
    };
    let stand_pitched = |mut bench: Bench, trot_first: bool| {
        bench.send(command(TeleopMode::Stand));
        until_standing(&mut bench);
        if trot_first {
            bench.send(command(TeleopMode::TrotForward));
            bench.run(ms(1_000));
            assert!(matches!(bench.state(), State::Legs(LegMotion::Trot(_))));
            bench.send(command(TeleopMode::Stop));
        }
        until_standing(&mut bench);
        assert_eq!(bench.state(), State::Legs(LegMotion::Stand));
        bench.pitch_rad = 0.15;
        bench.run(ms(2_000));
        foot_depth_m(&bench, Leg::Fl) - foot_depth_m(&bench, Leg::Bl)
    };
    let risen_m = stand_pitched(Bench::on_the_wheels(), false);
    assert!(
        (0.03..=0.05).contains(&risen_m),
        "back feet {risen_m} m shallower than the front"
    );
    let stood_m = stand_pitched(Bench::ready(), false);
    assert!(stood_m.abs() < 1e-3, "back feet {stood_m} m shallower");
    let trotted_m = stand_pitched(Bench::on_the_wheels(), true);
    assert!(
        trotted_m.abs() < 1e-3,
        "after a trot: {trotted_m} m shallower"
    );
}

/// A stand after a stand-up from the wheels whose torso stays pitched past 15° for a second
/// (front legs that gave way on the way up) is reported, `stand_tilted`: kept while the torso
/// comes level, cleared by the operator's next request, raised again a second later if the
/// stand is still tilted; nothing moves for it. A stand-up asked from `Hold` on the wheels (the
/// controller started with the robot folded) is watched as well. A stand within the levelling's reach, or one that
/// did not rise from the wheels, is not reported.
#[test]
fn a_stand_after_a_stand_up_that_stays_tilted_is_reported_until_the_next_request() {
    let tilted = |bench: &mut Bench, ms_for: u32| {
        let mut first_ms = None;
        for tick in 0..ms(ms_for) {
            let faults = bench.tick().status.faults;
            if first_ms.is_none() && faults.contains(FaultFlags::STAND_TILTED) {
                first_ms = Some(tick * 4);
            }
        }
        first_ms
    };
    let stand_pitched = |mut bench: Bench, pitch_rad: f32| {
        bench.send(command(TeleopMode::Stand));
        for _ in 0..ms(8_000) {
            bench.tick();
            if bench.state() == State::Legs(LegMotion::Stand) {
                break;
            }
        }
        assert_eq!(bench.state(), State::Legs(LegMotion::Stand));
        bench.pitch_rad = pitch_rad;
        let first_ms = tilted(&mut bench, 2_000);
        (bench, first_ms)
    };
    let (mut bench, first_ms) = stand_pitched(Bench::on_the_wheels(), 0.5);
    let first_ms = first_ms.expect("a stand 29 deg nose down is reported");
    assert!(
        (1_000..1_100).contains(&first_ms),
        "reported after {first_ms} ms"
    );
    assert_eq!(
        bench.state(),
        State::Legs(LegMotion::Stand),
        "nothing moves"
    );
    bench.pitch_rad = 0.0;
    bench.run(ms(1_000));
    let faults = bench.tick().status.faults;
    assert!(
        faults.contains(FaultFlags::STAND_TILTED),
        "kept while it comes level"
    );
    bench.send(command(TeleopMode::Stop));
    assert_eq!(
        tilted(&mut bench, 2_000),
        None,
        "cleared by the request, level"
    );
    bench.pitch_rad = 0.5;
    let again_ms = tilted(&mut bench, 2_000).expect("still tilted: reported again");
    assert!(
        (1_000..1_200).contains(&again_ms),
        "again after {again_ms} ms"
    );
    let (_, within) = stand_pitched(Bench::on_the_wheels(), 0.2);
    assert_eq!(within, None, "11 deg is the levelling's to take");
    let (_, from_legs) = stand_pitched(Bench::ready(), 0.5);
    assert_eq!(from_legs, None, "a stand from the legs is not watched");
    let mut powered_up = Bench::new();
    powered_up.joints_rad = CONFIG.levelling.family.pose(0.0);
    powered_up.run(5);
    powered_up.send(command(TeleopMode::Stop));
    powered_up.run(ms(100));
    assert_eq!(powered_up.state(), State::Hold);
    let (_, from_hold) = stand_pitched(powered_up, 0.5);
    assert!(
        from_hold.is_some(),
        "a stand-up from Hold, started folded, is watched"
    );
}

/// A stand-up from the wheels first brings the legs to the fold it starts from, balancing; a
/// fold asked for meanwhile starts on the wheels, where it has nothing to return: the speed
/// reference stays at zero (an earlier fold's return must not drive the robot again).
#[test]
fn a_fold_during_a_stand_up_on_the_wheels_does_not_drive() {
    let mut bench = Bench::on_the_wheels();
    bench.send(command(TeleopMode::Stand));
    bench.run(25);
    assert!(matches!(bench.state(), State::Standing(_)));
    bench.send(command(TeleopMode::Fold));
    for tick in 0..500 {
        bench.tick();
        let reference_m_s = bench.controller.balance().velocity_ref_m_s();
        assert!(
            reference_m_s.abs() < 1e-6,
            "tick {tick}: {reference_m_s} m/s"
        );
    }
    assert_eq!(bench.state(), State::Wheels(WheelMotion::Balance));
}

#[test]
fn a_turn_on_the_spot_brings_its_wheel_torque_in_gradually() {
    let mut bench = Bench::on_the_wheels();
    bench.send(command(TeleopMode::WheelRotate));
    let differential_nm = |output: &firmware::Output| {
        let [left, right] = output.wheel_torque_nm;
        (right - left).abs() / 2.0
    };
    // A step to the full turn rate asked the turn loop for its whole torque at once, and on
    // low friction the wheels slipped.
    let first = bench.tick();
    let limit_nm = CONFIG.turn.limit_nm;
    assert!(
        differential_nm(&first) < 0.1 * limit_nm,
        "first tick: {} N·m",
        differential_nm(&first)
    );
    // … and it does ask for the turn: the bench's wheels do not turn, so the loop's torque
    // grows to its limit once the reference has ramped up.
    bench.run(ms(500));
    let later = bench.tick();
    assert!(
        differential_nm(&later) > 0.5 * limit_nm,
        "after 0.5 s: {} N·m",
        differential_nm(&later)
    );
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

/// `walk` trots the way the operator's speed points, turning round only past a dead band, and
/// inside it never strides the wrong way; its yaw rate is held to the trot's limit.
#[test]
fn walk_follows_the_speeds_sign_past_a_dead_band_and_never_strides_the_wrong_way() {
    use firmware::control::fsm::Direction;
    let mut bench = Bench::ready();
    bench.send(common::velocity_command(TeleopMode::Walk, 0.1, 0.0));
    bench.run(2_000);
    assert_eq!(bench.state(), State::Legs(LegMotion::Walk));
    let motion = |bench: &Bench| bench.controller.trot_motion().unwrap();
    let (direction, command) = motion(&bench);
    assert_eq!(direction, Direction::Forward);
    assert!(
        (command.stride_share - 0.1 / 0.145).abs() < 0.01,
        "{command:?}"
    );
    // A stick resting just behind centre: no stride, and still forward.
    bench.send(common::velocity_command(TeleopMode::Walk, -0.005, 0.0));
    bench.tick();
    let (direction, command) = motion(&bench);
    assert_eq!((direction, command.stride_share), (Direction::Forward, 0.0));
    // Past the dead band it turns round, and the yaw rate is clamped to 0.4 rad/s.
    bench.send(common::velocity_command(TeleopMode::Walk, -0.1, 2.0));
    bench.tick();
    let (direction, command) = motion(&bench);
    assert_eq!(direction, Direction::Backward);
    assert!(
        (command.stride_share - 0.1 / 0.145).abs() < 0.01,
        "{command:?}"
    );
    assert_eq!(command.yaw_rate_rad_s, 0.4);
    assert_eq!(bench.state(), State::Legs(LegMotion::Walk));
}

fn any_message() -> impl Strategy<Value = AnyMessage> {
    let angle = (-3.3f32..3.3).prop_map(Angle::saturating_from_si);
    let leg = prop::sample::select(Leg::ALL.to_vec());
    let mode = (0u8..10).prop_map(|raw| TeleopMode::from_raw(raw).unwrap());
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
            prop::array::uniform3(-30.0f32..30.0),
            prop::array::uniform3(-20.0f32..20.0)
        )
            .prop_map(|(w, a)| AnyMessage::Imu(Imu {
                angular_rate: w.map(AngularRate::saturating_from_si),
                acceleration: a.map(Acceleration::saturating_from_si),
            })),
        prop::array::uniform2(-300.0f32..300.0).prop_map(|v| AnyMessage::WheelFeedback(
            WheelFeedback {
                velocity: v.map(WheelVelocity::saturating_from_si),
                effort: [Torque::saturating_from_si(0.0); 2],
            }
        )),
        (mode, -0.2f32..0.2, 0u8..=100, -2.5f32..2.5, -3.5f32..3.5).prop_map(
            |(mode, h, s, v, w)| AnyMessage::TeleopCommand(TeleopCommand {
                mode,
                body_height: BodyHeight::saturating_from_si(h),
                speed_scale: SpeedScale::from_raw(s).unwrap(),
                speed: protocol::GroundSpeed::saturating_from_si(v),
                yaw_rate: protocol::YawRate::saturating_from_si(w),
            })
        ),
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
