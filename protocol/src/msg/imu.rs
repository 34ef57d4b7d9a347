use serde::{Deserialize, Serialize};

use crate::codec::{check_layout, Message};
use crate::id::MessageId;
use crate::signal::{array, Field};
use crate::units::{Acceleration, AngularRate};

/// Torso IMU sample, id `0x185`, IMU → controller: what the chip measures, no orientation (the
/// controller estimates its attitude from these). Body frame: x forward, y left, z up.
///
/// | byte  | field          | type    | meaning                                              |
/// |-------|----------------|---------|------------------------------------------------------|
/// | 6–11  | `angular_rate` | 3 × i16 | gyro x, y, z; 1e-3 rad/s, ±32.767 rad/s               |
/// | 12–17 | `acceleration` | 3 × i16 | accelerometer x, y, z (specific force); 1e-2 m/s², ±327.67 m/s² |
///
/// The scales fit the robot's chip, a Bosch BMI088 at ±1000 °/s and ±6 g (see
/// `docs/simulator.md`): both ranges lie inside the fields' (±17.5 rad/s, ±58.8 m/s²), and
/// each step is below the chip's noise at its output rate (gyro 1e-3 rad/s against 4.1e-3
/// rad/s RMS, accelerometer 1e-2 m/s² against 2.7e-2 m/s² RMS), so rounding adds under 3 % to
/// the noise's RMS. The 18-byte frame goes out as a 20-byte CAN FD frame.
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
    /// Angular rate about x, y, z.
    pub angular_rate: [AngularRate; 3],
    /// Specific force along x, y, z (at rest: +g along up).
    pub acceleration: [Acceleration; 3],
}

impl Message for Imu {
    type Address = ();
    const NAME: &'static str = "Imu";
    const DOC: &'static str = "Torso angular rate and specific force";
    const FIELDS: &'static [Field] = &[
        array::<AngularRate>("angular_rate", &["x", "y", "z"]),
        array::<Acceleration>("acceleration", &["x", "y", "z"]),
    ];
    fn id(_: ()) -> MessageId {
        MessageId::Imu
    }
}
check_layout!(Imu);
