//! The stall and runaway detector in the closed loop (`firmware::wheels::runaway`): driving W
//! into a step the wheels cannot climb raises a stall fault and sets the robot down against
//! the step, and nothing runs away — on the robot as drawn, and in seeded randomized trials
//! over the campaign's robots as built and the distance to the step.
//!
//! `cargo test -p sim-host --test stall -- --nocapture` prints the figures. Lockstep is
//! deterministic, so they repeat exactly.

use std::path::Path;

use firmware::control::fsm::State;
use host_can::fault_plan::Faults;
use protocol::{FaultFlags, TeleopMode};
use sim_host::campaign::draw::{Draw, Draws};
use sim_host::campaign::Drives;
use sim_host::faults::rig::{Rig, PERIOD_US};
use sim_host::robot::model::DEFAULT_MODEL;
use sim_host::robot::plant::Plant;
use sim_host::scene::{mjcf, Scene, Step};
use sim_host::session::simulator::StartPose;
use teleop_core::scripted::PlanStep;

/// The obstacle scene: a 6 cm step whose riser stands at x = 1.5 m.
const OBSTACLES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/models/obstacles.xml");

/// What driving into the step did, from the first contact with it.
#[derive(Debug, Default)]
struct Figures {
    /// First contact of any part of the robot with the step, s, and the torso's x then, m.
    contact: Option<(f64, f64)>,
    /// Ground speed at the contact, m/s.
    speed_at_contact_m_s: f64,
    /// From the contact to the first cycle reporting `Fault`, s, and the fault flags then.
    fault_after_s: Option<(f64, FaultFlags)>,
    /// From the contact to the last cycle the torso moved faster than 2 cm/s, s.
    moving_until_s: f64,
    /// Torso x range from the contact to the end, m.
    x_range_m: [f64; 2],
    /// Largest tilt from the contact on, degrees.
    max_tilt_deg: f64,
    /// Whether the robot fell (tilt past 45° or the torso on the ground).
    fell: bool,
    /// Whether the controller left `Fault` without the operator.
    left_fault: bool,
}

fn drive_into_the_step(end_s: f64) -> Figures {
    let plan = vec![
        PlanStep::at(0.0, TeleopMode::Fold),
        PlanStep::at(1.5, TeleopMode::WheelForward),
    ];
    drive(Path::new(OBSTACLES), plan, Plant::default(), end_s)
}

/// Runs `plan` on `plant` in the scene `model` until `end_s`, from the first touch of the step.
fn drive(model: &Path, plan: Vec<PlanStep>, plant: Plant, end_s: f64) -> Figures {
    drive_from(model, plan, (plant, StartPose::standing()), end_s)
}

/// As [`drive`], the robot starting at `start` (turned to a heading).
fn drive_from(
    model: &Path,
    plan: Vec<PlanStep>,
    (plant, start): (Plant, StartPose),
    end_s: f64,
) -> Figures {
    let faults = Faults::default();
    let mut rig = Rig::with_start(model, plan, (&faults, &faults), plant, start).unwrap();
    let mut f = Figures::default();
    let end_us = (end_s * 1e6).round() as u64;
    while rig.stats().cycles * PERIOD_US < end_us {
        rig.step().unwrap();
        let t = (rig.stats().cycles * PERIOD_US) as f64 * 1e-6;
        let record = rig.records().last().unwrap().clone();
        let torso = rig.sim().physics().torso();
        let x = torso.pos_m[0];
        let speed = torso.vel_m_s[0].hypot(torso.vel_m_s[1]);
        let Some((contact_s, _)) = f.contact else {
            if rig.sim().physics().touches_geom("step") {
                f.contact = Some((t, x));
                f.speed_at_contact_m_s = speed;
                f.x_range_m = [x, x];
            }
            continue;
        };
        f.x_range_m = [f.x_range_m[0].min(x), f.x_range_m[1].max(x)];
        f.max_tilt_deg = f.max_tilt_deg.max(record.tilt_deg);
        f.fell |= record.fallen();
        if speed > 0.02 {
            f.moving_until_s = t - contact_s;
        }
        let faulted = record.state == Some(State::Fault);
        match f.fault_after_s {
            None if faulted => f.fault_after_s = Some((t - contact_s, record.faults)),
            Some(_) => f.left_fault |= !faulted,
            None => {}
        }
    }
    f
}

/// The acceptance: a stall fault within 0.5 s of the first touch of the step, the robot
/// within 0.5 m of where it met the step ever after (no runaway), no fall, and `Fault` held.
fn assert_stopped(f: &Figures) {
    let (_, contact_x) = f.contact.expect("never reached the step");
    let (fault_s, flags) = f.fault_after_s.expect("no fault");
    assert!(fault_s <= 0.5, "{f:#?}");
    assert!(flags.contains(FaultFlags::WHEEL_STALL), "{f:#?}");
    assert!(!f.left_fault, "{f:#?}");
    let [low, high] = f.x_range_m;
    assert!(contact_x - low <= 0.5 && high - contact_x <= 0.5, "{f:#?}");
    assert!(!f.fell, "{f:#?}");
}

#[test]
fn driving_into_a_step_the_wheels_cannot_climb_stops_with_a_stall_fault() {
    let f = drive_into_the_step(12.0);
    println!("MEASURED W into the 6 cm step: {f:#?}");
    assert!(f.speed_at_contact_m_s > 0.4, "not at speed: {f:#?}");
    assert_stopped(&f);
}

/// Drives W, after the fold, into a 6 cm step `riser_x_m` ahead on `plant`, named `name`.
fn drive_w_into_step(name: &str, plant: Plant, riser_x_m: f64) -> Figures {
    drive_w_into_step_at(name, (plant, StartPose::standing()), riser_x_m)
}

/// As [`drive_w_into_step`], the robot starting at `start` (turned to a heading).
fn drive_w_into_step_at(name: &str, (plant, start): (Plant, StartPose), riser_x_m: f64) -> Figures {
    let scene = Scene::Step(Step {
        height_m: 0.06,
        riser_x_m,
        depth_m: 1.2,
        behind: false,
    });
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("stall")
        .join(name);
    let model = mjcf::write(&scene, Path::new(DEFAULT_MODEL), &dir).unwrap();
    let plan = vec![
        PlanStep::at(0.0, TeleopMode::Fold),
        PlanStep::at(4.0, TeleopMode::WheelForward),
    ];
    drive_from(&model, plan, (plant, start), 4.0 + riser_x_m / 0.3 + 3.0)
}

/// The robot as drawn at the distances where it reached the step still catching up with its
/// reference (0.8 and 1.0 m: 0.62 m/s against 0.48) or at speed (2.5 m), which a thrown-back
/// robot once turned into a runaway 0.8–1.1 m long; then seeded trials: the campaign's robot of
/// each seed (drives rated) with the step 1.3–3.0 m ahead (at 1.0 m some robots' folds end
/// against it).
#[test]
fn on_robots_as_built_and_at_any_distance_a_step_stops_the_wheels_with_a_stall_fault() {
    for riser_x_m in [0.8, 1.0, 2.5] {
        let f = drive_w_into_step(&format!("drawn-{riser_x_m}"), Plant::default(), riser_x_m);
        println!("MEASURED robot as drawn, step at {riser_x_m:.2} m: {f:?}");
        assert_stopped(&f);
    }
    const TRIALS: u64 = 12;
    for seed in 0..TRIALS {
        let riser_x_m = 1.3 + 1.7 * Draw::new(seed ^ 0x57a1_1000).unit();
        let plant = Draws::of(seed).plant(Drives::Rated.ratings());
        let f = drive_w_into_step(&seed.to_string(), plant, riser_x_m);
        println!("MEASURED seed {seed}, step at {riser_x_m:.2} m: {f:?}");
        assert_stopped(&f);
    }
}

/// Met at an angle, one wheel reaches the riser first and stops while the other rolls on.
/// Seeded trials: the campaign's robots as built, the step 1.3–3.0 m ahead, met at 5–15°
/// either way; each stops within the same acceptance as the square-on trials. This test passes
/// with the detector reading the axle alone too: forward, the folded front shanks meet the
/// riser with the wheels and the axle stops hard. (Backing into a riser in the autonomous
/// mode, it is the lagging wheel the detector reads that starts the climb at once: see
/// `tests/climb.rs`.)
#[test]
fn met_at_an_angle_a_step_stops_the_wheels_with_a_stall_fault() {
    const TRIALS: u64 = 12;
    let mut worst_s = 0.0_f64;
    for seed in 0..TRIALS {
        let mut draw = Draw::new(seed ^ 0x57a1_2000);
        let riser_x_m = 1.3 + 1.7 * draw.unit();
        let side = if draw.unit() < 0.5 { -1.0 } else { 1.0 };
        let heading_deg = side * (5.0 + 10.0 * draw.unit());
        let plant = Draws::of(seed).plant(Drives::Rated.ratings());
        let start = StartPose::standing().turned(heading_deg.to_radians());
        let f = drive_w_into_step_at(&format!("turned-{seed}"), (plant, start), riser_x_m);
        println!("MEASURED seed {seed}, step at {riser_x_m:.2} m, {heading_deg:.1}°: {f:?}");
        assert_stopped(&f);
        worst_s = worst_s.max(f.fault_after_s.map_or(f64::INFINITY, |(s, _)| s));
    }
    println!("MEASURED at an angle: the slowest stall fault {worst_s:.3} s after the contact");
}
