//! The E2E receiver's search for a frame it cannot place in its sequence: its candidates, what
//! it never finds, and what a frame forged with a CMAC costs it.

mod common;

use common::checker::{checker_after, offer, offer_forged};
use common::protected::protected;
use common::search::{among_candidates, nearest};
use protocol::e2e::{check_value, header, Freshness, Search};
use protocol::{Check, E2eChecker, E2eStatus, Epoch, Key, TEST_KEY};

/// Every receiver makes the same search, whatever the check and whoever it is: two candidates,
/// the counter with the frame's low half nearest its session time, then the one 2^16 below:
/// 2^15 ahead of its time to 2^15 + 2^16 behind it.
#[test]
fn a_first_frame_is_looked_for_nearest_the_receivers_time_then_one_period_below() {
    let first = |sent: u32, search: Search| {
        let mut checker = E2eChecker::new();
        let status = checker.check(sent as u16, search, |full| full == sent);
        let accepted = status.is_accepted();
        assert_eq!(checker.last(), accepted.then_some(sent), "{sent:#x}");
        assert!(matches!(
            status,
            E2eStatus::Initial | E2eStatus::CheckFailed
        ));
        accepted
    };
    for now in [5 << 16 | 0x1234, 5 << 16 | 0x9234] {
        let search = |tries| Search {
            reference: now,
            tries,
        };
        assert_eq!(Search::new(now), search(2));
        // The tie at 2^15 goes to the counter in the period of `now`.
        let (behind, ahead) = if now & 0xFFFF < 0x8000 {
            (0x7FFF, 0x8000)
        } else {
            (0x8000, 0x7FFF)
        };
        // The nearest, found at the first try.
        for sent in [now, now - 1, now + 1, now - behind, now + ahead] {
            assert!(first(sent, search(1)), "{now:#x} {sent:#x}");
        }
        // One period below it: the second try.
        for sent in [now - behind - 1, now - 0x1_0000, now - behind - 0x1_0000] {
            assert!(!first(sent, search(1)), "{now:#x} {sent:#x}");
            assert!(first(sent, search(2)), "{now:#x} {sent:#x}");
            assert!(first(sent, Search::new(now)), "{now:#x} {sent:#x}");
        }
        // Further below: not with two tries, with more.
        for (sent, tries) in [
            (now - behind - 0x1_0001, 3),
            (now - 0x2_0000, 3),
            (now - 0x3_0000, 4),
            (now & 0xFFFF, 6),
        ] {
            assert!(!first(sent, Search::new(now)), "{now:#x} {sent:#x}");
            assert!(!first(sent, search(tries - 1)), "{now:#x} {sent:#x}");
            assert!(first(sent, search(tries)), "{now:#x} {sent:#x}");
        }
        // Past the nearest ahead: never, however many tries.
        for sent in [now + ahead + 1, now + 0x1_0000, now + 0x10_0000] {
            assert!(!first(sent, search(1 << 16)), "{now:#x} {sent:#x}");
        }
        assert!(!first(now, search(0)), "no tries, no search");
    }
    // Near zero there are no candidates below it: a low half whose nearest would be negative
    // is not looked for at all.
    assert!(!first(0x9000, Search::new(10)));
    assert!(first(0x8000, Search::new(0)));
    assert!(first(0x7000, Search::new(10)));
    // A teleop that joined on an announcement just below a boundary of 2^16 ms, its first frame
    // received by the controller just past it. (Wire version 2 first looked from the period
    // after the receiver's time's downward, the controller two periods: 2^17 + 65 500 and
    // 2^16 + 65 500, never 65 500 itself.)
    assert!(first(65_500, Search::new(65_540)));
    assert_eq!(nearest(65_540, 65_500_u32 as u16), 65_500);
}

#[test]
fn half_the_counter_range_ahead_is_found_by_the_search() {
    let mut checker = checker_after(&[10]);
    assert_eq!(
        offer(&mut checker, 10 + 0x7FFF),
        E2eStatus::OkSomeLost { lost: 0x7FFE }
    );
    // 2^15 ahead reads as 2^15 behind, where the check does not hold; the receiver, whose time
    // has reached the frame's counter, finds it in the search and restarts the sequence there.
    let mut checker = checker_after(&[10]);
    assert_eq!(offer(&mut checker, 10 + 0x8000), E2eStatus::Initial);
    assert_eq!(checker.last(), Some(10 + 0x8000));
    // A receiver whose time is more than a half behind the frame does not find it.
    let mut checker = checker_after(&[10]);
    let sent = 10 + 0x2_8000;
    let behind = Search::new(10);
    assert_eq!(
        checker.check(sent as u16, behind, |full| full == sent),
        E2eStatus::CheckFailed
    );
    assert_eq!(checker.last(), Some(10));
    // A genuine frame 2^15 behind is stale; one 2^15 + 1 behind reads as ahead and fails.
    let mut checker = checker_after(&[0x9000]);
    assert_eq!(offer(&mut checker, 0x1000), E2eStatus::WrongSequence);
    assert_eq!(offer(&mut checker, 0x0FFF), E2eStatus::CheckFailed);
}

/// The search never goes back to or behind the last accepted counter: a frame one or more
/// periods of 2^16 old with the low half of a counter ahead is not found, however many periods
/// are tried and wherever the receiver's time is.
#[test]
fn the_search_never_finds_a_counter_at_or_behind_the_last_accepted() {
    let last = 9 << 16 | 0x0100;
    for sent in [last, last - 1, 8 << 16 | 0x0200, 3 << 16 | 0x0100, 0x0100] {
        for reference in [sent, last, last + 0x8000, last + 0x1_0000, 0x7FFF_0000] {
            let mut checker = checker_after(&[last]);
            let search = Search {
                reference,
                tries: 1 << 16,
            };
            assert!(
                among_candidates(reference, 1 << 16, sent),
                "reached but for the last"
            );
            let status = checker.check(sent as u16, search, |full| full == sent);
            assert!(!status.is_accepted(), "{sent:#x}: {status:?}");
            assert_eq!(checker.last(), Some(last));
        }
    }
}

/// A CMAC costs a block cipher run per try: a frame forged without the key costs any receiver,
/// the controller or a member, one try where the sequence places it and at most two in the
/// search, within the budget of 1 + 1 + 2. The search skips candidates at or behind the last
/// accepted counter without a try, so with a recent sequence it costs at most one; both tries
/// are spent only with no sequence or one last heard more than 2^15 + 2^16 ms ago. (Wire
/// version 2 first let a member look through 2^8 periods for a CMAC frame: up to 1 + 256 runs
/// per forged frame.)
#[test]
fn a_forged_cmac_costs_at_most_one_verification_in_the_sequence_and_two_in_the_search() {
    let epoch = Some(Epoch::new(12));
    let data_id = 0xC200;
    let forger = Key([0x66; 16]);
    let payload = *b"drive!";
    let mut worst = 0;
    for now in [7 << 16 | 0x4000, 7 << 16 | 0xC000, 65_540, 100] {
        let recent: Vec<u32> = (now - 40..now - 20).collect();
        let stale: Vec<u32> = (now.saturating_sub(0x4_0000)..).take(20).collect();
        for (history, most) in [(&[][..], 2), (&recent[..], 1 + 1), (&stale[..], 1 + 2)] {
            for counter in [
                0,
                1,
                now - 21,
                now - 20,
                now - 19,
                now - 30,
                now,
                now - 0x8000.min(now),
                now - 0x1_0000.min(now),
                now + 0x8000,
                !0,
            ] {
                let mut checker = checker_after(history);
                let before = checker.last();
                let freshness = Freshness {
                    data_id,
                    epoch,
                    counter,
                };
                let message = protected(Check::Mac, &forger, &freshness, &payload);
                let (sent, low) = header(&message).unwrap();
                let mut runs = 0;
                let status = checker.check(low, Search::new(now), |counter| {
                    runs += 1;
                    let at = Freshness {
                        data_id,
                        epoch,
                        counter,
                    };
                    check_value(Check::Mac, &TEST_KEY, &at, &payload) == sent
                });
                assert_eq!(status, E2eStatus::CheckFailed, "{counter:#x}");
                assert_eq!(checker.last(), before);
                assert!(runs <= 1 + 1 + 2, "{counter:#x}: {runs} CMACs");
                assert!(
                    runs <= most,
                    "{now:#x} {counter:#x} {history:?}: {runs} CMACs"
                );
                worst = worst.max(runs);
            }
        }
    }
    assert_eq!(worst, 3, "one try in the sequence, two in the search");
}

#[test]
fn a_frame_whose_check_fails_is_check_failed_and_leaves_the_sequence_alone() {
    let mut checker = E2eChecker::new();
    assert_eq!(offer_forged(&mut checker, 0), E2eStatus::CheckFailed);
    assert_eq!(checker.last(), None);
    let mut checker = checker_after(&[10]);
    for low in [9, 10, 11, 5000, 0x8000 + 10] {
        assert_eq!(
            offer_forged(&mut checker, low),
            E2eStatus::CheckFailed,
            "{low}"
        );
    }
    assert_eq!(offer(&mut checker, 11), E2eStatus::Ok);
}
