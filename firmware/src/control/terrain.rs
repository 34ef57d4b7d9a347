//! The ground behind the robot, as the rangefinder sees it: level, a step (a riser or an edge)
//! or a slope, told apart before the wheels reach it.
//!
//! The rangefinder on the torso's rear face looks back and down. Each ranging, with the
//! estimated pitch, gives the height of the ground where the beam meets it, over the wheels'
//! contact, and where that is along the path (the distance the robot has backed plus how far
//! behind the axle the beam lands). A step and a slope both raise (or lower) that height; they
//! differ in how far the beam's spot travels along the path while the height changes: at a
//! riser the spot climbs its face and stays where it is, off an edge it jumps along the beam to
//! the lower ground, on a slope it moves on with the rise at the slope's grade. So the watch
//! notes where the spot last read the level ground, follows a height that leaves it by
//! [`TerrainConfig::onset_m`], and decides once it has left it by [`TerrainConfig::decide_m`]:
//! a slope if the height changed from the level at a grade well under the beam's
//! ([`TerrainConfig::steep_share`]), a step otherwise.
//!
//! Heights are taken against a level learned from the ground behind while it is level, not
//! against zero: an estimated pitch 1° off puts the spot 1.4 cm high or low at 0.8 m, and the
//! accelerometer's offset leaves the estimate that far off on some robots. After each
//! decision, and after a ranging without a return, the level is learned anew (the robot is
//! about to change what it stands on; the ground left the beam's range), from rangings that
//! agree for a tenth of a second.

/// Where the rangefinder sits and how the watch reads it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TerrainConfig {
    /// The rangefinder's position relative to the wheel axle in the torso's frame, m: x
    /// forward, z up.
    pub mount_x_m: f32,
    /// … and up.
    pub mount_z_m: f32,
    /// How far below the torso's x axis the beam points, rad.
    pub depression_rad: f32,
    /// Wheel radius, m: the wheels' contact lies this far below the axle.
    pub wheel_radius_m: f32,
    /// A height this far from the level starts a feature, m.
    pub onset_m: f32,
    /// … and this far decides it, m.
    pub decide_m: f32,
    /// Heights within this of the level end a feature that went no further, and agree with
    /// each other for a new level, m.
    pub level_band_m: f32,
    /// Heights within this of the level keep learning it, m: narrower than the band, so that
    /// the foot of a slope is not learned as level (a 10° slope rises 5 mm in 3 cm).
    pub learn_band_m: f32,
    /// A feature is a slope when the height changed between the last level ranging and the
    /// decision by less than this share of what the beam's own grade gives over the spot's
    /// run in between: at a riser's face the spot stands still while the height changes; off
    /// an edge the spot jumps along the beam, from the edge to the lower ground, its height
    /// changing at the beam's grade, tan(25° − pitch); a 10° slope changes at its own,
    /// tan 10°. A robot leaning 10° nose down brings the two within 0.66 of each other.
    pub steep_share: f32,
    /// The beam must meet level ground at least this steeply for a decision between a slope
    /// and an edge, rad: below it a 10° slope's grade comes within [`Self::steep_share`] of
    /// the beam's own, and the two cannot be told apart (a robot leaning 14° nose down looks
    /// back 11° down, and read a ramp there as a riser); the watch then waits for a steeper
    /// ranging, and decides meanwhile only a riser's face, which rises far faster.
    pub min_beam_rad: f32,
    /// How much of each new level height the learned level takes, per ranging.
    pub level_gain: f32,
    /// How far along the path past a decision the spot must move before a level is learned
    /// again, m: the rest of a riser's face (the spot stands still on it) is no level.
    pub quiet_m: f32,
    /// How far along the path an onset may run without a decision, m, before the height it
    /// has stayed at becomes the level (a 10° slope decides 0.17 m past its last level
    /// ranging; one under 5° may not decide, and is level ground at its new height).
    pub onset_run_m: f32,
}

impl TerrainConfig {
    /// Where a ranging of `distance_m` puts the beam's spot in the torso's frame, relative to
    /// the wheel axle, m: (x forward, z up).
    pub fn spot_on_torso_m(&self, distance_m: f32) -> (f32, f32) {
        let (sin_d, cos_d) = crate::math::sin_cos(self.depression_rad);
        (
            self.mount_x_m - distance_m * cos_d,
            self.mount_z_m - distance_m * sin_d,
        )
    }

    /// The robot's VL53L1X on the rear face of the torso, 0.30 m behind and 0.09 m above the
    /// axle, 25° down (the beam meets level ground 0.7–0.9 m behind the axle on the wheels). A
    /// 10° slope rises 2.5 cm while the spot moves 14 cm; a riser's face rises with the spot
    /// standing still.
    pub const ROBOT: Self = Self {
        mount_x_m: -0.30,
        mount_z_m: 0.09,
        depression_rad: 25.0 * core::f32::consts::PI / 180.0,
        wheel_radius_m: 0.12,
        onset_m: 0.015,
        decide_m: 0.04,
        level_band_m: 0.01,
        learn_band_m: 0.005,
        steep_share: 0.85,
        min_beam_rad: 13.0 * core::f32::consts::PI / 180.0,
        level_gain: 0.05,
        quiet_m: 0.05,
        onset_run_m: 0.35,
    };
}

/// What lies behind the robot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Feature {
    /// A riser (`rise_m` > 0) or an edge (< 0), `rise_m` being the height decided on.
    Step {
        /// How far the ground rose at the decision, m.
        rise_m: f32,
    },
    /// A slope, up (`rise_m` > 0) or down.
    Slope {
        /// How far the ground rose at the decision, m.
        rise_m: f32,
    },
}

/// One ranging, with what the watch needs to place it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ranging {
    /// The distance along the beam, m (`None`: no return within the part's range).
    pub distance_m: Option<f32>,
    /// The torso's estimated pitch, rad (+ nose down).
    pub pitch_rad: f32,
    /// How far the robot has backed so far, m (any origin; + backward).
    pub backed_m: f32,
}

/// The watch.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TerrainWatch {
    /// The level ground's height as the beam reads it, m (`None`: not learned yet).
    level_m: Option<f32>,
    /// Whether the height has left the level by [`TerrainConfig::onset_m`] (either way: a
    /// feature decides on how far it went, whichever way it went on).
    onset: bool,
    /// The last ranging that read the level (within [`TerrainConfig::level_band_m`]).
    mark: Mark,
    /// Rangings in a row back within the level band during a feature.
    back_level: u8,
    /// After a decision: where along the path the spot must be for the watch to learn again.
    quiet_until_m: Option<f32>,
    /// A level being learned: the first height and how many rangings in a row have agreed
    /// with it.
    candidate: Option<(f32, u8)>,
}

/// Where a ranging's spot was, m: along the path, how far the robot had backed, and how far
/// the height stood off the level.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Mark {
    along_m: f32,
    backed_m: f32,
    rise_m: f32,
}

/// A height that changed by more than this share of what the beam's own grade gives over the
/// spot's run is a riser's face however shallow the beam: an edge's jump and a slope both
/// change it at no more than the beam's grade.
const RISER_SHARE: f32 = 1.5;

/// Rangings in a row back at the level that end a feature's onset (a pitch wobble).
const BACK_LEVEL_RANGINGS: u8 = 3;

/// Rangings in a row within the level band of each other that make a new level (0.1 s): after
/// a climb the robot pitches as it settles onto its wheels, and one ranging then saw the ground
/// beyond the plateau's far edge instead of the plateau.
const LEVEL_RANGINGS: u8 = 5;

impl TerrainWatch {
    /// Forgets the level and any onset: the next ranging starts a new level.
    pub fn reset(&mut self) {
        *self = Self::default();
    }

    /// Forgets the level and any onset, as [`Self::reset`], but keeps the quiet stretch of a
    /// decision: a body that pitched fast on a riser's face is still before that face.
    pub fn unsteady(&mut self) {
        *self = Self {
            quiet_until_m: self.quiet_until_m,
            ..Self::default()
        };
    }

    /// The ground's height over the wheels' contact where the beam meets it, m, and how far
    /// behind the axle that is, m.
    pub fn spot_m(config: &TerrainConfig, distance_m: f32, pitch_rad: f32) -> (f32, f32) {
        let (x, z) = config.spot_on_torso_m(distance_m);
        // Rotated into the level frame by the pitch (+ nose down: the front goes down).
        let (sin_p, cos_p) = crate::math::sin_cos(pitch_rad);
        let level_x = x * cos_p + z * sin_p;
        let level_z = -x * sin_p + z * cos_p;
        (level_z + config.wheel_radius_m, -level_x)
    }

    /// Takes one ranging; returns the feature it decides, if any.
    pub fn update(&mut self, config: &TerrainConfig, ranging: &Ranging) -> Option<Feature> {
        let Some(distance_m) = ranging.distance_m else {
            // The ground left the part's range (down a slope the beam runs flat): what the
            // spot meets next may be anywhere, and a jump there is no riser.
            self.reset();
            return None;
        };
        let (height_m, behind_m) = Self::spot_m(config, distance_m, ranging.pitch_rad);
        let along_m = ranging.backed_m + behind_m;
        if !height_m.is_finite() || !along_m.is_finite() {
            return None;
        }
        if let Some(until_m) = self.quiet_until_m {
            if along_m < until_m {
                return None;
            }
            self.quiet_until_m = None;
        }
        let Some(level_m) = self.level_m else {
            self.candidate = match self.candidate {
                Some((first_m, n)) if (height_m - first_m).abs() <= config.level_band_m => {
                    if n.saturating_add(1) >= LEVEL_RANGINGS {
                        self.level_m = Some(first_m);
                        self.mark = Mark {
                            along_m,
                            backed_m: ranging.backed_m,
                            rise_m: height_m - first_m,
                        };
                        None
                    } else {
                        Some((first_m, n.saturating_add(1)))
                    }
                }
                _ => Some((height_m, 1)),
            };
            return None;
        };
        let rise_m = height_m - level_m;
        let here = Mark {
            along_m,
            backed_m: ranging.backed_m,
            rise_m,
        };
        if !self.onset {
            if rise_m.abs() <= config.learn_band_m {
                self.level_m = Some(level_m + config.level_gain * rise_m);
            }
            if rise_m.abs() <= config.level_band_m {
                self.mark = here;
            }
            if rise_m.abs() >= config.onset_m {
                self.onset = true;
                self.back_level = 0;
            }
        }
        if rise_m.abs() >= config.decide_m {
            return self.decide(config, ranging.pitch_rad, here);
        }
        if !self.onset {
            return None;
        }
        if (along_m - self.mark.along_m).abs() > config.onset_run_m {
            // No slope rises this little this far: the ground is level at a new height, learned
            // as at the start, from rangings that agree.
            self.unsteady();
        } else if rise_m.abs() <= config.level_band_m {
            self.back_level = self.back_level.saturating_add(1);
            if self.back_level >= BACK_LEVEL_RANGINGS {
                self.onset = false;
                self.mark = here;
            }
        } else {
            self.back_level = 0;
        }
        None
    }

    /// The feature the ranging `here` decides (pitched `pitch_rad`), from the grade between
    /// the last level ranging and it; the watch then learns anew.
    fn decide(&mut self, config: &TerrainConfig, pitch_rad: f32, here: Mark) -> Option<Feature> {
        let mark = self.mark;
        let run_m = (here.along_m - mark.along_m).abs();
        // The spot runs up a slope because the robot backs along it; a body that pitches
        // sweeps it up onto an edge standing still.
        let backed_m = (here.backed_m - mark.backed_m).abs();
        let swept = here.rise_m > 0.0 && backed_m < 0.5 * run_m;
        // The beam meets level ground at its depression less the pitch (nose down lifts the
        // rear face's beam toward the horizontal).
        let beam_rad = config.depression_rad - pitch_rad;
        let (sin, cos) = crate::math::sin_cos(beam_rad);
        let beam_change_m = run_m * sin / cos;
        let change_m = (here.rise_m - mark.rise_m).abs();
        // Too shallow to tell a slope from an edge, only a change well past the beam's own
        // grade is sure (a riser's face); the rest waits, the feature still open, for a
        // ranging from a steadier body.
        let riser = beam_rad > 0.0 && change_m > RISER_SHARE * beam_change_m;
        if beam_rad < config.min_beam_rad && !riser {
            return None;
        }
        self.reset();
        self.quiet_until_m = Some(here.along_m + config.quiet_m);
        let slope = change_m < config.steep_share * beam_change_m && !swept;
        let rise_m = here.rise_m;
        Some(if slope {
            Feature::Slope { rise_m }
        } else {
            Feature::Step { rise_m }
        })
    }
}

pub mod rise;
#[cfg(test)]
mod tests;
