//! The fault matrix: the closed loop ([`crate::faults::rig`]) under each fault of the bus and its
//! peers, each cell judged from ground truth and the nodes' own counters. `sim-host faults`
//! prints it; `cargo xtask faults` puts it in docs/faults.md; `tests/faults.rs` asserts it.
//!
//! Every run is lockstep and seeded, so the figures repeat exactly.

use std::path::Path;

use firmware::control::fsm::{LegMotion, State, WheelMotion};
use host_can::fault_plan::{FaultPlan, Faults};
use protocol::{NodeId, TeleopMode};
use teleop_core::scripted::PlanStep;

use crate::faults::cells::{
    estop, feedback_silent, firmware_killed, flips_and_replays, flood, keeps_going,
    safe_stop_on_loss, simulator_restarted,
};
use crate::faults::judge::{fell, forward_m, max_tilt_deg};
use crate::faults::rig::Rig;
use crate::faults::security::{forged_commands, release_replayed, restart_interlock};
use crate::session::SessionError;

/// One judged cell.
#[derive(Debug, Clone, PartialEq)]
pub struct CellResult {
    /// What ran: the motion and the fault.
    pub name: String,
    /// The fault plan or event.
    pub fault: String,
    /// What must happen.
    pub expected: &'static str,
    /// What happened.
    pub measured: String,
    /// Whether it is what must happen.
    pub pass: bool,
}

/// The motion a cell runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Motion {
    /// L: trot forward from 0.2 s.
    Trot,
    /// W: fold and drive forward on the wheels from 0.2 s.
    Drive,
}

impl Motion {
    pub(super) fn plan(self) -> Vec<PlanStep> {
        let mode = match self {
            Motion::Trot => TeleopMode::TrotForward,
            Motion::Drive => TeleopMode::WheelForward,
        };
        vec![step(0.0, TeleopMode::Stop), step(0.2, mode)]
    }

    pub(super) fn name(self) -> &'static str {
        match self {
            Motion::Trot => "trot (L)",
            Motion::Drive => "drive (W)",
        }
    }

    pub(super) fn moving(self, state: Option<State>) -> bool {
        match self {
            Motion::Trot => matches!(state, Some(State::Legs(LegMotion::Trot(_)))),
            Motion::Drive => matches!(state, Some(State::Wheels(WheelMotion::Drive(_)))),
        }
    }
}

pub(super) fn step(at_s: f64, mode: TeleopMode) -> PlanStep {
    PlanStep::at(at_s, mode)
}

/// How long a motion cell runs, s.
pub(super) const RUN_S: f64 = 8.0;

/// The same faults in both directions.
pub(super) fn both(plan: FaultPlan, seed: u64) -> Faults {
    Faults {
        tx: plan.clone(),
        rx: plan,
        seed,
    }
}

/// Faults on frames sent only.
pub(super) fn sent(plan: FaultPlan) -> Faults {
    Faults {
        tx: plan,
        ..Faults::default()
    }
}

pub(super) fn run_motion(
    model: &Path,
    motion: Motion,
    sim_faults: &Faults,
    teleop_faults: &Faults,
) -> Result<Rig, SessionError> {
    let mut rig = Rig::new(model, motion.plan(), sim_faults, teleop_faults)?;
    rig.run_until(RUN_S)?;
    Ok(rig)
}

/// `motion` on a clean bus until `until_s`, for a cell that breaks something then.
pub(super) fn clean_until(model: &Path, motion: Motion, until_s: f64) -> Result<Rig, SessionError> {
    let mut rig = Rig::new(model, motion.plan(), &Faults::default(), &Faults::default())?;
    rig.run_until(until_s)?;
    Ok(rig)
}

/// One cell of the matrix, to run on its own MuJoCo instance.
#[derive(Debug, Clone)]
enum Cell {
    /// `motion` under `plan` keeps going (compared with its clean run).
    KeepsGoing(Motion, String, Faults),
    /// `motion` with the link lost from 2 s, for a burst of this many cycles or for good (0).
    SafeStopOnLoss(Motion, u32),
    /// The trot with flipped bits or replayed frames.
    FlipsAndReplays(&'static str, Faults),
    Flood,
    FeedbackSilent,
    FirmwareKilled,
    SimulatorRestarted,
    EStop(NodeId),
    ReleaseReplayed,
    ForgedCommands,
    RestartInterlock,
}

/// Runs every cell on `model`, on every core (each cell its own MuJoCo instance, as the
/// campaign's runs; the table comes out in the same order whatever the cores): the clean runs
/// first, which the loss and delay cells are compared with.
pub fn run(model: &Path) -> Result<Vec<CellResult>, SessionError> {
    let jobs = crate::campaign::pool::default_jobs();
    let motions = [Motion::Trot, Motion::Drive];
    let (baselines, _) = crate::campaign::pool::run_all(
        &motions,
        jobs,
        false,
        |&motion| baseline(model, motion),
        Result::is_err,
    );
    let mut base_cells = Vec::new();
    let mut base_m = [0.0; 2];
    for (baseline, base) in baselines.into_iter().zip(&mut base_m) {
        let (cell, forward_m) = baseline?;
        *base = forward_m;
        base_cells.push(cell);
    }
    let per_motion: Vec<Vec<Cell>> = motions.iter().map(|&m| motion_cells(m)).collect();
    let all: Vec<Cell> = per_motion
        .iter()
        .flatten()
        .cloned()
        .chain(matrix_cells())
        .collect();
    let (results, _) = crate::campaign::pool::run_all(
        &all,
        jobs,
        true,
        |cell| run_cell(model, cell, &motions, &base_m),
        Result::is_err,
    );
    // The table's order: each clean run with its cells, then the rest.
    let mut results = results.into_iter();
    let mut cells = Vec::with_capacity(all.len() + base_cells.len());
    for (base, motion_cells) in base_cells.into_iter().zip(&per_motion) {
        cells.push(base);
        for result in results.by_ref().take(motion_cells.len()) {
            cells.push(result?);
        }
    }
    for result in results {
        cells.push(result?);
    }
    Ok(cells)
}

/// `motion` on a clean bus: its cell, and how far it went, m.
fn baseline(model: &Path, motion: Motion) -> Result<(CellResult, f64), SessionError> {
    let clean = Faults::default();
    let baseline = run_motion(model, motion, &clean, &clean)?;
    let base_m = forward_m(baseline.records());
    let cell = CellResult {
        name: format!("{}, clean bus", motion.name()),
        fault: "none".into(),
        expected: "reference run",
        measured: format!(
            "{base_m:.2} m in {RUN_S} s, max tilt {:.1}°",
            max_tilt_deg(baseline.records())
        ),
        pass: !fell(baseline.records()) && base_m > 0.5,
    };
    Ok((cell, base_m))
}

/// A motion's loss and delay cells, in the table's order.
fn motion_cells(motion: Motion) -> Vec<Cell> {
    let mut cells = Vec::new();
    for p in [0.01, 0.05] {
        let plan = both(
            FaultPlan {
                drop: p,
                ..FaultPlan::default()
            },
            2,
        );
        cells.push(Cell::KeepsGoing(
            motion,
            format!("loss {:.0}%", p * 100.0),
            plan,
        ));
    }
    cells.push(Cell::SafeStopOnLoss(motion, 0));
    // 5 cycles are 20 ms at 250 Hz.
    cells.push(Cell::SafeStopOnLoss(motion, 5));
    for delay in 1..=3 {
        let plan = both(
            FaultPlan {
                delay_cycles: delay,
                ..FaultPlan::default()
            },
            1,
        );
        cells.push(Cell::KeepsGoing(
            motion,
            format!("delay {delay} cycles each way"),
            plan,
        ));
    }
    cells
}

/// The cells that need no clean run, in the table's order.
fn matrix_cells() -> Vec<Cell> {
    let flips = FaultPlan {
        flip: 0.02,
        ..FaultPlan::default()
    };
    let replays = FaultPlan {
        replay: 0.02,
        ..FaultPlan::default()
    };
    vec![
        Cell::FlipsAndReplays("flip", both(flips, 5)),
        Cell::FlipsAndReplays("replay", both(replays, 6)),
        Cell::Flood,
        Cell::FeedbackSilent,
        Cell::FirmwareKilled,
        Cell::SimulatorRestarted,
        Cell::EStop(NodeId::Teleop),
        Cell::EStop(NodeId::Tool),
        Cell::ReleaseReplayed,
        Cell::ForgedCommands,
        Cell::RestartInterlock,
    ]
}

/// Runs `cell`; a motion's cells compare with its clean run's distance (`base_m`, in the order
/// of `motions`).
fn run_cell(
    model: &Path,
    cell: &Cell,
    motions: &[Motion],
    base_m: &[f64],
) -> Result<CellResult, SessionError> {
    match cell {
        Cell::KeepsGoing(motion, what, plan) => {
            let base = motions
                .iter()
                .zip(base_m)
                .find(|(m, _)| *m == motion)
                .map_or(0.0, |(_, b)| *b);
            keeps_going(model, *motion, what, plan, base)
        }
        Cell::SafeStopOnLoss(motion, burst) => safe_stop_on_loss(model, *motion, *burst),
        Cell::FlipsAndReplays(what, plan) => flips_and_replays(model, what, plan.clone()),
        Cell::Flood => flood(model),
        Cell::FeedbackSilent => feedback_silent(model),
        Cell::FirmwareKilled => firmware_killed(model),
        Cell::SimulatorRestarted => simulator_restarted(model),
        Cell::EStop(from) => estop(model, *from),
        Cell::ReleaseReplayed => release_replayed(model),
        Cell::ForgedCommands => forged_commands(model),
        Cell::RestartInterlock => restart_interlock(model),
    }
}

/// The matrix's E-stop cells alone (from the teleop, and from `cansend`).
pub fn estop_cells(model: &Path) -> Result<Vec<CellResult>, SessionError> {
    Ok(vec![
        estop(model, NodeId::Teleop)?,
        estop(model, NodeId::Tool)?,
    ])
}

/// The matrix as a Markdown table.
pub fn markdown(cells: &[CellResult]) -> String {
    let mut text = String::from("| cell | fault | must | measured | |\n|---|---|---|---|---|\n");
    for cell in cells {
        text.push_str(&format!(
            "| {} | `{}` | {} | {} | {} |\n",
            cell.name,
            cell.fault,
            cell.expected,
            cell.measured,
            if cell.pass { "pass" } else { "**FAIL**" }
        ));
    }
    text
}
