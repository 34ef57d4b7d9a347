//! The model on its own (no bus, no controller): does the report's robot, with its physics
//! fixed, stand on its legs and tip over on its wheels?

use std::path::Path;

use protocol::Leg;
use sim_host::robot::leg_drive::SERVO_KP_NM_RAD;
use sim_host::robot::model::{ModelError, DEFAULT_MODEL, OBSTACLES_MODEL};
use sim_host::robot::physics::Physics;
use sim_host::session::simulator::StartPose;

const STEPS_PER_S: usize = 250;

fn physics() -> Physics {
    Physics::load(Path::new(DEFAULT_MODEL)).expect("the shipped model loads")
}

#[test]
fn the_model_keeps_the_reports_timestep_and_mass() {
    let p = physics();
    assert_eq!(p.timestep_s(), 0.004);
    let layout = p.layout();
    assert_eq!(
        layout.leg_group,
        [1, 2, 3, 4],
        "one actuator group per leg drive"
    );
}

#[test]
fn dropped_with_legs_extended_it_settles_standing_within_2_s() {
    let mut p = physics();
    let start = StartPose::standing();
    // Dropped from 3 cm above the ground, the leg drives' position loops holding the pose (the
    // model's leg actuators are torque motors).
    p.place(start.height_m + 0.03, &start.leg_joint_rad, 0.0);
    let mut heights = Vec::new();
    for _ in 0..2 * STEPS_PER_S {
        let angles = p.leg_positions_rad();
        for leg in Leg::ALL {
            let (now, goal) = (angles.leg(leg), start.leg_joint_rad.leg(leg));
            let torques = std::array::from_fn(|i| SERVO_KP_NM_RAD[i] * (goal[i] - now[i]));
            p.set_leg_torques(leg, &torques);
            p.set_leg_enabled(leg as usize, true);
        }
        p.step();
        assert!(p.is_finite(), "NaN at t = {}", p.time_s());
        heights.push(p.torso().pos_m[2]);
    }
    let torso = p.torso();
    let [roll, pitch, _] = torso.rpy_rad().map(f64::to_degrees);
    let nominal = start.height_m;
    // Settled: the last 0.5 s stays inside a 5 mm band, 0…2 cm below the nominal stance height
    // (the servos sag under the 33 kg torso).
    let last = &heights[heights.len() - STEPS_PER_S / 2..];
    let (lo, hi) = last
        .iter()
        .fold((f64::MAX, f64::MIN), |(lo, hi), h| (lo.min(*h), hi.max(*h)));
    assert!(hi - lo < 0.005, "still moving: {lo:.4}…{hi:.4} m");
    assert!(
        (nominal - 0.02..=nominal).contains(&torso.pos_m[2]),
        "torso at {:.4} m, nominal stance {nominal:.4} m",
        torso.pos_m[2]
    );
    assert!(
        roll.abs() < 2.0 && pitch.abs() < 2.0,
        "roll {roll:.2}°, pitch {pitch:.2}°"
    );
    let contacts = p.ground_contacts();
    assert_eq!(contacts.feet, [true; 4], "{contacts:?}");
    assert_eq!(contacts.wheels, [false; 2], "{contacts:?}");
    assert!(!contacts.other, "{contacts:?}");
    let load: f64 = p.foot_forces_n().iter().sum();
    assert!(load > 300.0, "the feet carry the robot: {load:.0} N");
}

#[test]
fn folded_on_free_wheels_it_tips_over() {
    let mut p = physics();
    let levelling = firmware::config::Config::ROBOT.levelling;
    let fold = levelling.family.pose(levelling.start_shift);
    let legs = protocol::Joints::from_leg_fn(|leg| fold.leg(leg).map(f64::from));
    // Wheels (r 0.12 at z −0.15) just on the ground, torso level, wheels unpowered.
    p.place(0.12 + 0.15 + 0.001, &legs, 0.0);
    let mut max_tilt_deg: f64 = 0.0;
    let mut touched_down = false;
    for _ in 0..2 * STEPS_PER_S {
        p.set_wheel_torques([0.0; 2]);
        p.step();
        assert!(p.is_finite());
        max_tilt_deg = max_tilt_deg.max(p.torso().tilt_rad().to_degrees());
        let c = p.ground_contacts();
        touched_down |= c.other || c.feet.iter().any(|f| *f);
    }
    assert!(max_tilt_deg > 10.0, "tilted only {max_tilt_deg:.1}°");
    assert!(
        touched_down,
        "no part besides the wheels reached the ground"
    );
}

#[test]
fn the_obstacle_scene_has_the_robot_a_step_and_a_ramp() {
    let p = Physics::load(Path::new(OBSTACLES_MODEL)).expect("the obstacle scene loads");
    assert_eq!(p.timestep_s(), 0.004);
    let ids = sim_host::robot::model::obstacle_ids(&p).expect("step and ramp geoms");
    assert_eq!(ids.len(), 2);
}

#[test]
fn a_broken_model_file_is_an_error_naming_the_file_and_line() {
    let dir = std::env::temp_dir().join(format!("sim-host-model-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("broken.xml");
    std::fs::write(
        &bad,
        "<mujoco>\n  <worldbody>\n    <body><geom type=\"sphere\"/>\n</mujoco>\n",
    )
    .unwrap();
    let err = Physics::load(&bad).unwrap_err();
    let text = err.to_string();
    assert!(matches!(err, ModelError::Load { .. }), "{err:?}");
    assert!(text.contains("broken.xml"), "{text}");
    assert!(text.to_lowercase().contains("line"), "{text}");

    let missing = dir.join("no_robot.xml");
    std::fs::write(
        &missing,
        "<mujoco><worldbody><geom type=\"plane\" size=\"1 1 0.1\"/></worldbody></mujoco>",
    )
    .unwrap();
    let err = Physics::load(&missing).unwrap_err();
    assert!(matches!(err, ModelError::Missing { .. }), "{err:?}");
    assert!(err.to_string().contains("no_robot.xml"), "{err}");
}

#[test]
fn a_sensor_with_the_wrong_size_or_a_joint_without_range_is_named() {
    let dir = std::env::temp_dir().join(format!("sim-host-model-sizes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let robot = std::fs::read_to_string(sim_host::robot::model::DEFAULT_MODEL).unwrap();
    // The IMU's orientation as a 3-value sensor: the hardware reads 4 (a quaternion).
    let three = robot.replace(
        r#"<framequat name="imu_quat" objtype="site" objname="imu"/>"#,
        r#"<framepos name="imu_quat" objtype="site" objname="imu"/>"#,
    );
    assert_ne!(three, robot, "the model's IMU quaternion sensor moved");
    let path = dir.join("imu_quat_3.xml");
    std::fs::write(&path, three).unwrap();
    let err = Physics::load(&path).unwrap_err();
    assert!(
        matches!(&err, ModelError::SensorSize { name, expected: 4, found: 3, .. } if name == "imu_quat"),
        "{err:?}"
    );
    assert!(err.to_string().contains("imu_quat_3.xml"), "{err}");
    // A leg joint without its range: its drive could not enforce one.
    let unlimited = robot.replacen(r#"range="-110 15""#, "", 1);
    assert_ne!(unlimited, robot, "the model's knee range moved");
    let path = dir.join("no_knee_range.xml");
    std::fs::write(&path, unlimited).unwrap();
    let err = Physics::load(&path).unwrap_err();
    assert!(matches!(err, ModelError::JointRange { .. }), "{err:?}");
    assert!(err.to_string().contains("knee"), "{err}");
}
