use serde::{Deserialize, Serialize};

use crate::codec::{check_layout, Message};
use crate::id::MessageId;
use crate::node::WHEEL_NAMES;
use crate::signal::{array, Field};
use crate::units::{Torque, WheelAngle, WheelVelocity};

/// Feedback of both wheels, id `0x184`, wheel drive → controller.
///
/// | byte  | field      | type    | meaning                                      |
/// |-------|------------|---------|----------------------------------------------|
/// | 6–9   | `position` | 2 × i16 | left, right; wrapped to ±π, 1e-4 rad         |
/// | 10–13  | `velocity` | 2 × i16 | left, right; 1e-2 rad/s, + = forward         |
/// | 14–17 | `effort`   | 2 × i16 | left, right; applied torque, 1e-2 N·m        |
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
pub struct WheelFeedback {
    /// Wheel angles, wrapped.
    pub position: [WheelAngle; 2],
    /// Wheel speeds.
    pub velocity: [WheelVelocity; 2],
    /// Wheel torques.
    pub effort: [Torque; 2],
}

impl Message for WheelFeedback {
    type Address = ();
    const NAME: &'static str = "WheelFeedback";
    const DOC: &'static str = "Angle, speed and torque of both wheels";
    const FIELDS: &'static [Field] = &[
        array::<WheelAngle>("position", &WHEEL_NAMES),
        array::<WheelVelocity>("velocity", &WHEEL_NAMES),
        array::<Torque>("effort", &WHEEL_NAMES),
    ];
    fn id(_: ()) -> MessageId {
        MessageId::WheelFeedback
    }
}
check_layout!(WheelFeedback);
