use serde::{Deserialize, Serialize};

use crate::codec::{check_layout, Message};
use crate::id::MessageId;
use crate::signal::{scalar, Field};
use crate::units::Millis;

/// Operator liveness, id `0x201`, teleop → controller, sent continuously. When it stops, the
/// controller brings the robot to STOP.
///
/// | byte | field    | type | meaning                   |
/// |------|----------|------|---------------------------|
/// | 6–9  | `uptime` | u32  | teleop uptime, 1 ms       |
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
pub struct TeleopHeartbeat {
    /// Time since the teleop program started.
    pub uptime: Millis,
}

impl Message for TeleopHeartbeat {
    type Address = ();
    const NAME: &'static str = "TeleopHeartbeat";
    const DOC: &'static str = "Operator liveness";
    const FIELDS: &'static [Field] = &[scalar::<Millis>("uptime")];
    const PROTECTION: crate::e2e::Protection = crate::e2e::AUTHENTICATED;
    fn id(_: ()) -> MessageId {
        MessageId::TeleopHeartbeat
    }
}
check_layout!(TeleopHeartbeat);
