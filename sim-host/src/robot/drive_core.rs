//! What every emulated drive shares, as real drives (moteus, DDT) behave: an acceptance filter,
//! E2E checks on what passes it, a command timeout, a latching E-stop, and counters for the
//! status frame.

use protocol::{
    AnyMessage, Count, DriveFlags, DriveStatus, EStopAction, EncodeError, Frame, Key, MessageId,
};

use crate::robot::link::NodeLink;

/// Drive command timeout, as moteus' default: no valid command for this long → torque off.
pub const COMMAND_TIMEOUT_US: u64 = 100_000;

/// What a drive should do this instant.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Authority {
    /// Apply the last command.
    Drive,
    /// Torque off: no command yet, the command said so, it timed out, or an E-stop is latched.
    TorqueOff,
}

/// The receive side and state flags of one drive.
#[derive(Debug, Clone)]
pub struct DriveCore {
    listens_to: MessageId,
    link: NodeLink,
    last_command_us: Option<u64>,
    commanded_enable: bool,
    estop: bool,
    rejected: u32,
    commands: u32,
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
            estop: false,
            rejected: 0,
            commands: 0,
        }
    }

    /// Runs a frame from the bus through the acceptance filter and the E2E checks. Returns the
    /// command message when it is one for this drive and valid; E-stops are handled here; a
    /// rejected frame is counted and never returned.
    pub fn on_frame(&mut self, now_us: u64, frame: &Frame) -> Option<AnyMessage> {
        let id = frame.id();
        let filter = [MessageId::EStop, MessageId::Announce, self.listens_to];
        if !filter.iter().any(|listened| listened.raw() == id) {
            return None;
        }
        match self.link.receive(id, frame.data()) {
            Ok(accepted) => match accepted.message {
                AnyMessage::EStop(estop) => {
                    self.estop = estop.action == EStopAction::Latch;
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

    /// Records whether the last valid command asked for torque.
    pub fn set_commanded_enable(&mut self, enable: bool) {
        self.commanded_enable = enable;
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
            && !self.estop
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
        self.estop
    }

    /// Seals one of this drive's frames in its session (`None` before it has joined one).
    pub fn seal(&mut self, message: &AnyMessage) -> Result<Option<Frame>, EncodeError> {
        self.link.seal(message)
    }

    /// The status message: flags and counters.
    pub fn status(&self, now_us: u64) -> DriveStatus {
        let mut flags = DriveFlags::EMPTY;
        if self.authority(now_us) == Authority::Drive {
            flags = flags.with(DriveFlags::ENABLED);
        }
        if self.timed_out(now_us) {
            flags = flags.with(DriveFlags::TIMED_OUT);
        }
        if self.estop {
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
