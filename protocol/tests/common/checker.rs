//! Genuine and forged frames offered to an E2E checker, and a checker after a history.

use protocol::e2e::Search;
use protocol::{E2eChecker, E2eStatus};

/// The receiver's session time when `checker` is offered a genuine frame of counter `sent`: a
/// sender's counter never passes the session time, so the receiver's time is at or past both
/// `sent` and every counter it accepted before.
pub fn now_for(checker: &E2eChecker, sent: u32) -> u32 {
    checker.last().map_or(sent, |last| last.max(sent))
}

/// Offers `checker` a frame of a genuine sender whose full counter is `sent`: its check value
/// holds at that counter and at no other, as a check that covers the full counter does. The
/// receiver searches as every receiver does (two candidates).
pub fn offer(checker: &mut E2eChecker, sent: u32) -> E2eStatus {
    let search = Search::new(now_for(checker, sent));
    checker.check(sent as u16, search, |full| full == sent)
}

/// Offers `checker` a frame whose check holds at no counter: corrupted, forged, or from
/// another session. The receiver searches far wider than any does: every period of 2^16 from
/// the top of the counter range down.
pub fn offer_forged(checker: &mut E2eChecker, low: u16) -> E2eStatus {
    let search = Search {
        reference: 0xFFFF_0000,
        tries: 1 << 16,
    };
    checker.check(low, search, |_| false)
}

pub fn checker_after(counters: &[u32]) -> E2eChecker {
    let mut checker = E2eChecker::new();
    for &c in counters {
        assert!(offer(&mut checker, c).is_accepted(), "setup counter {c}");
    }
    checker
}
