//! The operator as a CAN node. It sends the teleop command whenever it changes and again every
//! 20 ms, and a heartbeat every 20 ms, so the controller knows someone is at the keys: when
//! the heartbeat stops (teleop quit or died) the controller stops the robot within 500 ms.
//! Space latches an E-stop at once, and the latch is sent again every 4 ms until the controller
//! reports `EStop` (a single lost frame must not leave the robot moving); releasing it takes
//! `R` twice within 2 s, so that no single stray key does it.

use protocol::{
    AnyMessage, BodyHeight, ControllerMode, EStop, EStopAction, EncodeError, Frame, GroundSpeed,
    Millis, NodeId, SpeedScale, TeleopCommand, TeleopHeartbeat, TeleopMode, YawRate, TEST_KEY,
};

use protocol::motion_limits::{DRIVE_LIMITS, WALK_LIMITS};

use crate::keys::Action;
use crate::link::OperatorLink;
use crate::release::{Release, ReleaseOutcome};

/// Period of the command and heartbeat, ms (50 Hz).
pub const PERIOD_MS: u64 = 20;
/// The heartbeat goes out this long after the periodic command, ms: half a period apart, so
/// that in steady operation the controller checks one authenticated frame per tick (a CMAC is
/// the dearest thing it does with a frame; see the bus schedule's phases). A key press or a
/// release may still land in the heartbeat's tick.
pub const HEARTBEAT_OFFSET_MS: u64 = PERIOD_MS / 2;
/// How often an unconfirmed E-stop latch is sent again, ms: one control period of the
/// controller at 250 Hz, so that on a lossy link the latch gets through within a few of them.
pub const LATCH_REPEAT_MS: u64 = 4;
/// Window in which the second `R` releases the E-stop, ms.
pub const RELEASE_WINDOW_MS: u64 = 2_000;
/// Body-height range of the wire, m.
pub const BODY_HEIGHT_RANGE_M: (f32, f32) = (-0.10, 0.12);

/// The keys' steering range, rad/s: the controller's own limits are tighter on the legs
/// (0.4 rad/s) and take what it can.
pub const STEER_RANGE_RAD_S: f32 = 1.0;

/// What a key press led to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Keep going.
    Continue,
    /// The operator asked to leave.
    Quit,
}

/// The operator's state and its bus traffic.
#[derive(Debug, Clone)]
pub struct Operator {
    mode: TeleopMode,
    body_height_m: f32,
    speed_scale_pct: f32,
    /// Yaw rate that steers the moving keys, rad/s, + left.
    yaw_rate_rad_s: f32,
    /// A gamepad's sticks, forward and left turn, fractions of the mode's limits.
    sticks: (f32, f32),
    /// Whether the input device is gone: nothing but an E-stop goes out (after the STOP that
    /// says so), as if the operator had left.
    silent: bool,
    /// Falls silent once the pending command (the STOP) is out.
    silence_after_command: bool,
    estop_latched: bool,
    /// Whether the controller has reported its E-stop since this operator's last latch.
    estop_confirmed: bool,
    /// When the latch was last sent (it is repeated until confirmed).
    latch_sent_ms: Option<u64>,
    release_armed_at_ms: Option<u64>,
    pending_estop: Option<EStopAction>,
    command_changed: bool,
    next_send_ms: u64,
    next_heartbeat_ms: u64,
    link: OperatorLink,
    release: Release,
}

impl Default for Operator {
    fn default() -> Self {
        Self::new()
    }
}

impl Operator {
    /// At STOP, nominal height, full speed, no E-stop, with the simulation's test key.
    pub fn new() -> Self {
        Self::with_link(OperatorLink::new(TEST_KEY))
    }

    /// As [`Operator::new`], on `link` (the operator's key and resume point).
    pub fn with_link(link: OperatorLink) -> Self {
        Self {
            mode: TeleopMode::Stop,
            body_height_m: 0.0,
            speed_scale_pct: 100.0,
            yaw_rate_rad_s: 0.0,
            sticks: (0.0, 0.0),
            silent: false,
            silence_after_command: false,
            estop_latched: false,
            estop_confirmed: false,
            latch_sent_ms: None,
            release_armed_at_ms: None,
            pending_estop: None,
            command_changed: true,
            next_send_ms: 0,
            next_heartbeat_ms: 0,
            link,
            release: Release::default(),
        }
    }

    /// The session link (for its resume point).
    pub fn link(&self) -> &OperatorLink {
        &self.link
    }

    /// Takes a frame heard on the bus: the controller's announcement joins its session; an
    /// authentic status heard now confirms a latch this operator sent, gives the token a
    /// release must echo, and ends a release on its way.
    pub fn observe(&mut self, frame: &Frame) {
        let epoch = self.link.epoch();
        let heard = self.link.observe(frame);
        if self.link.epoch() != epoch {
            // A new session (the controller restarted): nothing of the old one's E-stop holds,
            // least of all a release on its way.
            self.release = Release::default();
        }
        if let Some(AnyMessage::ControllerStatus(status)) = heard {
            self.release.observe(&status);
            self.observe_controller(status.mode);
        }
    }

    /// The E-stop release: whether one is on its way, and how the last one ended.
    pub fn release(&self) -> &Release {
        &self.release
    }

    /// How the last release ended, once (for a UI's note).
    pub fn take_release_outcome(&mut self) -> Option<ReleaseOutcome> {
        self.release.take_outcome()
    }

    /// Whether the controller's session has been joined (commands go out only then).
    pub fn joined(&self) -> bool {
        self.link.epoch().is_some()
    }

    /// The commanded mode.
    pub fn mode(&self) -> TeleopMode {
        self.mode
    }

    /// The commanded body-height offset, m.
    pub fn body_height_m(&self) -> f32 {
        self.body_height_m
    }

    /// The commanded speed scale, %.
    pub fn speed_scale_pct(&self) -> f32 {
        self.speed_scale_pct
    }

    /// The commanded yaw rate, rad/s, + left: it steers `W`, `S`, `L` and `K`.
    pub fn yaw_rate_rad_s(&self) -> f32 {
        self.yaw_rate_rad_s
    }

    /// The ground speed (m/s) and yaw rate (rad/s, + left) the command carries now: the sticks
    /// within the mode's limits in `drive` and `walk`, plus the keys' steering.
    pub fn velocity(&self) -> (f32, f32) {
        let (forward, turn) = self.sticks;
        // A full stick asks for the robot's limits in the mode.
        let limits = match self.mode {
            TeleopMode::Drive => Some(DRIVE_LIMITS),
            TeleopMode::Walk => Some(WALK_LIMITS),
            _ => None,
        };
        match limits {
            Some(limits) => (
                forward * limits.speed_m_s,
                turn * limits.yaw_rate_rad_s + self.yaw_rate_rad_s,
            ),
            None => (0.0, self.yaw_rate_rad_s),
        }
    }

    /// Whether the input device is gone and the operator silent.
    pub fn silent(&self) -> bool {
        self.silent
    }

    /// Whether this operator latched an E-stop that is not yet released.
    pub fn estop_latched(&self) -> bool {
        self.estop_latched
    }

    /// Whether the controller has reported its E-stop since this operator latched one: until it
    /// has, the latch is repeated every [`LATCH_REPEAT_MS`].
    pub fn estop_confirmed(&self) -> bool {
        self.estop_confirmed
    }

    /// Takes the controller's reported mode from a status frame just heard: an `EStop` confirms
    /// a latch this operator has sent (a status heard before the latch went out confirms
    /// nothing).
    fn observe_controller(&mut self, mode: ControllerMode) {
        if self.estop_latched && self.latch_sent_ms.is_some() && mode == ControllerMode::EStop {
            self.estop_confirmed = true;
        }
    }

    /// Whether one `R` has been pressed and a second within the window would release.
    pub fn release_armed(&self, now_ms: u64) -> bool {
        self.release_armed_at_ms
            .is_some_and(|t| now_ms.saturating_sub(t) <= RELEASE_WINDOW_MS)
    }

    /// Takes one key action at `now_ms`.
    pub fn press(&mut self, now_ms: u64, action: Action) -> Outcome {
        if !matches!(action, Action::Release | Action::Sticks { .. }) {
            self.release_armed_at_ms = None;
        }
        if !matches!(action, Action::Sticks { .. } | Action::InputLost) {
            // Someone is at the controls.
            self.silent = false;
            self.silence_after_command = false;
        }
        match action {
            Action::Sticks { forward, turn } => {
                // Levels: they ride on the next periodic command (a stick moving all the time
                // adds no frames to the bus schedule's 50 Hz slot).
                self.sticks = (clamp_unit(forward), clamp_unit(turn));
            }
            Action::InputLost => {
                self.mode = TeleopMode::Stop;
                self.sticks = (0.0, 0.0);
                self.yaw_rate_rad_s = 0.0;
                self.command_changed = true;
                self.silence_after_command = true;
            }
            Action::InputFound => {}
            Action::Mode(mode) => {
                // Every motion starts straight.
                self.command_changed |= mode != self.mode || self.yaw_rate_rad_s != 0.0;
                self.mode = mode;
                self.yaw_rate_rad_s = 0.0;
            }
            Action::Steer(step_rad_s) => {
                let yaw =
                    (self.yaw_rate_rad_s + step_rad_s).clamp(-STEER_RANGE_RAD_S, STEER_RANGE_RAD_S);
                // Whole hundredths, so repeated steps do not drift.
                let yaw = (yaw * 100.0).round() / 100.0;
                self.command_changed |= yaw != self.yaw_rate_rad_s;
                self.yaw_rate_rad_s = yaw;
            }
            Action::Height(step_m) => {
                let (low, high) = BODY_HEIGHT_RANGE_M;
                let height = (self.body_height_m + step_m).clamp(low, high);
                // Whole centimetres, so repeated steps do not drift.
                let height = (height * 100.0).round() / 100.0;
                self.command_changed |= height != self.body_height_m;
                self.body_height_m = height;
            }
            Action::Speed(step_pct) => {
                let speed = (self.speed_scale_pct + step_pct).clamp(0.0, 100.0);
                self.command_changed |= speed != self.speed_scale_pct;
                self.speed_scale_pct = speed;
            }
            Action::EStop => {
                // A release on its way answers an older latch: it must not undo this one.
                self.release.abandon();
                self.estop_latched = true;
                self.estop_confirmed = false;
                self.latch_sent_ms = None;
                self.pending_estop = Some(EStopAction::Latch);
                // After a stop, motion must be asked for again.
                self.mode = TeleopMode::Stop;
                self.yaw_rate_rad_s = 0.0;
                self.command_changed = true;
            }
            Action::Release => {
                if !self.release_armed(now_ms) {
                    self.release_armed_at_ms = Some(now_ms);
                } else {
                    self.release_armed_at_ms = None;
                    if self.release.start(now_ms) {
                        self.estop_latched = false;
                        self.estop_confirmed = false;
                        self.latch_sent_ms = None;
                        self.pending_estop = None;
                    }
                }
            }
            Action::Quit => return Outcome::Quit,
        }
        Outcome::Continue
    }

    /// The frames due at `now_ms`: an E-stop latch or release at once (a latch again every
    /// [`LATCH_REPEAT_MS`] until the controller confirms it: a lost latch frame must not leave
    /// the robot moving; a release again every [`RELEASE_REPEAT_MS`](crate::release::RELEASE_REPEAT_MS) until the controller
    /// leaves its E-stop, for at most [`RELEASE_TIMEOUT_MS`](crate::release::RELEASE_TIMEOUT_MS)), the command at once when it
    /// changed, and the command and heartbeat every [`PERIOD_MS`], the heartbeat
    /// [`HEARTBEAT_OFFSET_MS`] after the command. Until the controller's
    /// session is joined only a latch goes out.
    pub fn poll(&mut self, now_ms: u64) -> Result<Vec<Frame>, EncodeError> {
        let mut frames = Vec::with_capacity(3);
        let repeat_latch = self.estop_latched
            && !self.estop_confirmed
            && self
                .latch_sent_ms
                .is_some_and(|sent| now_ms.saturating_sub(sent) >= LATCH_REPEAT_MS);
        if repeat_latch && self.pending_estop.is_none() {
            self.pending_estop = Some(EStopAction::Latch);
        }
        if let Some(action) = self.pending_estop.take() {
            self.latch_sent_ms = Some(now_ms);
            let latch = AnyMessage::EStop(EStop::latch(NodeId::Teleop));
            match self.link.seal(&latch)? {
                Some(frame) => frames.push(frame),
                None => self.pending_estop = Some(action),
            }
        }
        if let Some(release) = self.release.due(now_ms) {
            if let Some(frame) = self.link.seal(&AnyMessage::EStop(release))? {
                self.release.sent(now_ms);
                frames.push(frame);
            }
        }
        if self.silent {
            return Ok(frames);
        }
        let periodic = now_ms >= self.next_send_ms;
        if self.command_changed || periodic {
            let (speed, yaw_rate) = self.wire_velocity();
            let command = AnyMessage::TeleopCommand(TeleopCommand {
                mode: self.mode,
                body_height: BodyHeight::saturating_from_si(self.body_height_m),
                speed_scale: SpeedScale::saturating_from_si(self.speed_scale_pct),
                speed,
                yaw_rate,
            });
            // Before the session is joined nothing goes out, and a change waits for it.
            if let Some(frame) = self.link.seal(&command)? {
                frames.push(frame);
                self.command_changed = false;
                if std::mem::take(&mut self.silence_after_command) {
                    self.silent = true;
                    return Ok(frames);
                }
            }
            if periodic {
                self.next_send_ms = now_ms - now_ms % PERIOD_MS + PERIOD_MS;
            }
        }
        if now_ms >= self.next_heartbeat_ms {
            let uptime = u32::try_from(now_ms).unwrap_or(u32::MAX);
            let heartbeat = AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
                uptime: Millis::from_raw(uptime).unwrap_or(Millis::saturating_from_si(0.0)),
            });
            frames.extend(self.link.seal(&heartbeat)?);
            // The next time after now at the heartbeat's phase of the period.
            let ahead = (HEARTBEAT_OFFSET_MS + PERIOD_MS - now_ms % PERIOD_MS) % PERIOD_MS;
            self.next_heartbeat_ms = now_ms + if ahead == 0 { PERIOD_MS } else { ahead };
        }
        Ok(frames)
    }
}

#[cfg(test)]
mod tests;

impl Operator {
    /// The velocity as the wire carries it.
    fn wire_velocity(&self) -> (GroundSpeed, YawRate) {
        let (speed_m_s, yaw_rad_s) = self.velocity();
        (
            GroundSpeed::saturating_from_si(speed_m_s),
            YawRate::saturating_from_si(yaw_rad_s),
        )
    }
}

/// `value` within −1…1 (0 for a non-finite one).
fn clamp_unit(value: f32) -> f32 {
    if value.is_finite() {
        value.clamp(-1.0, 1.0)
    } else {
        0.0
    }
}
