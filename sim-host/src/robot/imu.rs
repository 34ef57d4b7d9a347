//! The torso IMU as a CAN node: MuJoCo's ideal gyro and accelerometer readings, through the
//! chip's model ([`crate::robot::imu_chip`], the default) or straight ([`ImuModel::Ideal`]),
//! plus optional extra white noise and constant bias (default off), published as `Imu` frames
//! of angular rate and specific force.

use rand::rngs::SmallRng;
use rand::SeedableRng;

use protocol::{Acceleration, AngularRate, AnyMessage, EncodeError, Frame, Imu, Key, MessageId};

use crate::robot::imu_chip::{ChipSpec, ImuChip};
use crate::robot::link::NodeLink;
use crate::robot::noise::gaussian;
use crate::robot::physics::Physics;

/// What sits between the simulated truth and the wire.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ImuModel {
    /// A real part: noise, turn-on bias and its walk, range, resolution, sample rate and filter
    /// delay (see [`crate::robot::imu_chip`]).
    Chip(ChipSpec),
    /// A perfect chip: the true rate and specific force at the moment of sending (for
    /// debugging a controller).
    Ideal,
}

/// Extra noise and bias on top of the model, added to the truth before the chip. All zero by
/// default.
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
    /// The chip mounted pitched by this against the torso, rad (about the torso's y axis): a
    /// board or bracket off its drawing; the chip measures the torso's rate and specific force
    /// in its own, rotated axes.
    pub mount_pitch_rad: f64,
    /// Seed of the noise generator and of the chip's biases and noise, so that runs repeat
    /// exactly.
    pub seed: u64,
}

/// The emulated IMU.
#[derive(Debug, Clone)]
pub struct ImuNode {
    noise: ImuNoise,
    rng: SmallRng,
    chip: Option<ImuChip>,
    link: NodeLink,
}

impl ImuNode {
    /// An IMU of `model` with extra `noise` that joins the sessions it hears with `key`.
    pub fn new(model: ImuModel, noise: ImuNoise, key: Key) -> Self {
        let chip = match model {
            ImuModel::Chip(spec) => Some(ImuChip::new(spec, noise.seed)),
            ImuModel::Ideal => None,
        };
        Self {
            noise,
            // A stream of its own, so that the extras do not shift the chip's draws.
            rng: SmallRng::seed_from_u64(noise.seed ^ 0x1A2B_3C4D_5E6F_7081),
            chip,
            link: NodeLink::new(key),
        }
    }

    /// The chip, if the model has one (its biases, for tests and diagnostics).
    pub fn chip(&self) -> Option<&ImuChip> {
        self.chip.as_ref()
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
        gaussian(&mut self.rng, std)
    }

    /// The sample the node sends at `now_us`: the chip's newest output for the current state.
    pub fn sample(&mut self, now_us: u64, physics: &Physics) -> AnyMessage {
        let (_, gyro, accel) = physics.imu();
        let n = self.noise;
        let mut rate = pitched(gyro, n.mount_pitch_rad);
        let accel = pitched(accel, n.mount_pitch_rad);
        for (value, bias) in rate.iter_mut().zip(n.gyro_bias_rad_s) {
            *value += bias + self.gaussian(n.gyro_std_rad_s);
        }
        let mut force = accel;
        for (value, bias) in force.iter_mut().zip(n.accel_bias_m_s2) {
            *value += bias + self.gaussian(n.accel_std_m_s2);
        }
        let (rate, force) = match &mut self.chip {
            Some(chip) => chip.read(now_us as f64 * 1e-6, rate, force),
            None => (rate, force),
        };
        AnyMessage::Imu(Imu {
            angular_rate: rate.map(|r| AngularRate::saturating_from_si(r as f32)),
            acceleration: force.map(|a| Acceleration::saturating_from_si(a as f32)),
        })
    }
}

/// `v` (torso axes) in the axes of a chip pitched by `pitch_rad` about y.
fn pitched(v: [f64; 3], pitch_rad: f64) -> [f64; 3] {
    if pitch_rad == 0.0 {
        return v;
    }
    let (sin, cos) = pitch_rad.sin_cos();
    [cos * v[0] - sin * v[2], v[1], sin * v[0] + cos * v[2]]
}
