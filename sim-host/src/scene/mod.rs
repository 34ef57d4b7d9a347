//! Scenes: the ground the robot meets, as parameters a scenario or the command line picks
//! (`--scene step:height_m=0.08`, or a scenario's `[scene]` table), made into MJCF around the
//! robot's model ([`mjcf`]).
//!
//! The robot starts at x = 0 facing +x. Every obstacle lies ahead of it (or behind it, x
//! mirrored, for the autonomous mode that drives back first), 3 m wide (centred on
//! the robot's path, so a heading off by 15° still meets it), and is a static ground geom: it
//! collides with every part of the robot that collides with the floor — torso, wheels, thighs,
//! shanks and feet — so a shank cannot pass through a step's edge.
//!
//! The scene also knows its own ground profile ([`Scene::ground_height_m`]): tests and summaries
//! judge what was crossed from where the robot is, without reading the MJCF back.

pub mod mjcf;
pub mod parse;

pub use parse::SceneError;

/// Width of every obstacle across the path, m.
pub const OBSTACLE_WIDTH_M: f64 = 3.0;

/// What a scene puts ahead of the robot (or behind it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Scene {
    /// Flat ground only.
    Flat,
    /// One step up onto a plateau and down off it.
    Step(Step),
    /// A flight of steps up, a landing, the same flight down.
    Flight(Flight),
    /// A ramp up, a plateau, a ramp down.
    Ramp(Ramp),
    /// The course: a step up, a plateau, a step down, flat ground, then a ramp up, a plateau and
    /// a ramp down.
    Course(Course),
}

/// A step up at `riser_x_m` onto a plateau `depth_m` deep, and down off its far edge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    /// Riser height, m.
    pub height_m: f64,
    /// Where the riser stands, m from the start (ahead, or behind when `behind`).
    pub riser_x_m: f64,
    /// Plateau depth, m (the step down is at `riser_x_m + depth_m`).
    pub depth_m: f64,
    /// Behind the robot instead of ahead (x mirrored): the autonomous mode drives back first.
    pub behind: bool,
}

/// `count` steps of `rise_m` up, each tread `tread_m` deep, a landing `top_depth_m` deep, and
/// the same flight down.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Flight {
    /// Each riser's height, m.
    pub rise_m: f64,
    /// Steps up (and as many down).
    pub count: u32,
    /// Depth of each tread between risers, m.
    pub tread_m: f64,
    /// Where the first riser stands, m from the start (ahead, or behind when `behind`).
    pub riser_x_m: f64,
    /// Depth of the landing at the top, m.
    pub top_depth_m: f64,
    /// Behind the robot instead of ahead (x mirrored).
    pub behind: bool,
}

/// A ramp of `angle_deg` and `length_m` (along its slope) from `start_x_m`, a plateau
/// `top_depth_m` deep, and the same ramp down.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ramp {
    /// Slope, degrees.
    pub angle_deg: f64,
    /// Where the ramp leaves the ground, m from the start (ahead, or behind when `behind`).
    pub start_x_m: f64,
    /// Length along the slope, m.
    pub length_m: f64,
    /// Plateau depth at the top, m.
    pub top_depth_m: f64,
    /// Behind the robot instead of ahead (x mirrored).
    pub behind: bool,
}

/// The course's two obstacles; their places are fixed (see [`Course::features`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Course {
    /// The step's height, m.
    pub step_height_m: f64,
    /// The ramp's slope, degrees.
    pub ramp_angle_deg: f64,
    /// Behind the robot instead of ahead (x mirrored).
    pub behind: bool,
}

impl Step {
    /// A 6 cm step 1 m ahead, 1.2 m deep: the report's step, with room for the whole robot
    /// (0.6 m long, 0.44 m between its hips) on the plateau.
    pub const DEFAULT: Self = Self {
        height_m: 0.06,
        riser_x_m: 1.0,
        depth_m: 1.2,
        behind: false,
    };
}

impl Flight {
    /// Two 6 cm steps, treads 0.6 m deep (the robot's length), a 1.2 m landing.
    pub const DEFAULT: Self = Self {
        rise_m: 0.06,
        count: 2,
        tread_m: 0.6,
        riser_x_m: 1.0,
        top_depth_m: 1.2,
        behind: false,
    };
}

impl Ramp {
    /// The report's 10° ramp, 1.5 m long, 1 m ahead, with a 1 m plateau.
    pub const DEFAULT: Self = Self {
        angle_deg: 10.0,
        start_x_m: 1.0,
        length_m: 1.5,
        top_depth_m: 1.0,
        behind: false,
    };
}

impl Course {
    /// The report's obstacles: a 6 cm step and a 10° ramp.
    pub const DEFAULT: Self = Self {
        step_height_m: 0.06,
        ramp_angle_deg: 10.0,
        behind: false,
    };

    /// Where the course puts its step: 1 m ahead, a 1.2 m plateau.
    pub fn step(&self) -> Step {
        Step {
            height_m: self.step_height_m,
            behind: self.behind,
            ..Step::DEFAULT
        }
    }

    /// Where the course puts its ramp: 1.5 m of flat ground after the step.
    pub fn ramp(&self) -> Ramp {
        let step = self.step();
        Ramp {
            angle_deg: self.ramp_angle_deg,
            start_x_m: step.riser_x_m + step.depth_m + 1.5,
            behind: self.behind,
            ..Ramp::DEFAULT
        }
    }
}

/// One piece of ground, as its profile along x: flat at `height_m` over `x_m`, or a slope
/// rising from `height_m[0]` to `height_m[1]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Feature {
    /// The geom's name in the MJCF (unique in the scene).
    pub name: String,
    /// Start and end along x, m.
    pub x_m: [f64; 2],
    /// Ground height at the start and at the end, m (equal: a flat top).
    pub height_m: [f64; 2],
}

impl Feature {
    fn flat(name: String, x0: f64, x1: f64, height_m: f64) -> Self {
        Self {
            name,
            x_m: [x0, x1],
            height_m: [height_m, height_m],
        }
    }

    /// The feature mirrored in x (`x → −x`): the same ground met backward.
    fn mirrored(self) -> Self {
        let [x0, x1] = self.x_m;
        let [h0, h1] = self.height_m;
        Self {
            name: self.name,
            x_m: [-x1, -x0],
            height_m: [h1, h0],
        }
    }

    /// Ground height over x, m, inside the feature.
    pub fn height_at(&self, x_m: f64) -> Option<f64> {
        let [x0, x1] = self.x_m;
        (x0..=x1).contains(&x_m).then(|| {
            let share = if x1 > x0 { (x_m - x0) / (x1 - x0) } else { 0.0 };
            self.height_m[0] + share * (self.height_m[1] - self.height_m[0])
        })
    }
}

impl Scene {
    /// The scene's name, as `--scene` takes it.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Flat => "flat",
            Self::Step(_) => "step",
            Self::Flight(_) => "flight",
            Self::Ramp(_) => "ramp",
            Self::Course(_) => "course",
        }
    }

    /// The obstacles, in order along the path.
    pub fn features(&self) -> Vec<Feature> {
        match self {
            Self::Flat => Vec::new(),
            Self::Step(step) => step.features("step"),
            Self::Flight(flight) => flight.features(),
            Self::Ramp(ramp) => ramp.features("ramp"),
            Self::Course(course) => {
                let mut features = course.step().features("step");
                features.extend(course.ramp().features("ramp"));
                features
            }
        }
    }

    /// Ground height under `x_m`, m (0 off every obstacle).
    pub fn ground_height_m(&self, x_m: f64) -> f64 {
        self.features()
            .iter()
            .filter_map(|f| f.height_at(x_m))
            .fold(0.0, f64::max)
    }
}

/// `features` mirrored in x when `behind`, in order along the path backward.
fn placed(features: Vec<Feature>, behind: bool) -> Vec<Feature> {
    if behind {
        features.into_iter().map(Feature::mirrored).collect()
    } else {
        features
    }
}

impl Step {
    fn features(&self, name: &str) -> Vec<Feature> {
        let x0 = self.riser_x_m;
        let step = Feature::flat(name.to_owned(), x0, x0 + self.depth_m, self.height_m);
        placed(vec![step], self.behind)
    }
}

impl Flight {
    fn features(&self) -> Vec<Feature> {
        let (mut features, mut x) = (Vec::new(), self.riser_x_m);
        for i in 1..=self.count {
            let depth = if i == self.count {
                self.top_depth_m
            } else {
                self.tread_m
            };
            let height = self.rise_m * f64::from(i);
            features.push(Feature::flat(
                format!("flight_up_{i}"),
                x,
                x + depth,
                height,
            ));
            x += depth;
        }
        for i in (1..self.count).rev() {
            let height = self.rise_m * f64::from(i);
            let name = format!("flight_down_{i}");
            features.push(Feature::flat(name, x, x + self.tread_m, height));
            x += self.tread_m;
        }
        placed(features, self.behind)
    }
}

impl Ramp {
    /// Rise of the ramp, m.
    pub fn rise_m(&self) -> f64 {
        self.length_m * self.angle_deg.to_radians().sin()
    }

    /// Run of the ramp along x, m.
    pub fn run_m(&self) -> f64 {
        self.length_m * self.angle_deg.to_radians().cos()
    }

    fn features(&self, name: &str) -> Vec<Feature> {
        let (rise, run) = (self.rise_m(), self.run_m());
        let top = self.start_x_m + run;
        let down = top + self.top_depth_m;
        let features = vec![
            Feature {
                name: format!("{name}_up"),
                x_m: [self.start_x_m, top],
                height_m: [0.0, rise],
            },
            Feature::flat(format!("{name}_top"), top, down, rise),
            Feature {
                name: format!("{name}_down"),
                x_m: [down, down + run],
                height_m: [rise, 0.0],
            },
        ];
        placed(features, self.behind)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_profile_follows_the_obstacles() {
        let step = Scene::Step(Step::DEFAULT);
        assert_eq!(step.ground_height_m(0.5), 0.0);
        assert_eq!(step.ground_height_m(1.5), 0.06);
        assert_eq!(step.ground_height_m(2.3), 0.0);
        let flight = Scene::Flight(Flight::DEFAULT);
        assert_eq!(flight.ground_height_m(1.3), 0.06);
        assert_eq!(flight.ground_height_m(2.0), 0.12);
        assert_eq!(flight.ground_height_m(3.0), 0.06);
        assert_eq!(flight.ground_height_m(3.5), 0.0);
        let ramp = Ramp::DEFAULT;
        let scene = Scene::Ramp(ramp);
        let mid = ramp.start_x_m + ramp.run_m() / 2.0;
        assert!((scene.ground_height_m(mid) - ramp.rise_m() / 2.0).abs() < 1e-12);
        assert!((ramp.rise_m() - 1.5 * 10f64.to_radians().sin()).abs() < 1e-12);
    }

    #[test]
    fn behind_the_robot_the_ground_is_mirrored() {
        let ahead = Scene::Ramp(Ramp::DEFAULT);
        let behind = Scene::Ramp(Ramp {
            behind: true,
            ..Ramp::DEFAULT
        });
        for x in [0.5, 1.3, 2.2, 3.0, 4.1, 5.0] {
            let (back, front) = (behind.ground_height_m(-x), ahead.ground_height_m(x));
            assert!(
                (back - front).abs() < 1e-12,
                "at {x} m: {back} against {front}"
            );
            assert_eq!(behind.ground_height_m(x), 0.0);
        }
    }

    #[test]
    fn the_course_has_its_step_then_its_ramp() {
        let course = Scene::Course(Course::DEFAULT);
        let names: Vec<_> = course.features().into_iter().map(|f| f.name).collect();
        assert_eq!(names, ["step", "ramp_up", "ramp_top", "ramp_down"]);
        assert_eq!(course.ground_height_m(1.5), 0.06);
        assert_eq!(course.ground_height_m(3.0), 0.0);
    }
}
