//! One test per rejection cause of a frame's content (identifier, length, check, range): the
//! frame is rejected with a typed error, counted under its cause by the receiver, and never
//! returned as a message. The causes of sequence and session are in `sequence_rejects.rs`.

mod common;

use common::rejects::{controller, only_cause, teleop, teleop_frame};
use common::{controller_session, joined_member, EPOCH};
use protocol::e2e::{self, Freshness, HEADER_LEN};
use protocol::*;

/// `frame`, sent with full counter `counter` in the controller's session, with `edit` applied
/// to its bytes and the check value recomputed with the key, as a sender with a bug (not a
/// corrupted link) would produce it.
fn resealed(frame: &Frame, counter: u32, edit: impl FnOnce(&mut [u8])) -> Vec<u8> {
    let id = MessageId::from_raw(frame.id()).unwrap();
    let mut data = frame.data().to_vec();
    edit(&mut data);
    let (protection, covered) = protection_of(id, &data);
    let freshness = Freshness {
        data_id: id.data_id(),
        epoch: protection.bound.then_some(EPOCH),
        counter,
    };
    e2e::protect(
        protection.check,
        &TEST_KEY,
        &freshness,
        &mut data[..HEADER_LEN + covered],
    )
    .unwrap();
    data
}

#[test]
fn unknown_id_is_rejected_and_counted() {
    let mut rx = controller();
    let frame = teleop_frame(0);
    assert_eq!(
        rx.receive(0x7AB, frame.data()),
        Err(DecodeError::UnknownId(0x7AB))
    );
    only_cause(&rx, RejectCause::UnknownId);
}

#[test]
fn wrong_length_is_rejected_and_counted() {
    let mut rx = joined_member(EPOCH);
    let frame = encode(
        &LegTargets {
            enable: DriveEnable::Enabled,
            position: [Angle::default(); 16].into(),
        },
        (),
        &controller_session(),
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
    // Only the E-stop latch has a classic 8-byte form.
    assert!(matches!(
        rx.receive(frame.id(), &frame.data()[..8]),
        Err(DecodeError::WrongLength { got: 8, .. })
    ));
    // The E-stop has two lengths, its CAN FD one and the classic 8 bytes: any other is refused
    // like any frame's, a latch padded longer included.
    let latch = AnyMessage::EStop(EStop::latch(NodeId::Tool))
        .encode(&Session::unjoined(TEST_KEY), 0)
        .unwrap();
    let mut padded = latch.data().to_vec();
    padded.resize(64, 0);
    assert!(matches!(
        rx.receive(latch.id(), &padded),
        Err(DecodeError::WrongLength { got: 64, .. })
    ));
    // The length is judged first, before the check value: a wrong length is named as such
    // whatever else is wrong.
    padded[0] ^= 0xFF;
    assert!(matches!(
        rx.receive(latch.id(), &padded),
        Err(DecodeError::WrongLength { got: 64, .. })
    ));
    assert_eq!(rx.counters().get(RejectCause::WrongLength).raw(), 5);
    assert_eq!(rx.counters().total(), 5);
}

#[test]
fn a_flipped_bit_anywhere_in_an_authenticated_frame_makes_it_unauthentic() {
    let frame = teleop_frame(7);
    let len = MessageId::TeleopCommand.layout().len;
    for byte in 0..len {
        for bit in 0..8 {
            let mut rx = controller();
            let mut data = frame.data().to_vec();
            data[byte] ^= 1 << bit;
            assert_eq!(
                rx.receive(frame.id(), &data),
                Err(DecodeError::Unauthentic { id: 0x200 }),
                "flip of byte {byte} bit {bit} was not caught"
            );
            only_cause(&rx, RejectCause::Unauthentic);
        }
    }
}

#[test]
fn a_flipped_bit_anywhere_in_a_crc_frame_fails_the_crc() {
    let status = ControllerStatus {
        mode: ControllerMode::Stop,
        faults: FaultFlags::EMPTY,
        tick: Tick::from_raw(77).unwrap(),
        body_height: BodyHeight::default(),
        pitch: Angle::default(),
        roll: Angle::default(),
        release_token: ReleaseToken::new(3),
    };
    let frame = encode(&status, (), &controller_session(), 7).unwrap();
    let len = MessageId::ControllerStatus.layout().len;
    for byte in 0..len {
        for bit in 0..8 {
            let mut rx = joined_member(EPOCH);
            let mut data = frame.data().to_vec();
            data[byte] ^= 1 << bit;
            assert_eq!(
                rx.receive(frame.id(), &data),
                Err(DecodeError::CrcMismatch { id: 0x400 }),
                "flip of byte {byte} bit {bit} was not caught"
            );
            only_cause(&rx, RejectCause::Crc);
        }
    }
}

#[test]
fn a_frame_moved_to_another_id_of_the_same_length_fails_its_check() {
    let mut rx = controller();
    // A heartbeat (uptime 0: its first payload byte is not the latch's action) moved onto the
    // E-stop's identifier would read as a release: its check covers the data id, so it fails.
    let heartbeat = TeleopHeartbeat {
        uptime: Millis::from_raw(0).unwrap(),
    };
    let frame = encode(&heartbeat, (), &controller_session(), 0).unwrap();
    assert_eq!(MessageId::EStop.layout().wire_len, frame.data().len());
    assert_eq!(
        rx.receive(MessageId::EStop.raw(), frame.data()),
        Err(DecodeError::Unauthentic { id: 0x000 })
    );
    only_cause(&rx, RejectCause::Unauthentic);
}

#[test]
fn out_of_range_values_are_rejected_even_with_a_valid_check() {
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
        let mut rx = controller();
        let data = resealed(&frame, 0, edit);
        assert_eq!(
            rx.receive(frame.id(), &data),
            Err(DecodeError::OutOfRange { id: 0x200 }),
            "{what}"
        );
        only_cause(&rx, RejectCause::OutOfRange);
    }
    // An unknown flag bit, on a CRC frame.
    let status = encode(
        &DriveStatus {
            flags: DriveFlags::ENABLED,
            rejected: Count::ZERO,
            commands: Count::ZERO,
        },
        Drive::Wheel,
        &controller_session(),
        0,
    )
    .unwrap();
    let data = resealed(&status, 0, |d| d[HEADER_LEN] = 0x80);
    assert!(matches!(
        decode_frame(status.id(), &data),
        Err(DecodeError::OutOfRange { .. })
    ));
    let mut rx = controller();
    assert_eq!(
        rx.receive(status.id(), &data),
        Err(DecodeError::OutOfRange { id: 0x414 })
    );
    only_cause(&rx, RejectCause::OutOfRange);
}

#[test]
fn decode_frame_parses_without_verifying_the_check() {
    // `decode_frame` is the stateless parser: a frame with a wrong check value parses, and only
    // the receiver refuses it.
    let frame = teleop_frame(3);
    let mut data = frame.data().to_vec();
    data[0] ^= 0xFF;
    let decoded = decode_frame(frame.id(), &data).unwrap();
    assert_eq!(
        decoded.message,
        AnyMessage::TeleopCommand(teleop(TeleopMode::WheelForward))
    );
    assert_eq!(decoded.counter, 3);
    assert_eq!(
        controller().receive(frame.id(), &data),
        Err(DecodeError::Unauthentic { id: 0x200 })
    );
}

#[test]
fn every_cause_has_its_own_counter_and_name() {
    let mut counters = RejectCounters::default();
    for (i, cause) in RejectCause::ALL.into_iter().enumerate() {
        assert_eq!(cause as usize, i);
        counters.record(cause);
        assert_eq!(counters.get(cause).raw(), 1, "{cause:?}");
        assert_eq!(counters.total(), i as u32 + 1);
    }
    let mut names: Vec<&str> = RejectCause::ALL.iter().map(|c| c.name()).collect();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), RejectCause::ALL.len());
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
    // A version mismatch names both versions, so the operator knows which side to update.
    let text = DecodeError::WireVersion { theirs: 7 }.to_string();
    assert!(
        text.contains('7') && text.contains(&WIRE_VERSION.to_string()),
        "{text}"
    );
    for error in [
        DecodeError::Unauthentic { id: 0x200 },
        DecodeError::NoSession { id: 0x200 },
        DecodeError::StaleSession { id: 0x020 },
        DecodeError::StaleRelease { id: 0x000 },
    ] {
        let text = error.to_string();
        assert!(text.starts_with("CAN id 0x"), "{text}");
    }
}
