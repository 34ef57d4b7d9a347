//! Every status of the E2E receiver.

use protocol::e2e::{crc, protect, verify, HEADER_LEN};
use protocol::{E2eChecker, E2eCounter, E2eStatus};

fn checker_after(counters: &[u16]) -> E2eChecker {
    let mut checker = E2eChecker::new(3);
    for &c in counters {
        assert!(checker.check_counter(c).is_accepted(), "setup counter {c}");
    }
    checker
}

#[test]
fn first_frame_is_initial_then_ok() {
    let mut checker = E2eChecker::new(3);
    assert_eq!(checker.check_counter(40), E2eStatus::Initial);
    assert_eq!(checker.check_counter(41), E2eStatus::Ok);
}

#[test]
fn a_gap_within_the_window_is_ok_some_lost() {
    let mut checker = checker_after(&[10]);
    assert_eq!(checker.check_counter(13), E2eStatus::OkSomeLost { lost: 2 });
    assert_eq!(checker.check_counter(14), E2eStatus::Ok);
}

#[test]
fn the_same_counter_twice_is_repeated() {
    let mut checker = checker_after(&[10]);
    assert_eq!(checker.check_counter(10), E2eStatus::Repeated);
    assert_eq!(
        checker.check_counter(11),
        E2eStatus::Ok,
        "a repeat does not disturb the sequence"
    );
}

#[test]
fn a_jump_beyond_the_window_or_backwards_is_wrong_sequence() {
    let mut checker = checker_after(&[10]);
    assert_eq!(checker.check_counter(14), E2eStatus::WrongSequence);
    assert_eq!(checker.check_counter(9), E2eStatus::WrongSequence);
    assert_eq!(
        checker.check_counter(11),
        E2eStatus::Ok,
        "rejected frames do not move the sequence"
    );
}

#[test]
fn a_restarted_sender_is_resynchronised_after_two_consecutive_frames() {
    let mut checker = checker_after(&[5000, 5001]);
    assert_eq!(checker.check_counter(0), E2eStatus::WrongSequence);
    assert_eq!(checker.check_counter(1), E2eStatus::Initial);
    assert_eq!(checker.check_counter(2), E2eStatus::Ok);
}

#[test]
fn a_single_replayed_frame_does_not_resynchronise() {
    let mut checker = checker_after(&[5000]);
    assert_eq!(checker.check_counter(100), E2eStatus::WrongSequence);
    assert_eq!(checker.check_counter(5001), E2eStatus::Ok);
    assert_eq!(
        checker.check_counter(101),
        E2eStatus::WrongSequence,
        "the replay candidate was dropped"
    );
}

#[test]
fn the_counter_wraps() {
    let mut checker = checker_after(&[u16::MAX - 1, u16::MAX]);
    assert_eq!(checker.check_counter(0), E2eStatus::Ok);
    let mut counter = E2eCounter::starting_at(u16::MAX);
    assert_eq!((counter.advance(), counter.advance()), (u16::MAX, 0));
}

#[test]
fn a_corrupted_message_is_crc_error_and_leaves_the_sequence_alone() {
    let data_id = 0xC123;
    let mut message = [0_u8; HEADER_LEN + 6];
    message[HEADER_LEN..].copy_from_slice(b"robot!");
    protect(data_id, 7, &mut message);
    assert_eq!(verify(data_id, &message), Some(7));

    let mut checker = E2eChecker::default();
    let mut corrupted = message;
    corrupted[HEADER_LEN + 2] ^= 0x10;
    assert_eq!(
        checker.check_message(data_id, &corrupted),
        E2eStatus::CrcError
    );
    assert_eq!(
        checker.check_message(data_id ^ 1, &message),
        E2eStatus::CrcError,
        "wrong data id"
    );
    assert_eq!(checker.check_message(data_id, &message), E2eStatus::Initial);
    assert_eq!(
        checker.check_message(data_id, &message),
        E2eStatus::Repeated
    );
}

#[test]
fn crc_is_ccitt_false_over_data_then_data_id() {
    // CRC-16/CCITT-FALSE check value: "123456789" → 0x29B1; the data id is appended low byte
    // first, so the E2E CRC equals the plain CRC of the concatenation.
    let reference = crc::Crc::<u16>::new(&crc::CRC_16_IBM_3740);
    assert_eq!(reference.checksum(b"123456789"), 0x29B1);
    let mut concatenated = b"123456789".to_vec();
    concatenated.extend_from_slice(&[0x12, 0x34]);
    assert_eq!(crc(0x3412, b"123456789"), reference.checksum(&concatenated));
}

#[test]
fn too_short_messages_are_never_verified() {
    assert_eq!(verify(0, &[]), None);
    assert_eq!(verify(0, &[1, 2, 3]), None);
}

#[test]
fn a_jump_past_the_window_names_the_frames_skipped_and_a_step_back_none() {
    let mut checker = checker_after(&[10]);
    assert_eq!(checker.skipped_ahead(11), None, "in sequence");
    assert_eq!(
        checker.skipped_ahead(13),
        None,
        "inside the window: OkSomeLost counts it"
    );
    assert_eq!(checker.skipped_ahead(10), None, "a repeat");
    assert_eq!(
        checker.skipped_ahead(5),
        None,
        "behind: stale or replayed, not lost"
    );
    assert_eq!(checker.skipped_ahead(10u16.wrapping_sub(20)), None);
    assert_eq!(checker.skipped_ahead(30), Some(19));
    assert_eq!(checker.check_counter(30), E2eStatus::WrongSequence);
    // A second jump counts from the pending one, so no frame is counted twice.
    assert_eq!(checker.skipped_ahead(40), Some(9));
    assert_eq!(checker.check_counter(40), E2eStatus::WrongSequence);
    assert_eq!(
        checker.skipped_ahead(40),
        None,
        "the pending counter again: a repeat"
    );
    assert_eq!(
        checker.skipped_ahead(35),
        Some(24),
        "behind the pending counter but past the window: counted from the last accepted"
    );
    assert_eq!(
        checker.skipped_ahead(41),
        None,
        "the sequence resynchronises here"
    );
    assert_eq!(checker.check_counter(41), E2eStatus::Initial);
}

#[test]
fn half_the_counter_range_ahead_counts_as_behind() {
    let checker = checker_after(&[10]);
    assert_eq!(checker.skipped_ahead(10 + 0x7FFF), Some(0x7FFE));
    assert_eq!(checker.skipped_ahead(10 + 0x8000), None);
    // A pending counter half the range ahead is no reference either.
    let mut checker = checker_after(&[10]);
    assert_eq!(checker.check_counter(10 + 0x8000), E2eStatus::WrongSequence);
    assert_eq!(checker.skipped_ahead(10 + 0x8005), None);
}

#[test]
fn the_receiver_counts_frames_skipped_by_a_long_burst_as_lost() {
    let mut receiver = protocol::Receiver::default();
    let sync = |counter: u16| {
        protocol::AnyMessage::Sync(protocol::Sync {
            tick: protocol::Tick::from_raw(u32::from(counter)).unwrap(),
        })
        .encode(counter)
        .unwrap()
    };
    for counter in [0, 1, 2] {
        let frame = sync(counter);
        receiver.receive(frame.id(), frame.data()).unwrap();
    }
    // 30 frames lost in one burst (beyond the 10-frame window), then the sender goes on.
    let frame = sync(33);
    assert!(receiver.receive(frame.id(), frame.data()).is_err());
    let frame = sync(34);
    assert!(receiver.receive(frame.id(), frame.data()).is_ok());
    assert_eq!(receiver.counters().lost.raw(), 30);
    // A replay of an old frame is refused and counts no loss.
    let frame = sync(1);
    assert!(receiver.receive(frame.id(), frame.data()).is_err());
    assert_eq!(receiver.counters().lost.raw(), 30);
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
        E2eStatus::CrcError,
    ] {
        assert!(!status.is_accepted(), "{status:?}");
    }
}
