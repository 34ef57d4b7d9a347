use serde::{Deserialize, Serialize};

use crate::codec::{check_layout, Message};
use crate::id::MessageId;
use crate::signal::{scalar, Field};
use crate::units::{BodyHeight, GroundSpeed, SpeedScale, TeleopMode, YawRate};

/// Operator command, id `0x200`, teleop → controller. Sent on every change and repeated at a
/// low rate; the controller acts on the latest.
///
/// | byte | field         | type | meaning                                            |
/// |------|---------------|------|----------------------------------------------------|
/// | 6    | `mode`        | u8   | [`TeleopMode`]: X W S A L K, stand, fold, drive, walk |
/// | 7–8  | `body_height` | i16  | offset from nominal height, 1e-4 m, −0.10…+0.12 m   |
/// | 9    | `speed_scale` | u8   | 1 %, 0…100                                           |
/// | 10–11| `speed`       | i16  | ground speed, 1e-3 m/s, −2…+2 m/s, + forward         |
/// | 12–13| `yaw_rate`    | i16  | 1e-3 rad/s, −3…+3 rad/s, + turning left              |
///
/// `speed` and `yaw_rate` are what [`TeleopMode::Drive`] and [`TeleopMode::Walk`] follow (a
/// gamepad's sticks). The report's keys keep their presets: `speed_scale` sets their speed,
/// `speed` is ignored, and `yaw_rate` steers `W`, `S`, `L` and `K` (a curve while driving, a
/// turning trot); `A`, stop, stand and fold ignore both. The controller clamps both to its own
/// limits.
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
    /// Ground speed for [`TeleopMode::Drive`] and [`TeleopMode::Walk`].
    pub speed: GroundSpeed,
    /// Yaw rate: steers the moving modes but `A`.
    pub yaw_rate: YawRate,
}

impl Message for TeleopCommand {
    type Address = ();
    const NAME: &'static str = "TeleopCommand";
    const DOC: &'static str =
        "Operator command: mode key, body height, speed scale, ground speed and yaw rate";
    const FIELDS: &'static [Field] = &[
        scalar::<TeleopMode>("mode"),
        scalar::<BodyHeight>("body_height"),
        scalar::<SpeedScale>("speed_scale"),
        scalar::<GroundSpeed>("speed"),
        scalar::<YawRate>("yaw_rate"),
    ];
    const PROTECTION: crate::e2e::Protection = crate::e2e::AUTHENTICATED;
    fn id(_: ()) -> MessageId {
        MessageId::TeleopCommand
    }
}
check_layout!(TeleopCommand);
