//! The interactive operator's state, sans-IO: keys in, frames out, bus frames observed, and
//! everything the screen shows. The terminal loop ([`crate::terminal`]) feeds it time, keys and
//! frames; [`crate::ui`] draws it; tests drive it directly.

use std::collections::VecDeque;

use protocol::{EncodeError, Frame, MessageId};
use teleop_core::bus_status::BusStatus;
use teleop_core::keys::{action, Action, Key};
use teleop_core::link::OperatorLink;
use teleop_core::operator::{Operator, Outcome};
use teleop_core::release::ReleaseOutcome;

/// Lines kept in the event log.
const LOG_LINES: usize = 4;

/// Ground truth from an in-process simulator (only with `--bus inproc`; a real bus has none).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimView {
    /// Simulated time, s.
    pub time_s: f64,
    /// Torso position in the world (x forward at the start), m.
    pub position_m: [f64; 2],
    /// Heading, degrees (+ = left).
    pub yaw_deg: f64,
    /// Torso height above the ground, m.
    pub height_m: f64,
    /// Torso tilt from upright, degrees.
    pub tilt_deg: f64,
}

/// The operator at the keys.
#[derive(Debug, Clone)]
pub struct App {
    bus_name: String,
    operator: Operator,
    status: BusStatus,
    sim: Option<SimView>,
    last_heartbeat_ms: Option<u64>,
    frames_sent: u64,
    log: VecDeque<String>,
    quit: bool,
}

impl App {
    /// An operator on the bus called `bus_name` (shown in the title), with the simulation's
    /// test key.
    pub fn new(bus_name: &str) -> Self {
        Self::with_key(bus_name, protocol::TEST_KEY)
    }

    /// An operator on the bus called `bus_name`, sealing its frames with `key`.
    pub fn with_key(bus_name: &str, key: protocol::Key) -> Self {
        Self {
            bus_name: bus_name.to_owned(),
            operator: Operator::with_link(OperatorLink::new(key)),
            status: BusStatus::default(),
            sim: None,
            last_heartbeat_ms: None,
            frames_sent: 0,
            log: VecDeque::new(),
            quit: false,
        }
    }

    /// Takes a key pressed at `now_ms`. A key with no meaning is logged, not sent.
    pub fn key(&mut self, now_ms: u64, key: Key) {
        let Some(act) = action(key) else {
            self.note(format!(
                "{} does nothing (the keys are listed below)",
                describe(key)
            ));
            return;
        };
        if self.operator.press(now_ms, act) == Outcome::Quit {
            self.quit = true;
            return;
        }
        match act {
            Action::EStop => self.note("E-STOP latched: press R twice to release".into()),
            Action::Release if self.operator.release().pending() => {
                self.note("releasing the E-stop: waiting for the controller to confirm".into())
            }
            Action::Release if self.operator.release_armed(now_ms) => {
                self.note("press R again within 2 s to release the E-stop".into())
            }
            Action::Mode(mode) => self.note(format!("command {}", mode_text(mode))),
            _ => {}
        }
    }

    /// Takes a gamepad's action at `now_ms` ([`teleop_core::gamepad`]).
    pub fn pad(&mut self, now_ms: u64, act: Action) {
        self.operator.press(now_ms, act);
        match act {
            Action::EStop => self.note("E-STOP latched (pad): press Start twice to release".into()),
            Action::InputLost => self
                .note("gamepad lost: the robot was told to stop and the operator is silent".into()),
            Action::InputFound => self.note("gamepad back: press a motion to move".into()),
            Action::Mode(mode) => self.note(format!("command {} (pad)", mode_text(mode))),
            _ => {}
        }
    }

    /// The frames due at `now_ms` (send them on the bus).
    pub fn poll(&mut self, now_ms: u64) -> Result<Vec<Frame>, EncodeError> {
        let frames = self.operator.poll(now_ms)?;
        if let Some(outcome) = self.operator.take_release_outcome() {
            self.note(release_note(outcome).into());
        }
        if frames
            .iter()
            .any(|f| f.id() == MessageId::TeleopHeartbeat.raw())
        {
            self.last_heartbeat_ms = Some(now_ms);
        }
        self.frames_sent += frames.len() as u64;
        Ok(frames)
    }

    /// The frames that stop the robot when the operator leaves: a STOP command at once (the
    /// controller would also stop on the lost heartbeat, 460 ms later).
    pub fn farewell(&mut self, now_ms: u64) -> Result<Vec<Frame>, EncodeError> {
        self.operator
            .press(now_ms, Action::Mode(protocol::TeleopMode::Stop));
        self.poll(now_ms)
    }

    /// Takes a frame seen on the bus at `now_ms`.
    pub fn observe(&mut self, now_ms: u64, frame: &Frame) {
        self.status.observe(now_ms, frame);
        // Only an authentic status frame heard now confirms an E-stop, never one stored from
        // before; the announcement joins the controller's session.
        self.operator.observe(frame);
    }

    /// Takes the in-process simulator's ground truth.
    pub fn set_sim(&mut self, view: SimView) {
        self.sim = Some(view);
    }

    /// Logs a line (bus errors, say) for the operator.
    pub fn note(&mut self, line: String) {
        if self.log.len() == LOG_LINES {
            self.log.pop_front();
        }
        self.log.push_back(line);
    }

    /// Whether the operator asked to quit.
    pub fn quit_requested(&self) -> bool {
        self.quit
    }

    /// The bus name.
    pub fn bus_name(&self) -> &str {
        &self.bus_name
    }

    /// The operator's command state.
    pub fn operator(&self) -> &Operator {
        &self.operator
    }

    /// The bus as heard.
    pub fn status(&self) -> &BusStatus {
        &self.status
    }

    /// The simulator's ground truth, with `--bus inproc`.
    pub fn sim(&self) -> Option<&SimView> {
        self.sim.as_ref()
    }

    /// Milliseconds since the last heartbeat went out, `None` before the first.
    pub fn heartbeat_age_ms(&self, now_ms: u64) -> Option<u64> {
        self.last_heartbeat_ms.map(|t| now_ms.saturating_sub(t))
    }

    /// Frames sent so far.
    pub fn frames_sent(&self) -> u64 {
        self.frames_sent
    }

    /// The event log, oldest first.
    pub fn log(&self) -> impl Iterator<Item = &str> {
        self.log.iter().map(String::as_str)
    }
}

/// A mode as the operator reads it: the report's key and what it does.
pub fn mode_text(mode: protocol::TeleopMode) -> &'static str {
    use protocol::TeleopMode as M;
    match mode {
        M::Stop => "X stop",
        M::WheelForward => "W wheels forward",
        M::WheelBackward => "S wheels backward",
        M::WheelRotate => "A rotate on the wheels",
        M::TrotForward => "L trot forward",
        M::TrotBackward => "K trot backward",
        M::Stand => "T stand on the legs",
        M::Fold => "F fold onto the wheels",
        M::Drive => "drive on the wheels at the sticks' speed and yaw rate",
        M::Walk => "walk on the legs at the sticks' speed and yaw rate",
        M::Auto => "H drive on by itself, back first, climbing steps",
    }
}

fn describe(key: Key) -> String {
    match key {
        Key::Char(' ') => "space".into(),
        Key::Char(c) => format!("`{c}`"),
        Key::Up => "↑".into(),
        Key::Down => "↓".into(),
        Key::Left => "←".into(),
        Key::Right => "→".into(),
        Key::Esc => "Esc".into(),
    }
}

/// What the operator is told when a release ends.
fn release_note(outcome: ReleaseOutcome) -> &'static str {
    match outcome {
        ReleaseOutcome::Released => "E-stop released: the robot waits for a new command (X first)",
        ReleaseOutcome::Superseded => {
            "the release was not taken: the E-stop latched again; press R twice to release it"
        }
        ReleaseOutcome::TimedOut => {
            "the controller kept its E-stop for 1 s: press R twice to try again"
        }
        ReleaseOutcome::NothingToRelease => {
            "no E-stop to release: the controller does not report one"
        }
    }
}
