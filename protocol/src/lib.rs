//! The CAN FD wire contract of the hybrid wheel–leg robot: identifiers, messages, E2E
//! protection, bus-load maths and the DBC, shared by the firmware, the simulator and teleop.
//!
//! `#![no_std]`, no allocation, no panics: every decoder returns a typed [`DecodeError`] that a
//! receiver can count ([`Receiver`] does).
//!
//! # The bus
//!
//! CAN FD, 1 Mbit/s arbitration, 5 Mbit/s data ([`busload::ROBOT_BUS`]), 11-bit identifiers.
//! A lower identifier wins arbitration:
//!
//! | id              | message              | sender       | class       | rate at 1 kHz control |
//! |-----------------|----------------------|--------------|-------------|-----------------------|
//! | `0x000`         | [`EStop`]            | teleop, tool | emergency   | on event              |
//! | `0x010`         | [`Sync`]             | simulator    | clock       | every cycle (lockstep only) |
//! | `0x100`         | [`LegTargets`]       | controller   | command     | 250 Hz                |
//! | `0x101`         | [`WheelCommand`]     | controller   | command     | every cycle           |
//! | `0x180`–`0x183` | [`LegFeedback`] FL, FR, BL, BR | leg drives | feedback | 250 Hz          |
//! | `0x184`         | [`WheelFeedback`]    | wheel drive  | feedback    | every cycle           |
//! | `0x185`         | [`Imu`]              | IMU          | feedback    | every cycle           |
//! | `0x200`         | [`TeleopCommand`]    | teleop       | teleop      | on change, ≤ 50 Hz    |
//! | `0x201`         | [`TeleopHeartbeat`]  | teleop       | teleop      | 50 Hz                 |
//! | `0x400`         | [`ControllerStatus`] | controller   | status      | 50 Hz                 |
//! | `0x410`–`0x414` | [`DriveStatus`] legs FL, FR, BL, BR, wheels | drives | status | 10 Hz     |
//! | `0x600`         | [`RejectCounters`]   | controller   | diagnostics | 10 Hz                 |
//!
//! Each frame is `[CRC-16][counter u16][payload][zero padding]` ([`e2e`]); each message's doc
//! comment gives its payload layout with units and scales. [`busload`] computes the worst-case
//! load of this schedule; `cargo xtask busload` prints it.
//!
//! # Use
//!
//! ```
//! use protocol::{encode, Receiver, AnyMessage, TeleopCommand, TeleopMode, BodyHeight, SpeedScale};
//!
//! let command = TeleopCommand {
//!     mode: TeleopMode::WheelForward,
//!     body_height: BodyHeight::from_si(0.05).unwrap(),
//!     speed_scale: SpeedScale::from_si(80.0).unwrap(),
//! };
//! let frame = encode(&command, (), 0).unwrap();
//! let mut rx = Receiver::default();
//! let accepted = rx.receive(frame.id(), frame.data()).unwrap();
//! assert_eq!(accepted.message, AnyMessage::TeleopCommand(command));
//! ```
// Functions stay short enough to read whole (clippy.toml: 80 lines); tests may run longer.
#![cfg_attr(not(test), warn(clippy::too_many_lines))]
#![cfg_attr(not(test), no_std)]
#![deny(
    missing_docs,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::default_numeric_fallback
)]
#![cfg_attr(
    test,
    allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)
)]

pub mod busload;
mod codec;
pub mod dbc;
pub mod dlc;
pub mod e2e;
mod error;
mod frame;
mod id;
mod joints;
mod message;
mod msg;
mod node;
mod receiver;
pub mod signal;
mod units;
mod wire;

pub use codec::{decode, encode, EncodeError, Message};
pub use e2e::{E2eChecker, E2eCounter, E2eStatus};
pub use error::{DecodeError, RejectCause};
pub use frame::Frame;
pub use id::{MessageId, MAX_STANDARD_ID};
pub use joints::{Joints, PerDrive};
pub use message::{decode_frame, AnyMessage, Decoded, Layout};
pub use msg::*;
pub use node::{Drive, Leg, NodeId, JOINT_NAMES, LEG_JOINT_NAMES, WHEEL_NAMES};
pub use receiver::{Accepted, Receiver};
pub use units::*;
