use serde::{Deserialize, Serialize};

use crate::codec::{check_layout, Message};
use crate::id::MessageId;
use crate::signal::{array, Field};
use crate::units::{Acceleration, AngularRate, QuatComponent};

/// Torso IMU sample, id `0x185`, IMU → controller. Body frame: x forward, y left, z up.
///
/// | byte  | field          | type    | meaning                                            |
/// |-------|----------------|---------|----------------------------------------------------|
/// | 6–11  | `orientation`  | 3 × i16 | quaternion x, y, z (world ← body); 1e-4, ±1         |
/// | 12–17 | `angular_rate` | 3 × i16 | gyro x, y, z; 1e-3 rad/s                            |
/// | 18–23 | `acceleration` | 3 × i16 | accelerometer x, y, z (specific force); 1e-2 m/s²   |
///
/// The quaternion's w is not sent: the IMU sends the sign of the unit quaternion with w ≥ 0
/// (both signs are the same rotation), so w = √(1 − x² − y² − z²) ([`Imu::quaternion`]). The
/// 24-byte frame keeps the 1 kHz schedule's busiest cycle within half the bus.
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
    /// Orientation quaternion x, y, z (w ≥ 0 implied).
    pub orientation: [QuatComponent; 3],
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
        array::<QuatComponent>("orientation", &["x", "y", "z"]),
        array::<AngularRate>("angular_rate", &["x", "y", "z"]),
        array::<Acceleration>("acceleration", &["x", "y", "z"]),
    ];
    fn id(_: ()) -> MessageId {
        MessageId::Imu
    }
}
check_layout!(Imu);

impl Imu {
    /// The unit quaternion w, x, y, z of a full orientation `[w, x, y, z]` (either sign), as
    /// sent: the sign with w ≥ 0, w dropped.
    pub fn orientation_of(q: [f32; 4]) -> [QuatComponent; 3] {
        let [w, x, y, z] = q;
        let sign = if w < 0.0 { -1.0 } else { 1.0 };
        [x, y, z].map(|c| QuatComponent::saturating_from_si(sign * c))
    }

    /// The orientation as a quaternion w, x, y, z, with w ≥ 0 recovered from x, y, z by
    /// `sqrt` (the caller's: the MCU has a square-root instruction); w is 0 when wire rounding
    /// puts x² + y² + z² above 1.
    pub fn quaternion(&self, sqrt: impl Fn(f32) -> f32) -> [f32; 4] {
        let [x, y, z] = self.orientation.map(|c| c.si());
        let w_sq = 1.0 - (x * x + y * y + z * z);
        let w = if w_sq > 0.0 { sqrt(w_sq) } else { 0.0 };
        [w, x, y, z]
    }
}
