//! The rangefinder as a CAN node: an ST VL53L1X time-of-flight sensor on the torso's rear face,
//! looking back and 25° down at the ground the autonomous mode backs onto, published as
//! `Range` frames.
//!
//! # The part
//!
//! - **Mode**: short distance (up to 1.3 m, whatever the ambient light), the 20 ms timing
//!   budget (the least that mode allows), ranging back to back: a ranging every 20 ms, sent
//!   when it ends.
//! - **What a ranging measures**: the part integrates its laser's returns over the timing
//!   budget and over its field of view. Here: five MuJoCo rays (the centre and 5° up, down, left
//!   and right, the field of a reduced region of interest), their median each control cycle,
//!   averaged over the cycles of the budget. So a ranging reports where the ground was about
//!   10 ms before its frame, and an edge inside the field reads as the median ray sees it.
//! - **Error**: the data sheet gives a ranging error of typically ±20 mm in the dark, the sum of
//!   an offset (per part, drawn once: 1σ 5 mm) and a repeatability (per ranging: 1σ 5 mm).
//! - **Output**: whole millimetres and a status: no return within 1.3 m on most of the
//!   budget's cycles is `SignalFail`.
//!
//! [`RangeModel::Ideal`] sends the centre ray's exact length of each cycle, for debugging.

use rand::rngs::SmallRng;
use rand::SeedableRng;

use protocol::{AnyMessage, EncodeError, Frame, Key, MessageId, Range, RangeDistance, RangeStatus};

use crate::robot::link::NodeLink;
use crate::robot::noise::gaussian;
use crate::robot::physics::Physics;

/// The figures of a time-of-flight part.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeSpec {
    /// Farthest target the mode ranges, m.
    pub max_range_m: f64,
    /// Standard deviation of the part's offset, drawn once, m.
    pub offset_std_m: f64,
    /// Standard deviation of one ranging's repeatability error, m.
    pub noise_std_m: f64,
    /// Output resolution, m.
    pub resolution_m: f64,
}

impl RangeSpec {
    /// ST VL53L1X, short distance mode, 20 ms timing budget (its data sheet and user manual
    /// UM2356): 1.3 m, ±20 mm typical ranging error in the dark, 1 mm output.
    pub const VL53L1X: Self = Self {
        max_range_m: 1.3,
        offset_std_m: 0.005,
        noise_std_m: 0.005,
        resolution_m: 0.001,
    };
}

/// What sits between the simulated rays and the wire.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RangeModel {
    /// A real part, drawn with `seed` (its offset, then its noise).
    Part {
        /// The part's figures.
        spec: RangeSpec,
        /// Seed of the part's offset and noise.
        seed: u64,
    },
    /// The centre ray's exact length when the frame goes out.
    Ideal,
}

/// The emulated rangefinder.
#[derive(Debug, Clone)]
pub struct RangeNode {
    model: RangeModel,
    rng: SmallRng,
    offset_m: f64,
    /// This ranging's cycles so far: the sum of their distances, how many, how many saw
    /// nothing within range.
    sum_m: f64,
    seen: u32,
    missed: u32,
    link: NodeLink,
}

impl RangeNode {
    /// A rangefinder of `model` that joins the sessions it hears with `key`.
    pub fn new(model: RangeModel, key: Key) -> Self {
        let (seed, offset_std_m) = match model {
            RangeModel::Part { spec, seed } => (seed, spec.offset_std_m),
            RangeModel::Ideal => (0, 0.0),
        };
        let mut rng = SmallRng::seed_from_u64(seed ^ 0x7A0F_5EED_0000_0186);
        let offset_m = gaussian(&mut rng, offset_std_m);
        Self {
            model,
            rng,
            offset_m,
            sum_m: 0.0,
            seen: 0,
            missed: 0,
            link: NodeLink::new(key),
        }
    }

    /// The part's offset, m (0 for the ideal model).
    pub fn offset_m(&self) -> f64 {
        self.offset_m
    }

    /// Takes a frame from the bus: the rangefinder listens to the controller's announcement
    /// only.
    pub fn on_frame(&mut self, frame: &Frame) {
        if frame.id() == MessageId::Announce.raw() {
            // A refused announcement is counted by the link; nothing else to do.
            let _ = self.link.receive(frame.id(), frame.data());
        }
    }

    /// Integrates one control cycle of the ranging under way.
    pub fn observe(&mut self, physics: &Physics) {
        let RangeModel::Part { spec, .. } = self.model else {
            return;
        };
        // A ray that met nothing (MuJoCo's −1) is the farthest, not the nearest.
        let mut rays = physics
            .range_rays_m()
            .map(|ray_m| if ray_m < 0.0 { f64::INFINITY } else { ray_m });
        rays.sort_by(f64::total_cmp);
        let median = rays[rays.len() / 2];
        if median > spec.max_range_m {
            self.missed += 1;
        } else {
            self.sum_m += median;
            self.seen += 1;
        }
    }

    /// The ranging that ends now (and starts the next).
    pub fn ranging(&mut self, physics: &Physics) -> AnyMessage {
        let (seen, missed, sum_m) = (self.seen, self.missed, self.sum_m);
        (self.seen, self.missed, self.sum_m) = (0, 0, 0.0);
        let distance_m = match self.model {
            RangeModel::Ideal => {
                let centre = physics.range_rays_m()[0];
                (centre >= 0.0).then_some(centre)
            }
            RangeModel::Part { spec, .. } => (seen > missed).then(|| {
                let noise = gaussian(&mut self.rng, spec.noise_std_m);
                let measured = sum_m / f64::from(seen) + self.offset_m + noise;
                (measured / spec.resolution_m).round() * spec.resolution_m
            }),
        };
        let (distance, status) = match distance_m {
            Some(m) => (
                RangeDistance::saturating_from_si(m as f32),
                RangeStatus::Valid,
            ),
            None => (
                RangeDistance::saturating_from_si(0.0),
                RangeStatus::SignalFail,
            ),
        };
        AnyMessage::Range(Range { distance, status })
    }

    /// Seals a ranging in the node's session (`None` before it has joined one).
    pub fn seal(&mut self, message: &AnyMessage) -> Result<Option<Frame>, EncodeError> {
        self.link.seal(message)
    }
}
