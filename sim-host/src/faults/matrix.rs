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

/// Runs every cell on `model`.
pub fn run(model: &Path) -> Result<Vec<CellResult>, SessionError> {
    let clean = Faults::default();
    let mut cells = Vec::new();
    for motion in [Motion::Trot, Motion::Drive] {
        let baseline = run_motion(model, motion, &clean, &clean)?;
        let base_m = forward_m(baseline.records());
        cells.push(CellResult {
            name: format!("{}, clean bus", motion.name()),
            fault: "none".into(),
            expected: "reference run",
            measured: format!(
                "{base_m:.2} m in {RUN_S} s, max tilt {:.1}°",
                max_tilt_deg(baseline.records())
            ),
            pass: !fell(baseline.records()) && base_m > 0.5,
        });
        for p in [0.01, 0.05] {
            let plan = both(
                FaultPlan {
                    drop: p,
                    ..FaultPlan::default()
                },
                2,
            );
            let what = format!("loss {:.0}%", p * 100.0);
            cells.push(keeps_going(model, motion, &what, &plan, base_m)?);
        }
        cells.push(safe_stop_on_loss(model, motion, 0)?);
        // 5 cycles are 20 ms at 250 Hz.
        cells.push(safe_stop_on_loss(model, motion, 5)?);
        for delay in 1..=3 {
            let plan = both(
                FaultPlan {
                    delay_cycles: delay,
                    ..FaultPlan::default()
                },
                1,
            );
            let what = format!("delay {delay} cycles each way");
            cells.push(keeps_going(model, motion, &what, &plan, base_m)?);
        }
    }
    let flips = FaultPlan {
        flip: 0.02,
        ..FaultPlan::default()
    };
    cells.push(flips_and_replays(model, "flip", both(flips, 5))?);
    let replays = FaultPlan {
        replay: 0.02,
        ..FaultPlan::default()
    };
    cells.push(flips_and_replays(model, "replay", both(replays, 6))?);
    cells.push(flood(model)?);
    cells.push(feedback_silent(model)?);
    cells.push(firmware_killed(model)?);
    cells.push(simulator_restarted(model)?);
    cells.extend(estop_cells(model)?);
    cells.push(release_replayed(model)?);
    cells.push(forged_commands(model)?);
    cells.push(restart_interlock(model)?);
    Ok(cells)
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
