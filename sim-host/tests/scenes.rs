//! Scenes made from parameters (`sim_host::scene`): the MJCF written for each loads with the
//! robot in it, and MuJoCo's own ground, probed by casting rays down onto it, is where the
//! scene's profile says (what tests and summaries judge crossings by).

mod common;

use std::path::{Path, PathBuf};

use mujoco_rs::prelude::{MjData, MjModel};
use sim_host::output::metrics::SegmentSummary;
use sim_host::robot::model::DEFAULT_MODEL;
use sim_host::robot::physics::Physics;
use sim_host::robot::plant::Plant;
use sim_host::scene::{mjcf, Scene};
use sim_host::session;

fn written(scene: &Scene, name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("scenes")
        .join(name);
    mjcf::write(scene, Path::new(DEFAULT_MODEL), &dir).unwrap()
}

/// Height of the first surface a ray cast straight down at (`x_m`, `y_m`) meets, m.
fn probed_height_m(data: &mut MjData<Box<MjModel>>, x_m: f64, y_m: f64) -> f64 {
    let (_, distance) = data.ray(&[x_m, y_m, 2.0], &[0.0, 0.0, -1.0], None, true, None, None);
    2.0 - distance
}

#[test]
fn every_scene_loads_and_its_ground_is_where_its_profile_says() {
    let scenes = [
        ("step", "step:height_m=0.08,riser_x_m=1.5,depth_m=1.0"),
        ("flight", "flight:rise_m=0.06,count=3"),
        ("ramp", "ramp:angle_deg=10"),
        ("course", "course"),
        ("flat", "flat"),
    ];
    for (name, arg) in scenes {
        let scene = Scene::from_arg(arg).unwrap();
        let path = written(&scene, name);
        // The robot's hardware finds every part it needs in the scene.
        Physics::load(&path).unwrap_or_else(|e| panic!("{arg}: {e}"));
        let model = MjModel::from_xml(&path).unwrap();
        let mut data = MjData::new(Box::new(model));
        data.forward();
        let edges: Vec<f64> = scene.features().iter().flat_map(|f| f.x_m).collect();
        let mut worst_m: f64 = 0.0;
        for i in 0..=160 {
            let x_m = 0.5 + f64::from(i) * 0.05;
            if edges.iter().any(|e| (e - x_m).abs() < 0.01) {
                continue;
            }
            // Beside the robot's path (it stands at x = 0, 0.6 m long), on every obstacle.
            for y_m in [-1.0, 0.0, 1.0] {
                let error = probed_height_m(&mut data, x_m, y_m) - scene.ground_height_m(x_m);
                worst_m = worst_m.max(error.abs());
            }
        }
        println!("MEASURED scene {arg}: ground off its profile by at most {worst_m:.2e} m");
        assert!(worst_m < 1e-3, "{arg}: {worst_m} m");
    }
}

#[test]
fn a_scenario_names_its_scene_and_sim_host_builds_it() {
    let file = "duration_s = 4\n[[step]]\nat_s = 0\nmode = \"fold\"\n[scene]\nkind = \"flight\"\ncount = 2\n";
    let path = Path::new("flight.toml");
    // The operator's side reads the same file and ignores the scene.
    teleop_core::scenario::Scenario::parse(path, file).unwrap();
    let scene = Scene::from_scenario(path, file).unwrap().unwrap();
    assert_eq!(scene.kind(), "flight");
    assert_eq!(scene.ground_height_m(2.0), 0.12);
}

/// The robot as drawn stands, then trots (L at 1 s) for `duration_s` in the scene `arg`
/// (written under `name`): the two segments' figures.
fn stand_and_trot(arg: &str, name: &str, duration_s: f64) -> [SegmentSummary; 2] {
    let scene = Scene::from_arg(arg).unwrap();
    let (plan, segments) = common::plan(&[(0.0, "stand"), (1.0, "L")]);
    let mut config = common::config(Plant::default(), plan, segments, duration_s);
    config.model = written(&scene, name);
    config.scene = scene;
    let report = session::run(&config).unwrap();
    let count = report.segments.len();
    report
        .segments
        .try_into()
        .unwrap_or_else(|_| panic!("{count} segments"))
}

#[test]
fn the_summary_names_the_parts_of_the_robot_that_touched_an_obstacle() {
    let [stand, trot] = stand_and_trot("step:height_m=0.10,riser_x_m=0.6", "summary", 9.0);
    println!(
        "MEASURED contacts with the step while trotting: {:?}",
        trot.obstacle_contacts
    );
    // Stopped at the riser: no foot ever stood on the step.
    let [crossing] = &trot.crossings[..] else {
        panic!("{:?}", trot.crossings)
    };
    assert_eq!(crossing.obstacle, "step");
    assert_eq!((crossing.first_foot_on_s, crossing.past_s), (None, None));
    assert!(crossing.first_touch_s.is_some(), "{crossing:?}");
    assert!(
        stand.obstacle_contacts.is_empty(),
        "{:?}",
        stand.obstacle_contacts
    );
    // The front feet meet the riser; the floor is not an obstacle.
    let parts: Vec<&str> = trot
        .obstacle_contacts
        .iter()
        .map(|c| c.part.as_str())
        .collect();
    assert!(parts.iter().any(|p| p.starts_with("foot_f")), "{parts:?}");
    assert!(trot
        .obstacle_contacts
        .iter()
        .all(|c| c.obstacle == "step" && c.cycles > 0));
    assert!(!parts.iter().any(|p| p.starts_with("foot_b")), "{parts:?}");
}

/// A trot over a 1 cm step and off its far edge 1.2 m on: the summary says when the robot first
/// touched it, when the first foot stood on it, when all four did, when all four were past it,
/// and how long it took (from the feet's positions and the step's profile).
#[test]
fn the_summary_says_when_the_robot_stood_on_an_obstacle_and_when_it_was_past_it() {
    let [_, trot] = stand_and_trot("step:height_m=0.01,riser_x_m=0.8", "crossing", 30.0);
    let [crossing] = &trot.crossings[..] else {
        panic!("{:?}", trot.crossings)
    };
    println!("MEASURED a trot over a 1 cm step: {crossing:?}");
    let (Some(touch), Some(first), Some(all), Some(past), Some(took)) = (
        crossing.first_touch_s,
        crossing.first_foot_on_s,
        crossing.all_feet_on_s,
        crossing.past_s,
        crossing.crossing_s,
    ) else {
        panic!("not crossed: {crossing:?}")
    };
    assert!(touch <= first && first < all && all < past, "{crossing:?}");
    assert!((took - (past - touch)).abs() < 1e-9, "{crossing:?}");
    // The front feet stand 0.52 m from the riser: no foot is on the step at once.
    assert!(first > 2.0, "{crossing:?}");
}
