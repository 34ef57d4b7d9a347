use serde::{Deserialize, Serialize};

use crate::codec::{check_layout, Message};
use crate::error::RejectCause;
use crate::id::MessageId;
use crate::signal::{array, scalar, Field};
use crate::units::Count;

/// Names of the rejection counters, in [`RejectCause`] order.
pub const REJECT_NAMES: [&str; RejectCause::ALL.len()] = [
    RejectCause::UnknownId.name(),
    RejectCause::WrongLength.name(),
    RejectCause::Crc.name(),
    RejectCause::OutOfRange.name(),
    RejectCause::Repeated.name(),
    RejectCause::WrongSequence.name(),
    RejectCause::RateLimited.name(),
    RejectCause::Unauthentic.name(),
    RejectCause::Session.name(),
    RejectCause::StaleRelease.name(),
];

/// Frames the controller rejected, by cause, id `0x600` (diagnostics), controller → anyone.
///
/// | byte  | field      | type    | meaning                                            |
/// |-------|------------|---------|----------------------------------------------------|
/// | 6–25  | `rejected` | 10 × u16 | by [`RejectCause`]: unknown id, wrong length, CRC, out of range, repeated, wrong sequence, rate limited, unauthentic, session, stale release; wraps |
/// | 26–27 | `lost`     | u16      | frames missing from accepted sequences, wraps      |
///
/// 28 bytes, padded to 32.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    Serialize,
    Deserialize,
    postcard::experimental::max_size::MaxSize,
)]
pub struct RejectCounters {
    /// Rejections, indexed by `RejectCause as usize`.
    pub rejected: [Count; RejectCause::ALL.len()],
    /// Frames lost (gaps in accepted counter sequences).
    pub lost: Count,
}

impl RejectCounters {
    /// The count of one cause.
    pub fn get(&self, cause: RejectCause) -> Count {
        self.rejected
            .get(cause as usize)
            .copied()
            .unwrap_or_default()
    }

    /// Counts one rejection.
    pub fn record(&mut self, cause: RejectCause) {
        if let Some(count) = self.rejected.get_mut(cause as usize) {
            *count = count.increment();
        }
    }

    /// Counts `frames` lost frames (the count wraps at 2^16).
    pub fn record_lost(&mut self, frames: u32) {
        let low = (frames & 0xFFFF) as u16;
        self.lost = Count::from_raw(self.lost.raw().wrapping_add(low)).unwrap_or_default();
    }

    /// Rejections over all causes.
    pub fn total(&self) -> u32 {
        self.rejected.iter().map(|c| u32::from(c.raw())).sum()
    }
}

impl Message for RejectCounters {
    type Address = ();
    const NAME: &'static str = "RejectCounters";
    const DOC: &'static str = "Frames the controller rejected, by cause";
    const FIELDS: &'static [Field] = &[
        array::<Count>("rejected", &REJECT_NAMES),
        scalar::<Count>("lost"),
    ];
    fn id(_: ()) -> MessageId {
        MessageId::RejectCounters
    }
}
check_layout!(RejectCounters);
