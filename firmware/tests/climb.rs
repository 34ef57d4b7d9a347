//! The climb's phases (`firmware::legs::climb`) on made-up drive readings: every foot carries as
//! soon as it is lowered onto something. With the body level throughout, the climb crawls over
//! and ends on the wheels; a body pitched past its limits ends it refused: nose down at the
//! probe (a riser the wheels started up), or either way once the legs have set it down (the
//! wheels did not reach the plateau).

use firmware::legs::climb::{Climb, ClimbConfig, ClimbEnd, ClimbInput, Phase};
use firmware::legs::crawl::frame::PerLeg;
use firmware::legs::kinematics::{LegGeometry, LegJoints};
use firmware::legs::levelling::FoldFamily;
use firmware::math::deg_to_rad;
use firmware::time::{Tick, TickRate};

const RATE: TickRate = TickRate::SIM_250_HZ;

/// Runs a climb from the fold, the body pitched `pitch_rad(phase)` (positive nose down), until
/// it ends (at most a minute); its end and the phases it went through.
fn climb(pitch_rad: impl Fn(Phase) -> f32) -> (Option<ClimbEnd>, Vec<Phase>) {
    let config = ClimbConfig::ROBOT;
    let fold = FoldFamily::ROBOT.pose(0.6);
    let measured = PerLeg::from_fn(|leg| LegJoints::from_array(*fold.leg(leg)));
    let mut climb = Climb::new(Tick(0), &LegGeometry::ROBOT, &measured);
    let mut phases = vec![climb.phase()];
    for t in 1..60 * 250 {
        let input = ClimbInput {
            loads_n: PerLeg::splat(Some(20.0)),
            lag_m: PerLeg::splat(0.02),
            pitch_rad: pitch_rad(climb.phase()),
        };
        climb.tick(&config, RATE, Tick(t), &input);
        if phases.last() != Some(&climb.phase()) {
            phases.push(climb.phase());
        }
        if let Phase::Ended(end) = climb.phase() {
            return (Some(end), phases);
        }
    }
    (None, phases)
}

#[test]
fn a_level_climb_crawls_over_and_ends_on_the_wheels() {
    let (end, phases) = climb(|_| 0.0);
    assert_eq!(end, Some(ClimbEnd::Over), "{phases:?}");
    assert!(phases.contains(&Phase::Rise), "{phases:?}");
    assert!(phases.contains(&Phase::Lower), "{phases:?}");
}

#[test]
fn a_body_pitched_past_its_limit_when_set_down_is_not_over_the_step() {
    let limit_rad = ClimbConfig::ROBOT.over_pitch_max_rad;
    for pitch_rad in [limit_rad + deg_to_rad(2.0), -limit_rad - deg_to_rad(2.0)] {
        let (end, phases) = climb(|phase| {
            if phase == Phase::Lower {
                pitch_rad
            } else {
                0.0
            }
        });
        assert_eq!(end, Some(ClimbEnd::NotOver), "{pitch_rad}: {phases:?}");
    }
    let (end, _) = climb(|phase| {
        if phase == Phase::Lower {
            0.8 * limit_rad
        } else {
            0.0
        }
    });
    assert_eq!(end, Some(ClimbEnd::Over));
}

#[test]
fn a_body_pitched_nose_down_at_the_probe_is_not_lifted() {
    let pitch_rad = ClimbConfig::ROBOT.pitch_max_rad + deg_to_rad(2.0);
    let (end, phases) = climb(|phase| {
        if phase == Phase::Probe {
            pitch_rad
        } else {
            0.0
        }
    });
    assert_eq!(end, Some(ClimbEnd::StepOutOfRange), "{phases:?}");
    assert!(phases.contains(&Phase::Retreat), "{phases:?}");
    assert!(!phases.contains(&Phase::Rise), "{phases:?}");
}
