//! What the controller reports each tick: its mode, its faults (the causes that keep it in
//! `Fault`, and the conditions it shows besides), its posture and attitude.

use protocol::FaultFlags;

use super::{Controller, Status};
use crate::control::fsm::{Event, State};
use crate::time::Tick;

impl Controller {
    pub(super) fn status(&self, now: Tick, depth_m: f32) -> Status {
        let mut faults = self.fault_causes(now);
        if self.state == State::EStop {
            faults = faults.with(FaultFlags::ESTOP_LATCHED);
        }
        if self.teleop.stale(now) {
            faults = faults.with(FaultFlags::TELEOP_TIMEOUT);
        }
        if self.non_finite {
            faults = faults.with(FaultFlags::NON_FINITE);
        }
        if self.link_degraded {
            faults = faults.with(FaultFlags::LINK_DEGRADED);
        }
        faults = faults.with(self.wheel_fault);
        if self.leg_blocked {
            faults = faults.with(FaultFlags::LEG_BLOCKED);
        }
        if self.auto.step_refused {
            faults = faults.with(FaultFlags::STEP_REFUSED);
        }
        if self.auto.range_lost {
            faults = faults.with(FaultFlags::RANGE_TIMEOUT);
        }
        if self.stand_tilt.reported() {
            faults = faults.with(FaultFlags::STAND_TILTED);
        }
        if self.teleop.interlocked() {
            faults = faults.with(FaultFlags::AWAITING_STOP);
        }
        let attitude = self.sensors.attitude;
        Status {
            mode: self.state.mode(),
            faults,
            tick: now,
            body_height_m: depth_m - self.config.posture.depth_nominal_m,
            pitch_rad: attitude.pitch_rad,
            roll_rad: attitude.roll_rad,
            ik_failures: self.ik_failures,
        }
    }

    /// Causes that keep (or would put) the robot in `Fault`.
    pub(super) fn fault_causes(&self, now: Tick) -> FaultFlags {
        let mut faults = FaultFlags::EMPTY;
        if self.sensors.drives_stale(now) {
            faults = faults.with(FaultFlags::FEEDBACK_TIMEOUT);
        }
        if self.sensors.imu_stale(now)
            || (!self.sensors.attitude_known(now) && self.needs_attitude())
        {
            faults = faults.with(FaultFlags::IMU_TIMEOUT);
        }
        if self.tilted {
            faults = faults.with(FaultFlags::TILT_LIMIT);
        }
        if self.drive_faults.iter().any(|&faulted| faulted) {
            faults = faults.with(FaultFlags::DRIVE_FAULT);
        }
        if self.clock_stalled {
            faults = faults.with(FaultFlags::SYNC_LOST);
        }
        faults
    }

    /// `Fault` while a cause that only `Fault` holds remains — a drive's reported fault, a
    /// SYNC that froze — checked as a level, not only when it is first reported: an E-stop
    /// outranks a fault, so a cause reported while latched would otherwise be forgotten by
    /// the release, which would reset it without the check a STOP in `Fault` makes.
    pub(super) fn fault_on_held_cause(&mut self) {
        let held = self.drive_faults.iter().any(|&faulted| faulted) || self.clock_stalled;
        if held && !matches!(self.state, State::EStop | State::Fault) {
            self.apply(Event::Fault);
        }
    }
}
