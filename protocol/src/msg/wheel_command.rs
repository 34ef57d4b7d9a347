use serde::{Deserialize, Serialize};

use crate::codec::{check_layout, Message};
use crate::id::MessageId;
use crate::node::WHEEL_NAMES;
use crate::signal::{array, scalar, Field};
use crate::units::{DriveEnable, Torque};

/// Wheel torques, id `0x101`, controller → wheel drive. Zero torque leaves the wheels free;
/// `enable` 0 takes the motors' torque away (the drive's bridge off), as a controlled stop ends
/// — and in time: the drive's own SS1 timer runs from when it heard the latch, which a bus
/// with transport delay brings late.
///
/// CRC-protected and bound to the session, not authenticated: a CMAC of this frame and of the
/// leg targets (one and three AES blocks) every tick would take the Cortex-M4F's control step
/// past its instruction budget (see `docs/protocol.md`, "Threat model").
///
/// | byte | field    | type    | meaning                                  |
/// |------|----------|---------|------------------------------------------|
/// | 6    | `enable` | u8      | 0 = torque-free, 1 = apply the torques   |
/// | 7–10 | `torque` | 2 × i16 | left, right; 1e-2 N·m, + = forward       |
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
pub struct WheelCommand {
    /// Apply the torques or go torque-free.
    pub enable: DriveEnable,
    /// Left, right.
    pub torque: [Torque; 2],
}

impl Message for WheelCommand {
    type Address = ();
    const NAME: &'static str = "WheelCommand";
    const DOC: &'static str = "Torque of the left and right wheel";
    const FIELDS: &'static [Field] = &[
        scalar::<DriveEnable>("enable"),
        array::<Torque>("torque", &WHEEL_NAMES),
    ];
    fn id(_: ()) -> MessageId {
        MessageId::WheelCommand
    }
}
check_layout!(WheelCommand);
