//! The trot the state asks for: `L` and `K` at the speed scale, steered by the operator's yaw
//! rate; `Walk` at the operator's speed and yaw rate, its direction following the speed's sign.

use super::Controller;
use crate::control::fsm::{Direction, LegMotion, State};
use crate::legs::gait::TrotCommand;

/// In `Walk`, the speed must pass this the other way before the trot turns round, m/s: a
/// stick resting near its centre does not flip the gait's direction back and forth.
const WALK_REVERSE_M_S: f32 = 0.01;

impl Controller {
    /// The trot's direction and stride in the present state (`None` when the legs do not
    /// trot). The report's sinusoids have no stride in metres: `Walk` drives them at the
    /// speed's share of the walking limit the operator is told of
    /// ([`protocol::motion_limits::WALK_LIMITS`]).
    pub fn trot_motion(&self) -> Option<(Direction, TrotCommand)> {
        let yaw_rate_rad_s = self.heading.1;
        let stride_share = match self.state {
            State::Legs(LegMotion::Trot(direction)) => {
                return Some((
                    direction,
                    TrotCommand {
                        stride_share: self.teleop.speed_scale,
                        yaw_rate_rad_s,
                    },
                ));
            }
            State::Legs(LegMotion::Walk) => {
                let full_m_s = self
                    .trot
                    .full_speed_m_s()
                    .unwrap_or(protocol::motion_limits::WALK_LIMITS.speed_m_s);
                // The speed in the trot's direction: inside the reversal's dead band a speed
                // of the other sign is no speed, not a stride the wrong way.
                let along_m_s = match self.walk_direction {
                    Direction::Forward => self.teleop.speed_m_s,
                    Direction::Backward => -self.teleop.speed_m_s,
                };
                if along_m_s.is_finite() && full_m_s > 0.0 {
                    crate::math::clamp(along_m_s / full_m_s, 0.0, 1.0)
                } else {
                    0.0
                }
            }
            _ => return None,
        };
        Some((
            self.walk_direction,
            TrotCommand {
                stride_share,
                yaw_rate_rad_s,
            },
        ))
    }

    /// One tick of the heading hold ([`crate::control::heading`]): while the legs stride, the
    /// yaw rate the trot takes (the operator's, or the hold's correction once the gyro's bias
    /// is measured); otherwise the hold restarts. A trot at no speed holds nothing: a
    /// correction would lift its feet, which stay down there.
    pub(super) fn hold_heading(&mut self, dt_s: f32) {
        let operator_rad_s = self
            .config
            .steering
            .trot_yaw_rad_s(self.teleop.yaw_rate_rad_s);
        let striding = self
            .trot_motion()
            .is_some_and(|(_, command)| command.advances());
        let held = striding && self.sensors.estimator().calibrated();
        let [_, _, measured_rad_s] = self.sensors.angular_rate_rad_s;
        let (hold, yaw_rate_rad_s) = &mut self.heading;
        *yaw_rate_rad_s = hold.yaw_rate_rad_s(
            &self.config.heading,
            held,
            operator_rad_s,
            measured_rad_s,
            dt_s,
        );
    }

    /// In `Walk`, turns the trot round when the operator's speed changes sign (past
    /// [`WALK_REVERSE_M_S`]); the blocked-swing counts start afresh with the new leading feet.
    pub(super) fn follow_walk_direction(&mut self) {
        if self.state != State::Legs(LegMotion::Walk) {
            return;
        }
        let speed_m_s = self.teleop.speed_m_s;
        let wanted = if speed_m_s > WALK_REVERSE_M_S {
            Direction::Forward
        } else if speed_m_s < -WALK_REVERSE_M_S {
            Direction::Backward
        } else {
            self.walk_direction
        };
        if wanted != self.walk_direction {
            self.walk_direction = wanted;
            self.blocked_swings.reset();
        }
    }
}
