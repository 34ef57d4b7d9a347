use serde::{Deserialize, Serialize};

use crate::codec::{check_layout, Message};
use crate::id::MessageId;
use crate::signal::{scalar, Field};
use crate::units::Tick;

/// Lockstep clock, id `0x010`, sent by the simulator once per control cycle in lockstep mode.
/// Absent on a real robot, where the controller keeps its own time.
///
/// | byte | field  | type | meaning                     |
/// |------|--------|------|-----------------------------|
/// | 6–9  | `tick` | u32  | control tick, 1 tick, wraps |
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
pub struct Sync {
    /// The tick the receiver should compute.
    pub tick: Tick,
}

impl Message for Sync {
    type Address = ();
    const NAME: &'static str = "Sync";
    const DOC: &'static str = "Lockstep tick from the simulator";
    const FIELDS: &'static [Field] = &[scalar::<Tick>("tick")];
    fn id(_: ()) -> MessageId {
        MessageId::Sync
    }
}
check_layout!(Sync);
