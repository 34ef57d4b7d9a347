//! The rangefinder node: what its `Range` frames say of the ground behind the torso, against
//! the geometry of the beam — the VL53L1X's figures on level ground, a riser in the beam, and
//! nothing within its 1.3 m.

use std::path::Path;

use protocol::{AnyMessage, Range, RangeStatus};
use sim_host::robot::model::DEFAULT_MODEL;
use sim_host::robot::physics::Physics;
use sim_host::robot::rangefinder::{RangeModel, RangeNode, RangeSpec};
use sim_host::scene::{mjcf, Scene, Step};

/// The beam leaves the rear face 0.06 m below the torso's centre, 25° down.
const MOUNT_DROP_M: f64 = 0.06;
const DEPRESSION_DEG: f64 = 25.0;

/// The model at rest as loaded: the torso level, its centre 0.40 m up.
fn physics(scene: &Scene, name: &str) -> Physics {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("rangefinder")
        .join(name);
    let model = mjcf::write(scene, Path::new(DEFAULT_MODEL), &dir).unwrap();
    let mut physics = Physics::load(&model).unwrap();
    physics.step();
    physics
}

/// One ranging of `node` over five control cycles of the physics as it is.
fn ranging(node: &mut RangeNode, physics: &Physics) -> Range {
    for _ in 0..5 {
        node.observe(physics);
    }
    match node.ranging(physics) {
        AnyMessage::Range(range) => range,
        other => panic!("a rangefinder sent {other:?}"),
    }
}

/// The distance along the beam to level ground from the torso as it stands, m.
fn to_level_ground_m(physics: &Physics) -> f64 {
    let height_m = physics.torso().pos_m[2] - MOUNT_DROP_M;
    height_m / DEPRESSION_DEG.to_radians().sin()
}

#[test]
fn ten_parts_range_level_ground_within_the_data_sheets_error() {
    let physics = physics(&Scene::Flat, "flat");
    let expected_m = to_level_ground_m(&physics);
    for seed in 0..10 {
        let model = RangeModel::Part {
            spec: RangeSpec::VL53L1X,
            seed,
        };
        let mut node = RangeNode::new(model, protocol::TEST_KEY);
        let errors_m: Vec<f64> = (0..20)
            .map(|_| {
                let range = ranging(&mut node, &physics);
                assert_eq!(range.status, RangeStatus::Valid);
                f64::from(range.distance.si()) - expected_m
            })
            .collect();
        for error_m in &errors_m {
            assert!(
                error_m.abs() <= 0.025,
                "part {seed}: {error_m:.3} m off {expected_m:.3} m"
            );
        }
        // Each ranging has the part's own noise (1σ 5 mm), not only its fixed offset.
        let mean_m = errors_m.iter().sum::<f64>() / 20.0;
        let std_m = (errors_m.iter().map(|e| (e - mean_m).powi(2)).sum::<f64>() / 19.0).sqrt();
        assert!(
            (0.0025..0.009).contains(&std_m),
            "part {seed}: noise 1σ {std_m:.4} m"
        );
    }
    let mut ideal = RangeNode::new(RangeModel::Ideal, protocol::TEST_KEY);
    let exact_m = f64::from(ranging(&mut ideal, &physics).distance.si());
    assert!(
        (exact_m - expected_m).abs() < 0.002,
        "{exact_m} against {expected_m}"
    );
}

#[test]
fn a_riser_in_the_beam_shortens_the_ranging_by_its_geometry() {
    let flat = physics(&Scene::Flat, "level");
    let level_m = to_level_ground_m(&flat);
    // Where the beam meets level ground, measured from the torso's centre.
    let behind_m = 0.30 + level_m * DEPRESSION_DEG.to_radians().cos();
    let riser = Scene::Step(Step {
        height_m: 0.10,
        riser_x_m: behind_m - 0.3,
        depth_m: 1.0,
        behind: true,
    });
    let physics = physics(&riser, "riser");
    let mut node = RangeNode::new(RangeModel::Ideal, protocol::TEST_KEY);
    let on_plateau_m = f64::from(ranging(&mut node, &physics).distance.si());
    let expected_m =
        (flat.torso().pos_m[2] - MOUNT_DROP_M - 0.10) / DEPRESSION_DEG.to_radians().sin();
    assert!(
        (on_plateau_m - expected_m).abs() < 0.002,
        "{on_plateau_m:.3} m on a 10 cm plateau, expected {expected_m:.3} m"
    );
}

#[test]
fn nothing_within_range_is_a_signal_fail() {
    // A part that ranges half a metre, the ground 0.8 m along the beam.
    let physics = physics(&Scene::Flat, "short");
    assert!(to_level_ground_m(&physics) > 0.6);
    let spec = RangeSpec {
        max_range_m: 0.5,
        ..RangeSpec::VL53L1X
    };
    let model = RangeModel::Part { spec, seed: 1 };
    let mut node = RangeNode::new(model, protocol::TEST_KEY);
    let range = ranging(&mut node, &physics);
    assert_eq!(range.status, RangeStatus::SignalFail, "{range:?}");
}
