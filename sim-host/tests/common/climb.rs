//! What the climb tests share: one robot of the campaign, in a plan, toward a step behind it,
//! with the controller's states, its falls and its tilt recorded.

use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

use firmware::control::fsm::State;
use host_can::fault_plan::Faults;
use protocol::{AnyMessage, EStop, FaultFlags, NodeId, Session, TeleopMode, TEST_KEY};
use sim_host::campaign::draw::Draws;
use sim_host::campaign::Drives;
use sim_host::faults::rig::Rig;
use sim_host::robot::model::DEFAULT_MODEL;
use sim_host::scene::{mjcf, Scene, Step};
use sim_host::session::simulator::StartPose;
use teleop_core::scripted::PlanStep;

/// Height of the torso's origin over the ground balancing on the wheels, m.
pub const ON_WHEELS_M: f64 = 0.27;

/// How deep a plateau is that the robot only climbs onto, m: room to drive on after a climb.
pub const LONG_PLATEAU_M: f64 = 6.0;

/// When the robot, folded from 0 s as in the campaign's scenarios, is sent its mode, s.
pub const MODE_AT_S: f64 = 4.0;

/// Runs so far in this process: each writes its scene to a directory of its own (the tests
/// run in parallel, and two writing one file read it half-written).
static RUNS: AtomicU64 = AtomicU64::new(0);

/// Where the step stands: `height_m` high, its riser `distance_m` behind the start.
#[derive(Debug, Clone, Copy)]
pub struct StepBehind {
    /// Riser height, m.
    pub height_m: f64,
    /// How far behind the start the riser stands, m.
    pub distance_m: f64,
    /// How deep the plateau is, m: its far edge is a step down as high.
    pub plateau_m: f64,
    /// The robot's heading to the riser, rad (0: square to it).
    pub heading_rad: f64,
}

/// What one trial did.
#[derive(Debug)]
pub struct Trial {
    /// When it first fell (tilt past 45° or the torso on the ground), s, and the controller's
    /// state then.
    pub fell_at: Option<(f64, Option<State>)>,
    /// The controller's states in order, with when each began, s.
    pub states: Vec<(f64, State)>,
    /// How far past the riser the axle ended, onto the plateau, m.
    pub onto_plateau_m: f64,
    /// The torso's height at the end, m.
    pub torso_z_m: f64,
    /// Largest tilt after the mode was sent, degrees.
    pub max_tilt_deg: f64,
    /// Largest roll after the mode was sent, degrees.
    pub max_roll_deg: f64,
    /// Each part of the robot that touched the step, with when it first did, s.
    pub contacts: Vec<(f64, String)>,
    /// Where the torso was along the path at the end, m (the start at 0, the step behind).
    pub torso_x_m: f64,
    /// … and when the first climb began, m.
    pub climb_start_x_m: Option<f64>,
    /// Every fault the controller reported after the mode was sent.
    pub faults: FaultFlags,
    /// The torso's place each cycle.
    pub path: TorsoPath,
}

/// The torso's place each cycle: time, s, and x and z, m. Its debug form is its length, so
/// that a trial printed whole stays readable.
pub struct TorsoPath(pub Vec<(f64, f64, f64)>);

impl std::fmt::Debug for TorsoPath {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "TorsoPath({} cycles)", self.0.len())
    }
}

impl Trial {
    /// The controller's state at the end.
    pub fn last(&self) -> Option<State> {
        self.states.last().map(|&(_, s)| s)
    }

    /// When its first climb began, s.
    pub fn climb_start_s(&self) -> Option<f64> {
        self.states
            .iter()
            .find(|(_, s)| matches!(s, State::Climbing(_)))
            .map(|&(t, _)| t)
    }
}

/// Runs robot `seed` of the campaign (rated drives) toward `step`: folded at 0 s, `mode` at
/// [`MODE_AT_S`], the operator's STOP at `stop_s` and an E-stop latched at `latch_s` if any;
/// until `end_s`.
pub fn run(
    seed: u64,
    step: StepBehind,
    mode: TeleopMode,
    (stop_s, latch_s): (Option<f64>, Option<f64>),
    end_s: f64,
) -> Trial {
    let mut plan = vec![
        PlanStep::at(0.0, TeleopMode::Fold),
        PlanStep::at(MODE_AT_S, mode),
    ];
    plan.extend(stop_s.map(|at_s| PlanStep::at(at_s, TeleopMode::Stop)));
    run_plan(seed, step, plan, (MODE_AT_S, latch_s), end_s)
}

/// As [`run`] in the autonomous mode without stops, but the robot first stands still for
/// 1.5 s and is folded from there, the mode sent 4 s later.
pub fn run_standing_first(seed: u64, step: StepBehind, end_s: f64) -> Trial {
    let mode_at_s = 1.5 + MODE_AT_S;
    let plan = vec![
        PlanStep::at(0.0, TeleopMode::Stand),
        PlanStep::at(1.5, TeleopMode::Fold),
        PlanStep::at(mode_at_s, TeleopMode::Auto),
    ];
    run_plan(seed, step, plan, (mode_at_s, None), end_s)
}

/// Runs `plan` (its mode sent at `mode_at_s`, from when tilt and roll count), an E-stop
/// latched at `latch_s` if any.
fn run_plan(
    seed: u64,
    step: StepBehind,
    plan: Vec<PlanStep>,
    (mode_at_s, latch_s): (f64, Option<f64>),
    end_s: f64,
) -> Trial {
    let riser_x_m = -step.distance_m;
    let scene = Scene::Step(Step {
        height_m: step.height_m,
        riser_x_m: step.distance_m,
        depth_m: step.plateau_m,
        behind: true,
    });
    let start = StartPose::standing().turned(step.heading_rad);
    let mut trial = run_scene_from(seed, &scene, plan, (mode_at_s, latch_s), end_s, start);
    trial.onto_plateau_m = riser_x_m - trial.torso_x_m;
    trial
}

/// Runs robot `seed` of the campaign (rated drives) on `scene` through `plan` (its mode sent
/// at `mode_at_s`, from when tilt and roll count), an E-stop latched at `latch_s` if any.
/// [`Trial::onto_plateau_m`] is left at 0 (the caller knows where its riser is).
pub fn run_scene(
    seed: u64,
    scene: &Scene,
    plan: Vec<PlanStep>,
    (mode_at_s, latch_s): (f64, Option<f64>),
    end_s: f64,
) -> Trial {
    let start = StartPose::standing();
    run_scene_from(seed, scene, plan, (mode_at_s, latch_s), end_s, start)
}

/// As [`run_scene`], the robot starting at `start` (turned to a heading).
pub fn run_scene_from(
    seed: u64,
    scene: &Scene,
    plan: Vec<PlanStep>,
    (mode_at_s, latch_s): (f64, Option<f64>),
    end_s: f64,
    start: StartPose,
) -> Trial {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("climb")
        .join(format!("{seed}-{}", RUNS.fetch_add(1, Ordering::Relaxed)));
    let model = mjcf::write(scene, Path::new(DEFAULT_MODEL), &dir).unwrap();
    let faults = Faults::default();
    let plant = Draws::of(seed).plant(Drives::Rated.ratings());
    let mut rig = Rig::with_start(&model, plan, (&faults, &faults), plant, start).unwrap();
    let (mut fell_at, mut states, mut max_tilt_deg) = (None, Vec::new(), 0.0_f64);
    let mut max_roll_deg = 0.0_f64;
    let mut contacts: Vec<(f64, String)> = Vec::new();
    let (mut faults, mut climb_start_x_m) = (FaultFlags::EMPTY, None);
    let mut latch_s = latch_s;
    let mut path = Vec::new();
    while rig.time_s() < end_s {
        if latch_s.is_some_and(|at_s| rig.time_s() >= at_s) {
            latch_s = None;
            // Bound to no session, as an E-stop panel's constant frame.
            let latch = AnyMessage::EStop(EStop::latch(NodeId::Tool))
                .encode(&Session::unjoined(TEST_KEY), 0)
                .unwrap();
            rig.tool_send(&latch).unwrap();
        }
        rig.step().unwrap();
        let record = rig.records().last().unwrap();
        if record.fallen() && fell_at.is_none() {
            fell_at = Some((rig.time_s(), record.state));
        }
        if let Some(state) = record.state {
            if climb_start_x_m.is_none() && matches!(state, State::Climbing(_)) {
                climb_start_x_m = Some(record.torso_pos_m[0]);
            }
            if states.last().is_none_or(|&(_, last)| last != state) {
                states.push((rig.time_s(), state));
            }
        }
        let physics = rig.sim().physics();
        let pos_m = physics.torso().pos_m;
        path.push((rig.time_s(), pos_m[0], pos_m[2]));
        if rig.time_s() > mode_at_s {
            faults = faults.with(record.faults);
            max_tilt_deg = max_tilt_deg.max(record.tilt_deg);
            let [roll_rad, _, _] = physics.torso().rpy_rad();
            max_roll_deg = max_roll_deg.max(roll_rad.to_degrees().abs());
        }
        for (_, part) in physics.obstacle_contacts() {
            let name = physics.geom_name(part);
            if contacts.iter().all(|(_, seen)| seen != name) {
                contacts.push((rig.time_s(), name.to_owned()));
            }
        }
    }
    let torso = rig.sim().physics().torso();
    Trial {
        fell_at,
        states,
        onto_plateau_m: 0.0,
        torso_z_m: torso.pos_m[2],
        max_tilt_deg,
        max_roll_deg,
        contacts,
        torso_x_m: torso.pos_m[0],
        climb_start_x_m,
        faults,
        path: TorsoPath(path),
    }
}
