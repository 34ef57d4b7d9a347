use serde::{Deserialize, Serialize};

use crate::codec::{check_layout, Message};
use crate::id::MessageId;
use crate::node::WHEEL_NAMES;
use crate::signal::{array, Field};
use crate::units::{Torque, WheelVelocity};

/// Feedback of both wheels, id `0x184`, wheel drive → controller.
///
/// | byte  | field      | type    | meaning                                      |
/// |-------|------------|---------|----------------------------------------------|
/// | 6–9   | `velocity` | 2 × i16 | left, right; 1e-2 rad/s, + = forward         |
/// | 10–13 | `effort`   | 2 × i16 | left, right; applied torque, 1e-2 N·m        |
///
/// No wheel angle: the controller balances and drives on speed, and the 16-byte frame keeps the
/// 1 kHz schedule's busiest cycle within half the bus (`cargo xtask busload`).
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
    /// Wheel speeds.
    pub velocity: [WheelVelocity; 2],
    /// Wheel torques.
    pub effort: [Torque; 2],
}

impl Message for WheelFeedback {
    type Address = ();
    const NAME: &'static str = "WheelFeedback";
    const DOC: &'static str = "Speed and torque of both wheels";
    const FIELDS: &'static [Field] = &[
        array::<WheelVelocity>("velocity", &WHEEL_NAMES),
        array::<Torque>("effort", &WHEEL_NAMES),
    ];
    fn id(_: ()) -> MessageId {
        MessageId::WheelFeedback
    }
}
check_layout!(WheelFeedback);
