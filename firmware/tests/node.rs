//! The controller as a CAN node: what goes out each tick, and what happens to bad frames.

mod common;

use firmware::control::fsm::{Direction, LegMotion, State, WheelMotion};
use firmware::node::TELEOP_COMMANDS_PER_TICK;
use firmware::{Config, Node, Tick};
use protocol::{
    decode_frame, AnyMessage, DecodeError, DriveEnable, EStop, EStopAction, Joints, MessageId,
    NodeId, RejectCause, TeleopHeartbeat, TeleopMode,
};

fn teleop_frame(mode: TeleopMode, counter: u16) -> protocol::Frame {
    common::command(mode).encode(counter).unwrap()
}

#[test]
fn sends_the_bus_schedule_at_250_hz() {
    let mut node = Node::new(Config::ROBOT).unwrap();
    let mut counts = std::collections::HashMap::new();
    for tick in 0..250 {
        let (_, frames) = node.poll(Tick(tick));
        for frame in &frames {
            let decoded = decode_frame(frame.id(), frame.data()).expect("own frames decode");
            *counts.entry(decoded.id).or_insert(0) += 1;
        }
    }
    assert_eq!(counts[&MessageId::LegTargets], 250);
    assert_eq!(counts[&MessageId::WheelCommand], 250);
    assert_eq!(counts[&MessageId::ControllerStatus], 50);
    assert_eq!(counts[&MessageId::RejectCounters], 10);
    assert_eq!(node.encode_failures(), 0);
}

#[test]
fn a_corrupted_frame_is_rejected_counted_and_never_applied() {
    let mut node = Node::new(Config::ROBOT).unwrap();
    let good = teleop_frame(TeleopMode::WheelForward, 0);
    let mut bad = good.data().to_vec();
    bad[6] ^= 0x01; // flip a payload bit
    assert!(matches!(
        node.on_frame(Tick(0), good.id(), &bad),
        Err(DecodeError::CrcMismatch { .. })
    ));
    assert_eq!(node.controller().state(), State::Hold);
    assert_eq!(node.reject_counters().get(RejectCause::Crc).raw(), 1);
    // Wrong length and unknown id are counted under their own causes.
    assert!(node
        .on_frame(Tick(0), good.id(), &good.data()[..good.data().len() - 1])
        .is_err());
    assert!(node.on_frame(Tick(0), 0x7FF, &[0; 8]).is_err());
    assert_eq!(
        node.reject_counters().get(RejectCause::WrongLength).raw(),
        1
    );
    assert_eq!(node.reject_counters().get(RejectCause::UnknownId).raw(), 1);
    // A replay of an accepted frame is rejected too.
    node.on_frame(Tick(0), good.id(), good.data()).unwrap();
    assert!(node.on_frame(Tick(1), good.id(), good.data()).is_err());
    assert_eq!(node.reject_counters().get(RejectCause::Repeated).raw(), 1);
    // And the counters go out on the bus in the RejectCounters frame.
    let mut seen = None;
    for tick in 0..25 {
        let (_, frames) = node.poll(Tick(tick));
        for frame in &frames {
            if let Ok(decoded) = decode_frame(frame.id(), frame.data()) {
                if let AnyMessage::RejectCounters(counters) = decoded.message {
                    seen = Some(counters);
                }
            }
        }
    }
    let counters = seen.expect("a RejectCounters frame within 100 ms");
    assert_eq!(counters.total(), 4);
}

#[test]
fn the_documented_cansend_estop_latches_and_clears() {
    let mut node = Node::new(Config::ROBOT).unwrap();
    // `cansend vcan0 000##129660000010A` (latch, counter 0) and `000##155B80100020A`
    // (clear, counter 1) from docs/protocol.md.
    let latch = [0x29, 0x66, 0x00, 0x00, 0x01, 0x0A];
    let clear = [0x55, 0xB8, 0x01, 0x00, 0x02, 0x0A];
    node.on_frame(Tick(0), 0x000, &latch).unwrap();
    assert_eq!(node.controller().state(), State::EStop);
    let (output, frames) = node.poll(Tick(0));
    assert!(!output.legs_enabled && output.wheel_torque_nm == [0.0, 0.0]);
    let targets = frames
        .iter()
        .find_map(|f| match decode_frame(f.id(), f.data()).unwrap().message {
            AnyMessage::LegTargets(t) => Some(t),
            _ => None,
        })
        .unwrap();
    assert_eq!(targets.enable, DriveEnable::Disabled);
    // The clear, next in sequence, releases it; the same latch again (now out of sequence)
    // still acts, while a replayed clear does not.
    node.on_frame(Tick(1), 0x000, &clear).unwrap();
    assert_eq!(node.controller().state(), State::Hold);
    node.on_frame(Tick(2), 0x000, &latch).unwrap();
    assert_eq!(node.controller().state(), State::EStop);
    assert!(node.on_frame(Tick(3), 0x000, &clear).is_err());
    assert_eq!(node.controller().state(), State::EStop);
}

/// The feedback of one tick (four legs at zero, wheels, IMU) with rolling counter `counter`.
fn feedback_frames(counter: u16) -> Vec<protocol::Frame> {
    common::plant_feedback(&Joints::splat(0.0))
        .iter()
        .map(|m| m.encode(counter).unwrap())
        .collect()
}

/// Sends one teleop command per mode, counters from `*counter` on; returns how many the node
/// applied and how many it refused as rate limited (any other refusal fails the test).
fn flood(node: &mut Node, now: u32, modes: &[TeleopMode], counter: &mut u16) -> (u32, u32) {
    let (mut applied, mut limited) = (0, 0);
    for mode in modes {
        let frame = teleop_frame(*mode, *counter);
        *counter += 1;
        match node.on_frame(Tick(now), frame.id(), frame.data()) {
            Ok(()) => applied += 1,
            Err(DecodeError::RateLimited { id: 0x200 }) => limited += 1,
            Err(other) => panic!("teleop frame {counter} refused: {other:?}"),
        }
    }
    (applied, limited)
}

#[test]
fn a_teleop_flood_is_rate_limited_per_tick_and_counted_and_other_traffic_still_flows() {
    assert_eq!(TELEOP_COMMANDS_PER_TICK, 2);
    let mut node = Node::new(Config::ROBOT).unwrap();
    let mut counter = 0;
    // 10 000 frames/s from a babbling teleop: 40 valid frames, in sequence, in one 4 ms tick.
    // The first two act (Stand, then trot); any of the 38 Folds after them would fold the legs.
    let mut modes = vec![TeleopMode::Stand, TeleopMode::TrotForward];
    modes.extend([TeleopMode::Fold; 38]);
    assert_eq!(flood(&mut node, 0, &modes, &mut counter), (2, 38));
    assert_eq!(
        node.controller().state(),
        State::Standing(LegMotion::Trot(Direction::Forward))
    );
    assert_eq!(
        node.reject_counters().get(RejectCause::RateLimited).raw(),
        38
    );
    assert_eq!(node.reject_counters().total(), 38);
    // The rest of the bus is served in the same tick: feedback, heartbeats (not limited).
    for frame in feedback_frames(0) {
        node.on_frame(Tick(0), frame.id(), frame.data())
            .unwrap_or_else(|e| panic!("feedback {:03X} refused: {e:?}", frame.id()));
    }
    for n in 0..40 {
        let heartbeat = AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
            uptime: protocol::Millis::from_raw(n).unwrap(),
        })
        .encode(n as u16)
        .unwrap();
        node.on_frame(Tick(0), heartbeat.id(), heartbeat.data())
            .unwrap();
    }
    let (output, _) = node.poll(Tick(0));
    assert!(output.legs_enabled, "the feedback armed the drives");
    // The next tick has a new budget, and the limited frames kept the sequence in step: the
    // next two act (stop, then fold), the rest is limited again, none is out of sequence.
    let mut modes = vec![TeleopMode::Stop, TeleopMode::Fold];
    modes.extend([TeleopMode::Stand; 38]);
    assert_eq!(flood(&mut node, 1, &modes, &mut counter), (2, 38));
    assert_eq!(
        node.controller().state(),
        State::Folding(WheelMotion::Balance)
    );
    for frame in feedback_frames(1) {
        node.on_frame(Tick(1), frame.id(), frame.data()).unwrap();
    }
    let counters = node.reject_counters();
    assert_eq!(counters.get(RejectCause::RateLimited).raw(), 76);
    assert_eq!(counters.total(), 76);
    assert_eq!(counters.lost.raw(), 0);
    // The limit holds per tick, whatever the gap between ticks: one command per poll is served.
    for tick in 2..50 {
        node.poll(Tick(tick));
        assert_eq!(
            flood(&mut node, tick, &[TeleopMode::Fold], &mut counter),
            (1, 0)
        );
    }
}

#[test]
fn an_estop_in_a_teleop_flood_acts() {
    let mut node = Node::new(Config::ROBOT).unwrap();
    let mut counter = 0;
    assert_eq!(
        flood(&mut node, 0, &[TeleopMode::Fold; 20], &mut counter),
        (2, 18)
    );
    assert_eq!(
        node.controller().state(),
        State::Folding(WheelMotion::Balance)
    );
    // The budget is spent, and an E-stop still acts at once.
    let latch = AnyMessage::EStop(EStop {
        action: EStopAction::Latch,
        source: NodeId::Teleop,
    })
    .encode(0)
    .unwrap();
    node.on_frame(Tick(0), latch.id(), latch.data())
        .expect("an E-stop is never rate limited");
    assert_eq!(node.controller().state(), State::EStop);
    assert_eq!(
        flood(&mut node, 0, &[TeleopMode::Fold; 20], &mut counter),
        (0, 20)
    );
    node.poll(Tick(0));
    assert_eq!(
        flood(&mut node, 1, &[TeleopMode::Stand; 40], &mut counter),
        (2, 38)
    );
    assert_eq!(node.controller().state(), State::EStop);
    assert_eq!(node.reject_counters().total(), 18 + 20 + 38);
}
