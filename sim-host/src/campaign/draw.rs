//! One trial's plant, drawn from its seed alone: the body (masses, centre of mass, friction,
//! wheel damping), the transport delay, the drives' torque ratings, and which IMU chip and
//! which drive sensors (their seeds) the robot carries. The ranges are the robustness issue's;
//! [`BODY`] lists them with the end of each range that is hard on the controller, for the
//! table's "most extreme parameter". Everything not drawn is [`Plant::default`]'s: a trial is
//! the tested default robot, varied.
//!
//! The generator is SplitMix64, written out here rather than taken from `rand`: a seed then
//! draws the same plant on every machine and with every version of every dependency, which
//! is the contract of `--seed` (a trial is reproducible from its seed alone). The chip and the
//! sensors draw their own parts from the seeds this stream gives them (the simulator's models,
//! as `sim-host run --seed` does).

use serde::{Deserialize, Serialize};

use crate::robot::plant::{DriveRatings, Plant};
use crate::robot::rating::Rating;
use crate::robot::variation::Variation;

/// SplitMix64 (Steele, Lea, Flood 2014): 64 bits of state, every seed a good stream.
#[derive(Debug, Clone)]
pub struct Draw {
    state: u64,
}

impl Draw {
    /// The stream of `seed`.
    pub fn new(seed: u64) -> Self {
        Self { state: seed }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1) (53 bits).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// How a parameter's value is drawn from a uniform `u` in [0, 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Scale {
    /// `lo + u·(hi − lo)`.
    Linear,
    /// `lo·(hi/lo)^u`: every decade as likely (a range over two decades).
    Log,
    /// One of the whole numbers `lo…hi`, each as likely.
    Integer,
    /// Not drawn here: the IMU chip draws it from its seed, normal with 1σ a quarter of the
    /// range (the range is ±2σ, where 95 % of parts lie; the sweep sets its ends). Its `u` is
    /// its place in that spread, Φ(value/σ).
    Chip,
}

/// Which end of a parameter's range is hard on the controller.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Harsh {
    /// Both ends (a centre of mass off either way): harshness `|2u − 1|`.
    BothEnds,
    /// The low end (weaker drives): harshness `1 − u`.
    Low,
    /// The high end (heavier legs, more delay): harshness `u`.
    High,
}

/// One drawn parameter of the plant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Parameter {
    /// Name in the JSON results and the table.
    pub name: &'static str,
    /// Lowest and highest value.
    pub range: (f64, f64),
    /// Unit, for the table.
    pub unit: &'static str,
    /// How it is drawn.
    pub scale: Scale,
    /// Its hard end.
    pub harsh: Harsh,
}

impl Parameter {
    const fn new(
        name: &'static str,
        range: (f64, f64),
        unit: &'static str,
        scale: Scale,
        harsh: Harsh,
    ) -> Self {
        Self {
            name,
            range,
            unit,
            scale,
            harsh,
        }
    }

    /// The value of a uniform draw `u` (a [`Scale::Chip`] parameter: `None`, the chip draws
    /// it).
    pub fn value(&self, u: f64) -> Option<f64> {
        let (lo, hi) = self.range;
        match self.scale {
            Scale::Linear => Some(lo + u * (hi - lo)),
            Scale::Log => Some(lo * (hi / lo).powf(u)),
            Scale::Integer => Some((lo + (u * (hi - lo + 1.0)).floor()).min(hi)),
            Scale::Chip => None,
        }
    }

    /// How close a draw `u` lies to the hard end, 0 (mildest) … 1 (hardest). For a
    /// [`Scale::Chip`] parameter, the share of parts closer to nominal.
    pub fn harshness(&self, u: f64) -> f64 {
        match self.harsh {
            Harsh::BothEnds => (2.0 * u - 1.0).abs(),
            Harsh::Low => 1.0 - u,
            Harsh::High => u,
        }
    }
}

/// The parameters drawn from the trial's stream, in draw order (changing the order changes
/// every trial's plant): the list. After them the stream gives the IMU chip's seed and
/// the drive sensors' seed; the chip's offsets, [`crate::campaign::imu::PARAMETERS`], follow
/// from its seed.
pub const BODY: [Parameter; 9] = [
    Parameter::new("mass", (0.9, 1.1), "×", Scale::Linear, Harsh::BothEnds),
    Parameter::new("com_x", (-0.02, 0.02), "m", Scale::Linear, Harsh::BothEnds),
    Parameter::new("com_y", (-0.02, 0.02), "m", Scale::Linear, Harsh::BothEnds),
    Parameter::new("leg_mass", (1.0, 3.0), "×", Scale::Linear, Harsh::High),
    Parameter::new("friction", (0.6, 1.2), "", Scale::Linear, Harsh::Low),
    // The controller feeds forward the model's 2 N·m·s/rad: the low end is the far one.
    Parameter::new(
        "wheel_damping",
        (0.02, 2.0),
        "N·m·s/rad",
        Scale::Log,
        Harsh::Low,
    ),
    Parameter::new(
        "transport_delay",
        (0.0, 2.0),
        "cycles",
        Scale::Integer,
        Harsh::High,
    ),
    Parameter::new("leg_rating", (0.8, 1.0), "×", Scale::Linear, Harsh::Low),
    Parameter::new("wheel_rating", (0.8, 1.0), "×", Scale::Linear, Harsh::Low),
];

/// Every parameter, drawn then the chip's: the columns of a trial's draw.
pub fn parameters() -> impl Iterator<Item = &'static Parameter> {
    BODY.iter().chain(crate::campaign::imu::PARAMETERS.iter())
}

/// One trial's draw.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Draws {
    /// The seed.
    pub seed: u64,
    /// Per parameter of [`parameters`], the uniform `u` it came from (the chip's: its place in
    /// the part spread).
    pub unit: Vec<f64>,
    /// Per parameter of [`parameters`], its value.
    pub values: Vec<f64>,
    /// The IMU chip's seed: which part of the data sheet's spread the robot carries.
    pub chip_seed: u64,
    /// The drive sensors' seed: each joint's effort gain error.
    pub sensing_seed: u64,
}

impl Draws {
    /// The draw of `seed`.
    pub fn of(seed: u64) -> Self {
        let mut draw = Draw::new(seed);
        let mut unit = Vec::new();
        let mut values = Vec::new();
        for p in &BODY {
            let u = draw.unit();
            unit.push(u);
            values.push(p.value(u).unwrap_or(0.0));
        }
        let chip_seed = draw.next_u64();
        let sensing_seed = draw.next_u64();
        for (u, value) in crate::campaign::imu::offsets(chip_seed) {
            unit.push(u);
            values.push(value);
        }
        Self {
            seed,
            unit,
            values,
            chip_seed,
            sensing_seed,
        }
    }

    /// Parameter `name`'s value (0 for a name not drawn: a bug the tests catch).
    pub fn value(&self, name: &str) -> f64 {
        parameters()
            .zip(&self.values)
            .find(|(p, _)| p.name == name)
            .map_or(0.0, |(_, v)| *v)
    }

    /// The parameter nearest its hard end, its value and harshness.
    pub fn most_extreme(&self) -> (&'static Parameter, f64, f64) {
        let mut best = (&BODY[0], self.value(BODY[0].name), -1.0);
        for ((p, u), value) in parameters().zip(&self.unit).zip(&self.values) {
            let h = p.harshness(*u);
            if h > best.2 {
                best = (p, *value, h);
            }
        }
        best
    }

    /// The plant these draws describe, on `drives` with their torques scaled: the drawn body,
    /// delay and ratings, this trial's chip and sensors.
    pub fn plant(&self, drives: DriveRatings) -> Plant {
        let drawn = |name: &str| {
            BODY.iter()
                .any(|p| p.name == name)
                .then(|| self.value(name))
        };
        let mut plant = plant_of(&drawn, drives);
        plant.sensing.seed = self.sensing_seed;
        crate::campaign::imu::fit_chip(&mut plant, self.chip_seed);
        plant
    }
}

/// Parameter values by name: `Some` where set, `None` where the robot is as modelled.
pub type Values<'a> = &'a dyn Fn(&str) -> Option<f64>;

/// [`Plant::default`] with the [`BODY`] parameters `value` sets, on `drives` (torques scaled
/// by the ratings' parameters). The IMU and the sensors stay the default's.
pub fn plant_of(value: Values<'_>, drives: DriveRatings) -> Plant {
    let base = Plant::default();
    let nominal = base.variation;
    let or = |name, nominal| value(name).unwrap_or(nominal);
    Plant {
        drives: DriveRatings {
            leg_joint: scaled(drives.leg_joint, or("leg_rating", 1.0)),
            wheel: scaled(drives.wheel, or("wheel_rating", 1.0)),
        },
        transport_delay_cycles: value("transport_delay")
            .map_or(base.transport_delay_cycles, |cycles| cycles as u32),
        variation: Variation {
            mass_scale: or("mass", nominal.mass_scale),
            leg_mass_scale: or("leg_mass", nominal.leg_mass_scale),
            torso_com_offset_m: [
                or("com_x", nominal.torso_com_offset_m[0]),
                or("com_y", nominal.torso_com_offset_m[1]),
                nominal.torso_com_offset_m[2],
            ],
            friction: value("friction").or(nominal.friction),
            wheel_damping_nm_s_rad: value("wheel_damping").or(nominal.wheel_damping_nm_s_rad),
        },
        ..base
    }
}

/// `rating` with its peak and continuous torques times `scale` (speeds and heating as rated).
pub fn scaled(rating: Rating, scale: f64) -> Rating {
    Rating {
        peak_torque_nm: rating.peak_torque_nm * scale,
        continuous_torque_nm: rating.continuous_torque_nm * scale,
        ..rating
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix_repeats_its_published_stream() {
        // The first outputs for seed 0 (the reference implementation's test vector).
        let mut draw = Draw::new(0);
        assert_eq!(draw.next_u64(), 0xE220_A839_7B1D_CDAF);
        assert_eq!(draw.next_u64(), 0x6E78_9E6A_A1B9_65F4);
    }

    #[test]
    fn every_value_lies_in_its_range_and_a_seed_draws_the_same_plant() {
        for seed in 0..200 {
            let draws = Draws::of(seed);
            assert_eq!(draws, Draws::of(seed));
            assert_eq!(draws.values.len(), parameters().count());
            for ((p, u), v) in parameters().zip(&draws.unit).zip(&draws.values) {
                // The chip's offsets are normal: beyond ±2σ one part in twenty.
                if p.scale != Scale::Chip {
                    assert!(
                        (p.range.0..=p.range.1).contains(v),
                        "{}: {v} outside {:?}",
                        p.name,
                        p.range
                    );
                }
                assert!((0.0..=1.0).contains(&p.harshness(*u)));
            }
        }
        assert_ne!(Draws::of(1), Draws::of(2));
        assert_ne!(Draws::of(1).chip_seed, Draws::of(2).chip_seed);
    }

    #[test]
    fn integers_take_each_value_and_harshness_points_to_the_hard_end() {
        let delay = BODY[6];
        assert_eq!(delay.name, "transport_delay");
        assert_eq!(delay.value(0.0), Some(0.0));
        assert_eq!(delay.value(0.5), Some(1.0));
        assert_eq!(delay.value(0.999), Some(2.0));
        let damping = BODY[5];
        assert!((damping.value(0.5).unwrap_or(0.0) - 0.2).abs() < 1e-12);
        assert_eq!(damping.harshness(0.0), 1.0);
        assert_eq!(BODY[1].harshness(0.5), 0.0);
    }

    #[test]
    fn the_plant_is_the_default_with_the_draws() {
        let draws = Draws::of(7);
        let plant = draws.plant(DriveRatings::RATED);
        let scale = draws.value("leg_rating");
        assert!((plant.drives.leg_joint.peak_torque_nm - 33.5 * scale).abs() < 1e-9);
        assert_eq!(plant.variation.mass_scale, draws.value("mass"));
        assert_eq!(
            plant.transport_delay_cycles,
            draws.value("transport_delay") as u32
        );
        assert_eq!(plant.sensing.seed, draws.sensing_seed);
        assert_eq!(plant.imu_noise.seed, draws.chip_seed);
        let base = Plant::default();
        assert_eq!(plant.imu, base.imu);
        assert_eq!(
            plant.sensing.effort_gain_error,
            base.sensing.effort_gain_error
        );
        // Nothing set: the tested default itself.
        assert_eq!(plant_of(&|_| None, base.drives), base);
    }
}
