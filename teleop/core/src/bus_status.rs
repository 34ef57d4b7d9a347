//! What the operator sees of the robot, read off the bus: the controller's mode, faults and
//! attitude, the wheel speeds, each drive's state, the frames the controller rejected, the
//! traffic rate — and who has gone silent. Teleop decodes without sequence checks: it only
//! listens, and a status it cannot decode is counted, not shown.

use protocol::{
    decode_frame, AnyMessage, ControllerStatus, DriveFlags, Frame, PerDrive, RejectCounters,
};

/// A node is silent when nothing came from it for this long, ms (its status runs at 50 Hz;
/// a drive's feedback at 250 Hz).
pub const SILENT_MS: u64 = 200;
/// Window of the frame-rate figure, ms.
pub const RATE_WINDOW_MS: u64 = 1_000;

/// The bus as the operator sees it.
#[derive(Debug, Clone, Default)]
pub struct BusStatus {
    controller: Option<(u64, ControllerStatus)>,
    wheel_speed_rad_s: Option<(u64, [f32; 2])>,
    drives: PerDrive<Option<(u64, DriveFlags)>>,
    rejected: Option<RejectCounters>,
    last_feedback_ms: Option<u64>,
    undecodable: u64,
    window: Vec<u64>,
}

impl BusStatus {
    /// Takes a frame seen at `now_ms`.
    pub fn observe(&mut self, now_ms: u64, frame: &Frame) {
        let start = now_ms.saturating_sub(RATE_WINDOW_MS);
        self.window.retain(|t| *t > start);
        self.window.push(now_ms);
        let Ok(decoded) = decode_frame(frame.id(), frame.data()) else {
            self.undecodable += 1;
            return;
        };
        match decoded.message {
            AnyMessage::ControllerStatus(status) => self.controller = Some((now_ms, status)),
            AnyMessage::WheelFeedback(wheels) => {
                self.wheel_speed_rad_s = Some((now_ms, wheels.velocity.map(|v| v.si())));
                self.last_feedback_ms = Some(now_ms);
            }
            AnyMessage::LegFeedback(..) | AnyMessage::Imu(_) | AnyMessage::Range(_) => {
                self.last_feedback_ms = Some(now_ms)
            }
            AnyMessage::DriveStatus(drive, status) => {
                *self.drives.get_mut(drive) = Some((now_ms, status.flags));
            }
            AnyMessage::RejectCounters(counters) => self.rejected = Some(counters),
            _ => {}
        }
    }

    /// The controller's last status, if it spoke within [`SILENT_MS`].
    pub fn controller(&self, now_ms: u64) -> Option<&ControllerStatus> {
        self.controller
            .as_ref()
            .filter(|(t, _)| now_ms.saturating_sub(*t) <= SILENT_MS)
            .map(|(_, s)| s)
    }

    /// Whether the controller has been silent for [`SILENT_MS`] (or never spoke).
    pub fn controller_silent(&self, now_ms: u64) -> bool {
        self.controller(now_ms).is_none()
    }

    /// Whether the drives' feedback has been silent for [`SILENT_MS`] (or never came).
    pub fn drives_silent(&self, now_ms: u64) -> bool {
        self.last_feedback_ms
            .is_none_or(|t| now_ms.saturating_sub(t) > SILENT_MS)
    }

    /// Milliseconds since the drives' last feedback, `None` before the first.
    pub fn feedback_age_ms(&self, now_ms: u64) -> Option<u64> {
        self.last_feedback_ms.map(|t| now_ms.saturating_sub(t))
    }

    /// Milliseconds since the controller's last status, `None` before the first.
    pub fn controller_age_ms(&self, now_ms: u64) -> Option<u64> {
        self.controller
            .as_ref()
            .map(|(t, _)| now_ms.saturating_sub(*t))
    }

    /// Wheel speeds, left and right, rad/s.
    pub fn wheel_speed_rad_s(&self) -> Option<[f32; 2]> {
        self.wheel_speed_rad_s.map(|(_, s)| s)
    }

    /// Each drive's last flags.
    pub fn drive_flags(&self) -> PerDrive<Option<DriveFlags>> {
        self.drives.map(|d| d.map(|(_, f)| f))
    }

    /// The controller's reject counters.
    pub fn rejected(&self) -> Option<&RejectCounters> {
        self.rejected.as_ref()
    }

    /// Frames teleop could not decode.
    pub fn undecodable(&self) -> u64 {
        self.undecodable
    }

    /// Frames per second over the last [`RATE_WINDOW_MS`].
    pub fn frames_per_s(&self, now_ms: u64) -> f64 {
        let start = now_ms.saturating_sub(RATE_WINDOW_MS);
        let recent = self.window.iter().filter(|t| **t > start).count();
        recent as f64 * 1_000.0 / RATE_WINDOW_MS as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use protocol::{
        Angle, BodyHeight, ControllerMode, Epoch, FaultFlags, ReleaseToken, Session, Tick, Torque,
        WheelFeedback, WheelVelocity, TEST_KEY,
    };

    const SESSION: Session = Session::owned(TEST_KEY, Epoch::new(1));

    fn status(mode: ControllerMode) -> Frame {
        AnyMessage::ControllerStatus(ControllerStatus {
            mode,
            faults: FaultFlags::EMPTY,
            tick: Tick::from_raw(5).unwrap(),
            body_height: BodyHeight::saturating_from_si(0.0),
            pitch: Angle::saturating_from_si(0.1),
            roll: Angle::saturating_from_si(0.0),
            release_token: ReleaseToken::new(0),
        })
        .encode(&SESSION, 0)
        .unwrap()
    }

    fn wheels(speed: f32) -> Frame {
        AnyMessage::WheelFeedback(WheelFeedback {
            velocity: [WheelVelocity::saturating_from_si(speed); 2],
            effort: [Torque::saturating_from_si(0.0); 2],
        })
        .encode(&SESSION, 0)
        .unwrap()
    }

    #[test]
    fn shows_what_it_heard_and_who_went_silent() {
        let mut bus = BusStatus::default();
        assert!(bus.controller_silent(0) && bus.drives_silent(0));
        bus.observe(10, &status(ControllerMode::WheelForward));
        bus.observe(12, &wheels(4.0));
        assert_eq!(
            bus.controller(100).map(|s| s.mode),
            Some(ControllerMode::WheelForward)
        );
        assert_eq!(bus.wheel_speed_rad_s(), Some([4.0, 4.0]));
        assert!(!bus.drives_silent(100));
        assert!(bus.controller_silent(10 + SILENT_MS + 1));
        assert!(bus.drives_silent(12 + SILENT_MS + 1));
        bus.observe(20, &Frame::new(0x7FF, &[0; 8]).unwrap());
        assert_eq!(bus.undecodable(), 1);
        assert_eq!(bus.frames_per_s(500), 3.0);
        assert_eq!(bus.frames_per_s(1_015), 1.0);
    }
}
