use serde::{Deserialize, Serialize};

use crate::codec::{check_layout, Message};
use crate::id::MessageId;
use crate::signal::{array, Field};
use crate::units::{Acceleration, AngularRate, QuatComponent};

/// Torso IMU sample, id `0x185`, IMU → controller. Body frame: x forward, y left, z up.
///
/// | byte  | field          | type    | meaning                                            |
/// |-------|----------------|---------|----------------------------------------------------|
/// | 6–13  | `orientation`  | 4 × i16 | quaternion w, x, y, z (world ← body); 1e-4, ±1      |
/// | 14–19 | `angular_rate` | 3 × i16 | gyro x, y, z; 1e-3 rad/s                            |
/// | 20–25 | `acceleration` | 3 × i16 | accelerometer x, y, z (specific force); 1e-2 m/s²   |
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
pub struct Imu {
    /// Orientation quaternion w, x, y, z.
    pub orientation: [QuatComponent; 4],
    /// Angular rate about x, y, z.
    pub angular_rate: [AngularRate; 3],
    /// Specific force along x, y, z.
    pub acceleration: [Acceleration; 3],
}

impl Message for Imu {
    type Address = ();
    const NAME: &'static str = "Imu";
    const DOC: &'static str = "Torso orientation, angular rate and acceleration";
    const FIELDS: &'static [Field] = &[
        array::<QuatComponent>("orientation", &["w", "x", "y", "z"]),
        array::<AngularRate>("angular_rate", &["x", "y", "z"]),
        array::<Acceleration>("acceleration", &["x", "y", "z"]),
    ];
    fn id(_: ()) -> MessageId {
        MessageId::Imu
    }
}
check_layout!(Imu);
