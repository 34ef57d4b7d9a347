//! What the robot crossed in a segment: for each obstacle of the scene
//! ([`crate::scene::Feature`]), when a part of the robot first touched it (a wheel, a shank, a
//! foot), when a foot first stood on it, when all four did, and when all four feet were past
//! it, on the far side from where the segment began.

use serde::Serialize;

use crate::scene::Feature;
use crate::session::simulator::Simulator;

/// The feet's geoms, in the firmware's leg order.
const FEET: [&str; 4] = ["foot_fl", "foot_fr", "foot_bl", "foot_br"];
/// The feet's sphere radius, m.
const FOOT_RADIUS_M: f64 = 0.035;
/// A foot's centre this close to the foot's height over the ground under it stands on it, m.
const STANDING_M: f64 = 0.02;

/// What the robot did at one obstacle in a segment (times from the segment's start, s).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Crossing {
    /// The obstacle's geom (`step`, `ramp_up`, `flight_up_1`, …).
    pub obstacle: String,
    /// When a part of the robot first touched it.
    pub first_touch_s: Option<f64>,
    /// When a foot first stood on it.
    pub first_foot_on_s: Option<f64>,
    /// When all four feet first stood on it.
    pub all_feet_on_s: Option<f64>,
    /// When all four feet were first past it, on the far side from where the torso began.
    pub past_s: Option<f64>,
    /// From the first touch to all four feet past it: how long the crossing took.
    pub crossing_s: Option<f64>,
}

/// Follows the feet over a segment.
#[derive(Debug, Clone)]
pub struct CrossingTracker {
    features: Vec<Feature>,
    crossings: Vec<Crossing>,
    /// Whether the torso began before each feature (at lower x) rather than beyond it.
    from_below: Vec<bool>,
    feet: Option<[usize; 4]>,
    /// Each feature's geom.
    geoms: Vec<Option<usize>>,
    start_s: f64,
}

impl CrossingTracker {
    /// Starts on the simulator's present state, for the scene's `features`.
    pub fn start(features: &[Feature], sim: &Simulator) -> Self {
        let physics = sim.physics();
        let torso_x_m = physics.torso().pos_m[0];
        let ids = FEET.map(|name| physics.geom_id(name));
        let feet = match ids {
            [Some(a), Some(b), Some(c), Some(d)] => Some([a, b, c, d]),
            _ => None,
        };
        Self {
            features: features.to_vec(),
            crossings: features
                .iter()
                .map(|f| Crossing {
                    obstacle: f.name.clone(),
                    first_touch_s: None,
                    first_foot_on_s: None,
                    all_feet_on_s: None,
                    past_s: None,
                    crossing_s: None,
                })
                .collect(),
            from_below: features.iter().map(|f| torso_x_m < f.x_m[0]).collect(),
            feet,
            geoms: features.iter().map(|f| physics.geom_id(&f.name)).collect(),
            start_s: sim.time_s(),
        }
    }

    /// Takes one cycle's state.
    pub fn observe(&mut self, sim: &Simulator) {
        let Some(ids) = self.feet else {
            return;
        };
        let physics = sim.physics();
        let feet = ids.map(|id| physics.geom_position_m(id));
        let t = sim.time_s() - self.start_s;
        for (((feature, crossing), below), geom) in self
            .features
            .iter()
            .zip(self.crossings.iter_mut())
            .zip(&self.from_below)
            .zip(&self.geoms)
        {
            if crossing.first_touch_s.is_none()
                && physics
                    .obstacle_contacts()
                    .any(|(obstacle, _)| Some(obstacle) == *geom)
            {
                crossing.first_touch_s = Some(t);
            }
            let on = |p: &Option<[f64; 3]>| {
                p.is_some_and(|[x, _, z]| {
                    feature
                        .height_at(x)
                        .is_some_and(|ground| (z - ground - FOOT_RADIUS_M).abs() < STANDING_M)
                })
            };
            let past = |p: &Option<[f64; 3]>| {
                p.is_some_and(|[x, ..]| {
                    if *below {
                        x > feature.x_m[1]
                    } else {
                        x < feature.x_m[0]
                    }
                })
            };
            if feet.iter().any(on) {
                crossing.first_foot_on_s.get_or_insert(t);
            }
            if feet.iter().all(on) {
                crossing.all_feet_on_s.get_or_insert(t);
            }
            if crossing.past_s.is_none() && feet.iter().all(past) {
                crossing.past_s = Some(t);
                crossing.crossing_s = crossing.first_touch_s.map(|touch_s| t - touch_s);
            }
        }
    }

    /// The segment's crossings, one per obstacle of the scene.
    pub fn finish(self) -> Vec<Crossing> {
        self.crossings
    }
}
