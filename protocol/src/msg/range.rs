use serde::{Deserialize, Serialize};

use crate::codec::{check_layout, Message};
use crate::id::MessageId;
use crate::signal::{scalar, Field};
use crate::units::{RangeDistance, RangeStatus};

/// One ranging of the rangefinder that looks at the ground behind the torso, id `0x186`,
/// rangefinder → controller, 50 Hz (each ranging's end).
///
/// | byte | field      | type | meaning                                                      |
/// |------|------------|------|--------------------------------------------------------------|
/// | 6–7  | `distance` | u16  | along the beam to the target; 1e-3 m, 0…4 m                  |
/// | 8    | `status`   | u8   | [`RangeStatus`]: 0 valid, 2 no return (the distance is void) |
///
/// The part is an ST VL53L1X in its short distance mode (1.3 m, 20 ms timing budget; see
/// `docs/simulator.md`), which reports whole millimetres and a status per ranging. The 9-byte
/// frame goes out as a 12-byte CAN FD frame.
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
pub struct Range {
    /// Distance along the beam.
    pub distance: RangeDistance,
    /// Whether `distance` holds.
    pub status: RangeStatus,
}

impl Message for Range {
    type Address = ();
    const NAME: &'static str = "Range";
    const DOC: &'static str = "Distance to the ground behind the torso";
    const FIELDS: &'static [Field] = &[
        scalar::<RangeDistance>("distance"),
        scalar::<RangeStatus>("status"),
    ];
    fn id(_: ()) -> MessageId {
        MessageId::Range
    }
}
check_layout!(Range);
