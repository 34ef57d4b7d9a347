use serde::{Deserialize, Serialize};

use crate::codec::{check_layout, Message};
use crate::id::MessageId;
use crate::node::NodeId;
use crate::signal::{scalar, Field};
use crate::units::EStopAction;

/// Emergency stop, id `0x000` — the highest priority on the bus. A latch stops every drive and
/// holds until a clear; any node may send it.
///
/// | byte | field    | type | meaning                         |
/// |------|----------|------|---------------------------------|
/// | 4    | `action` | u8   | 1 = latch, 2 = clear            |
/// | 5    | `source` | u8   | [`NodeId`] of the sender         |
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
}

impl Message for EStop {
    type Address = ();
    const NAME: &'static str = "EStop";
    const DOC: &'static str = "Emergency stop: latch stops all drives until clear";
    const FIELDS: &'static [Field] = &[scalar::<EStopAction>("action"), scalar::<NodeId>("source")];
    fn id(_: ()) -> MessageId {
        MessageId::EStop
    }
}
check_layout!(EStop);
