//! CAN identifiers and their priority order; the table is in the [crate docs](crate).
//!
//! 11-bit identifiers; a lower id wins arbitration. The blocks leave room so that a new message
//! slots into its priority class without renumbering the bus.

use crate::node::NodeId;
use crate::node::{Drive, Leg};

/// Highest 11-bit identifier.
pub const MAX_STANDARD_ID: u16 = 0x7FF;

/// Every message the robot's bus carries, with the node or leg where one layout is used on
/// several identifiers.
///
/// An identifier outside this set is not an error of the sender's making that we can repair:
/// [`MessageId::from_raw`] returns `None` and the receiver counts it as
/// [`RejectCause::UnknownId`](crate::RejectCause::UnknownId).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MessageId {
    /// Emergency stop: latch or clear. Highest priority on the bus.
    EStop,
    /// Lockstep tick from the simulator.
    Sync,
    /// The controller's session announcement: wire version and boot epoch.
    Announce,
    /// Position targets for all 16 leg joints.
    LegTargets,
    /// Torque command for both wheels.
    WheelCommand,
    /// Joint feedback of one leg.
    LegFeedback(Leg),
    /// Feedback of both wheels.
    WheelFeedback,
    /// Torso IMU sample.
    Imu,
    /// The ground behind the torso, from the rangefinder.
    Range,
    /// Operator command (the report's keys plus stand, fold, drive, walk; height, speed scale,
    /// ground speed, yaw rate).
    TeleopCommand,
    /// Operator liveness.
    TeleopHeartbeat,
    /// Controller mode, faults and body state.
    ControllerStatus,
    /// State of one drive.
    DriveStatus(Drive),
    /// Counters of frames the controller rejected, by cause.
    RejectCounters,
}

impl MessageId {
    /// Every identifier on the bus, in priority order (highest first).
    pub const ALL: [MessageId; 21] = [
        MessageId::EStop,
        MessageId::Sync,
        MessageId::Announce,
        MessageId::LegTargets,
        MessageId::WheelCommand,
        MessageId::LegFeedback(Leg::Fl),
        MessageId::LegFeedback(Leg::Fr),
        MessageId::LegFeedback(Leg::Bl),
        MessageId::LegFeedback(Leg::Br),
        MessageId::WheelFeedback,
        MessageId::Imu,
        MessageId::Range,
        MessageId::TeleopCommand,
        MessageId::TeleopHeartbeat,
        MessageId::ControllerStatus,
        MessageId::DriveStatus(Drive::LegFl),
        MessageId::DriveStatus(Drive::LegFr),
        MessageId::DriveStatus(Drive::LegBl),
        MessageId::DriveStatus(Drive::LegBr),
        MessageId::DriveStatus(Drive::Wheel),
        MessageId::RejectCounters,
    ];

    /// The 11-bit CAN identifier.
    pub const fn raw(self) -> u16 {
        match self {
            MessageId::EStop => 0x000,
            MessageId::Sync => 0x010,
            MessageId::Announce => 0x020,
            MessageId::LegTargets => 0x100,
            MessageId::WheelCommand => 0x101,
            MessageId::LegFeedback(leg) => 0x180 + leg as u16,
            MessageId::WheelFeedback => 0x184,
            MessageId::Imu => 0x185,
            MessageId::Range => 0x186,
            MessageId::TeleopCommand => 0x200,
            MessageId::TeleopHeartbeat => 0x201,
            MessageId::ControllerStatus => 0x400,
            MessageId::DriveStatus(drive) => 0x410 + drive as u16,
            MessageId::RejectCounters => 0x600,
        }
    }

    /// The message for an identifier, or `None` for an identifier this bus does not define.
    pub const fn from_raw(raw: u16) -> Option<MessageId> {
        Some(match raw {
            0x000 => MessageId::EStop,
            0x010 => MessageId::Sync,
            0x020 => MessageId::Announce,
            0x100 => MessageId::LegTargets,
            0x101 => MessageId::WheelCommand,
            0x180 => MessageId::LegFeedback(Leg::Fl),
            0x181 => MessageId::LegFeedback(Leg::Fr),
            0x182 => MessageId::LegFeedback(Leg::Bl),
            0x183 => MessageId::LegFeedback(Leg::Br),
            0x184 => MessageId::WheelFeedback,
            0x185 => MessageId::Imu,
            0x186 => MessageId::Range,
            0x200 => MessageId::TeleopCommand,
            0x201 => MessageId::TeleopHeartbeat,
            0x400 => MessageId::ControllerStatus,
            0x410 => MessageId::DriveStatus(Drive::LegFl),
            0x411 => MessageId::DriveStatus(Drive::LegFr),
            0x412 => MessageId::DriveStatus(Drive::LegBl),
            0x413 => MessageId::DriveStatus(Drive::LegBr),
            0x414 => MessageId::DriveStatus(Drive::Wheel),
            0x600 => MessageId::RejectCounters,
            _ => return None,
        })
    }

    /// Position of this identifier in [`MessageId::ALL`]; indexes per-identifier state tables.
    pub const fn index(self) -> usize {
        match self {
            MessageId::EStop => 0,
            MessageId::Sync => 1,
            MessageId::Announce => 2,
            MessageId::LegTargets => 3,
            MessageId::WheelCommand => 4,
            MessageId::LegFeedback(leg) => 5 + leg as usize,
            MessageId::WheelFeedback => 9,
            MessageId::Imu => 10,
            MessageId::Range => 11,
            MessageId::TeleopCommand => 12,
            MessageId::TeleopHeartbeat => 13,
            MessageId::ControllerStatus => 14,
            MessageId::DriveStatus(drive) => 15 + drive as usize,
            MessageId::RejectCounters => 20,
        }
    }

    /// The nodes that act on this message (the DBC's receivers). A node's acceptance filter
    /// passes these identifiers and no others: the controller, say, never runs a frame that
    /// carries one of its own identifiers through its checks.
    pub const fn receivers(self) -> &'static [NodeId] {
        match self {
            MessageId::EStop => &[
                NodeId::Controller,
                NodeId::LegDriveFl,
                NodeId::LegDriveFr,
                NodeId::LegDriveBl,
                NodeId::LegDriveBr,
                NodeId::WheelDrive,
            ],
            // Every member joins the session it announces; the drives also read the status,
            // whose mode confirms that the controller left its E-stop before they leave theirs.
            MessageId::Announce => &[
                NodeId::LegDriveFl,
                NodeId::LegDriveFr,
                NodeId::LegDriveBl,
                NodeId::LegDriveBr,
                NodeId::WheelDrive,
                NodeId::Imu,
                NodeId::Rangefinder,
                NodeId::Teleop,
            ],
            MessageId::ControllerStatus => &[
                NodeId::LegDriveFl,
                NodeId::LegDriveFr,
                NodeId::LegDriveBl,
                NodeId::LegDriveBr,
                NodeId::WheelDrive,
                NodeId::Teleop,
            ],
            MessageId::Sync => &[
                NodeId::Controller,
                NodeId::LegDriveFl,
                NodeId::WheelDrive,
                NodeId::Imu,
            ],
            MessageId::LegTargets => &[
                NodeId::LegDriveFl,
                NodeId::LegDriveFr,
                NodeId::LegDriveBl,
                NodeId::LegDriveBr,
            ],
            MessageId::WheelCommand => &[NodeId::WheelDrive],
            MessageId::LegFeedback(_)
            | MessageId::WheelFeedback
            | MessageId::Imu
            | MessageId::Range
            | MessageId::TeleopCommand
            | MessageId::TeleopHeartbeat
            | MessageId::DriveStatus(_) => &[NodeId::Controller],
            MessageId::RejectCounters => &[NodeId::Teleop],
        }
    }

    /// The identifiers `node` acts on, as a set: bit [`MessageId::index`] of each. For an
    /// acceptance filter computed at build time, one mask test per frame.
    pub const fn heard_by(node: NodeId) -> IdSet {
        let mut bits = 0_u32;
        let mut i = 0;
        while i < MessageId::ALL.len() {
            #[allow(clippy::indexing_slicing)] // i < ALL.len()
            let id = MessageId::ALL[i];
            let receivers = id.receivers();
            let mut r = 0;
            while r < receivers.len() {
                #[allow(clippy::indexing_slicing)] // r < receivers.len()
                if receivers[r] as u8 == node as u8 {
                    bits |= 1_u32 << id.index();
                }
                r += 1;
            }
            i += 1;
        }
        IdSet(bits)
    }

    /// E2E data id mixed into the CRC: a frame moved to another identifier fails its CRC check.
    pub const fn data_id(self) -> u16 {
        0xC000 | self.raw()
    }
}

/// A set of message identifiers (see [`MessageId::heard_by`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct IdSet(u32);

impl IdSet {
    /// Whether `id` is in the set.
    pub const fn contains(self, id: MessageId) -> bool {
        self.0 & (1_u32 << id.index()) != 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_node_hears_exactly_the_receivers_list() {
        for node in [NodeId::Controller, NodeId::WheelDrive, NodeId::Teleop] {
            let heard = MessageId::heard_by(node);
            for id in MessageId::ALL {
                assert_eq!(
                    heard.contains(id),
                    id.receivers().contains(&node),
                    "{node:?} {id:?}"
                );
            }
        }
        let controller = MessageId::heard_by(NodeId::Controller);
        assert!(controller.contains(MessageId::Sync));
        assert!(controller.contains(MessageId::TeleopCommand));
        assert!(!controller.contains(MessageId::LegTargets));
        assert!(!controller.contains(MessageId::Announce));
    }
}
