//! The climb's phases (`firmware::legs::climb`) on made-up drive readings: every foot carries as
//! soon as it is lowered onto something. With the body level throughout, the climb crawls over
//! and ends on the wheels; a body pitched past its limits ends it refused: nose down at the
//! probe (a riser the wheels started up), or either way once the legs have set it down (the
//! wheels did not reach the plateau), a step that reads too high partway up the rise (the
//! legs step down from it before they lift the body further), or a body that tips nose down
//! past the rise's limit.

use firmware::legs::climb::{Climb, ClimbConfig, ClimbEnd, ClimbInput, Phase};
use firmware::legs::crawl::frame::PerLeg;
use firmware::legs::kinematics::{LegGeometry, LegJoints};
use firmware::legs::levelling::FoldFamily;
use firmware::math::deg_to_rad;
use firmware::time::{Tick, TickRate};

const RATE: TickRate = TickRate::SIM_250_HZ;

/// The body pitched `pitch_rad` (positive nose down) in `phase`, level otherwise.
fn pitched_in(phase: Phase, pitch_rad: f32) -> impl Fn(Phase) -> f32 {
    move |now| if now == phase { pitch_rad } else { 0.0 }
}

/// Whether `phases` (with the tick each began) include `phase`.
fn went_through(phases: &[(Phase, u32)], phase: Phase) -> bool {
    phases.iter().any(|(p, _)| *p == phase)
}

/// Runs a climb from the fold, the body pitched `pitch_rad(phase)` (positive nose down), until
/// it ends (at most a minute); its end and the phases it went through, with the tick each
/// began.
fn climb(pitch_rad: impl Fn(Phase) -> f32) -> (Option<ClimbEnd>, Vec<(Phase, u32)>) {
    let config = ClimbConfig::ROBOT;
    let fold = FoldFamily::ROBOT.pose(0.6);
    let measured = PerLeg::from_fn(|leg| LegJoints::from_array(*fold.leg(leg)));
    let mut climb = Climb::new(Tick(0), &LegGeometry::ROBOT, &measured);
    let mut phases = vec![(climb.phase(), 0)];
    for t in 1..60 * 250 {
        let input = ClimbInput {
            loads_n: PerLeg::splat(Some(20.0)),
            lag_m: PerLeg::splat(0.02),
            pitch_rad: pitch_rad(climb.phase()),
        };
        climb.tick(&config, RATE, Tick(t), &input);
        if phases.last().map(|(p, _)| *p) != Some(climb.phase()) {
            phases.push((climb.phase(), t));
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
    assert!(went_through(&phases, Phase::Rise), "{phases:?}");
    assert!(went_through(&phases, Phase::Lower), "{phases:?}");
}

#[test]
fn a_body_pitched_past_its_limit_when_set_down_is_not_over_the_step() {
    let limit_rad = ClimbConfig::ROBOT.over_pitch_max_rad;
    for pitch_rad in [limit_rad + deg_to_rad(2.0), -limit_rad - deg_to_rad(2.0)] {
        let (end, phases) = climb(pitched_in(Phase::Lower, pitch_rad));
        assert_eq!(end, Some(ClimbEnd::NotOver), "{pitch_rad}: {phases:?}");
    }
    let (end, _) = climb(pitched_in(Phase::Lower, 0.8 * limit_rad));
    assert_eq!(end, Some(ClimbEnd::Over));
}

#[test]
fn a_body_pitched_nose_down_at_the_probe_is_not_lifted() {
    let pitch_rad = ClimbConfig::ROBOT.pitch_max_rad + deg_to_rad(2.0);
    let (end, phases) = climb(pitched_in(Phase::Probe, pitch_rad));
    assert_eq!(end, Some(ClimbEnd::StepOutOfRange), "{phases:?}");
    assert!(went_through(&phases, Phase::Retreat), "{phases:?}");
    assert!(!went_through(&phases, Phase::Rise), "{phases:?}");
}

/// A body pitching nose down as the legs lift it says the back feet stand on a step higher
/// than the crawl takes: the legs step down from it where the height is first judged, not at
/// the end of the rise (at 9–11 cm the rise's last third tipped robots over their front feet).
#[test]
fn a_step_that_reads_too_high_partway_up_the_rise_is_stepped_down_from_there() {
    let config = ClimbConfig::ROBOT;
    // Under the rise's own pitch limit (below), but over what a step the crawl takes gives.
    let pitch_rad = config.rise_pitch_max_rad - deg_to_rad(1.0);
    let (end, phases) = climb(pitched_in(Phase::Rise, pitch_rad));
    assert_eq!(end, Some(ClimbEnd::StepOutOfRange), "{phases:?}");
    let began =
        |phases: &[(Phase, u32)], phase| phases.iter().find(|(p, _)| *p == phase).map(|(_, t)| *t);
    let (Some(rise), Some(retreat)) = (began(&phases, Phase::Rise), began(&phases, Phase::Retreat))
    else {
        panic!("{phases:?}");
    };
    let checked = RATE.ticks_from_ms((config.rise_check_share * config.rise_ms as f32) as u32);
    assert!(
        (checked.saturating_sub(1)..=checked + 1).contains(&(retreat - rise)),
        "{phases:?}"
    );
    // Pitched nose up as far, the estimate reads lower: the rise goes on to its end.
    let (_, phases) = climb(pitched_in(Phase::Rise, -pitch_rad));
    let (Some(rise), Some(after)) = (
        began(&phases, Phase::Rise),
        phases
            .iter()
            .skip_while(|(p, _)| *p != Phase::Rise)
            .nth(1)
            .map(|(_, t)| *t),
    ) else {
        panic!("{phases:?}");
    };
    assert!(
        after - rise >= RATE.ticks_from_ms(config.rise_ms),
        "{phases:?}"
    );
    // Level, the same climb lifts all the way and crawls over.
    let (end, _) = climb(pitched_in(Phase::Rise, 0.0));
    assert_eq!(end, Some(ClimbEnd::Over));
}

/// A body tipping nose down over its front feet as the legs lift it is stepped down from at
/// once, not where the height is judged: one robot that met a 10.7 cm riser slowly was 21°
/// over by then and 40° as its legs went back.
#[test]
fn a_body_tipping_past_the_rise_limit_is_stepped_down_from_at_once() {
    let config = ClimbConfig::ROBOT;
    let (end, phases) = climb(pitched_in(
        Phase::Rise,
        config.rise_pitch_max_rad + deg_to_rad(1.0),
    ));
    assert_eq!(end, Some(ClimbEnd::StepOutOfRange), "{phases:?}");
    let began = |phase| phases.iter().find(|(p, _)| *p == phase).map(|(_, t)| *t);
    let (Some(rise), Some(retreat)) = (began(Phase::Rise), began(Phase::Retreat)) else {
        panic!("{phases:?}");
    };
    assert!(retreat - rise <= 1, "{phases:?}");
}
