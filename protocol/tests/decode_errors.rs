//! One test per rejection cause: the frame is rejected with a typed error, counted under its
//! cause by the receiver, and never returned as a message.

use protocol::e2e::{self, HEADER_LEN};
use protocol::*;

fn teleop(mode: TeleopMode) -> TeleopCommand {
    TeleopCommand {
        mode,
        body_height: BodyHeight::from_si(0.0).unwrap(),
        speed_scale: SpeedScale::from_si(100.0).unwrap(),
    }
}

fn teleop_frame(counter: u16) -> Frame {
    encode(&teleop(TeleopMode::WheelForward), (), counter).unwrap()
}

/// `frame` with `edit` applied to its bytes and the E2E CRC recomputed, as a sender with a bug
/// (not a corrupted link) would produce it.
fn resealed(frame: &Frame, edit: impl FnOnce(&mut [u8])) -> Vec<u8> {
    let id = MessageId::from_raw(frame.id()).unwrap();
    let mut data = frame.data().to_vec();
    edit(&mut data);
    let counter = u16::from_le_bytes([data[2], data[3]]);
    e2e::protect(id.data_id(), counter, &mut data[..id.layout().len]);
    data
}

fn only_cause(rx: &Receiver, cause: RejectCause) {
    for other in RejectCause::ALL {
        let expected = u16::from(other == cause);
        assert_eq!(
            rx.counters().get(other).raw(),
            expected,
            "counter {other:?}"
        );
    }
}

#[test]
fn unknown_id_is_rejected_and_counted() {
    let mut rx = Receiver::default();
    let frame = teleop_frame(0);
    assert_eq!(
        rx.receive(0x7AB, frame.data()),
        Err(DecodeError::UnknownId(0x7AB))
    );
    only_cause(&rx, RejectCause::UnknownId);
}

#[test]
fn wrong_length_is_rejected_and_counted() {
    let mut rx = Receiver::default();
    let frame = encode(
        &LegTargets {
            enable: DriveEnable::Enabled,
            position: [Angle::default(); 16].into(),
        },
        (),
        0,
    )
    .unwrap();
    let short = &frame.data()[..32];
    assert_eq!(
        rx.receive(frame.id(), short),
        Err(DecodeError::WrongLength {
            id: 0x100,
            expected: 48,
            got: 32
        })
    );
    let mut long = frame.data().to_vec();
    long.extend_from_slice(&[0; 16]);
    assert!(matches!(
        rx.receive(frame.id(), &long),
        Err(DecodeError::WrongLength { got: 64, .. })
    ));
    assert_eq!(rx.counters().get(RejectCause::WrongLength).raw(), 2);
    assert_eq!(rx.counters().total(), 2);
}

#[test]
fn a_flipped_bit_anywhere_in_the_protected_bytes_fails_the_crc() {
    let frame = teleop_frame(7);
    let len = MessageId::TeleopCommand.layout().len;
    for byte in 0..len {
        for bit in 0..8 {
            let mut rx = Receiver::default();
            let mut data = frame.data().to_vec();
            data[byte] ^= 1 << bit;
            assert_eq!(
                rx.receive(frame.id(), &data),
                Err(DecodeError::CrcMismatch { id: 0x200 }),
                "flip of byte {byte} bit {bit} was not caught"
            );
            only_cause(&rx, RejectCause::Crc);
        }
    }
}

#[test]
fn a_frame_moved_to_another_id_of_the_same_length_fails_the_crc() {
    let mut rx = Receiver::default();
    let frame = teleop_frame(0);
    // TeleopHeartbeat has the same 8-byte length; the data id differs.
    assert_eq!(
        rx.receive(MessageId::TeleopHeartbeat.raw(), frame.data()),
        Err(DecodeError::CrcMismatch { id: 0x201 })
    );
    only_cause(&rx, RejectCause::Crc);
}

#[test]
fn out_of_range_values_are_rejected_even_with_a_valid_crc() {
    let frame = teleop_frame(0);
    type Edit = Box<dyn Fn(&mut [u8])>;
    let cases: [(&str, Edit); 3] = [
        (
            "body height 0.2 m",
            Box::new(|d: &mut [u8]| {
                d[HEADER_LEN + 1..HEADER_LEN + 3].copy_from_slice(&2000_i16.to_le_bytes())
            }),
        ),
        (
            "speed scale 101 %",
            Box::new(|d: &mut [u8]| d[HEADER_LEN + 3] = 101),
        ),
        (
            "unknown mode byte",
            Box::new(|d: &mut [u8]| d[HEADER_LEN] = 42),
        ),
    ];
    for (what, edit) in cases {
        let mut rx = Receiver::default();
        let data = resealed(&frame, edit);
        assert_eq!(
            rx.receive(frame.id(), &data),
            Err(DecodeError::OutOfRange { id: 0x200 }),
            "{what}"
        );
        only_cause(&rx, RejectCause::OutOfRange);
    }
    // An unknown flag bit and a quaternion component beyond ±1.
    let status = encode(
        &DriveStatus {
            flags: DriveFlags::ENABLED,
            rejected: Count::ZERO,
            commands: Count::ZERO,
        },
        Drive::Wheel,
        0,
    )
    .unwrap();
    let data = resealed(&status, |d| d[HEADER_LEN] = 0x80);
    assert!(matches!(
        decode_frame(status.id(), &data),
        Err(DecodeError::OutOfRange { .. })
    ));
    let imu = encode(
        &Imu {
            orientation: [QuatComponent::from_si(1.0).unwrap(); 4],
            angular_rate: [AngularRate::default(); 3],
            acceleration: [Acceleration::default(); 3],
        },
        (),
        0,
    )
    .unwrap();
    let data = resealed(&imu, |d| {
        d[HEADER_LEN..HEADER_LEN + 2].copy_from_slice(&20_000_i16.to_le_bytes())
    });
    assert!(matches!(
        decode_frame(imu.id(), &data),
        Err(DecodeError::OutOfRange { .. })
    ));
}

#[test]
fn a_repeated_frame_is_rejected_and_counted() {
    let mut rx = Receiver::default();
    let frame = teleop_frame(5);
    assert!(rx.receive(frame.id(), frame.data()).is_ok());
    assert_eq!(
        rx.receive(frame.id(), frame.data()),
        Err(DecodeError::Repeated { id: 0x200 })
    );
    only_cause(&rx, RejectCause::Repeated);
}

#[test]
fn a_replayed_old_frame_is_rejected_as_out_of_sequence() {
    let mut rx = Receiver::default();
    let old = teleop_frame(100);
    for counter in 100..=200 {
        let f = teleop_frame(counter);
        assert!(rx.receive(f.id(), f.data()).is_ok());
    }
    assert_eq!(
        rx.receive(old.id(), old.data()),
        Err(DecodeError::WrongSequence { id: 0x200 })
    );
    only_cause(&rx, RejectCause::WrongSequence);
    // The genuine sequence continues undisturbed.
    let next = teleop_frame(201);
    assert_eq!(
        rx.receive(next.id(), next.data()).unwrap().status,
        E2eStatus::Ok
    );
}

#[test]
fn a_frame_refused_after_acceptance_is_counted_as_rate_limited_and_keeps_the_sequence() {
    let mut rx = Receiver::default();
    let first = teleop_frame(7);
    assert!(rx.receive(first.id(), first.data()).is_ok());
    // The caller's rate limit drops the next frame after the receiver accepted it.
    let flooded = teleop_frame(8);
    assert!(rx.receive(flooded.id(), flooded.data()).is_ok());
    rx.refuse(DecodeError::RateLimited { id: flooded.id() });
    only_cause(&rx, RejectCause::RateLimited);
    assert_eq!(RejectCause::RateLimited.name(), "rate_limited");
    // The sender's next frame is in sequence: the refused one still counted as received.
    let next = teleop_frame(9);
    assert_eq!(
        rx.receive(next.id(), next.data()).unwrap().status,
        E2eStatus::Ok
    );
    assert_eq!(rx.counters().lost.raw(), 0);
}

#[test]
fn lost_frames_are_accepted_and_counted_as_lost_not_rejected() {
    let mut rx = Receiver::default();
    for counter in [0, 1, 4] {
        let f = teleop_frame(counter);
        rx.receive(f.id(), f.data()).unwrap();
    }
    assert_eq!(rx.counters().lost.raw(), 2);
    assert_eq!(rx.counters().total(), 0);
}

#[test]
fn sequences_are_tracked_per_identifier() {
    let mut rx = Receiver::default();
    let teleop = teleop_frame(10);
    let heartbeat = encode(
        &TeleopHeartbeat {
            uptime: Millis::from_raw(5).unwrap(),
        },
        (),
        10,
    )
    .unwrap();
    assert!(rx.receive(teleop.id(), teleop.data()).is_ok());
    assert!(
        rx.receive(heartbeat.id(), heartbeat.data()).is_ok(),
        "same counter on another id is not a repeat"
    );
}

#[test]
fn errors_explain_themselves() {
    let text = DecodeError::WrongLength {
        id: 0x100,
        expected: 48,
        got: 32,
    }
    .to_string();
    assert!(
        text.contains("0x100") && text.contains("48") && text.contains("32"),
        "{text}"
    );
}

#[test]
fn an_estop_latch_acts_whatever_its_counter_but_a_clear_must_be_in_sequence() {
    let latch = EStop {
        action: EStopAction::Latch,
        source: NodeId::Tool,
    };
    let clear = EStop {
        action: EStopAction::Clear,
        source: NodeId::Tool,
    };
    let mut rx = Receiver::default();
    for counter in [500, 501] {
        let f = encode(&latch, (), counter).unwrap();
        assert!(rx.receive(f.id(), f.data()).is_ok());
    }
    // An operator's cansend with counter 0, twice: both latches act, flagged by their status.
    let operator = encode(&latch, (), 0).unwrap();
    let first = rx.receive(operator.id(), operator.data()).unwrap();
    assert_eq!(first.status, E2eStatus::WrongSequence);
    assert_eq!(first.message, AnyMessage::EStop(latch));
    assert!(rx.receive(operator.id(), operator.data()).is_ok());
    assert_eq!(rx.counters().total(), 0);
    // A clear out of sequence is rejected; a corrupted latch is rejected too.
    let stale_clear = encode(&clear, (), 3).unwrap();
    assert_eq!(
        rx.receive(stale_clear.id(), stale_clear.data()),
        Err(DecodeError::WrongSequence { id: 0 })
    );
    let mut corrupted = operator.data().to_vec();
    corrupted[4] ^= 0x03;
    assert_eq!(
        rx.receive(operator.id(), &corrupted),
        Err(DecodeError::CrcMismatch { id: 0 })
    );
    // The genuine sequence's next clear is accepted.
    let clear_next = encode(&clear, (), 502).unwrap();
    assert!(rx.receive(clear_next.id(), clear_next.data()).is_ok());
}
