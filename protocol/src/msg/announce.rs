use serde::{Deserialize, Serialize};

use crate::codec::{check_layout, Message};
use crate::e2e::{Check, Protection};
use crate::id::MessageId;
use crate::signal::{scalar, Field};
use crate::units::{Epoch, SessionTime, WireVersion};

/// The controller's session announcement, id `0x020`, controller → every node, at start-up and
/// then at 50 Hz, so that a node started later (or restarted) joins within 20 ms: sooner than the
/// controller's 40 ms feedback timeout.
///
/// Authenticated (CMAC) and bound to no session: it is what opens one (see
/// [`crate::session`]). A node joins the first announcement it hears, moves to one with a
/// greater epoch (the controller restarted), and refuses one with a smaller epoch or, in its
/// epoch, a time before the last it heard (a replay), or another wire version (with a
/// message naming both versions).
///
/// | byte | field     | type | meaning                                  |
/// |------|-----------|------|------------------------------------------|
/// | 6    | `version` | u8   | wire version of the sender               |
/// | 7–10 | `epoch`   | u32  | the controller's boot epoch, 1           |
/// | 11–14| `time`    | u32  | time since the session opened, 1e-3 s    |
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Serialize,
    Deserialize,
    postcard::experimental::max_size::MaxSize,
)]
pub struct Announce {
    /// The wire version the controller speaks.
    pub version: WireVersion,
    /// The session it opens.
    pub epoch: Epoch,
    /// The controller's time in that session when it sent this: members place counters
    /// against it and start their own counters at it, and refuse an announcement that is not
    /// newer than the last they heard.
    pub time: SessionTime,
}

impl Message for Announce {
    type Address = ();
    const NAME: &'static str = "Announce";
    const DOC: &'static str = "Session announcement: wire version and the controller's boot epoch";
    const FIELDS: &'static [Field] = &[
        scalar::<WireVersion>("version"),
        scalar::<Epoch>("epoch"),
        scalar::<SessionTime>("time"),
    ];
    const PROTECTION: Protection = Protection {
        check: Check::Mac,
        bound: false,
        sequenced: false,
    };
    fn id(_: ()) -> MessageId {
        MessageId::Announce
    }
}
check_layout!(Announce);
