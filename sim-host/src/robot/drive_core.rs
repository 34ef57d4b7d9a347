//! What every emulated drive shares, as real drives (moteus, DDT) behave: an acceptance filter,
//! E2E checks on what passes it, a command timeout, a latching E-stop, and counters for the
//! status frame.
//!
//! The E-stop is a stop of category 1 (IEC 60204-1, "SS1-t"): a latch starts the drive's own
//! timer of [`SS1_TIMER_US`], during which the drive keeps obeying valid commands so that the
//! controller can bring the robot to rest and set it down; when the timer runs out the drive
//! goes torque-free whatever it hears, until a clear. A drive that cut at once would tip a
//! balancing robot over at speed; the timer bounds how long a controller that does not stop it
//! can keep it moving.
//!
//! Within the timer the drive takes only the controller's *stopping* commands: commands while
//! the controller reports its E-stop. A drive that hears the controller report any other mode
//! after the latch (without a release: a controller that ignores the latch, or a stale one), or
//! is told to take its torque back after it was told to let go, goes torque-free at once
//! (category 0) and stays so until the clear.

use protocol::{
    AnyMessage, ControllerMode, Count, DriveFlags, DriveStatus, EStopAction, EncodeError, Frame,
    Key, MessageId,
};

use crate::robot::link::NodeLink;

/// Drive command timeout, as moteus' default: no valid command for this long → torque off.
pub const COMMAND_TIMEOUT_US: u64 = 100_000;

/// How long a drive keeps obeying commands after an E-stop latch before it goes torque-free on
/// its own, µs: the controller's controlled stop (`firmware::control::safety::SS1_DEADLINE_MS`)
/// must end within it.
pub const SS1_TIMER_US: u64 = 2_000_000;

/// What a drive should do this instant.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Authority {
    /// Apply the last command.
    Drive,
    /// Torque off: no command yet, the command said so, it timed out, or an E-stop latched
    /// [`SS1_TIMER_US`] or more ago.
    TorqueOff,
}

/// The receive side and state flags of one drive.
#[derive(Debug, Clone)]
pub struct DriveCore {
    listens_to: MessageId,
    link: NodeLink,
    last_command_us: Option<u64>,
    commanded_enable: bool,
    /// When the E-stop latched, µs (`None`: not latched). A repeated latch keeps the first time.
    estop_since_us: Option<u64>,
    /// An authentic release was heard since the last latch: the E-stop clears when the
    /// controller's status shows it left its own (it checks the release's token; a release it
    /// refused leaves the drives latched too).
    release_heard: bool,
    /// During this E-stop a command was not a stopping one (see the module docs): torque off
    /// until the clear.
    stop_refused: bool,
    /// During this E-stop the controller commanded torque off.
    let_go: bool,
    rejected: u32,
    commands: u32,
    /// A torque was cut to the rating since the last status.
    saturated: bool,
}

impl DriveCore {
    /// A drive that takes its commands on `listens_to` (and E-stops and the controller's
    /// announcement), in the sessions it joins with `key`.
    pub fn new(listens_to: MessageId, key: Key) -> Self {
        Self {
            listens_to,
            link: NodeLink::new(key),
            last_command_us: None,
            commanded_enable: false,
            estop_since_us: None,
            release_heard: false,
            stop_refused: false,
            let_go: false,
            rejected: 0,
            commands: 0,
            saturated: false,
        }
    }

    /// Notes that the drive cut a torque to its rating: the next status says so.
    pub fn note_saturated(&mut self) {
        self.saturated = true;
    }

    /// Runs a frame from the bus through the acceptance filter and the E2E checks. Returns the
    /// command message when it is one for this drive and valid; E-stops are handled here; a
    /// rejected frame is counted and never returned.
    pub fn on_frame(&mut self, now_us: u64, frame: &Frame) -> Option<AnyMessage> {
        let id = frame.id();
        let filter = [
            MessageId::EStop,
            MessageId::Announce,
            MessageId::ControllerStatus,
            self.listens_to,
        ];
        if !filter.iter().any(|listened| listened.raw() == id) {
            return None;
        }
        match self.link.receive(id, frame.data()) {
            Ok(accepted) => match accepted.message {
                AnyMessage::EStop(estop) => {
                    match estop.action {
                        EStopAction::Latch => {
                            if self.estop_since_us.is_none() {
                                self.estop_since_us = Some(now_us);
                                self.let_go = !self.commanded_enable;
                            }
                            self.release_heard = false;
                        }
                        EStopAction::Clear => self.release_heard = self.estop_since_us.is_some(),
                    }
                    None
                }
                AnyMessage::ControllerStatus(status) => {
                    let stopping = status.mode == ControllerMode::EStop;
                    if self.release_heard && !stopping {
                        self.estop_since_us = None;
                        self.release_heard = false;
                        self.stop_refused = false;
                        self.let_go = false;
                    } else if self.estop() && !stopping {
                        self.stop_refused = true;
                    }
                    None
                }
                AnyMessage::Announce(_) => None,
                message => {
                    self.last_command_us = Some(now_us);
                    self.commands = self.commands.wrapping_add(1);
                    Some(message)
                }
            },
            Err(_) => {
                self.rejected = self.rejected.wrapping_add(1);
                None
            }
        }
    }

    /// Records whether the last valid command asked for torque. During an E-stop, torque asked
    /// back after the controller let go is not a stopping command: the drive stays torque-free.
    pub fn set_commanded_enable(&mut self, enable: bool) {
        if self.estop() {
            if enable && self.let_go {
                self.stop_refused = true;
            }
            self.let_go |= !enable;
        }
        self.commanded_enable = enable;
    }

    /// Whether this E-stop's rules cut the torque early: the controller did not carry out the
    /// stop (see the module docs).
    pub fn stop_refused(&self) -> bool {
        self.stop_refused
    }

    /// Whether no valid command arrived for [`COMMAND_TIMEOUT_US`] (false before the first).
    pub fn timed_out(&self, now_us: u64) -> bool {
        self.last_command_us
            .is_some_and(|t| now_us.saturating_sub(t) >= COMMAND_TIMEOUT_US)
    }

    /// What the drive does now.
    pub fn authority(&self, now_us: u64) -> Authority {
        if self.last_command_us.is_some()
            && self.commanded_enable
            && !self.ss1_expired(now_us)
            && !self.stop_refused
            && !self.timed_out(now_us)
        {
            Authority::Drive
        } else {
            Authority::TorqueOff
        }
    }

    /// Frames this drive rejected.
    pub fn rejected(&self) -> u32 {
        self.rejected
    }

    /// Valid commands accepted.
    pub fn commands(&self) -> u32 {
        self.commands
    }

    /// Whether an E-stop is latched.
    pub fn estop(&self) -> bool {
        self.estop_since_us.is_some()
    }

    /// Whether an E-stop latched [`SS1_TIMER_US`] or more ago: torque off whatever the commands
    /// say.
    pub fn ss1_expired(&self, now_us: u64) -> bool {
        self.estop_since_us
            .is_some_and(|t| now_us.saturating_sub(t) >= SS1_TIMER_US)
    }

    /// Seals one of this drive's frames in its session (`None` before it has joined one).
    pub fn seal(&mut self, message: &AnyMessage) -> Result<Option<Frame>, EncodeError> {
        self.link.seal(message)
    }

    /// The status message: flags and counters (the saturation flag covers the time since the
    /// last status, which this one starts).
    pub fn status(&mut self, now_us: u64) -> DriveStatus {
        let mut flags = DriveFlags::EMPTY;
        if std::mem::take(&mut self.saturated) {
            flags = flags.with(DriveFlags::SATURATED);
        }
        if self.authority(now_us) == Authority::Drive {
            flags = flags.with(DriveFlags::ENABLED);
        }
        if self.timed_out(now_us) {
            flags = flags.with(DriveFlags::TIMED_OUT);
        }
        if self.estop() {
            flags = flags.with(DriveFlags::ESTOP);
        }
        let wrap = |n: u32| Count::from_raw((n & 0xFFFF) as u16).unwrap_or(Count::ZERO);
        DriveStatus {
            flags,
            rejected: wrap(self.rejected),
            commands: wrap(self.commands),
        }
    }
}
