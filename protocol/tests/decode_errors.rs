//! One test per rejection cause: the frame is rejected with a typed error, counted under its
//! cause by the receiver, and never returned as a message.

mod common;

use common::{announce_frame, controller_session, joined_member, EPOCH};
use protocol::e2e::{self, Freshness, HEADER_LEN};
use protocol::*;

fn teleop(mode: TeleopMode) -> TeleopCommand {
    TeleopCommand {
        mode,
        body_height: BodyHeight::from_si(0.0).unwrap(),
        speed_scale: SpeedScale::from_si(100.0).unwrap(),
    }
}

/// The teleop's command with full counter `counter`, in the controller's session.
fn teleop_frame(counter: u32) -> Frame {
    encode(
        &teleop(TeleopMode::WheelForward),
        (),
        &controller_session(),
        counter,
    )
    .unwrap()
}

/// The controller's receiver.
fn controller() -> Receiver {
    Receiver::owner(controller_session())
}

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
    assert_eq!(rx.counters().get(RejectCause::WrongLength).raw(), 3);
    assert_eq!(rx.counters().total(), 3);
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
    let frame = teleop_frame(0);
    assert_eq!(
        MessageId::TeleopHeartbeat.layout().wire_len,
        frame.data().len()
    );
    // The data id differs.
    assert_eq!(
        rx.receive(MessageId::TeleopHeartbeat.raw(), frame.data()),
        Err(DecodeError::Unauthentic { id: 0x201 })
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
fn a_repeated_frame_is_rejected_and_counted() {
    let mut rx = controller();
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
    let mut rx = controller();
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
    let mut rx = controller();
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
fn a_release_for_another_latch_refused_by_the_caller_is_counted_as_stale_release() {
    let mut rx = controller();
    let release = encode(
        &EStop::release(NodeId::Teleop, ReleaseToken::new(4)),
        (),
        &controller_session(),
        0,
    )
    .unwrap();
    // The receiver authenticates the release; the token is the controller's to compare.
    let accepted = rx.receive(release.id(), release.data()).unwrap();
    assert_eq!(
        accepted.message,
        AnyMessage::EStop(EStop::release(NodeId::Teleop, ReleaseToken::new(4)))
    );
    rx.refuse(DecodeError::StaleRelease { id: release.id() });
    only_cause(&rx, RejectCause::StaleRelease);
    assert_eq!(
        rx.receive(release.id(), release.data()),
        Err(DecodeError::Repeated { id: 0 }),
        "and the same release again is a repeat"
    );
}

#[test]
fn a_forged_frame_is_rejected_as_unauthentic() {
    let mut rx = controller();
    let forged = encode(
        &teleop(TeleopMode::TrotForward),
        (),
        &Session::owned(Key([0x55; 16]), EPOCH),
        0,
    )
    .unwrap();
    assert_eq!(
        rx.receive(forged.id(), forged.data()),
        Err(DecodeError::Unauthentic { id: 0x200 })
    );
    only_cause(&rx, RejectCause::Unauthentic);
}

#[test]
fn a_bound_frame_before_the_announcement_is_rejected_as_no_session() {
    let mut rx = Receiver::member(TEST_KEY);
    let frame = teleop_frame(0);
    assert_eq!(
        rx.receive(frame.id(), frame.data()),
        Err(DecodeError::NoSession { id: 0x200 })
    );
    only_cause(&rx, RejectCause::Session);
}

#[test]
fn an_announcement_of_an_older_session_is_rejected_as_stale() {
    let mut rx = joined_member(EPOCH);
    let old = announce_frame(WireVersion::THIS, Epoch::new(EPOCH.raw() - 1), 0);
    assert_eq!(
        rx.receive(old.id(), old.data()),
        Err(DecodeError::StaleSession { id: 0x020 })
    );
    only_cause(&rx, RejectCause::Session);
}

#[test]
fn an_announcement_of_another_wire_version_is_rejected() {
    let mut rx = Receiver::member(TEST_KEY);
    let other = announce_frame(WireVersion::from_raw(WIRE_VERSION + 1).unwrap(), EPOCH, 0);
    assert_eq!(
        rx.receive(other.id(), other.data()),
        Err(DecodeError::WireVersion {
            theirs: WIRE_VERSION + 1
        })
    );
    only_cause(&rx, RejectCause::Session);
    assert_eq!(rx.session().epoch(), None, "not joined");
}

#[test]
fn lost_frames_are_accepted_and_counted_as_lost_not_rejected() {
    let mut rx = controller();
    for counter in [0, 1, 4] {
        let f = teleop_frame(counter);
        rx.receive(f.id(), f.data()).unwrap();
    }
    assert_eq!(rx.counters().lost.raw(), 2);
    assert_eq!(rx.counters().total(), 0);
}

#[test]
fn sequences_are_tracked_per_identifier() {
    let mut rx = controller();
    let teleop = teleop_frame(10);
    let heartbeat = encode(
        &TeleopHeartbeat {
            uptime: Millis::from_raw(5).unwrap(),
        },
        (),
        &controller_session(),
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

#[test]
fn an_estop_latch_acts_whatever_its_counter_but_a_release_must_be_in_sequence() {
    let latch = EStop::latch(NodeId::Tool);
    let release = EStop::release(NodeId::Tool, ReleaseToken::new(1));
    let session = controller_session();
    let mut rx = controller();
    for counter in [500, 501] {
        let f = encode(&release, (), &session, counter).unwrap();
        assert!(rx.receive(f.id(), f.data()).is_ok());
    }
    // An operator's cansend with counter 0, twice, and the same latch sent with no session
    // at all: every latch acts.
    for session in [session, Session::unjoined(TEST_KEY)] {
        let operator = encode(&latch, (), &session, 0).unwrap();
        for _ in 0..2 {
            let accepted = rx.receive(operator.id(), operator.data()).unwrap();
            assert_eq!(accepted.status, E2eStatus::Initial);
            assert_eq!(accepted.message, AnyMessage::EStop(latch));
        }
    }
    assert_eq!(rx.counters().total(), 0);
    // A release out of sequence is rejected; a corrupted latch is rejected too.
    let stale_release = encode(&release, (), &session, 3).unwrap();
    assert_eq!(
        rx.receive(stale_release.id(), stale_release.data()),
        Err(DecodeError::WrongSequence { id: 0 })
    );
    let operator = encode(&latch, (), &session, 0).unwrap();
    let mut corrupted = operator.data().to_vec();
    corrupted[4] ^= 0x03;
    assert_eq!(
        rx.receive(operator.id(), &corrupted),
        Err(DecodeError::CrcMismatch { id: 0 })
    );
    // The genuine sequence's next release is accepted, the latches between took no part.
    let release_next = encode(&release, (), &session, 502).unwrap();
    assert_eq!(
        rx.receive(release_next.id(), release_next.data())
            .unwrap()
            .status,
        E2eStatus::Ok
    );
}
