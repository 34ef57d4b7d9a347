//! The trot's watch for what it cannot step over ([`crate::legs::blocked`]): the leading feet's
//! swings compared, late in each, with where the drives' encoders put the feet.

use protocol::Leg;

use super::Controller;
use crate::control::fsm::{Direction, Event};
use crate::legs::blocked::lag_m;
use crate::legs::kinematics::LegJoints;

impl Controller {
    /// One tick of the watch, before the trot's phase advances: a leading foot (the front feet
    /// walking forward, the back feet walking backward) that passes
    /// [`crate::legs::blocked::BlockedConfig::at_swing`] of its swing with this
    /// tick is measured against its target; a leg blocked swing after swing stops the trot
    /// ([`Event::LegBlocked`]: the robot stands on four legs) and the controller reports
    /// [`protocol::FaultFlags::LEG_BLOCKED`] until the operator's next request.
    #[inline(never)] // Its frame stays off the control step's deepest path (PIL stack budget).
    pub(super) fn watch_swings(&mut self) {
        let Some((direction, command)) = self.trot_motion() else {
            return;
        };
        let (leading, sign) = match direction {
            Direction::Forward => ([Leg::Fl, Leg::Fr], 1.0),
            Direction::Backward => ([Leg::Bl, Leg::Br], -1.0),
        };
        let config = self.config.blocked;
        let mut next = self.trot;
        next.advance();
        for leg in leading {
            let share = self.trot.swing_share(leg, direction).unwrap_or(0.0);
            let after = next.swing_share(leg, direction).unwrap_or(0.0);
            if !(share < config.at_swing && after >= config.at_swing) {
                continue;
            }
            // The stride, and with it how far a stopped foot falls behind, shrinks with the
            // speed (and, turning, differs by leg); the lag is judged as at full stride. Below
            // the configured share a riser cannot be told from flat ground's lags, and the leg
            // is not watched.
            let scale = self.trot.stride(leg, direction, &command).along;
            if scale.is_nan() || scale < config.min_scale {
                continue;
            }
            let target = LegJoints::from_array(*self.legs_rad.leg(leg));
            let measured = LegJoints::from_array(*self.sensors.joint_position_rad.leg(leg));
            let lag = lag_m(&self.config.geometry, &target, &measured, sign) / scale;
            if self
                .blocked_swings
                .swing_measured(&config, leg, lag, direction)
            {
                self.leg_blocked = true;
                self.apply(Event::LegBlocked);
                return;
            }
        }
    }
}
