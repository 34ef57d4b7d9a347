//! One full control step of the core, measured on the host (`cargo xtask bench`):
//!
//! - `step/trot` and `step/wheels`: the typed core — six feedback messages in, then the step
//!   (supervisor, FSM, 4-leg IK + gait or fold, balance + turn loop, smoothing, clamps);
//! - `node/trot`: the same through the CAN node — six feedback frames and a heartbeat verified
//!   (CRC and CMAC) and decoded, the step, and the tick's frames sealed. The frames in are
//!   sealed before each iteration, outside the measurement: that is the other nodes' work.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use firmware::{Config, Controller, Node, Tick};
use protocol::{
    Acceleration, Angle, AngularRate, AnyMessage, BodyHeight, Epoch, Frame, Imu, JointVelocity,
    Joints, LegFeedback, Sender, Session, SpeedScale, TeleopCommand, TeleopHeartbeat, TeleopMode,
    Torque, WheelFeedback, WheelVelocity, TEST_KEY,
};

/// The node's session, in which the plant and the operator seal their frames.
const SESSION: Session = Session::owned(TEST_KEY, Epoch::new(1));

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
        velocity: [WheelVelocity::saturating_from_si(2.0); 2],
        effort: [Torque::saturating_from_si(1.0); 2],
    }));
    messages.push(AnyMessage::Imu(Imu {
        angular_rate: [0.0, 0.05, 0.0].map(AngularRate::saturating_from_si),
        acceleration: [-0.24, 0.0, 9.8].map(Acceleration::saturating_from_si),
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
            speed: Default::default(),
            yaw_rate: Default::default(),
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
    // Up to 20 s: the fold in place takes a few seconds on this plant.
    let mut reached = 0;
    for tick in 0..5_000 {
        if tick > 10 && controller.state() == target {
            reached = tick;
            break;
        }
        for message in feedback(&joints) {
            controller.on_message(Tick(tick), &message);
        }
        if tick % 5 == 0 {
            let [heartbeat, command] = operator(mode);
            controller.on_message(Tick(tick), &heartbeat);
            if tick == 5 {
                // X first: the controller starts interlocked.
                controller.on_message(Tick(tick), &operator(TeleopMode::Stop)[1]);
            }
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
    (controller, reached)
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

/// The plant's and the operator's side of the bus: each tick's feedback and heartbeat, sealed
/// in sequence in the node's session.
struct Peers {
    sender: Sender,
    feedback: Vec<AnyMessage>,
}

impl Peers {
    fn new() -> Self {
        Self {
            sender: Sender::new(),
            feedback: feedback(&Joints::splat(0.1)),
        }
    }

    fn seal(&mut self, message: &AnyMessage) -> Frame {
        self.sender.seal(&SESSION, message).unwrap()
    }

    /// One tick's frames, with `commands` more operator commands (a babbler's).
    fn tick(&mut self, commands: usize) -> Vec<Frame> {
        let [heartbeat, command] = operator(TeleopMode::TrotForward);
        let feedback = self.feedback.clone();
        let mut frames: Vec<Frame> = feedback.iter().map(|m| self.seal(m)).collect();
        frames.push(self.seal(&heartbeat));
        frames.extend((0..commands).map(|_| self.seal(&command)));
        frames
    }
}

fn feed(node: &mut Node, tick: u32, frames: &[Frame]) {
    for frame in frames {
        let _ = node.on_frame(Tick(tick), frame.id(), frame.data());
    }
}

fn bench_node(c: &mut Criterion) {
    let mut node = Node::new(Config::ROBOT, SESSION).unwrap();
    let mut peers = Peers::new();
    let mut tick: u32 = 0;
    for _ in 0..600 {
        let frames = peers.tick(0);
        feed(&mut node, tick, &frames);
        // X, then L: the controller starts interlocked.
        let mode = match tick {
            5 => Some(TeleopMode::Stop),
            10 => Some(TeleopMode::TrotForward),
            _ => None,
        };
        if let Some(mode) = mode {
            let command = peers.seal(&operator(mode)[1]);
            feed(&mut node, tick, &[command]);
        }
        black_box(node.poll(Tick(tick)));
        tick += 1;
    }
    let trotting = firmware::control::fsm::State::Legs(firmware::control::fsm::LegMotion::Trot(
        firmware::control::fsm::Direction::Forward,
    ));
    assert_eq!(node.controller().state(), trotting);
    let mut next_tick = tick;
    c.bench_function("node/trot", |b| {
        b.iter_batched(
            || {
                next_tick = next_tick.wrapping_add(1);
                (next_tick, peers.tick(0))
            },
            |(tick, frames)| {
                feed(&mut node, tick, &frames);
                black_box(node.poll(Tick(tick)))
            },
            BatchSize::SmallInput,
        )
    });
    assert_eq!(node.controller().state(), trotting);
    assert_eq!(node.reject_counters().total(), 0);

    // The same tick with a babbling teleop: 40 more TeleopCommand frames (10,000 frames/s at
    // 250 Hz), counters in sequence, 38 of them over the per-tick budget. The ratio to
    // `node/trot` is what a flood costs the control period.
    c.bench_function("node/trot+flood", |b| {
        b.iter_batched(
            || {
                next_tick = next_tick.wrapping_add(1);
                (next_tick, peers.tick(40))
            },
            |(tick, frames)| {
                feed(&mut node, tick, &frames);
                black_box(node.poll(Tick(tick)))
            },
            BatchSize::SmallInput,
        )
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
