//! The trot's watches for what it cannot step over: the leading feet's swings compared, late
//! in each, with where the drives' encoders put the feet ([`crate::legs::blocked`]); and,
//! walking backward, the ground behind as the rangefinder sees it
//! ([`crate::control::terrain::rise`]), which finds a riser or a slope before the feet do.

use protocol::Leg;

use super::Controller;
use crate::control::fsm::{Direction, Event, LegMotion, State};
use crate::legs::blocked::lag_m;
use crate::legs::kinematics::{leg_fk, LegJoints};

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
        if !command.advances() {
            // A walk come to a halt starts afresh when it walks off again.
            self.blocked_swings.reset();
            return;
        }
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

    /// One tick of the watch behind a backward trot, with the ranging received this tick
    /// (`None`: none): ground that rises ahead of the back feet stops the trot as a blocked
    /// foot does ([`Event::LegBlocked`], reported as `leg_blocked`). A trot's feet that land
    /// on a riser's edge tip it (a pair of feet 6 cm apart in height), so the trot stops
    /// before they reach it. A walk that does not stride (`Walk` at no speed) is not
    /// watched. Any other motion forgets what the watch saw, but the stand that a rise caused:
    /// walked back again, the robot stops again at once
    /// ([`crate::control::terrain::rise::RiseWatch::latched`]). A rangefinder that sends
    /// nothing leaves the watch blind, unreported: the feet's watch remains.
    #[inline(never)] // Once in five ticks: its frame stays off the others.
    pub(super) fn watch_behind(&mut self, ranging: Option<Option<f32>>) {
        // Nothing to take and nothing to forget: most ticks off a backward trot.
        if ranging.is_none() && self.auto.behind.fresh() {
            return;
        }
        let striding_back = matches!(
            self.trot_motion(),
            Some((Direction::Backward, command)) if command.advances()
        );
        if !striding_back {
            let standing_at_it =
                self.auto.behind.latched() && self.state == State::Legs(LegMotion::Stand);
            if !self.auto.behind.fresh() && !standing_at_it {
                self.auto.behind.reset();
            }
            return;
        }
        let Some(Some(distance_m)) = ranging else {
            return;
        };
        let height_m = self.ground_behind_m(distance_m);
        if self.auto.behind.update(&self.config.rise, height_m) {
            self.leg_blocked = true;
            self.apply(Event::LegBlocked);
        }
    }

    /// How high a ranging of `distance_m` puts the ground behind the robot over the ground its
    /// feet stand on, m: the spot's height over the line through the lowest front and the
    /// lowest back foot, all in the torso's frame from the drives' encoders. The estimated
    /// pitch is not used: in a trot it drifted by up to 10° in 8 s on some robots (robot 60),
    /// 15 cm of the spot's height; the feet give the body's attitude over the ground they
    /// stand on to the encoders' millimetres.
    fn ground_behind_m(&self, distance_m: f32) -> f32 {
        let config = &self.config;
        let mut lowest: [Option<(f32, f32)>; 2] = [None, None];
        for leg in Leg::ALL {
            let joints = LegJoints::from_array(*self.sensors.joint_position_rad.leg(leg));
            let foot = leg_fk(&config.geometry, &joints);
            let (hip_x_m, _) = config.rise.hips.offset_m(leg);
            let contact = (hip_x_m + foot.x_m, foot.z_m - config.support.foot_radius_m);
            let end = usize::from(hip_x_m < 0.0);
            if let Some(slot) = lowest.get_mut(end) {
                if contact.1.is_finite() && slot.is_none_or(|(_, z)| contact.1 < z) {
                    *slot = Some(contact);
                }
            }
        }
        let [Some(front), Some(back)] = lowest else {
            return f32::NAN;
        };
        // The hips' plane is the torso's origin; the axle lies the wheels' mount below it.
        let axle_z_m = config.terrain.wheel_radius_m - config.support.wheel_contact_height_m;
        let (spot_x_m, spot_z_m) = config.terrain.spot_on_torso_m(distance_m);
        let spot = (spot_x_m, axle_z_m + spot_z_m);
        let (dx, dz) = (front.0 - back.0, front.1 - back.1);
        let length_m = crate::math::sqrt(dx * dx + dz * dz);
        (dx * (spot.1 - back.1) - dz * (spot.0 - back.0)) / length_m
    }
}
