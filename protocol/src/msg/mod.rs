//! The messages of the bus, one per file. Each doc comment gives the byte layout after the
//! 6-byte E2E header (see [`e2e`](crate::e2e)); all integers are little-endian.

mod announce;
mod controller_status;
mod drive_status;
mod estop;
mod imu;
mod leg_feedback;
mod leg_targets;
mod range;
mod reject_counters;
mod sync;
mod teleop_command;
mod teleop_heartbeat;
mod wheel_command;
mod wheel_feedback;

pub use announce::Announce;
pub use controller_status::ControllerStatus;
pub use drive_status::DriveStatus;
pub use estop::{
    EStop, CLASSIC_LATCH_LEN, LATCH_CHECKED_LEN, LATCH_PROTECTION, RELEASE_PROTECTION,
};
pub use imu::Imu;
pub use leg_feedback::LegFeedback;
pub use leg_targets::LegTargets;
pub use range::Range;
pub use reject_counters::RejectCounters;
pub use sync::Sync;
pub use teleop_command::TeleopCommand;
pub use teleop_heartbeat::TeleopHeartbeat;
pub use wheel_command::WheelCommand;
pub use wheel_feedback::WheelFeedback;
