use serde::{Deserialize, Serialize};

use crate::codec::{check_layout, Message};
use crate::id::MessageId;
use crate::signal::{scalar, Field};
use crate::units::{BodyHeight, SpeedScale, TeleopMode};

/// Operator command, id `0x200`, teleop → controller. Sent on every change and repeated at a
/// low rate; the controller acts on the latest.
///
/// | byte | field         | type | meaning                                            |
/// |------|---------------|------|----------------------------------------------------|
/// | 6    | `mode`        | u8   | [`TeleopMode`]: X W S A L K, stand, fold            |
/// | 7–8  | `body_height` | i16  | offset from nominal height, 1e-4 m, −0.10…+0.12 m   |
/// | 9    | `speed_scale` | u8   | 1 %, 0…100                                           |
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
pub struct TeleopCommand {
    /// Requested mode.
    pub mode: TeleopMode,
    /// Requested body height offset.
    pub body_height: BodyHeight,
    /// Speed scale for the mode's nominal speed.
    pub speed_scale: SpeedScale,
}

impl Message for TeleopCommand {
    type Address = ();
    const NAME: &'static str = "TeleopCommand";
    const DOC: &'static str = "Operator command: mode key, body height, speed scale";
    const FIELDS: &'static [Field] = &[
        scalar::<TeleopMode>("mode"),
        scalar::<BodyHeight>("body_height"),
        scalar::<SpeedScale>("speed_scale"),
    ];
    const PROTECTION: crate::e2e::Protection = crate::e2e::AUTHENTICATED;
    fn id(_: ()) -> MessageId {
        MessageId::TeleopCommand
    }
}
check_layout!(TeleopCommand);
