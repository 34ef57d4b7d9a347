use serde::{Deserialize, Serialize};

use crate::codec::{check_layout, Message};
use crate::id::MessageId;
use crate::node::{Leg, LEG_JOINT_NAMES};
use crate::signal::{array, Field};
use crate::units::{Angle, JointVelocity, Torque};

/// Joint feedback of one leg, ids `0x180`–`0x183` (FL, FR, BL, BR), leg drive → controller.
///
/// | byte  | field      | type    | meaning                                  |
/// |-------|------------|---------|------------------------------------------|
/// | 6–13  | `position` | 4 × i16 | hip1, hip2, knee, ankle; 1e-4 rad        |
/// | 14–21 | `velocity` | 4 × i16 | same order; 1e-3 rad/s                   |
/// | 22–29 | `effort`   | 4 × i16 | same order; applied torque, 1e-2 N·m     |
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
pub struct LegFeedback {
    /// Joint positions.
    pub position: [Angle; 4],
    /// Joint velocities.
    pub velocity: [JointVelocity; 4],
    /// Joint torques.
    pub effort: [Torque; 4],
}

impl Message for LegFeedback {
    type Address = Leg;
    const NAME: &'static str = "LegFeedback";
    const DOC: &'static str = "Position, velocity and torque of one leg's four joints";
    const FIELDS: &'static [Field] = &[
        array::<Angle>("position", &LEG_JOINT_NAMES),
        array::<JointVelocity>("velocity", &LEG_JOINT_NAMES),
        array::<Torque>("effort", &LEG_JOINT_NAMES),
    ];
    fn id(leg: Leg) -> MessageId {
        MessageId::LegFeedback(leg)
    }
}
check_layout!(LegFeedback);
