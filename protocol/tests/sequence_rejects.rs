//! One test per rejection cause of sequence and session (repeated, replayed, rate-limited,
//! stale release, forged, no session, stale or foreign announcement) and what is counted but
//! not refused (lost frames, E-stop latches out of sequence): each frame is rejected with a
//! typed error, counted under its cause by the receiver, and never returned as a message.

mod common;

use common::rejects::{controller, only_cause, teleop, teleop_frame};
use common::{announce_frame, controller_session, joined_member, EPOCH};
use protocol::*;

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
