//! The E2E receiver's statuses along a sequence: initial, ok, frames lost, repeated, out of
//! sequence, a restarted sender and the wrap of the low counter.

mod common;

use common::checker::{checker_after, offer};
use protocol::e2e::Search;
use protocol::{
    AnyMessage, E2eChecker, E2eStatus, Epoch, Receiver, Session, SessionTime, Sync, Tick, TEST_KEY,
};

#[test]
fn first_frame_is_initial_then_ok() {
    let mut checker = E2eChecker::new();
    assert_eq!(checker.last(), None);
    assert_eq!(offer(&mut checker, 40), E2eStatus::Initial);
    assert_eq!(offer(&mut checker, 41), E2eStatus::Ok);
    assert_eq!(checker.last(), Some(41));
}

#[test]
fn a_gap_is_ok_some_lost() {
    let mut checker = checker_after(&[10]);
    assert_eq!(offer(&mut checker, 13), E2eStatus::OkSomeLost { lost: 2 });
    assert_eq!(offer(&mut checker, 14), E2eStatus::Ok);
    // No window short of half the counter range: a longer burst is accepted and counted too.
    assert_eq!(offer(&mut checker, 30), E2eStatus::OkSomeLost { lost: 15 });
    assert_eq!(checker.last(), Some(30));
}

/// A sender counts one frame a millisecond at most: a jump ahead by more frames than
/// milliseconds passed since the last accepted frame (with 100 ms of slack for a member's view
/// of the time) is a sender that restarted at the session time, not a loss.
#[test]
fn a_jump_past_the_elapsed_time_is_a_restart_not_a_loss() {
    let at = Search::new;
    let mut checker = E2eChecker::new();
    let mut offer_at = |sent: u32, now: u32| checker.check(sent as u16, at(now), |f| f == sent);
    assert_eq!(offer_at(1_000, 1_000), E2eStatus::Initial);
    // 300 ms later: up to 400 frames lost is a loss, 401 a restart.
    assert_eq!(offer_at(1_401, 1_300), E2eStatus::OkSomeLost { lost: 400 });
    assert_eq!(offer_at(1_803, 1_600), E2eStatus::Initial);
    assert_eq!(offer_at(1_804, 1_600), E2eStatus::Ok);
    // A slow sender's loss: 9 frames in 500 ms.
    assert_eq!(offer_at(1_814, 2_100), E2eStatus::OkSomeLost { lost: 9 });
}

#[test]
fn the_same_counter_twice_is_repeated() {
    let mut checker = checker_after(&[10]);
    assert_eq!(offer(&mut checker, 10), E2eStatus::Repeated);
    assert_eq!(
        offer(&mut checker, 11),
        E2eStatus::Ok,
        "a repeat does not disturb the sequence"
    );
}

#[test]
fn a_step_backwards_is_wrong_sequence() {
    let mut checker = checker_after(&[10]);
    assert_eq!(offer(&mut checker, 9), E2eStatus::WrongSequence);
    assert_eq!(offer(&mut checker, 0), E2eStatus::WrongSequence);
    assert_eq!(
        offer(&mut checker, 11),
        E2eStatus::Ok,
        "rejected frames do not move the sequence"
    );
}

/// Wire version 1 resynchronised on two consecutive frames, which let a replay of two
/// recorded frames take over the sequence. Now frames behind the sequence never move it, however
/// many there are in a row.
#[test]
fn frames_behind_the_sequence_never_take_it_over() {
    let mut checker = checker_after(&[5000, 5001]);
    for replayed in 0..100 {
        assert_eq!(
            offer(&mut checker, replayed),
            E2eStatus::WrongSequence,
            "replayed frame {replayed}"
        );
    }
    assert_eq!(checker.last(), Some(5001));
    // A new session: the receiver forgets the sequence and the sender starts at the session
    // time, here the start.
    checker.reset();
    assert_eq!(offer(&mut checker, 0), E2eStatus::Initial);
    assert_eq!(offer(&mut checker, 1), E2eStatus::Ok);
}

/// A sender restarted within the session starts its counters at the session time, which is
/// past every counter it sent before: it is in sequence (the frames between count as lost), or,
/// 2^15 or more ahead, found by the search.
#[test]
fn a_sender_restarted_within_the_session_is_taken_from_its_first_frame() {
    let mut checker = checker_after(&[5000, 5001]);
    // Restarted at session time 5100.
    assert_eq!(
        offer(&mut checker, 5100),
        E2eStatus::OkSomeLost { lost: 98 }
    );
    assert_eq!(offer(&mut checker, 5101), E2eStatus::Ok);
    // Restarted again, 100 s later: 2^15 and more ahead.
    let restart = 105_101;
    assert_eq!(offer(&mut checker, restart), E2eStatus::Initial);
    assert_eq!(offer(&mut checker, restart + 1), E2eStatus::Ok);
    // Its earlier lives' frames stay behind.
    for old in [5001, 5100, 5101, restart - 0x8000, restart] {
        assert!(!offer(&mut checker, old).is_accepted(), "{old}");
    }
    assert_eq!(checker.last(), Some(restart + 1));
}

#[test]
fn a_single_replayed_frame_does_not_disturb_the_sequence() {
    let mut checker = checker_after(&[5000]);
    assert_eq!(offer(&mut checker, 100), E2eStatus::WrongSequence);
    assert_eq!(offer(&mut checker, 5001), E2eStatus::Ok);
    assert_eq!(offer(&mut checker, 101), E2eStatus::WrongSequence);
    assert_eq!(offer(&mut checker, 5002), E2eStatus::Ok);
}

#[test]
fn the_counter_wraps_into_the_high_half() {
    let mut checker = checker_after(&[0xFFFE, 0xFFFF]);
    assert_eq!(offer(&mut checker, 0x1_0000), E2eStatus::Ok);
    assert_eq!(checker.last(), Some(0x1_0000));
    // The frame of full counter 0 has the same low half as the one just accepted, but its
    // check holds only at 0: a replay from 2^16 frames ago fails its check.
    assert_eq!(offer(&mut checker, 0), E2eStatus::CheckFailed);
    assert_eq!(offer(&mut checker, 0x1_0001), E2eStatus::Ok);
    assert_eq!(offer(&mut checker, 1), E2eStatus::CheckFailed);
    assert_eq!(offer(&mut checker, 0xFFFF), E2eStatus::WrongSequence);
    assert_eq!(checker.last(), Some(0x1_0001));
}

#[test]
fn the_receiver_counts_frames_lost_in_a_burst() {
    let session = Session::owned(TEST_KEY, Epoch::new(3)).at(SessionTime::from_ms(40));
    let mut receiver = Receiver::owner(session);
    let sync = |counter: u32| {
        AnyMessage::Sync(Sync {
            tick: Tick::from_raw(counter).unwrap(),
        })
        .encode(&session, counter)
        .unwrap()
    };
    for counter in [0, 1, 2] {
        let frame = sync(counter);
        receiver.receive(frame.id(), frame.data()).unwrap();
    }
    // 30 frames lost in one burst, then the sender goes on.
    let frame = sync(33);
    assert_eq!(
        receiver.receive(frame.id(), frame.data()).unwrap().status,
        E2eStatus::OkSomeLost { lost: 30 }
    );
    let frame = sync(34);
    assert_eq!(
        receiver.receive(frame.id(), frame.data()).unwrap().status,
        E2eStatus::Ok
    );
    assert_eq!(receiver.counters().lost.raw(), 30);
    // A replay of an old frame is refused and counts no loss.
    let frame = sync(1);
    assert!(receiver.receive(frame.id(), frame.data()).is_err());
    assert_eq!(receiver.counters().lost.raw(), 30);
    assert_eq!(receiver.counters().total(), 1);
}

#[test]
fn only_in_sequence_frames_are_accepted() {
    for status in [
        E2eStatus::Ok,
        E2eStatus::OkSomeLost { lost: 3 },
        E2eStatus::Initial,
    ] {
        assert!(status.is_accepted(), "{status:?}");
    }
    for status in [
        E2eStatus::Repeated,
        E2eStatus::WrongSequence,
        E2eStatus::CheckFailed,
    ] {
        assert!(!status.is_accepted(), "{status:?}");
    }
}
