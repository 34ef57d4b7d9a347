use serde::{Deserialize, Serialize};

use crate::codec::{check_layout, Message};
use crate::id::MessageId;
use crate::joints::Joints;
use crate::node::JOINT_NAMES;
use crate::signal::{array, scalar, Field};
use crate::units::{Angle, DriveEnable};

/// Position targets of all 16 leg joints, id `0x100`, controller → leg drives. Each leg drive
/// servos its four joints to their targets (the report's position actuators). CRC-protected,
/// not authenticated, like [`WheelCommand`](crate::WheelCommand).
///
/// | byte   | field      | type     | meaning                                              |
/// |--------|------------|----------|------------------------------------------------------|
/// | 6      | `enable`   | u8       | 0 = torque-free, 1 = servo to the targets             |
/// | 7–38   | `position` | 16 × i16 | joint target, 1e-4 rad, order of [`JOINT_NAMES`]       |
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
pub struct LegTargets {
    /// Servo or go torque-free.
    pub enable: DriveEnable,
    /// Joint targets, in [`JOINT_NAMES`] order.
    pub position: Joints<Angle>,
}

impl Message for LegTargets {
    type Address = ();
    const NAME: &'static str = "LegTargets";
    const DOC: &'static str = "Position targets of the 16 leg joints";
    const FIELDS: &'static [Field] = &[
        scalar::<DriveEnable>("enable"),
        array::<Angle>("position", &JOINT_NAMES),
    ];
    fn id(_: ()) -> MessageId {
        MessageId::LegTargets
    }
}
check_layout!(LegTargets);
