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
//! | `0x020`         | [`Announce`]         | controller   | session     | 50 Hz                 |
//! | `0x100`         | [`LegTargets`]       | controller   | command     | 250 Hz                |
//! | `0x101`         | [`WheelCommand`]     | controller   | command     | every cycle           |
//! | `0x180`–`0x183` | [`LegFeedback`] FL, FR, BL, BR | leg drives | feedback | 250 Hz          |
//! | `0x184`         | [`WheelFeedback`]    | wheel drive  | feedback    | every cycle           |
//! | `0x185`         | [`Imu`]              | IMU          | feedback    | every cycle           |
//! | `0x186`         | [`Range`]            | rangefinder  | feedback    | 50 Hz                 |
//! | `0x200`         | [`TeleopCommand`]    | teleop       | teleop      | on change, ≤ 50 Hz    |
//! | `0x201`         | [`TeleopHeartbeat`]  | teleop       | teleop      | 50 Hz                 |
//! | `0x400`         | [`ControllerStatus`] | controller   | status      | 50 Hz                 |
//! | `0x410`–`0x414` | [`DriveStatus`] legs FL, FR, BL, BR, wheels | drives | status | 10 Hz     |
//! | `0x600`         | [`RejectCounters`]   | controller   | diagnostics | 10 Hz                 |
//!
//! Each frame is `[check u32][counter, low 16 bits][payload][zero padding]` ([`e2e`]), bound to
//! the controller's session ([`session`]); each message's doc comment gives its payload layout
//! with units and scales. [`busload`] computes the worst-case load of this schedule;
//! `cargo xtask busload` prints it.
//!
//! # Use
//!
//! ```
//! use protocol::{
//!     Announce, AnyMessage, BodyHeight, DecodeError, Epoch, Receiver, Sender, Session,
//!     SpeedScale, TeleopCommand, TeleopMode, WireVersion, TEST_KEY,
//! };
//!
//! // The controller owns the session of this boot and announces it.
//! let epoch = Epoch::new(7);
//! let controller = Session::owned(TEST_KEY, epoch);
//! let mut controller_rx = Receiver::owner(controller);
//! let announce = AnyMessage::Announce(Announce {
//!     version: WireVersion::THIS,
//!     epoch,
//!     time: controller.time(),
//! });
//! let announce = Sender::new().seal(&controller, &announce).unwrap();
//!
//! // The teleop joins on the announcement, then sends an authenticated command.
//! let mut teleop_rx = Receiver::member(TEST_KEY);
//! teleop_rx.receive(announce.id(), announce.data()).unwrap();
//! assert_eq!(teleop_rx.session().epoch(), Some(epoch));
//! let command = TeleopCommand {
//!     mode: TeleopMode::WheelForward,
//!     body_height: BodyHeight::from_si(0.05).unwrap(),
//!     speed_scale: SpeedScale::from_si(80.0).unwrap(),
//!     speed: Default::default(),
//!     yaw_rate: Default::default(),
//! };
//! let mut teleop_tx = Sender::new();
//! let frame = teleop_tx
//!     .seal(teleop_rx.session(), &AnyMessage::TeleopCommand(command))
//!     .unwrap();
//!
//! let accepted = controller_rx.receive(frame.id(), frame.data()).unwrap();
//! assert_eq!(accepted.message, AnyMessage::TeleopCommand(command));
//! // The same frame again is a replay: refused, and counted.
//! assert_eq!(
//!     controller_rx.receive(frame.id(), frame.data()),
//!     Err(DecodeError::Repeated { id: frame.id() })
//! );
//! assert_eq!(controller_rx.counters().total(), 1);
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

pub mod aes;
pub mod busload;
pub mod cmac;
mod codec;
pub mod dbc;
pub mod dlc;
pub mod e2e;
mod error;
mod frame;
mod id;
mod joints;
mod message;
pub mod motion_limits;
mod msg;
mod node;
mod receiver;
mod sender;
pub mod session;
pub mod signal;
mod units;
mod wire;

pub use codec::{decode, encode, EncodeError, Message};
pub use e2e::{Check, E2eChecker, E2eStatus, Protection};
pub use error::{DecodeError, RejectCause};
pub use frame::Frame;
pub use id::{IdSet, MessageId, MAX_STANDARD_ID};
pub use joints::{Joints, PerDrive};
pub use message::{decode_frame, protection_of, AnyMessage, Decoded, Layout};
pub use msg::*;
pub use node::{Drive, Leg, NodeId, JOINT_NAMES, LEG_JOINT_NAMES, WHEEL_NAMES};
pub use receiver::{Accepted, Receiver};
pub use sender::{classic_latch, Sender};
pub use session::{Key, KeyError, Session, TEST_KEY, WIRE_VERSION};
pub use units::*;
