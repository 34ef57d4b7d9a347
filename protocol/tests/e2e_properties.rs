//! Properties of the E2E receiver over arbitrary histories, gaps, replays and searches, and of
//! its check values over arbitrary keys, counters and payloads.

mod common;

use common::checker::{offer, offer_forged};
use common::protected::protected;
use common::search::among_candidates;
use proptest::prelude::*;
use protocol::e2e::{check_value, header, Freshness, Search, HEADER_LEN};
use protocol::{Check, E2eChecker, E2eStatus, Epoch, TEST_KEY};

fn any_check() -> impl Strategy<Value = Check> {
    prop_oneof![Just(Check::Crc), Just(Check::Mac)]
}

fn any_epoch() -> impl Strategy<Value = Option<Epoch>> {
    proptest::option::of(any::<u32>().prop_map(Epoch::new))
}

/// A genuine sender's history as a checker saw it: a first counter anywhere in the first
/// `2^16 · 8` and gaps of up to half the counter range.
fn history() -> impl Strategy<Value = (u32, Vec<u32>)> {
    (
        0_u32..(8 << 16),
        proptest::collection::vec(
            prop_oneof![4 => Just(1_u32), 2 => 2_u32..100, 1 => 100_u32..0x8000],
            0..40,
        ),
    )
}

/// A checker that accepted the frames of `history`, and the last counter.
fn replay_history(start: u32, gaps: &[u32]) -> (E2eChecker, u32) {
    let mut checker = E2eChecker::new();
    assert_eq!(offer(&mut checker, start), E2eStatus::Initial);
    let mut last = start;
    for &gap in gaps {
        last += gap;
        let expected = if gap == 1 {
            E2eStatus::Ok
        } else {
            E2eStatus::OkSomeLost { lost: gap - 1 }
        };
        assert_eq!(offer(&mut checker, last), expected);
    }
    (checker, last)
}

proptest! {
    /// Every gap short of half the counter range is in sequence, counted as lost, and the
    /// checker follows the sender's full counter across any number of wraps of the low half.
    #[test]
    fn gaps_below_half_the_range_are_accepted_and_counted((start, gaps) in history()) {
        let (checker, last) = replay_history(start, &gaps);
        prop_assert_eq!(checker.last(), Some(last));
    }

    /// A genuine frame sent `age` frames before the last accepted one, replayed: a repeat, stale
    /// while the low half can tell, and a failed check from half the counter range on — never
    /// accepted, and the sequence goes on undisturbed.
    #[test]
    fn a_replayed_earlier_frame_is_refused_according_to_its_age(
        (start, gaps) in history(),
        age in prop_oneof![
            0_u32..0x100,
            0x7F00_u32..0x8100,
            0_u32..(6 << 16),
            proptest::sample::select(&[0x7FFF_u32, 0x8000, 0x8001, 0xFFFF, 0x1_0000, 0x1_0001][..]),
        ],
    ) {
        let start = start + (6 << 16);
        let (mut checker, last) = replay_history(start, &gaps);
        // 2^15 behind is still behind; ahead by 2^15 is not ahead (see below).
        let expected = match age {
            0 => E2eStatus::Repeated,
            1..=0x8000 => E2eStatus::WrongSequence,
            _ => E2eStatus::CheckFailed,
        };
        prop_assert_eq!(offer(&mut checker, last - age), expected);
        prop_assert_eq!(checker.last(), Some(last));
        prop_assert_eq!(offer(&mut checker, last + 1), E2eStatus::Ok);
    }

    /// A genuine frame half the counter range or more ahead (a gap of 2^15 frames or more) is
    /// found when the receiver's time has reached it, as a sender's counter never passes the
    /// session time: the sequence restarts there.
    #[test]
    fn a_frame_half_the_range_or_more_ahead_is_found_at_its_time(
        (start, gaps) in history(),
        ahead in prop_oneof![0x8000_u32..0x8100, 0xFF00_u32..0x1_0100, 0x8000_u32..0x1000_0000],
    ) {
        let (mut checker, last) = replay_history(start, &gaps);
        prop_assert_eq!(offer(&mut checker, last + ahead), E2eStatus::Initial);
        prop_assert_eq!(checker.last(), Some(last + ahead));
        prop_assert_eq!(offer(&mut checker, last + ahead + 1), E2eStatus::Ok);
    }

    /// The same frame, at a receiver whose time is `now`: found exactly when it is one of the
    /// two candidates of the search (2^15 ahead of `now` to 2^15 + 2^16 behind it); refused
    /// otherwise, and the sequence unchanged.
    #[test]
    fn a_frame_half_the_range_or_more_ahead_is_found_only_near_the_receivers_time(
        (start, gaps) in history(),
        ahead in prop_oneof![0x8000_u32..0x8100, 0xFF00_u32..0x1_0100, 0x8000_u32..0x1000_0000],
        lead in 0_u32..0x4_0000,
    ) {
        let (mut checker, last) = replay_history(start, &gaps);
        let sent = last + ahead;
        let now = (last + lead).min(sent + 0x2_0000);
        let status = checker.check(sent as u16, Search::new(now), |full| full == sent);
        let distance = i64::from(sent) - i64::from(now);
        prop_assert_eq!(
            among_candidates(now, 2, sent),
            (-0x1_8000..=0x8000).contains(&distance)
                && !(distance == 0x8000 && now & 0xFFFF >= 0x8000)
                && !(distance == -0x1_8000 && now & 0xFFFF < 0x8000)
        );
        if among_candidates(now, 2, sent) {
            prop_assert_eq!(status, E2eStatus::Initial);
            prop_assert_eq!(checker.last(), Some(sent));
        } else {
            prop_assert_eq!(status, E2eStatus::CheckFailed);
            prop_assert_eq!(checker.last(), Some(last));
        }
    }

    /// A frame whose check holds at no counter never enters or moves a sequence.
    #[test]
    fn a_forged_frame_never_moves_the_sequence(
        (start, gaps) in history(),
        low in any::<u16>(),
        reference in any::<u32>(),
        tries in 0_u32..300,
    ) {
        let mut fresh = E2eChecker::new();
        prop_assert_eq!(
            fresh.check(low, Search { reference, tries }, |_| false),
            E2eStatus::CheckFailed
        );
        prop_assert_eq!(fresh.last(), None);
        let (mut checker, last) = replay_history(start, &gaps);
        prop_assert_eq!(offer_forged(&mut checker, low), E2eStatus::CheckFailed);
        prop_assert_eq!(checker.last(), Some(last));
    }

    /// A first frame is found exactly when it is among the `tries` candidates: the counter with
    /// its low half nearest the receiver's time, and the `tries − 1` periods of 2^16 below it.
    #[test]
    fn a_first_frame_is_found_within_its_tries(
        sent in 0_u32..(600 << 16),
        reference in 0_u32..(600 << 16),
        tries in 0_u32..600,
    ) {
        let mut checker = E2eChecker::new();
        let search = Search { reference, tries };
        let status = checker.check(sent as u16, search, |full| full == sent);
        if among_candidates(reference, tries, sent) {
            prop_assert_eq!(status, E2eStatus::Initial);
            prop_assert_eq!(checker.last(), Some(sent));
        } else {
            prop_assert_eq!(status, E2eStatus::CheckFailed);
            prop_assert_eq!(checker.last(), None);
        }
    }

    /// Protect, then verify at the same freshness: the check holds; with any one bit of check
    /// value, counter or payload flipped, it does not (certain for CRC-32C, which detects every
    /// burst of up to 32 bits; 2^-32 for the MAC).
    #[test]
    fn a_flipped_bit_in_a_protected_message_fails_its_check(
        check in any_check(),
        data_id in any::<u16>(),
        epoch in any_epoch(),
        counter in any::<u32>(),
        payload in proptest::collection::vec(any::<u8>(), 1..58),
        bit in any::<prop::sample::Index>(),
    ) {
        let freshness = Freshness { data_id, epoch, counter };
        let message = protected(check, &TEST_KEY, &freshness, &payload);
        let holds = |message: &[u8]| {
            let (sent, low) = header(message).unwrap();
            let at = Freshness { counter: counter & !0xFFFF | u32::from(low), ..freshness };
            check_value(check, &TEST_KEY, &at, &message[HEADER_LEN..]) == sent
        };
        prop_assert!(holds(&message));
        let bit = bit.index(message.len() * 8);
        let mut flipped = message.clone();
        flipped[bit / 8] ^= 1 << (bit % 8);
        prop_assert!(!holds(&flipped), "bit {} flipped", bit);
    }

    /// The check covers the data id, the epoch and the full counter: a change of any one of
    /// them changes it, as it must for a frame moved to another id, replayed from another
    /// session or replayed from 2^16 frames ago to fail.
    #[test]
    fn the_check_binds_data_id_epoch_and_counter(
        check in any_check(),
        data_id in any::<u16>(),
        epoch in any::<u32>(),
        counter in any::<u32>(),
        field in 0_usize..3,
        other in any::<u32>(),
        payload in proptest::collection::vec(any::<u8>(), 0..58),
    ) {
        let freshness = Freshness { data_id, epoch: Some(Epoch::new(epoch)), counter };
        let changed = match field {
            0 => Freshness { data_id: other as u16, ..freshness },
            1 => Freshness { epoch: Some(Epoch::new(other)), ..freshness },
            _ => Freshness { counter: other, ..freshness },
        };
        prop_assume!(changed != freshness);
        prop_assert_ne!(
            check_value(check, &TEST_KEY, &freshness, &payload),
            check_value(check, &TEST_KEY, &changed, &payload)
        );
    }
}
