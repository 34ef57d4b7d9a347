use serde::{Deserialize, Serialize};

use crate::codec::{check_layout, Message};
use crate::id::MessageId;
use crate::signal::{scalar, Field};
use crate::units::{Angle, BodyHeight, ControllerMode, FaultFlags, ReleaseToken, Tick};

/// Controller status and telemetry, id `0x400`, controller → anyone listening.
///
/// | byte  | field         | type | meaning                                      |
/// |-------|---------------|------|----------------------------------------------|
/// | 6     | `mode`        | u8   | [`ControllerMode`]                            |
/// | 7–8   | `faults`      | u16  | [`FaultFlags`] bits                           |
/// | 9–12  | `tick`        | u32  | control tick, 1 tick                          |
/// | 13–14 | `body_height` | i16  | target height offset, 1e-4 m                  |
/// | 15–16 | `pitch`       | i16  | torso pitch estimate, 1e-4 rad, + = nose down |
/// | 17–18 | `roll`        | i16  | torso roll estimate, 1e-4 rad, + = left up    |
/// | 19–20 | `release_token` | u16 | the token a release must echo ([`EStop`](crate::EStop)) |
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
    /// The token a release of the present (or next) latch must echo.
    pub release_token: ReleaseToken,
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
        scalar::<ReleaseToken>("release_token"),
    ];
    fn id(_: ()) -> MessageId {
        MessageId::ControllerStatus
    }
}
check_layout!(ControllerStatus);
