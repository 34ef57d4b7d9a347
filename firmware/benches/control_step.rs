//! One full control step of the core, measured on the host (`cargo xtask bench`):
//!
//! - `step/trot` and `step/wheels`: the typed core — six feedback messages in, then the step
//!   (supervisor, FSM, 4-leg IK + gait or fold, balance + turn loop, smoothing, clamps);
//! - `node/trot`: the same through the CAN node — six feedback frames decoded and E2E-checked,
//!   the step, and the tick's frames encoded with CRC.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use firmware::{Config, Controller, Node, Tick};
use protocol::{
    Acceleration, Angle, AngularRate, AnyMessage, BodyHeight, Frame, Imu, JointVelocity, Joints,
    LegFeedback, QuatComponent, SpeedScale, TeleopCommand, TeleopHeartbeat, TeleopMode, Torque,
    WheelAngle, WheelFeedback, WheelVelocity,
};

fn feedback(joints_rad: &Joints<f32>) -> Vec<AnyMessage> {
    let mut messages: Vec<AnyMessage> = joints_rad
        .iter_legs()
        .map(|(leg, angles_rad)| {
            AnyMessage::LegFeedback(
                leg,
                LegFeedback {
                    position: angles_rad.map(Angle::saturating_from_si),
                    velocity: [JointVelocity::saturating_from_si(0.1); 4],
                    effort: [Torque::saturating_from_si(1.0); 4],
                },
            )
        })
        .collect();
    messages.push(AnyMessage::WheelFeedback(WheelFeedback {
        position: [WheelAngle::saturating_from_si(0.5); 2],
        velocity: [WheelVelocity::saturating_from_si(2.0); 2],
        effort: [Torque::saturating_from_si(1.0); 2],
    }));
    messages.push(AnyMessage::Imu(Imu {
        orientation: [0.9999, 0.0, 0.0123, 0.0].map(QuatComponent::saturating_from_si),
        angular_rate: [0.0, 0.05, 0.0].map(AngularRate::saturating_from_si),
        acceleration: [0.0, 0.0, 9.81].map(Acceleration::saturating_from_si),
    }));
    messages
}

fn operator(mode: TeleopMode) -> [AnyMessage; 2] {
    [
        AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
            uptime: protocol::Millis::from_raw(0).unwrap(),
        }),
        AnyMessage::TeleopCommand(TeleopCommand {
            mode,
            body_height: BodyHeight::saturating_from_si(0.0),
            speed_scale: SpeedScale::from_raw(100).unwrap(),
        }),
    ]
}

/// A controller brought into `mode` by an ideal plant, and the tick it reached.
fn controller_in(mode: TeleopMode) -> (Controller, u32) {
    let target = match mode {
        TeleopMode::TrotForward => firmware::control::fsm::State::Legs(
            firmware::control::fsm::LegMotion::Trot(firmware::control::fsm::Direction::Forward),
        ),
        _ => firmware::control::fsm::State::Wheels(firmware::control::fsm::WheelMotion::Drive(
            firmware::control::fsm::Direction::Forward,
        )),
    };
    let mut controller = Controller::new(Config::ROBOT).unwrap();
    let mut joints = Joints::splat(0.0_f32);
    for tick in 0..600 {
        for message in feedback(&joints) {
            controller.on_message(Tick(tick), &message);
        }
        if tick % 5 == 0 {
            let [heartbeat, command] = operator(mode);
            controller.on_message(Tick(tick), &heartbeat);
            if tick == 10 {
                controller.on_message(Tick(tick), &command);
            }
        }
        joints = controller.step(Tick(tick)).leg_targets_rad;
    }
    assert_eq!(
        controller.state(),
        target,
        "the plant did not bring the controller to {mode:?}"
    );
    (controller, 600)
}

fn bench_step(c: &mut Criterion) {
    for (name, mode) in [
        ("step/trot", TeleopMode::TrotForward),
        ("step/wheels", TeleopMode::WheelForward),
    ] {
        let (mut controller, start) = controller_in(mode);
        let mut messages = feedback(&Joints::splat(0.1));
        messages.push(operator(mode)[0]);
        let expected = controller.state();
        let mut tick = start;
        c.bench_function(name, |b| {
            b.iter(|| {
                for message in &messages {
                    controller.on_message(Tick(tick), black_box(message));
                }
                let output = controller.step(Tick(tick));
                tick = tick.wrapping_add(1);
                black_box(output)
            })
        });
        assert_eq!(
            controller.state(),
            expected,
            "{name} left its mode while measured"
        );
    }
}

fn bench_node(c: &mut Criterion) {
    let mut node = Node::new(Config::ROBOT).unwrap();
    // Every counter value once, so the ring of frames wraps exactly as the counters do.
    let messages = feedback(&Joints::splat(0.1));
    let ring: Vec<Vec<Frame>> = (0..=u16::MAX)
        .map(|counter| {
            messages
                .iter()
                .map(|m| m.encode(counter).unwrap())
                .collect()
        })
        .collect();
    let teleop: Vec<Frame> = (0..=u16::MAX)
        .map(|counter| {
            let [heartbeat, _] = operator(TeleopMode::TrotForward);
            heartbeat.encode(counter).unwrap()
        })
        .collect();
    let command = operator(TeleopMode::TrotForward)[1].encode(0).unwrap();
    let mut tick: u32 = 0;
    let feed = |node: &mut Node, tick: u32| {
        let index = (tick as usize) % ring.len();
        for frame in &ring[index] {
            let _ = node.on_frame(Tick(tick), frame.id(), frame.data());
        }
        let beat = &teleop[index];
        let _ = node.on_frame(Tick(tick), beat.id(), beat.data());
    };
    for _ in 0..600 {
        feed(&mut node, tick);
        if tick == 10 {
            let _ = node.on_frame(Tick(tick), command.id(), command.data());
        }
        black_box(node.poll(Tick(tick)));
        tick += 1;
    }
    let trotting = firmware::control::fsm::State::Legs(firmware::control::fsm::LegMotion::Trot(
        firmware::control::fsm::Direction::Forward,
    ));
    assert_eq!(node.controller().state(), trotting);
    c.bench_function("node/trot", |b| {
        b.iter(|| {
            feed(&mut node, tick);
            let out = node.poll(Tick(tick));
            tick = tick.wrapping_add(1);
            black_box(out)
        })
    });
    assert_eq!(node.controller().state(), trotting);
    assert_eq!(node.reject_counters().total(), 0);

    // The same tick with a babbling teleop: 40 more TeleopCommand frames (10,000 frames/s at
    // 250 Hz), counters in sequence, 38 of them over the per-tick budget. The ratio to
    // `node/trot` is what a flood costs the control period.
    let commands: Vec<Frame> = (0..=u16::MAX)
        .map(|counter| {
            operator(TeleopMode::TrotForward)[1]
                .encode(counter.wrapping_add(1))
                .unwrap()
        })
        .collect();
    let mut next_command = 0_usize;
    c.bench_function("node/trot+flood", |b| {
        b.iter(|| {
            feed(&mut node, tick);
            for _ in 0..40 {
                let frame = &commands[next_command];
                let _ = node.on_frame(Tick(tick), frame.id(), frame.data());
                next_command = (next_command + 1) % commands.len();
            }
            let out = node.poll(Tick(tick));
            tick = tick.wrapping_add(1);
            black_box(out)
        })
    });
    assert_eq!(node.controller().state(), trotting);
    let counters = node.reject_counters();
    assert_eq!(
        counters.total(),
        u32::from(counters.get(protocol::RejectCause::RateLimited).raw())
    );
}

criterion_group!(benches, bench_step, bench_node);
criterion_main!(benches);
