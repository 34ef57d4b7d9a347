//! The moves between legs and wheels in place, in the closed loop in lockstep: the fold from
//! standing (alone, or as the start of W, S or A, or right after a trot) and standing up from
//! the wheels. What a user checks: the robot ends where it started (within 5 cm), it did not
//! lean past 8°, and it ends in the mode asked for.
//!
//! `cargo test -p sim-host --test transitions -- --nocapture` prints the figures.

use std::path::Path;

use firmware::control::fsm::{LegMotion, State};
use host_can::fault_plan::Faults;
use protocol::{FaultFlags, TeleopMode};
use sim_host::campaign::draw::Draws;
use sim_host::campaign::scenario::Scenario;
use sim_host::campaign::Drives;
use sim_host::faults::rig::Rig;
use sim_host::robot::model::DEFAULT_MODEL;
use sim_host::robot::plant::Plant;
use teleop_core::scripted::PlanStep;

/// One transition, from the key press that starts it until the robot is at rest after it (or,
/// when the mode drives on, until the transition ends).
#[derive(Debug)]
struct Figures {
    what: &'static str,
    /// Horizontal torso displacement from the key press, m.
    moved_m: f64,
    /// Largest tilt meanwhile, degrees.
    max_tilt_deg: f64,
    /// How long the transition took, s.
    took_s: f64,
    /// The state at the end.
    state: Option<State>,
}

/// Runs `before` (modes from 0 s), then presses `key` at `at_s`; measures until the robot's
/// transition (`Folding` or `Standing`) is over and, if `rest`, the torso has come to rest.
fn transition(
    what: &'static str,
    before: &[(f64, TeleopMode)],
    key: TeleopMode,
    at_s: f64,
) -> Figures {
    let mut plan: Vec<PlanStep> = before.iter().map(|&(t, m)| PlanStep::at(t, m)).collect();
    plan.push(PlanStep::at(at_s, key));
    let clean = Faults::default();
    let mut rig = Rig::new(Path::new(DEFAULT_MODEL), plan, &clean, &clean).unwrap();
    rig.run_until(at_s).unwrap();
    let start = rig.sim().physics().torso().pos_m;
    let drives_on = matches!(
        key,
        TeleopMode::WheelForward | TeleopMode::WheelBackward | TeleopMode::WheelRotate
    );
    let (mut max_tilt_deg, mut began, mut ended_s) = (0.0_f64, false, None);
    while rig.time_s() < at_s + 10.0 {
        rig.step().unwrap();
        let record = rig.records().last().unwrap();
        max_tilt_deg = max_tilt_deg.max(record.tilt_deg);
        let moving = matches!(record.state, Some(State::Folding(_) | State::Standing(_)));
        began |= moving;
        if began && !moving && ended_s.is_none() {
            ended_s = Some(rig.time_s() - at_s);
            if drives_on {
                break;
            }
        }
        let speed = rig.sim().physics().torso().vel_m_s;
        if ended_s.is_some() && speed[0].hypot(speed[1]) < 0.01 {
            break;
        }
    }
    let end = rig.sim().physics().torso().pos_m;
    Figures {
        what,
        moved_m: (end[0] - start[0]).hypot(end[1] - start[1]),
        max_tilt_deg,
        took_s: ended_s.unwrap_or(f64::NAN),
        state: rig.records().last().unwrap().state,
    }
}

/// The goal is 5 cm and 8° for every case. Every fold meets it; where a transition does not
/// yet (the stand-up's distance, documented in docs/firmware.md, "Folding in place"), the bound
/// is what it reaches, so that it does not get worse: `moved_m` and `tilt_deg`.
fn assert_in_place(f: &Figures, moved_m: f64, tilt_deg: f64) {
    println!("MEASURED {}: {f:?} (goal 0.05 m, 8°)", f.what);
    assert!(f.took_s.is_finite(), "never ended: {f:?}");
    let ended_in = matches!(f.state, Some(State::Wheels(_) | State::Legs(_)));
    assert!(ended_in, "ended in {:?}: {f:?}", f.state);
    assert!(f.moved_m <= moved_m, "moved: {f:?}");
    assert!(f.max_tilt_deg <= tilt_deg, "tilted: {f:?}");
}

const STAND: [(f64, TeleopMode); 2] = [(0.0, TeleopMode::Stop), (0.1, TeleopMode::Stand)];

#[test]
fn the_fold_from_standing_happens_in_place() {
    let f = transition("fold from standing", &STAND, TeleopMode::Fold, 1.5);
    assert_in_place(&f, 0.05, 8.0);
}

#[test]
fn w_s_and_a_from_standing_fold_in_place() {
    for (what, key) in [
        ("W from standing", TeleopMode::WheelForward),
        ("S from standing", TeleopMode::WheelBackward),
        ("A from standing", TeleopMode::WheelRotate),
    ] {
        assert_in_place(&transition(what, &STAND, key, 1.5), 0.05, 8.0);
    }
}

#[test]
fn the_fold_right_after_a_trot_happens_in_place() {
    for (what, trot, tilt_deg) in [
        ("fold right after L", TeleopMode::TrotForward, 8.0),
        ("fold right after K", TeleopMode::TrotBackward, 8.0),
    ] {
        let before = [(0.0, TeleopMode::Stop), (0.1, trot)];
        assert_in_place(
            &transition(what, &before, TeleopMode::Fold, 4.0),
            0.05,
            tilt_deg,
        );
    }
}

#[test]
fn standing_up_from_the_wheels_happens_in_place() {
    let before = [(0.0, TeleopMode::Stop), (0.1, TeleopMode::Fold)];
    let f = transition("stand-up from the wheels", &before, TeleopMode::Stand, 6.0);
    // The unfolding feet push the robot back; it first rolls ahead by about as much
    // (`control::controller::stand_up`), its distance counted by the balance law: 0.6 cm and
    // 5.7° (2.8 cm with the count dropped, 11.5 cm and 6.2° without the roll). Bound at 2 cm,
    // inside the goal's 5, so that neither gets lost unnoticed.
    assert_in_place(&f, 0.02, 8.0);
}

/// A stand-up asked while the robot drives: the brake stops it, and it stands up where it
/// stopped. The brake's lag behind the speed reference is no distance to make up: a law that
/// kept it rolled the robot 15–26 cm on from its stop by itself.
#[test]
fn a_stand_up_asked_while_driving_stands_where_the_robot_stopped() {
    for (what, drive) in [
        ("stand-up while driving W", TeleopMode::WheelForward),
        ("stand-up while driving S", TeleopMode::WheelBackward),
    ] {
        let plan = vec![
            PlanStep::at(0.0, TeleopMode::Stop),
            PlanStep::at(0.1, TeleopMode::Fold),
            PlanStep::at(5.0, drive),
            PlanStep::at(7.0, TeleopMode::Stand),
        ];
        let clean = Faults::default();
        let mut rig = Rig::new(Path::new(DEFAULT_MODEL), plan, &clean, &clean).unwrap();
        rig.run_until(7.0).unwrap();
        let mut stopped_at = None;
        while rig.time_s() < 17.0 {
            rig.step().unwrap();
            let torso = rig.sim().physics().torso();
            let speed_m_s = torso.vel_m_s[0].hypot(torso.vel_m_s[1]);
            if stopped_at.is_none() && speed_m_s < 0.01 {
                stopped_at = Some(torso.pos_m);
            }
        }
        let stop = stopped_at.expect("the brake stopped the robot");
        let end = rig.sim().physics().torso().pos_m;
        let from_stop_m = (end[0] - stop[0]).hypot(end[1] - stop[1]);
        let state = rig.records().last().unwrap().state;
        println!("MEASURED {what}: {from_stop_m:.3} m from where it stopped, ended {state:?}");
        assert_eq!(state, Some(State::Legs(LegMotion::Stand)));
        assert!(from_stop_m <= 0.05, "{what}: {from_stop_m} m from its stop");
    }
}

/// How a stand-up from the wheels (the campaign's `stand-up` plan: fold, `stand` at 5 s)
/// ended on `plant` by `until_s`.
struct StandUpEnd {
    fallen: bool,
    /// When `stand_tilted` was first reported, s.
    tilted_at_s: Option<f64>,
    state: Option<State>,
    faults: FaultFlags,
    height_m: f64,
    pitch_deg: f64,
}

fn stand_up(plant: Plant, until_s: f64) -> StandUpEnd {
    let clean = Faults::default();
    let model = Path::new(DEFAULT_MODEL);
    let plan = Scenario::StandUp.plan();
    let mut rig = Rig::with_plant(model, plan, &clean, &clean, plant).unwrap();
    let (mut fallen, mut tilted_at_s) = (false, None);
    while rig.time_s() < until_s {
        rig.step().unwrap();
        let record = rig.records().last().unwrap();
        fallen |= record.fallen();
        if tilted_at_s.is_none() && record.faults.contains(FaultFlags::STAND_TILTED) {
            tilted_at_s = Some(rig.time_s());
        }
    }
    let record = rig.records().last().unwrap();
    let torso = rig.sim().physics().torso();
    StandUpEnd {
        fallen,
        tilted_at_s,
        state: record.state,
        faults: record.faults,
        height_m: torso.pos_m[2],
        pitch_deg: torso.rpy_rad()[1].to_degrees(),
    }
}

fn campaign_robot(seed: u64) -> Plant {
    Draws::of(seed).plant(Drives::Rated.ratings())
}

/// Campaign robots (0, 7, 8, 16, 25, 55 and 61, rated drives, their own IMU parts, delay)
/// whose front feet landed first as the legs unfolded rocked back onto their back feet, 15°
/// from their trim, and waited there for good: the rule that holds the legs while a robot on
/// its wheels leans kept holding them on wheels and feet. Still there for a second, they now
/// stand up, and none falls.
#[test]
fn a_stand_up_that_rocks_back_onto_its_back_feet_stands_up() {
    for seed in [0, 7, 8, 16, 25, 55, 61] {
        let end = stand_up(campaign_robot(seed), 13.0);
        let (height_m, pitch_deg, faults) = (end.height_m, end.pitch_deg, end.faults);
        println!(
            "MEASURED robot {seed}: ended {:?}, torso {height_m:.3} m high, pitched \
             {pitch_deg:.1}°",
            end.state
        );
        assert!(!end.fallen, "robot {seed} fell");
        assert!(
            pitch_deg.abs() < 8.0,
            "robot {seed} stands {pitch_deg}° pitched"
        );
        assert!(
            !faults.contains(FaultFlags::STAND_TILTED),
            "robot {seed}: {faults:?}"
        );
        assert_eq!(
            end.state,
            Some(State::Legs(LegMotion::Stand)),
            "robot {seed}"
        );
        assert!(
            height_m > 0.33,
            "robot {seed} at {height_m} m: not on its legs"
        );
    }
}

/// Campaign robots (4, 21, 96 and 97) whose feet took nearly all the weight while the wheels
/// were held with the stop's damping: the nearly unloaded wheels swung between their torque
/// limits, read as rolling, and the legs waited on them for good. The hold now lets unloaded
/// wheels turn: each ends on its legs, level, or reporting that it is not (`stand_tilted`),
/// and none falls.
#[test]
fn a_stand_up_whose_feet_unload_the_wheels_does_not_wait_on_them() {
    for seed in [4, 21, 96, 97] {
        let end = stand_up(campaign_robot(seed), 14.0);
        let pitch_deg = end.pitch_deg;
        let reported = end.faults.contains(FaultFlags::STAND_TILTED);
        println!(
            "MEASURED robot {seed}: ended {:?}, pitched {pitch_deg:.1}°, stand_tilted {reported}",
            end.state
        );
        assert!(!end.fallen, "robot {seed} fell");
        assert_eq!(
            end.state,
            Some(State::Legs(LegMotion::Stand)),
            "robot {seed}"
        );
        assert!(
            pitch_deg.abs() < 8.0 || reported,
            "robot {seed} stands {pitch_deg}° pitched, unreported"
        );
    }
}

/// Campaign robots (27 and 56) whose front legs give way as they unfold stand 30° nose down on
/// their front feet: the controller says so (`stand_tilted`) and holds them there. The robot as
/// drawn stands up level and says nothing.
#[test]
fn a_stand_up_that_ends_nose_down_is_reported() {
    for seed in [Some(27), Some(56), None] {
        let end = stand_up(seed.map_or_else(Plant::default, campaign_robot), 13.0);
        let (pitch_deg, reported_at_s) = (end.pitch_deg, end.tilted_at_s);
        println!(
            "MEASURED robot {seed:?}: pitch {pitch_deg:.1}°, ended {:?}, stand_tilted from \
             {reported_at_s:?} s",
            end.state
        );
        assert_eq!(end.state, Some(State::Legs(LegMotion::Stand)));
        match seed {
            Some(_) => {
                assert!(pitch_deg > 25.0, "robot {seed:?} at {pitch_deg}°");
                assert!(end.faults.contains(FaultFlags::STAND_TILTED));
            }
            None => assert_eq!(reported_at_s, None, "the drawn robot stands level"),
        }
    }
}

/// The stand-up from the wheels on the campaign's robots as built (rated drives, the IMU part
/// drawn, delay): how far each moved from the key press, its largest tilt, whether it stood,
/// stopped with a fault or fell (`cargo test --release -p sim-host --test transitions --
/// --ignored --nocapture`; docs/firmware.md, "Folding in place").
#[test]
#[ignore = "measurement: the stand-up on the campaign's robots in docs/firmware.md"]
fn stand_ups_on_the_campaign_robots_measured() {
    // Stood (and of those within the 5 cm and 8°), stopped with a fault, still
    // settling for the stand-up at the end, fell: each robot counts once, a fall first.
    let (mut stood, mut within, mut faulted, mut settling, mut fell) = (0, 0, 0, 0, 0);
    const ROBOTS: u64 = 30;
    for seed in 0..ROBOTS {
        let plan = vec![
            PlanStep::at(0.0, TeleopMode::Stop),
            PlanStep::at(0.1, TeleopMode::Fold),
            PlanStep::at(6.0, TeleopMode::Stand),
        ];
        let clean = Faults::default();
        let plant = Draws::of(seed).plant(Drives::Rated.ratings());
        let model = Path::new(DEFAULT_MODEL);
        let mut rig = Rig::with_plant(model, plan, &clean, &clean, plant).unwrap();
        rig.run_until(6.0).unwrap();
        let start = rig.sim().physics().torso().pos_m;
        let (mut max_tilt_deg, mut fallen) = (0.0_f64, false);
        while rig.time_s() < 14.0 {
            rig.step().unwrap();
            let record = rig.records().last().unwrap();
            max_tilt_deg = max_tilt_deg.max(record.tilt_deg);
            fallen |= record.fallen();
        }
        let end = rig.sim().physics().torso().pos_m;
        let moved_m = (end[0] - start[0]).hypot(end[1] - start[1]);
        let record = rig.records().last().unwrap();
        let state = record.state;
        println!(
            "MEASURED robot {seed}: moved {moved_m:.3} m, tilt {max_tilt_deg:.1}°, \
             fell {fallen}, ended {state:?}, faults {:?}",
            record.faults
        );
        match state {
            _ if fallen => fell += 1,
            Some(State::Legs(_)) => {
                stood += 1;
                within += u32::from(moved_m <= 0.05 && max_tilt_deg <= 8.0);
            }
            Some(State::Fault) => faulted += 1,
            _ => settling += 1,
        }
    }
    println!(
        "MEASURED stand-ups on {ROBOTS} robots: {stood} stood ({within} within 5 cm and 8°), \
         {faulted} stopped with a fault, {settling} still settling, {fell} fell"
    );
}
