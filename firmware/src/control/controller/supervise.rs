//! The supervisor: what the controller watches besides its inputs — the drives' and the IMU's
//! freshness, the tilt, the operator's heartbeat, the bus's loss and the tick's progress — and
//! the faults and stops they raise.

use super::Controller;
use crate::control::fsm::{Event, State};
use crate::time::Tick;

impl Controller {
    /// Whether the link is degraded (as last set by [`Controller::set_link_degraded`]).
    pub fn link_degraded(&self) -> bool {
        self.link_degraded
    }

    /// Tells the controller whether the bus is too lossy to move on (the node's
    /// [`LinkMonitor`](crate::node::link::LinkMonitor) decides; call before [`Controller::step`]).
    ///
    /// When the link becomes degraded the controller stops once, as for a lost operator
    /// ([`Event::LinkDegraded`]: a trot stands still on four legs, a wheel drive brakes to a
    /// standstill while balancing), and reports [`FaultFlags::LINK_DEGRADED`](protocol::FaultFlags::LINK_DEGRADED). While it stays
    /// degraded, operator requests other than Stop are refused — they are still taken as the
    /// operator's last key, so a teleop that keeps resending its mode neither restarts the
    /// motion now nor when the link recovers; after recovery the next new key acts.
    pub fn set_link_degraded(&mut self, degraded: bool) {
        if degraded && !self.link_degraded {
            self.apply(Event::LinkDegraded);
        }
        self.link_degraded = degraded;
    }

    /// Tells the controller that this tick did not come after the previous one (`stalled`): in
    /// lockstep the tick is the simulator's SYNC, and a SYNC whose tick froze or went back would
    /// freeze every watchdog. The controller faults ([`FaultFlags::SYNC_LOST`](protocol::FaultFlags::SYNC_LOST)) and stays in
    /// `Fault` until the ticks advance again and the operator sends STOP.
    pub fn set_clock_stalled(&mut self, stalled: bool) {
        if stalled && !self.clock_stalled {
            self.apply(Event::Fault);
        }
        self.clock_stalled = stalled;
    }

    pub(super) fn supervise(&mut self, now: Tick) {
        if !self.armed && self.sensors.drives_ever_reported() && !self.sensors.drives_stale(now) {
            self.armed = true;
            self.follow_measured();
        }
        let known = self.sensors.attitude_known(now);
        self.tilted = known && self.sensors.attitude.tilt_rad() > self.config.tilt_limit_rad;
        if self.teleop.just_lost(now) {
            self.apply(Event::TeleopLost);
        }
        self.fault_on_held_cause();
        if !self.armed || matches!(self.state, State::EStop | State::Fault) {
            return;
        }
        let moving = !matches!(self.state, State::Hold);
        if self.sensors.drives_stale(now)
            || (!known && self.state.balancing() && self.wheels_may_drive())
            || (self.tilted && moving)
        {
            self.apply(Event::Fault);
        }
    }
}
