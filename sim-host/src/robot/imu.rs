//! The torso IMU as a CAN node: MuJoCo's ideal framequat / gyro / accelerometer readings plus
//! optional white noise and constant bias (default off), published as `Imu` frames.

use rand::rngs::SmallRng;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

use protocol::{Acceleration, AngularRate, AnyMessage, EncodeError, Frame, Imu, Key, MessageId};

use crate::robot::link::NodeLink;

use crate::robot::physics::Physics;

/// Noise and bias of the IMU. All zero by default: the ideal sensor.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ImuNoise {
    /// White noise on each gyro axis, standard deviation, rad/s.
    pub gyro_std_rad_s: f64,
    /// Constant gyro bias, x y z, rad/s.
    pub gyro_bias_rad_s: [f64; 3],
    /// White noise on each accelerometer axis, standard deviation, m/s².
    pub accel_std_m_s2: f64,
    /// Constant accelerometer bias, x y z, m/s².
    pub accel_bias_m_s2: [f64; 3],
    /// Orientation noise: a random small rotation about each body axis, standard deviation, rad.
    pub orientation_std_rad: f64,
    /// Seed of the noise generator, so that noisy runs repeat exactly.
    pub seed: u64,
}

/// The emulated IMU.
#[derive(Debug, Clone)]
pub struct ImuNode {
    noise: ImuNoise,
    rng: SmallRng,
    link: NodeLink,
}

impl ImuNode {
    /// An IMU with `noise` that joins the sessions it hears with `key`.
    pub fn new(noise: ImuNoise, key: Key) -> Self {
        Self {
            noise,
            rng: SmallRng::seed_from_u64(noise.seed),
            link: NodeLink::new(key),
        }
    }

    /// Takes a frame from the bus: the IMU listens to the controller's announcement only.
    pub fn on_frame(&mut self, frame: &Frame) {
        if frame.id() == MessageId::Announce.raw() {
            // A refused announcement is counted by the link; the IMU has nothing else to do.
            let _ = self.link.receive(frame.id(), frame.data());
        }
    }

    /// Seals a sample in the IMU's session (`None` before it has joined one).
    pub fn seal(&mut self, message: &AnyMessage) -> Result<Option<Frame>, EncodeError> {
        self.link.seal(message)
    }

    fn gaussian(&mut self, std: f64) -> f64 {
        if std > 0.0 {
            Normal::new(0.0, std).map_or(0.0, |n| n.sample(&mut self.rng))
        } else {
            0.0
        }
    }

    /// One sample of the current state.
    pub fn sample(&mut self, physics: &Physics) -> AnyMessage {
        let (quat, gyro, accel) = physics.imu();
        let n = self.noise;
        let mut rotation = [0.0; 3];
        for axis in &mut rotation {
            *axis = self.gaussian(n.orientation_std_rad);
        }
        let quat = perturb(quat, rotation);
        let mut rate = gyro;
        for (value, bias) in rate.iter_mut().zip(n.gyro_bias_rad_s) {
            *value += bias + self.gaussian(n.gyro_std_rad_s);
        }
        let mut force = accel;
        for (value, bias) in force.iter_mut().zip(n.accel_bias_m_s2) {
            *value += bias + self.gaussian(n.accel_std_m_s2);
        }
        AnyMessage::Imu(Imu {
            orientation: Imu::orientation_of(quat.map(|c| c as f32)),
            angular_rate: rate.map(|r| AngularRate::saturating_from_si(r as f32)),
            acceleration: force.map(|a| Acceleration::saturating_from_si(a as f32)),
        })
    }
}

/// `q ⊗ δq` with `δq` the small rotation `v` (body frame), normalised.
fn perturb(q: [f64; 4], v: [f64; 3]) -> [f64; 4] {
    if v == [0.0; 3] {
        return q;
    }
    let d = [1.0, 0.5 * v[0], 0.5 * v[1], 0.5 * v[2]];
    let [w1, x1, y1, z1] = q;
    let [w2, x2, y2, z2] = d;
    let r = [
        w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
        w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
        w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
        w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
    ];
    let norm = r.iter().map(|c| c * c).sum::<f64>().sqrt();
    r.map(|c| c / norm)
}
