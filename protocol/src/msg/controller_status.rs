use serde::{Deserialize, Serialize};

use crate::codec::{check_layout, Message};
use crate::id::MessageId;
use crate::signal::{scalar, Field};
use crate::units::{Angle, BodyHeight, ControllerMode, FaultFlags, Tick};

/// Controller status and telemetry, id `0x400`, controller → anyone listening.
///
/// | byte  | field         | type | meaning                                      |
/// |-------|---------------|------|----------------------------------------------|
/// | 4     | `mode`        | u8   | [`ControllerMode`]                            |
/// | 5–6   | `faults`      | u16  | [`FaultFlags`] bits                           |
/// | 7–10  | `tick`        | u32  | control tick, 1 tick                          |
/// | 11–12 | `body_height` | i16  | target height offset, 1e-4 m                  |
/// | 13–14 | `pitch`       | i16  | torso pitch estimate, 1e-4 rad, + = nose down |
/// | 15–16 | `roll`        | i16  | torso roll estimate, 1e-4 rad, + = left up    |
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
pub struct ControllerStatus {
    /// Current mode.
    pub mode: ControllerMode,
    /// Active faults.
    pub faults: FaultFlags,
    /// Control tick of this status.
    pub tick: Tick,
    /// Target body height offset.
    pub body_height: BodyHeight,
    /// Torso pitch.
    pub pitch: Angle,
    /// Torso roll.
    pub roll: Angle,
}

impl Message for ControllerStatus {
    type Address = ();
    const NAME: &'static str = "ControllerStatus";
    const DOC: &'static str = "Controller mode, faults, tick and torso attitude";
    const FIELDS: &'static [Field] = &[
        scalar::<ControllerMode>("mode"),
        scalar::<FaultFlags>("faults"),
        scalar::<Tick>("tick"),
        scalar::<BodyHeight>("body_height"),
        scalar::<Angle>("pitch"),
        scalar::<Angle>("roll"),
    ];
    fn id(_: ()) -> MessageId {
        MessageId::ControllerStatus
    }
}
check_layout!(ControllerStatus);
