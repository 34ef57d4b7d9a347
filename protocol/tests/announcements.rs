//! The announcement rules: a member joins on one, moves to a greater epoch, refuses a smaller
//! one, an earlier time or another wire version; the controller takes its own at any time.

mod common;

use common::frames::{receive, wheel_command, NEW, OLD};
use common::{announce_frame, announce_frame_at, joined_member, member_at, owner_at};
use protocol::*;

#[test]
fn a_member_joins_on_the_announcement() {
    let mut member = Receiver::member(TEST_KEY);
    let mut tx = Sender::new();
    assert_eq!(member.session().epoch(), None);
    // Before it: bound frames neither go out nor come in; the latch does both.
    let command = AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
        uptime: Millis::from_raw(1).unwrap(),
    });
    assert_eq!(
        tx.seal(member.session(), &command),
        Err(EncodeError::NoSession)
    );
    assert_eq!(
        receive(&mut member, &wheel_command(0, OLD)),
        Err(DecodeError::NoSession { id: 0x101 })
    );
    let latch = tx
        .seal(
            member.session(),
            &AnyMessage::EStop(EStop::latch(NodeId::Teleop)),
        )
        .unwrap();
    assert!(receive(&mut Receiver::member(TEST_KEY), &latch).is_ok());

    let announce = announce_frame(WireVersion::THIS, OLD, 3);
    let accepted = receive(&mut member, &announce).unwrap();
    assert_eq!(accepted.status, E2eStatus::Initial);
    assert_eq!(
        accepted.message,
        AnyMessage::Announce(Announce {
            version: WireVersion::THIS,
            epoch: OLD,
            time: SessionTime::from_ms(300),
        })
    );
    assert_eq!(member.session().epoch(), Some(OLD));
    assert_eq!(member.session().time(), SessionTime::from_ms(300));
    assert_eq!(*member.session().key(), TEST_KEY);
    assert_eq!(
        receive(&mut member, &wheel_command(0, OLD)).unwrap().status,
        E2eStatus::Initial
    );
    // Its first bound frame starts its counter on that id at the session time it joined at:
    // the refused attempt above used none.
    let frame = tx.seal(member.session(), &command).unwrap();
    assert_eq!(decode_frame(frame.id(), frame.data()).unwrap().counter, 300);
    let mut owner = owner_at(OLD, 320);
    assert_eq!(
        receive(&mut owner, &frame).unwrap().status,
        E2eStatus::Initial
    );
}

#[test]
fn a_greater_epoch_moves_the_member_and_restarts_every_counter() {
    let mut member = joined_member(OLD);
    let mut tx = Sender::new();
    for counter in 0..=5000 {
        receive(&mut member, &wheel_command(counter, OLD)).unwrap();
    }
    let heartbeat = AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
        uptime: Millis::from_raw(1).unwrap(),
    });
    for expected in 0..10 {
        let frame = tx.seal(member.session(), &heartbeat).unwrap();
        assert_eq!(
            decode_frame(frame.id(), frame.data()).unwrap().counter,
            expected
        );
    }

    // The restarted controller opens its session at time 0 and announces it; a member hears
    // the announcement 200 ms in.
    let announce = announce_frame(WireVersion::THIS, NEW, 2);
    assert!(receive(&mut member, &announce).is_ok());
    assert_eq!(member.session().epoch(), Some(NEW));
    assert_eq!(member.session().time(), SessionTime::from_ms(200));
    // The controller's counters started at its session time, 0, and the member follows.
    assert_eq!(
        receive(&mut member, &wheel_command(0, NEW)).unwrap().status,
        E2eStatus::Initial
    );
    assert_eq!(
        receive(&mut member, &wheel_command(1, NEW)).unwrap().status,
        E2eStatus::Ok
    );
    // The old session's frames, before and after the point the member had reached, are dead.
    for counter in [0, 1, 2, 4999, 5000, 5001, 5002] {
        assert_eq!(
            receive(&mut member, &wheel_command(counter, OLD)),
            Err(DecodeError::CrcMismatch { id: 0x101 }),
            "old-session counter {counter}"
        );
    }
    // The member's own sender starts again too, at the session time it is in.
    let frame = tx.seal(member.session(), &heartbeat).unwrap();
    assert_eq!(decode_frame(frame.id(), frame.data()).unwrap().counter, 200);
    let mut owner = owner_at(NEW, 230);
    assert_eq!(
        receive(&mut owner, &frame).unwrap().status,
        E2eStatus::Initial
    );
    assert_eq!(member.counters().get(RejectCause::Crc).raw(), 7);
    assert_eq!(member.counters().total(), 7);
}

#[test]
fn a_smaller_epoch_is_refused_as_stale() {
    let mut member = joined_member(NEW);
    receive(&mut member, &wheel_command(0, NEW)).unwrap();
    for counter in [0, 1, 7, 0xFFFF] {
        let old = announce_frame(WireVersion::THIS, OLD, counter);
        assert_eq!(
            receive(&mut member, &old),
            Err(DecodeError::StaleSession { id: 0x020 })
        );
    }
    assert_eq!(
        receive(
            &mut member,
            &announce_frame(WireVersion::THIS, Epoch::new(0), 0)
        ),
        Err(DecodeError::StaleSession { id: 0x020 })
    );
    assert_eq!(member.session().epoch(), Some(NEW));
    assert_eq!(member.counters().get(RejectCause::Session).raw(), 5);
    // The session goes on.
    assert_eq!(
        receive(&mut member, &wheel_command(1, NEW)).unwrap().status,
        E2eStatus::Ok
    );
    // The controller refuses an announcement of any session but its own.
    let mut owner = Receiver::owner(Session::owned(TEST_KEY, OLD));
    for epoch in [Epoch::new(OLD.raw() - 1), NEW] {
        let frame = announce_frame(WireVersion::THIS, epoch, 0);
        assert_eq!(
            receive(&mut owner, &frame),
            Err(DecodeError::StaleSession { id: 0x020 }),
            "{epoch:?}"
        );
        assert_eq!(owner.session().epoch(), Some(OLD));
    }
}

#[test]
fn an_announcement_of_the_same_epoch_replayed_is_refused() {
    let mut member = Receiver::member(TEST_KEY);
    let announces: Vec<Frame> = (0..5)
        .map(|counter| announce_frame(WireVersion::THIS, OLD, counter))
        .collect();
    for frame in &announces[..4] {
        assert!(receive(&mut member, frame).is_ok());
    }
    receive(&mut member, &wheel_command(0, OLD)).unwrap();
    // The latest again (as the controller repeats it while its clock stands) is taken and
    // moves nothing; the earlier ones are refused.
    assert!(receive(&mut member, &announces[3]).is_ok());
    assert_eq!(member.session().time(), SessionTime::from_ms(300));
    for frame in &announces[..3] {
        assert_eq!(
            receive(&mut member, frame),
            Err(DecodeError::WrongSequence { id: 0x020 })
        );
    }
    assert_eq!(member.counters().get(RejectCause::Repeated).raw(), 0);
    assert_eq!(member.counters().get(RejectCause::WrongSequence).raw(), 3);
    assert_eq!(member.counters().total(), 3);
    // The next genuine one is taken, a gap is no matter, and none of this reset the session.
    assert!(receive(&mut member, &announces[4]).is_ok());
    assert!(receive(&mut member, &announce_frame(WireVersion::THIS, OLD, 40)).is_ok());
    assert_eq!(
        receive(&mut member, &wheel_command(1, OLD)).unwrap().status,
        E2eStatus::Ok
    );
    assert_eq!(member.session().time(), SessionTime::from_ms(4000));
}

/// In its epoch a member orders announcements by their session time, not their counter: it
/// moves to a time after the last it heard, takes the same time again without effect (the
/// controller repeats its announcement while its clock stands), and refuses an earlier one.
#[test]
fn a_member_takes_an_announcement_only_with_a_later_time() {
    let at = |ms, counter| announce_frame_at(WireVersion::THIS, OLD, ms, counter);
    let mut member = member_at(OLD, 5_000);
    receive(&mut member, &wheel_command(4_990, OLD)).unwrap();
    // The same time under another counter is taken and moves nothing; an earlier time is
    // stale, whatever its counter.
    assert!(receive(&mut member, &at(5_000, 77)).is_ok());
    assert_eq!(member.session().time(), SessionTime::from_ms(5_000));
    assert_eq!(
        receive(&mut member, &wheel_command(4_991, OLD))
            .unwrap()
            .status,
        E2eStatus::Ok,
        "the sequences stand"
    );
    assert_eq!(
        receive(&mut member, &at(4_999, 1_000)),
        Err(DecodeError::WrongSequence { id: 0x020 })
    );
    assert_eq!(
        receive(&mut member, &at(0, 0)),
        Err(DecodeError::WrongSequence { id: 0x020 })
    );
    assert_eq!(member.session().time(), SessionTime::from_ms(5_000));
    // A later time under a smaller counter moves it, however long after.
    let accepted = receive(&mut member, &at(5_001, 0)).unwrap();
    assert_eq!(accepted.status, E2eStatus::Initial);
    assert_eq!(member.session().time(), SessionTime::from_ms(5_001));
    assert!(receive(&mut member, &at(4_000_000_000, 3)).is_ok());
    assert_eq!(member.session().time(), SessionTime::from_ms(4_000_000_000));
    assert_eq!(member.counters().get(RejectCause::WrongSequence).raw(), 2);
    assert_eq!(member.counters().total(), 2);
    // A greater epoch moves it to that session's time, even an earlier one.
    assert!(receive(
        &mut member,
        &announce_frame_at(WireVersion::THIS, NEW, 10, 0)
    )
    .is_ok());
    assert_eq!(member.session().epoch(), Some(NEW));
    assert_eq!(member.session().time(), SessionTime::from_ms(10));
}

/// The controller hears its own announcements on the bus: in its epoch it takes them at any
/// time (its clock is its own, not the announcements'), and moves nowhere.
#[test]
fn the_controller_takes_its_own_announcements_whatever_their_time() {
    let mut owner = owner_at(OLD, 7_000);
    for (ms, counter) in [(7_000, 70), (7_000, 70), (100, 1), (9_000_000, 2)] {
        let frame = announce_frame_at(WireVersion::THIS, OLD, ms, counter);
        assert!(receive(&mut owner, &frame).is_ok(), "{ms} ms");
        assert_eq!(owner.session().time(), SessionTime::from_ms(7_000));
        assert_eq!(owner.session().epoch(), Some(OLD));
    }
    assert_eq!(owner.counters().total(), 0);
    // Its time is set by its clock alone; a member's is not.
    owner.set_time(SessionTime::from_ms(8_000));
    assert_eq!(owner.session().time(), SessionTime::from_ms(8_000));
    let mut member = member_at(OLD, 7_000);
    member.set_time(SessionTime::from_ms(8_000));
    assert_eq!(member.session().time(), SessionTime::from_ms(7_000));
}

#[test]
fn an_announcement_of_another_wire_version_is_refused_and_joins_nothing() {
    for theirs in [0, 1, WIRE_VERSION + 1, u8::MAX] {
        let version = WireVersion::from_raw(theirs).unwrap();
        let expected = Err(DecodeError::WireVersion { theirs });
        let mut unjoined = Receiver::member(TEST_KEY);
        assert_eq!(
            receive(&mut unjoined, &announce_frame(version, OLD, 0)),
            expected
        );
        assert_eq!(unjoined.session().epoch(), None);
        // Not even a newer controller moves a member to a session it cannot read.
        let mut member = joined_member(OLD);
        assert_eq!(
            receive(&mut member, &announce_frame(version, NEW, 0)),
            expected
        );
        assert_eq!(member.session().epoch(), Some(OLD));
        assert_eq!(member.counters().get(RejectCause::Session).raw(), 1);
        let mut owner = Receiver::owner(Session::owned(TEST_KEY, OLD));
        assert_eq!(
            receive(&mut owner, &announce_frame(version, OLD, 0)),
            expected
        );
    }
}
