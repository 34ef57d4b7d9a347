use serde::{Deserialize, Serialize};

use crate::codec::{check_layout, Message};
use crate::id::MessageId;
use crate::node::Drive;
use crate::signal::{scalar, Field};
use crate::units::{Count, DriveFlags};

/// State of one drive, ids `0x410`–`0x414` (legs FL, FR, BL, BR, wheels), drive → controller.
///
/// | byte | field      | type | meaning                                        |
/// |------|------------|------|------------------------------------------------|
/// | 6    | `flags`    | u8   | [`DriveFlags`]: enabled, timed out, fault, estop |
/// | 7–8  | `rejected` | u16  | frames this drive rejected, wraps              |
/// | 9–10  | `commands` | u16  | valid commands this drive accepted, wraps      |
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
pub struct DriveStatus {
    /// Drive state.
    pub flags: DriveFlags,
    /// Frames rejected (any cause).
    pub rejected: Count,
    /// Commands accepted.
    pub commands: Count,
}

impl Message for DriveStatus {
    type Address = Drive;
    const NAME: &'static str = "DriveStatus";
    const DOC: &'static str = "Drive state: enabled, timed out, fault; frame counters";
    const FIELDS: &'static [Field] = &[
        scalar::<DriveFlags>("flags"),
        scalar::<Count>("rejected"),
        scalar::<Count>("commands"),
    ];
    fn id(drive: Drive) -> MessageId {
        MessageId::DriveStatus(drive)
    }
}
check_layout!(DriveStatus);
