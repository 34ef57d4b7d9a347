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
    /// speed's share of the Cartesian default's full speed.
    pub(super) fn trot_motion(&self) -> Option<(Direction, TrotCommand)> {
        let yaw_rate_rad_s = self
            .config
            .steering
            .trot_yaw_rad_s(self.teleop.yaw_rate_rad_s);
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
                let full_m_s = self.trot.full_speed_m_s().unwrap_or(DEFAULT_FULL_M_S);
                let speed_m_s = self.teleop.speed_m_s;
                if speed_m_s.is_finite() && full_m_s > 0.0 {
                    crate::math::clamp(speed_m_s.abs() / full_m_s, 0.0, 1.0)
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

/// The Cartesian default's full speed, m/s (8 cm in 55 % of a 1 s cycle), for a trot that has
/// no stride in metres.
const DEFAULT_FULL_M_S: f32 = 0.145;
