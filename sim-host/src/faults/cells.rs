//! The fault matrix's cells, each a scenario with its faults and the judge of its outcome.

use std::path::Path;

use host_can::fault_plan::{feedback_nodes, FaultPlan, Faults};
use protocol::{AnyMessage, EStop, FaultFlags, MessageId, NodeId, RejectCause, Session, TEST_KEY};

use firmware::control::fsm::State;

use crate::faults::judge::{fell, forward_m, max_target_step, max_tilt_deg, records_from};
use crate::faults::matrix::{both, clean_until, run_motion, sent, CellResult, Motion, RUN_S};
use crate::faults::rig::PERIOD_US;
use crate::robot::drive_core::SS1_TIMER_US;
use crate::session::run_stats::RunError;
use crate::session::SessionError;

/// A motion under `plan` from the start: it must keep going, at least 60 % as far as on a
/// clean bus, and not fall.
pub(super) fn keeps_going(
    model: &Path,
    motion: Motion,
    what: &str,
    plan: &Faults,
    base_m: f64,
) -> Result<CellResult, SessionError> {
    let rig = run_motion(model, motion, plan, &Faults::default())?;
    let records = rig.records();
    let distance = forward_m(records);
    let still = records.last().is_some_and(|r| motion.moving(r.state));
    let [tx, rx] = rig.fault_stats();
    let dropped = if tx.dropped + rx.dropped > 0 {
        format!(", {} + {} frames dropped", tx.dropped, rx.dropped)
    } else {
        String::new()
    };
    Ok(CellResult {
        name: format!("{}, {what}", motion.name()),
        fault: plan.to_string(),
        expected: "keeps going, no fall",
        measured: format!(
            "{distance:.2} m ({:.0}% of clean), still {}, max tilt {:.1}°{dropped}",
            100.0 * distance / base_m,
            if still { "moving" } else { "STOPPED" },
            max_tilt_deg(records),
        ),
        pass: still && !fell(records) && distance > 0.6 * base_m,
    })
}

/// 20 % loss from 2 s, each frame on its own or (`burst_cycles > 0`) whole control cycles in
/// bursts of that many on average: either way the link monitor must stop the robot.
pub(super) fn safe_stop_on_loss(
    model: &Path,
    motion: Motion,
    burst_cycles: u32,
) -> Result<CellResult, SessionError> {
    let start_s = 2.0;
    let plan = both(
        FaultPlan {
            drop: 0.2,
            burst_cycles,
            ..FaultPlan::default()
        },
        3,
    );
    let mut rig = clean_until(model, motion, start_s)?;
    rig.set_faults(&plan);
    rig.run_until(RUN_S)?;
    let after = records_from(rig.records(), start_s);
    let stopped_at = after
        .iter()
        .find(|r| r.faults.contains(FaultFlags::LINK_DEGRADED) && !motion.moving(r.state));
    let last_s = records_from(rig.records(), RUN_S - 1.0);
    let creep_m = forward_m(last_s).abs();
    let measured = match stopped_at {
        Some(r) => format!(
            "LINK_DEGRADED and stopping {:.2} s after the loss began; {creep_m:.3} m in the last second, max tilt {:.1}°",
            r.time_us as f64 * 1e-6 - start_s,
            max_tilt_deg(after)
        ),
        None => format!("did not stop; max tilt {:.1}°", max_tilt_deg(after)),
    };
    Ok(CellResult {
        name: match burst_cycles {
            0 => format!("{}, loss 20% from 2 s", motion.name()),
            n => format!("{}, loss 20% in {n}-cycle bursts from 2 s", motion.name()),
        },
        fault: plan.to_string(),
        expected: "degrades to a safe stop, no fall",
        measured,
        pass: stopped_at.is_some() && !fell(after) && creep_m < 0.05,
    })
}

pub(super) fn flips_and_replays(
    model: &Path,
    what: &'static str,
    plan: Faults,
) -> Result<CellResult, SessionError> {
    let rig = run_motion(model, Motion::Trot, &plan, &Faults::default())?;
    let [tx, _] = rig.fault_stats();
    let count = |cause| rig.firmware_rejected(cause);
    let (firmware_bad, sent_bad) = match what {
        "flip" => (count(RejectCause::Crc), tx.flipped),
        _ => (
            count(RejectCause::Repeated) + count(RejectCause::WrongSequence),
            tx.replayed,
        ),
    };
    // Each drive checks the commands meant for it: every bad LegTargets must be refused by all
    // four leg drives, every bad WheelCommand by the wheel drive; and every drive checks the
    // controller's session announcements and status (for the E-stop's release), so a bad one
    // is refused by all five.
    let hardware = rig.sim().hardware();
    let bad_legs = rig.sim_bus().rx_bad_frames(MessageId::LegTargets.raw());
    let bad_wheels = rig.sim_bus().rx_bad_frames(MessageId::WheelCommand.raw());
    let bad_announce = rig.sim_bus().rx_bad_frames(MessageId::Announce.raw())
        + rig
            .sim_bus()
            .rx_bad_frames(MessageId::ControllerStatus.raw());
    let legs_refused: Vec<u64> = hardware
        .legs()
        .iter()
        .map(|leg| u64::from(leg.core().rejected()))
        .collect();
    let wheels_refused = u64::from(hardware.wheel().core().rejected());
    let drives_exact = legs_refused.iter().all(|&n| n == bad_legs + bad_announce)
        && wheels_refused == bad_wheels + bad_announce;
    let drives_bad: u64 = legs_refused.iter().sum::<u64>() + wheels_refused;
    let drives_sent = 4 * bad_legs + bad_wheels + 5 * bad_announce;
    let records = rig.records();
    let non_finite = records
        .iter()
        .any(|r| r.faults.contains(FaultFlags::NON_FINITE));
    let still = records.last().is_some_and(|r| Motion::Trot.moving(r.state));
    Ok(CellResult {
        name: format!("trot (L), {what}s both ways"),
        fault: plan.to_string(),
        expected: "every one rejected by E2E and counted, never applied",
        measured: format!(
            "firmware rejected {firmware_bad} of {sent_bad}, drives {drives_bad} of {drives_sent}; \
             {:.2} m, {}",
            forward_m(records),
            if still { "still trotting" } else { "STOPPED" }
        ),
        pass: firmware_bad == sent_bad
            && drives_exact
            && sent_bad > 0
            && drives_sent > 0
            && !non_finite
            && still
            && !fell(records),
    })
}

pub(super) fn flood(model: &Path) -> Result<CellResult, SessionError> {
    let teleop = sent(FaultPlan {
        flood_per_cycle: 40,
        ..FaultPlan::default()
    });
    let rig = run_motion(model, Motion::Trot, &Faults::default(), &teleop)?;
    let records = rig.records();
    let flooded = rig.teleop_fault_stats().flooded;
    let limited = rig.firmware_rejected(RejectCause::RateLimited);
    let missed = rig.stats().missed_cycles;
    // From the first cycle that stepped: before it the simulator has not joined the session
    // and sends no feedback yet.
    let stale = records
        .iter()
        .skip_while(|r| !r.stepped)
        .any(|r| r.faults.contains(FaultFlags::FEEDBACK_TIMEOUT));
    let still = records.last().is_some_and(|r| Motion::Trot.moving(r.state));
    let cycles = records.len() as u64;
    Ok(CellResult {
        name: "trot (L), teleop flood".into(),
        fault: format!("teleop {teleop} (10,000 frames/s)"),
        expected: "period holds, other traffic served, rate-limited commands counted",
        measured: format!(
            "{missed} of {cycles} cycles without a command, feedback {}, {limited} of {flooded} flood frames rate-limited, {:.2} m",
            if stale { "TIMED OUT" } else { "never late" },
            forward_m(records)
        ),
        // The rate limit lets a few commands per tick through; the rest must be counted.
        pass: missed == 0 && !stale && still && limited + 3 * cycles >= flooded && limited > 0,
    })
}

pub(super) fn feedback_silent(model: &Path) -> Result<CellResult, SessionError> {
    let start_s = 2.0;
    let plan = sent(FaultPlan {
        silence: feedback_nodes(),
        ..FaultPlan::default()
    });
    let mut rig = clean_until(model, Motion::Trot, start_s)?;
    rig.set_faults(&plan);
    rig.run_until(start_s + 1.0)?;
    let after = records_from(rig.records(), start_s);
    let first = after.iter().find(|r| r.state == Some(State::Fault));
    let latency_ms = first.map(|r| (r.time_us as f64 * 1e-3) - start_s * 1e3);
    let wheels_zero = after
        .iter()
        .skip_while(|r| r.state != Some(State::Fault))
        .all(|r| r.wheel_torque_nm == Some([0.0; 2]));
    Ok(CellResult {
        name: "trot (L), feedback silent from 2 s".into(),
        fault: plan.to_string(),
        expected: "firmware safe-stops (Fault) within 50 ms",
        measured: match latency_ms {
            Some(ms) => format!(
                "Fault after {ms:.0} ms, FEEDBACK_TIMEOUT, wheels at 0 N·m from then on: {wheels_zero}"
            ),
            None => "no Fault".into(),
        },
        pass: latency_ms.is_some_and(|ms| ms <= 50.0) && wheels_zero,
    })
}

pub(super) fn firmware_killed(model: &Path) -> Result<CellResult, SessionError> {
    let kill_s = 2.0;
    let mut rig = clean_until(model, Motion::Trot, kill_s)?;
    rig.kill_firmware();
    rig.run_until(kill_s + 0.5)?;
    let records = rig.records();
    let last_command_us = records
        .iter()
        .rev()
        .find(|r| r.commanded)
        .map_or(0, |r| r.time_us);
    let off = records.iter().find(|r| {
        r.time_us > last_command_us
            && r.torque_off.iter().all(|&o| o)
            && r.timed_out.iter().all(|&t| t)
    });
    let latency_ms = off.map(|r| (r.time_us - last_command_us) as f64 * 1e-3);
    Ok(CellResult {
        name: "trot (L), firmware killed at 2 s".into(),
        fault: "the firmware stops, sends nothing more".into(),
        expected: "drives torque-free within 100 ms of their last command, report the timeout",
        measured: match latency_ms {
            Some(ms) => {
                format!("all 5 drives torque-free with TIMED_OUT {ms:.0} ms after the last command")
            }
            None => "drives still driving".into(),
        },
        // The drives check their timeout once per control cycle.
        pass: latency_ms.is_some_and(|ms| ms <= 100.0 + PERIOD_US as f64 * 1e-3),
    })
}

pub(super) fn simulator_restarted(model: &Path) -> Result<CellResult, SessionError> {
    let restart_s = 3.0;
    let mut rig = clean_until(model, Motion::Trot, restart_s)?;
    rig.restart_simulator()?;
    rig.run_until(restart_s + 3.0)?;
    let before = max_target_step(
        records_from(rig.records(), 1.0)
            .get(..500)
            .unwrap_or_default(),
    );
    let after_records = records_from(rig.records(), restart_s - 0.1);
    let across = max_target_step(after_records.get(..150).unwrap_or_default());
    let detected = rig.controller().map_or(0, |c| c.sim_restarts());
    let after = records_from(rig.records(), restart_s);
    let faulted = after.iter().any(|r| r.state == Some(State::Fault));
    let trotting = after.last().is_some_and(|r| Motion::Trot.moving(r.state));
    let lost = rig
        .firmware_counters()
        .get(RejectCause::WrongSequence)
        .raw();
    Ok(CellResult {
        name: "trot (L), simulator restarted at 3 s".into(),
        fault: "a new simulator: robot back at the start, counters and SYNC from 0".into(),
        expected: "firmware detects it and resynchronises without a jump in commands",
        measured: format!(
            "detected {detected}×, {lost} frames refused until each sequence resynchronised, \
             largest target step {:.1} mrad/tick across the restart vs {:.1} in steady trot, {}",
            across * 1e3,
            before * 1e3,
            if faulted {
                "FAULT"
            } else if trotting {
                "trotting again"
            } else {
                "NOT trotting"
            }
        ),
        pass: detected == 1
            && across <= before * 1.05 + 1e-4
            && !faulted
            && trotting
            && !fell(after),
    })
}

/// An E-stop mid-trot, then a clear: the firmware reports `EStop` from the latch on and makes a
/// controlled stop (IEC 60204-1 category 1); the drives obey it for their SS1 timer and are
/// torque-free from its end at the latest, until the clear.
pub(super) fn estop(model: &Path, from: NodeId) -> Result<CellResult, SessionError> {
    let latch_s = 2.0;
    let clear_s = 5.0;
    let mut rig = clean_until(model, Motion::Trot, latch_s)?;
    // A teleop counts its E-stops; `cansend` sends a fixed frame (counter 0), every time.
    let counter = if from == NodeId::Teleop { 1 } else { 0 };
    let latch = AnyMessage::EStop(EStop::latch(from))
        .encode(&Session::unjoined(TEST_KEY), counter)
        .map_err(RunError::from)?;
    rig.tool_send(&latch)?;
    rig.run_until(clear_s)?;
    // A release needs the key and the controller's token: a keyholder's tool or teleop.
    let clear = rig
        .release_frame(from)
        .ok_or(RunError::Encode(protocol::EncodeError::NoSession))?;
    rig.tool_send(&clear)?;
    rig.run_until(clear_s + 1.5)?;
    // Records strictly after the latch was sent (the one at `latch_s` closed the cycle before).
    let latched = records_from(rig.records(), latch_s + 1e-6);
    let until_clear: Vec<_> = latched
        .iter()
        .take_while(|r| r.time_us <= (clear_s * 1e6) as u64)
        .collect();
    let reported = until_clear
        .iter()
        .all(|r| r.state == Some(State::EStop) && r.faults.contains(FaultFlags::ESTOP_LATCHED));
    let first_off = until_clear
        .iter()
        .position(|r| r.torque_off.iter().all(|&o| o) && r.estop.iter().all(|&e| e));
    // Rig time at the end of the cycle in which every drive was off, from the latch.
    let off_after_ms = first_off
        .and_then(|i| until_clear.get(i))
        .map(|r| r.time_us as f64 * 1e-3 - latch_s * 1e3);
    let held = until_clear
        .iter()
        .skip(first_off.unwrap_or(usize::MAX))
        .all(|r| r.torque_off.iter().all(|&o| o));
    let resumed = records_from(rig.records(), clear_s + 1e-6)
        .iter()
        .find(|r| r.torque_off.iter().all(|&o| !o))
        .map(|r| r.time_us as f64 * 1e-3 - clear_s * 1e3);
    let source = if from == NodeId::Teleop {
        "teleop"
    } else {
        "cansend (constant latch frame)"
    };
    let deadline_ms = SS1_TIMER_US as f64 * 1e-3;
    Ok(CellResult {
        name: format!("trot (L), E-stop from {source}"),
        fault: format!("EStop latch at {latch_s} s, clear at {clear_s} s; L keeps coming"),
        expected: "EStop reported from the latch tick; a controlled stop, all drives torque-free by the SS1 deadline (2 s) and until the clear; no fall",
        measured: format!(
            "EStop reported throughout: {reported}; all 5 drives torque-free {} after the latch, held until the clear: {held}; max tilt {:.1}°; drives powered again (holding, until STOP and a new command) {}",
            off_after_ms.map_or("never".into(), |ms| format!("{ms:.0} ms")),
            max_tilt_deg(latched),
            resumed.map_or("never".into(), |ms| format!("{ms:.0} ms after the clear"))
        ),
        pass: reported
            && off_after_ms.is_some_and(|ms| ms <= deadline_ms + 1e-6)
            && held
            && !fell(latched)
            && resumed.is_some(),
    })
}
