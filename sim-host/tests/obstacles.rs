//! A trot into a step it cannot clear (`firmware::legs::blocked`): the robot stops, stands and
//! reports `leg_blocked`, never falls or marches on against the riser; walking backward the
//! rangefinder stops it before a riser it sees coming (`firmware::control::terrain::rise`);
//! on flat ground the watches never stop a trot. Seeded randomized trials: each trial is one
//! of the campaign's robots as built (`campaign::draw`, drives rated), a riser height and an
//! approach distance.
//!
//! `cargo test --release -p sim-host --test obstacles -- --nocapture` prints the figures.

use std::path::{Path, PathBuf};

use firmware::control::fsm::{LegMotion, State};
use host_can::fault_plan::Faults;
use protocol::{FaultFlags, TeleopMode};
use sim_host::campaign::draw::{Draw, Draws};
use sim_host::campaign::Drives;
use sim_host::faults::rig::{Rig, PERIOD_US};
use sim_host::robot::model::DEFAULT_MODEL;
use sim_host::scene::{mjcf, Scene, Step};
use teleop_core::scripted::PlanStep;

/// The front feet stand this far ahead of the torso's centre, m (the stance's 3 cm ahead of
/// the hips at 0.22 m, and the foot's radius).
const FEET_AHEAD_M: f64 = 0.28;

/// The back feet's rear stands this far behind the torso's centre, m (the stance under the
/// hips at 0.22 m, and the foot's radius).
const FEET_BEHIND_M: f64 = 0.255;

/// The operator's STOP after the run, s: it clears the report.
const STOP_AT_S: f64 = 20.0;

fn scene_file(scene: &Scene, name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("obstacles")
        .join(name);
    mjcf::write(scene, Path::new(DEFAULT_MODEL), &dir).unwrap()
}

/// What a trot toward a step did.
#[derive(Debug, Default)]
struct Figures {
    seed: u64,
    height_m: f64,
    approach_m: f64,
    /// First touch of the step, s.
    contact_s: Option<f64>,
    /// First cycle reporting `leg_blocked`, s, and the state then.
    blocked: Option<(f64, Option<State>)>,
    /// Torso x range from the report to the STOP, m.
    after_m: f64,
    max_tilt_deg: f64,
    fell: bool,
    /// Whether the report was gone after the operator's STOP.
    cleared: bool,
    /// How far the leading feet stood from the riser when the report came, m.
    gap_m: f64,
    /// With a retry, the first cycle reporting `leg_blocked` after it, s.
    again_s: Option<f64>,
}

/// With `retry`, the operator's STOP at this time, s, …
const RETRY_STOP_S: f64 = 16.0;

/// … and the trot again at this one.
const RETRY_S: f64 = 17.0;

/// Stand, then L toward a `height_m` step whose riser is `approach_m` ahead of the front feet
/// (`backward`: K toward one as far behind the back feet), on the robot of campaign seed
/// `seed`; with `retry`, X and the same trot again ([`RETRY_STOP_S`], [`RETRY_S`]); STOP at
/// [`STOP_AT_S`].
fn trot_into_step(
    seed: u64,
    height_m: f64,
    approach_m: f64,
    backward: bool,
    retry: bool,
) -> Figures {
    const DEPTH_M: f64 = 1.2;
    let riser_x_m = if backward {
        // The plateau lies behind the robot: its far edge is the riser it meets.
        -(FEET_BEHIND_M + approach_m) - DEPTH_M
    } else {
        FEET_AHEAD_M + approach_m
    };
    let scene = Scene::Step(Step {
        height_m,
        riser_x_m,
        depth_m: DEPTH_M,
        behind: false,
    });
    // One file per scene: the tests run in parallel, and two trials of one seed with
    // different steps read each other's scene.
    let path = scene_file(
        &scene,
        &format!("seed-{seed}-{backward}-{height_m:.4}-{approach_m:.4}"),
    );
    let (mode, start_s) = if backward {
        // As the campaign's K: stood up first.
        (TeleopMode::TrotBackward, 2.0)
    } else {
        (TeleopMode::TrotForward, 1.0)
    };
    let mut plan = vec![
        PlanStep::at(0.0, TeleopMode::Stand),
        PlanStep::at(start_s, mode),
    ];
    if retry {
        plan.push(PlanStep::at(RETRY_STOP_S, TeleopMode::Stop));
        plan.push(PlanStep::at(RETRY_S, mode));
    }
    plan.push(PlanStep::at(STOP_AT_S, TeleopMode::Stop));
    let plant = Draws::of(seed).plant(Drives::Rated.ratings());
    let faults = Faults::default();
    let mut rig = Rig::with_plant(&path, plan, &faults, &faults, plant).unwrap();
    let mut f = Figures {
        seed,
        height_m,
        approach_m,
        ..Figures::default()
    };
    let mut x_range = [f64::MAX, f64::MIN];
    while rig.stats().cycles * PERIOD_US < ((STOP_AT_S + 1.0) * 1e6) as u64 {
        rig.step().unwrap();
        let t = rig.time_s();
        let record = rig.records().last().unwrap().clone();
        f.max_tilt_deg = f.max_tilt_deg.max(record.tilt_deg);
        f.fell |= record.fallen();
        if f.contact_s.is_none() && rig.sim().physics().touches_geom("step") {
            f.contact_s = Some(t);
        }
        let reported = record.faults.contains(FaultFlags::LEG_BLOCKED);
        if retry && reported && t > RETRY_S && f.again_s.is_none() {
            f.again_s = Some(t);
        }
        if reported && f.blocked.is_none() {
            f.blocked = Some((t, record.state));
            let x = rig.sim().physics().torso().pos_m[0];
            f.gap_m = if backward {
                x - FEET_BEHIND_M - (riser_x_m + DEPTH_M)
            } else {
                riser_x_m - x - FEET_AHEAD_M
            };
        }
        if f.blocked.is_some() && t < STOP_AT_S {
            let x = rig.sim().physics().torso().pos_m[0];
            x_range = [x_range[0].min(x), x_range[1].max(x)];
        }
        f.cleared = t > STOP_AT_S + 0.5 && !reported;
    }
    f.after_m = x_range[1] - x_range[0];
    f
}

/// Whether a trot into a riser ended in a safe stop: it met the step, stood with
/// `leg_blocked` within 8 s of the touch, never fell nor tilted past 20°, moved less than
/// `after_m` after the report, and the operator's STOP cleared the report.
fn safe_stop(f: &Figures, after_m: f64) -> bool {
    f.contact_s.is_some()
        && !f.fell
        && f.max_tilt_deg < 20.0
        && f.blocked.is_some_and(|(blocked_s, state)| {
            f.contact_s
                .is_some_and(|contact_s| blocked_s - contact_s < 8.0)
                && state == Some(State::Legs(LegMotion::Stand))
        })
        && f.after_m < after_m
        && f.cleared
}

/// Seeded trials of a trot into a riser `height_m` ± 1 cm high, 0.2–0.6 m away (the issue's
/// approach): the figures of each.
fn trials(trials: u64, height_m: f64, backward: bool) -> Vec<Figures> {
    (0..trials)
        .map(|seed| {
            let mut draw = Draw::new(seed ^ 0x0b57_ac1e);
            let approach_m = 0.2 + 0.4 * draw.unit();
            let height_m = height_m + 0.02 * (draw.unit() - 0.5);
            let f = trot_into_step(seed, height_m, approach_m, backward, false);
            println!(
                "MEASURED {} seed {}, {:.3} m step {:.2} m away: {f:?}",
                if backward { "K" } else { "L" },
                f.seed,
                f.height_m,
                f.approach_m
            );
            f
        })
        .collect()
}

/// Every trot stops safely (its torso within 15 cm after the report); nearly all move less
/// than 10 cm. The one the rate allows is measured: robot 8, shoved back by the riser, stood
/// 4 cm short of where it stood before when the report came, and its torso swayed 12 cm over
/// its planted feet. Over robots 0–47, all 48 stop and 47 stay within 10 cm; none falls.
#[test]
fn a_trot_into_a_step_it_cannot_clear_stops_and_says_why() {
    const TRIALS: u64 = 16;
    let figures = trials(TRIALS, 0.10, false);
    let within = figures.iter().filter(|f| safe_stop(f, 0.10)).count() as u64;
    println!("MEASURED L into 10 cm: stopped with leg_blocked {within} of {TRIALS}");
    let unsafe_stops: Vec<&Figures> = figures.iter().filter(|f| !safe_stop(f, 0.15)).collect();
    assert!(unsafe_stops.is_empty(), "{unsafe_stops:#?}");
    assert!(within >= TRIALS - 1, "{figures:#?}");
}

/// Walking backward the back feet are watched as the front feet are forward, with a lower
/// threshold for a single swing ([`firmware::legs::blocked::BlockedConfig`]). A riser behind
/// the robot is the harder case: the back feet land on its edge as often as it stops them,
/// and a trot on feet a riser apart in height tips over. Before the back feet were watched,
/// 11 of 16 trots into a 6 cm riser behind fell (seeds 0–15, the riser 0.3 m behind). After
/// the report a robot shoved by the riser moves up to 0.16 m (forward, under 0.15 m).
#[test]
fn a_backward_trot_into_a_riser_mostly_stops_before_it_falls() {
    const TRIALS: u64 = 16;
    for (height_m, least) in [(0.10, 15), (0.06, 12)] {
        let figures = trials(TRIALS, height_m, true);
        let stopped = figures.iter().filter(|f| safe_stop(f, 0.2)).count();
        let others: Vec<&Figures> = figures.iter().filter(|f| !safe_stop(f, 0.2)).collect();
        let fell = others.iter().filter(|f| f.fell).count();
        println!("MEASURED K into {height_m} m: stopped {stopped} of {TRIALS}, fell {fell}");
        assert!(stopped >= least, "{height_m} m: {others:#?}");
    }
}

/// Walking backward the rangefinder watches the ground behind
/// (`firmware::control::terrain::rise`): a riser the trot meets from farther than the beam's
/// spot (0.6 m behind the back feet) and the watch's first 4 s stops it before its feet touch
/// the step, so none lands on the riser's edge; the operator's X and K again stop it again at
/// once, its feet still off the step. Robots 0–15, a 5–7 cm
/// riser 1.0–1.6 m behind the back feet.
#[test]
fn a_backward_trot_stops_before_a_riser_the_rangefinder_sees() {
    let mut gaps_m = Vec::new();
    for seed in 0..16 {
        let mut draw = Draw::new(seed ^ 0x0b57_ac1e);
        let approach_m = 1.0 + 0.6 * draw.unit();
        let height_m = 0.06 + 0.02 * (draw.unit() - 0.5);
        let f = trot_into_step(seed, height_m, approach_m, true, true);
        println!("MEASURED K toward {height_m:.3} m, {approach_m:.2} m behind: {f:?}");
        let (stopped_s, state) = f.blocked.unwrap_or_else(|| panic!("never stopped: {f:?}"));
        assert_eq!(state, Some(State::Legs(LegMotion::Stand)), "{f:?}");
        assert!(f.contact_s.is_none(), "touched the step: {f:?}");
        assert!(!f.fell && f.max_tilt_deg < 20.0, "{f:?}");
        assert!(stopped_s < RETRY_STOP_S && f.cleared, "{f:?}");
        let again_s = f.again_s.unwrap_or_else(|| panic!("walked on: {f:?}"));
        assert!(again_s - RETRY_S < 0.5, "{f:?}");
        gaps_m.push((seed, stopped_s, f.gap_m, again_s - RETRY_S));
    }
    println!(
        "MEASURED K toward a riser seen behind: (seed, stopped at s, back feet to riser m, \
         stopped again after s) {gaps_m:.2?}"
    );
}

#[test]
fn on_flat_ground_the_watch_never_stops_a_trot() {
    let path = scene_file(&Scene::Flat, "flat");
    for seed in 0..8 {
        for (mode, sign) in [
            (TeleopMode::TrotForward, 1.0),
            (TeleopMode::TrotBackward, -1.0),
        ] {
            // As the campaign's L and K: stood up first.
            let plan = vec![
                PlanStep::at(0.0, TeleopMode::Stand),
                PlanStep::at(2.0, mode),
            ];
            let plant = Draws::of(seed).plant(Drives::Rated.ratings());
            let faults = Faults::default();
            let mut rig = Rig::with_plant(&path, plan, &faults, &faults, plant).unwrap();
            rig.run_until(26.0).unwrap();
            let blocked = rig
                .records()
                .iter()
                .filter(|r| r.faults.contains(FaultFlags::LEG_BLOCKED))
                .count();
            let [x, y, _] = rig.sim().physics().torso().pos_m;
            println!(
                "MEASURED seed {seed} {mode:?} 24 s on flat ground: at ({x:.2}, {y:.2}) m, \
                 {blocked} cycles blocked"
            );
            assert_eq!(blocked, 0, "seed {seed} {mode:?}");
            // The trot walked all along (the campaign's L and K ask 0.4 m in 8 s); the trot
            // holds no heading, and some robots walk a circle (robot 6: 136° in 24 s).
            let walked_m = x.hypot(y);
            assert!(
                walked_m > 1.0 && sign * x > -0.2,
                "seed {seed} {mode:?}: ({x:.2}, {y:.2}) m"
            );
        }
    }
}
