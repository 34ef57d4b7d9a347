//! The fault matrix's cells for what a faulty or hostile node does on purpose: replay a
//! recorded E-stop release, forge operator commands without the key, and a controller that
//! restarts while the operator holds a motion key (no unexpected start-up).

use std::path::Path;

use protocol::{
    AnyMessage, BodyHeight, EStop, Epoch, FaultFlags, Key, NodeId, RejectCause, Session,
    SpeedScale, TeleopCommand, TeleopMode, TEST_KEY,
};

use firmware::control::fsm::State;

use crate::faults::judge::{fell, records_from};
use crate::faults::matrix::{clean_until, CellResult, Motion};
use crate::faults::rig::{Rig, PERIOD_US, RIG_EPOCH};
use crate::session::SessionError;

/// A key that is not the robot's.
const FORGER_KEY: Key = Key(*b"not-the-real-key");

fn latch() -> Option<protocol::Frame> {
    AnyMessage::EStop(EStop::latch(NodeId::Tool))
        .encode(&Session::unjoined(TEST_KEY), 0)
        .ok()
}

fn refused_as_stale(rig: &Rig) -> u64 {
    [
        RejectCause::StaleRelease,
        RejectCause::Repeated,
        RejectCause::WrongSequence,
    ]
    .into_iter()
    .map(|cause| rig.firmware_rejected(cause))
    .sum()
}

/// Latch at 2 s, a genuine release at 3 s, a new latch at 4 s, and at 5 s the release of 3 s
/// replayed: it must be refused and counted, and the E-stop stay latched.
pub(super) fn release_replayed(model: &Path) -> Result<CellResult, SessionError> {
    let mut rig = clean_until(model, Motion::Trot, 2.0)?;
    let latch = latch().ok_or(SessionError::Internal("the latch frame"))?;
    rig.tool_send(&latch)?;
    rig.run_until(3.0)?;
    let release = rig
        .release_frame(NodeId::Tool)
        .ok_or(SessionError::Internal("the release frame"))?;
    rig.tool_send(&release)?;
    rig.run_until(4.0)?;
    let released = rig
        .records()
        .last()
        .is_some_and(|r| r.state != Some(State::EStop));
    rig.tool_send(&latch)?;
    rig.run_until(5.0)?;
    let before = refused_as_stale(&rig);
    rig.tool_send(&release)?;
    rig.run_until(6.0)?;
    let refused = refused_as_stale(&rig) - before;
    let held = records_from(rig.records(), 4.1)
        .iter()
        .all(|r| r.state == Some(State::EStop));
    Ok(CellResult {
        name: "trot (L), recorded E-stop release replayed".into(),
        fault: "latch 2 s, release 3 s, latch 4 s; the 3 s release replayed at 5 s".into(),
        expected: "the genuine release releases; the replay is refused and counted; the E-stop stays latched",
        measured: format!(
            "released at 3 s: {released}; replay refused and counted: {refused}; latched from 4 s to the end: {held}"
        ),
        pass: released && refused == 1 && held,
    })
}

/// From 2 s to 4 s a node without the key sends STAND commands at 50 Hz, in the live session
/// with fresh counters: every one must be refused as unauthentic and the trot go on.
pub(super) fn forged_commands(model: &Path) -> Result<CellResult, SessionError> {
    let mut rig = clean_until(model, Motion::Trot, 2.0)?;
    let before = rig.firmware_rejected(RejectCause::Unauthentic);
    let command = AnyMessage::TeleopCommand(TeleopCommand {
        mode: TeleopMode::Stand,
        body_height: BodyHeight::saturating_from_si(0.0),
        speed_scale: SpeedScale::saturating_from_si(100.0),
        speed: Default::default(),
        yaw_rate: Default::default(),
    });
    let mut sent = 0_u64;
    let every = (20_000 / PERIOD_US).max(1);
    let mut cycle = 0_u64;
    while rig.time_s() < 4.0 {
        if cycle % every == 0 {
            let session = rig
                .controller()
                .map(|c| *c.node().session())
                .ok_or(SessionError::Internal("the controller"))?;
            let forged =
                Session::owned(FORGER_KEY, session.epoch().unwrap_or(RIG_EPOCH)).at(session.time());
            let frame = command
                .encode(&forged, session.time().ms())
                .map_err(|_| SessionError::Internal("the forged frame"))?;
            rig.tool_send(&frame)?;
            sent += 1;
        }
        rig.step()?;
        cycle += 1;
    }
    rig.run_until(6.0)?;
    let refused = rig.firmware_rejected(RejectCause::Unauthentic) - before;
    let after = records_from(rig.records(), 2.0);
    let trotting = after.iter().all(|r| Motion::Trot.moving(r.state));
    Ok(CellResult {
        name: "trot (L), forged operator commands".into(),
        fault: "STAND at 50 Hz from 2 s to 4 s, sealed with another key".into(),
        expected: "every forged frame refused as unauthentic; the trot goes on",
        measured: format!(
            "{refused} of {sent} refused as unauthentic; trotting throughout: {trotting}"
        ),
        pass: sent > 0 && refused == sent && trotting && !fell(after),
    })
}

/// The controller restarts at 3 s (a new session) while the teleop keeps sending L: it must
/// hold, report that it awaits STOP, and the robot must not trot again.
pub(super) fn restart_interlock(model: &Path) -> Result<CellResult, SessionError> {
    let restart_s = 3.0;
    let mut rig = clean_until(model, Motion::Trot, restart_s)?;
    rig.restart_firmware(Epoch::new(RIG_EPOCH.raw() + 1))?;
    rig.run_until(restart_s + 3.0)?;
    // From the first cycle of the new controller.
    let after = records_from(rig.records(), restart_s + 1e-6);
    let moved = after.iter().any(|r| Motion::Trot.moving(r.state));
    let awaiting = after
        .iter()
        .rev()
        .take(10)
        .all(|r| r.faults.contains(FaultFlags::AWAITING_STOP));
    let settled = records_from(rig.records(), restart_s + 0.5);
    let drift_m = match (settled.first(), settled.last()) {
        (Some(a), Some(b)) => {
            (b.torso_pos_m[0] - a.torso_pos_m[0]).hypot(b.torso_pos_m[1] - a.torso_pos_m[1])
        }
        _ => f64::INFINITY,
    };
    Ok(CellResult {
        name: "trot (L), controller restarted at 3 s".into(),
        fault: "a new controller process (new session) while L keeps coming".into(),
        expected: "no motion until STOP and a new command: holds, reports AWAITING_STOP",
        measured: format!(
            "trotted again: {moved}; AWAITING_STOP reported: {awaiting}; torso moved {:.3} m from 0.5 s after the restart",
            drift_m
        ),
        // The trot covers some 0.12 m in those 2.5 s; a robot caught mid-step settles by a
        // couple of centimetres.
        pass: !moved && awaiting && drift_m < 0.05 && !fell(after),
    })
}
