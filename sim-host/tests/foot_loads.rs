//! The feet's loads as the firmware can know them (`firmware::legs::crawl::foot_loads_n`: each
//! leg's measured angles and the hip and knee torques its drive reports, with the drive's
//! gain error), against the contact forces MuJoCo computes, on robots standing.
//!
//! `cargo test --release -p sim-host --test foot_loads -- --nocapture` prints the figures.

use std::path::Path;

use firmware::legs::crawl::foot_loads_n;
use firmware::legs::kinematics::LegGeometry;
use host_can::fault_plan::Faults;
use protocol::{Joints, Leg, TeleopMode};
use sim_host::campaign::draw::Draws;
use sim_host::campaign::Drives;
use sim_host::faults::rig::Rig;
use sim_host::robot::model::DEFAULT_MODEL;
use sim_host::robot::plant::Plant;
use teleop_core::scripted::PlanStep;

/// Each foot's estimated and simulated load, N, after `until_s` of `plan` on `plant`.
fn loads(plant: Plant, plan: Vec<PlanStep>, until_s: f64) -> [(f32, f32); 4] {
    let sensing = plant.sensing;
    let faults = Faults::default();
    let mut rig = Rig::with_plant(Path::new(DEFAULT_MODEL), plan, &faults, &faults, plant).unwrap();
    rig.run_until(until_s).unwrap();
    let physics = rig.sim().physics();
    let angles = physics.leg_positions_rad().map(|a| a as f32);
    let true_nm = physics.leg_efforts_nm();
    // As the drives report them: each drive's joints with their own gain error.
    let mut reported_nm = Joints::splat(0.0_f32);
    for (index, leg) in Leg::ALL.into_iter().enumerate() {
        let gains: [f64; 4] = sensing.effort_gains(index as u64);
        let efforts = true_nm.leg(leg);
        *reported_nm.leg_mut(leg) = std::array::from_fn(|i| (efforts[i] * gains[i]) as f32);
    }
    let estimated = foot_loads_n(&LegGeometry::ROBOT, &angles, &reported_nm);
    let simulated = physics.foot_forces_n();
    std::array::from_fn(|i| {
        let leg = Leg::ALL[i];
        (estimated.get(leg).unwrap_or(f32::NAN), simulated[i] as f32)
    })
}

#[test]
fn standing_robots_read_each_foots_load_within_6_percent_of_their_weight() {
    let plan = vec![PlanStep::at(0.0, TeleopMode::Stand)];
    let mut plants = vec![("as drawn".to_string(), Plant::default())];
    for seed in 0..6 {
        plants.push((
            format!("seed {seed}"),
            Draws::of(seed).plant(Drives::Rated.ratings()),
        ));
    }
    for (name, plant) in plants {
        let feet = loads(plant, plan.clone(), 3.0);
        let weight_n: f32 = feet.iter().map(|(_, simulated)| simulated).sum();
        println!("MEASURED {name}: (estimated, simulated) N {feet:.0?}");
        for (estimated, simulated) in feet {
            assert!(
                (estimated - simulated).abs() < 0.06 * weight_n,
                "{name}: {feet:?}"
            );
        }
    }
}
