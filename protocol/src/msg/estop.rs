use serde::{Deserialize, Serialize};

use postcard::experimental::max_size::MaxSize;

use crate::codec::{check_layout, Message};
use crate::e2e::{Check, Protection};
use crate::id::MessageId;
use crate::node::NodeId;
use crate::signal::{scalar, Field};
use crate::units::{EStopAction, ReleaseToken};

/// Emergency stop, id `0x000` — the highest priority on the bus. A latch stops every drive and
/// holds until a release ("clear"); any node may send a latch.
///
/// | byte | field    | type | meaning                                                  |
/// |------|----------|------|----------------------------------------------------------|
/// | 6    | `action` | u8   | 1 = latch, 2 = clear (release)                           |
/// | 7    | `source` | u8   | [`NodeId`] of the sender                                  |
/// | 8–9  | `token`  | u16  | release: the controller's published [`ReleaseToken`]; latch: ignored |
///
/// The two actions are protected differently ([`EStop::protection`]):
///
/// - a **latch** carries a CRC-32C over `action` and `source` only, bound to no session, so one
///   constant frame works at any time — also as a classic CAN frame of 8 bytes (header,
///   action, source), as an E-stop panel sends it; its counter is not checked;
/// - a **release** carries a CMAC bound to the session, with a fresh counter, and echoes the
///   token the controller publishes while latched (in
///   [`ControllerStatus`](crate::ControllerStatus)), so that no release recorded or withheld
///   before this latch can release it.
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
pub struct EStop {
    /// Latch or clear.
    pub action: EStopAction,
    /// Who asked.
    pub source: NodeId,
    /// For a release, the token of the latch it releases.
    pub token: ReleaseToken,
}

impl EStop {
    /// A latch from `source`.
    pub const fn latch(source: NodeId) -> EStop {
        EStop {
            action: EStopAction::Latch,
            source,
            token: ReleaseToken::new(0),
        }
    }

    /// A release of the latch the controller published `token` for.
    pub const fn release(source: NodeId, token: ReleaseToken) -> EStop {
        EStop {
            action: EStopAction::Clear,
            source,
            token,
        }
    }
}

/// Bytes of a latch's payload its check covers (action and source).
pub const LATCH_CHECKED_LEN: usize = 2;

/// Data length of a latch sent as a classic CAN frame.
pub const CLASSIC_LATCH_LEN: usize = crate::e2e::HEADER_LEN + LATCH_CHECKED_LEN;

impl Message for EStop {
    type Address = ();
    const NAME: &'static str = "EStop";
    const DOC: &'static str = "Emergency stop: latch stops all drives until clear";
    const FIELDS: &'static [Field] = &[
        scalar::<EStopAction>("action"),
        scalar::<NodeId>("source"),
        scalar::<ReleaseToken>("token"),
    ];
    const PROTECTION: Protection = RELEASE_PROTECTION;
    fn protection(&self) -> (Protection, usize) {
        match self.action {
            EStopAction::Latch => (LATCH_PROTECTION, LATCH_CHECKED_LEN),
            EStopAction::Clear => (RELEASE_PROTECTION, Self::POSTCARD_MAX_SIZE),
        }
    }
    fn id(_: ()) -> MessageId {
        MessageId::EStop
    }
}
check_layout!(EStop);

/// A latch: CRC over action and source, bound to no session.
pub const LATCH_PROTECTION: Protection = Protection {
    check: Check::Crc,
    bound: false,
    sequenced: false,
};

/// A release: CMAC bound to the session.
pub const RELEASE_PROTECTION: Protection = Protection {
    check: Check::Mac,
    bound: true,
    sequenced: true,
};
