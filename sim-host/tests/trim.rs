//! A robot built off its drawing: the torso's centre of mass moved. Balancing at rest on its
//! wheels, the controller learns where its balance point is (`Balance::pitch_trim_rad`) and
//! the robot does not drift away.
//!
//! `cargo test -p sim-host --test trim -- --nocapture` prints the figures.

use std::path::Path;

use firmware::control::fsm::{State, WheelMotion};
use host_can::fault_plan::Faults;
use protocol::TeleopMode;
use sim_host::faults::rig::{Rig, PERIOD_US};
use sim_host::robot::model::DEFAULT_MODEL;
use sim_host::robot::plant::Plant;
use sim_host::robot::variation::Variation;
use teleop_core::scripted::PlanStep;

/// What resting on the wheels did, for one centre-of-mass offset.
#[derive(Debug)]
struct Figures {
    /// Torso centre-of-mass offset forward, m.
    offset_m: f64,
    /// Torso x range over the 30 s after settling, m.
    drift_m: f64,
    /// The controller's learned trim at the end, degrees.
    trim_deg: f32,
    /// The torso's pitch at the end, degrees, positive nose down (as the trim).
    pitch_deg: f64,
    /// Whether the controller balanced at rest from the settling time on.
    balancing: bool,
}

/// Folds, waits `settle_s`, then rests 30 s, the torso's centre of mass `offset_m` forward.
fn rest(offset_m: f64, settle_s: f64) -> Figures {
    let plant = Plant {
        variation: Variation {
            torso_com_offset_m: [offset_m, 0.0, 0.0],
            ..Variation::NOMINAL
        },
        ..Plant::default()
    };
    rest_on(plant, offset_m, settle_s)
}

/// Folds `plant`'s robot, waits `settle_s`, then rests 30 s.
fn rest_on(plant: Plant, offset_m: f64, settle_s: f64) -> Figures {
    let plan = vec![PlanStep::at(0.0, TeleopMode::Fold)];
    let (faults, model) = (Faults::default(), Path::new(DEFAULT_MODEL));
    let mut rig = Rig::with_plant(model, plan, &faults, &faults, plant).unwrap();
    rig.run_until(settle_s).unwrap();
    let x0 = rig.sim().physics().torso().pos_m[0];
    let (mut low, mut high, mut balancing) = (x0, x0, true);
    let end_us = ((settle_s + 30.0) * 1e6) as u64;
    while rig.stats().cycles * PERIOD_US < end_us {
        rig.step().unwrap();
        let x = rig.sim().physics().torso().pos_m[0];
        (low, high) = (low.min(x), high.max(x));
        let state = rig.records().last().unwrap().state;
        balancing &= state == Some(State::Wheels(WheelMotion::Balance));
    }
    let controller = rig.controller().unwrap().node().controller();
    Figures {
        offset_m,
        drift_m: high - low,
        trim_deg: controller.balance().pitch_trim_rad().to_degrees(),
        pitch_deg: rig.sim().physics().torso().rpy_rad()[1].to_degrees(),
        balancing,
    }
}

#[test]
fn a_centre_of_mass_off_the_drawing_is_learned_and_the_robot_stays_put() {
    // ±3 cm, the acceptance's range.
    for offset_m in [-0.03, -0.02, -0.01, 0.0, 0.015, 0.03] {
        let f = rest(offset_m, 10.0);
        println!("MEASURED resting with the torso's centre of mass off: {f:?}");
        assert!(f.balancing, "{f:?}");
        assert!(f.drift_m < 0.05, "{f:?}");
        // The trim is where the robot balances (within the chip's accelerometer offset), and
        // it moves against the centre of mass: behind, the body leans forward.
        assert!((f64::from(f.trim_deg) - f.pitch_deg).abs() < 1.5, "{f:?}");
        let nominal_deg = f64::from(firmware::config::Config::ROBOT.balance.pitch_trim_rad);
        let moved_deg = f64::from(f.trim_deg) - nominal_deg.to_degrees();
        if f.offset_m != 0.0 {
            assert!(
                moved_deg * f.offset_m < 0.0 && moved_deg.abs() > 2.0,
                "{f:?}"
            );
        }
    }
}

#[test]
fn an_imu_mounted_5_degrees_off_is_learned_and_the_robot_stays_put() {
    for mount_deg in [-5.0_f64, 5.0] {
        let mut plant = Plant::default();
        plant.imu_noise.mount_pitch_rad = mount_deg.to_radians();
        let f = rest_on(plant, 0.0, 10.0);
        println!("MEASURED resting with the IMU mounted {mount_deg:+}° in pitch: {f:?}");
        assert!(f.balancing, "{f:?}");
        assert!(f.drift_m < 0.05, "{f:?}");
    }
}
