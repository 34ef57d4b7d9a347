//! The controller as a CAN node: what goes out each tick, and what happens to bad frames.

use firmware::fsm::State;
use firmware::{Config, Node, Tick};
use protocol::{
    decode_frame, AnyMessage, BodyHeight, DecodeError, DriveEnable, MessageId, RejectCause,
    SpeedScale, TeleopCommand, TeleopMode,
};

fn teleop_frame(mode: TeleopMode, counter: u16) -> protocol::Frame {
    AnyMessage::TeleopCommand(TeleopCommand {
        mode,
        body_height: BodyHeight::saturating_from_si(0.0),
        speed_scale: SpeedScale::from_raw(100).unwrap(),
    })
    .encode(counter)
    .unwrap()
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
fn the_readmes_cansend_estop_latches_and_clears() {
    let mut node = Node::new(Config::ROBOT).unwrap();
    // `cansend vcan0 000##129660000010A` (latch, counter 0) and `000##155B80100020A`
    // (clear, counter 1) from the README.
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
