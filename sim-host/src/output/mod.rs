//! What a run leaves for its user: the [`telemetry`] rows and their [`telemetry_csv`] file;
//! the [`recorder`] that streams the bus to a candump log through the [`log_writer`] thread
//! (batches passed by [`handoff`]); the figures per segment ([`metrics`], [`summary`], the
//! obstacles' [`crossings`]); the [`plots`]; rendered frames ([`render`], feature
//! `renderer`) and their [`animation`]; the [`foxglove`] MCAP log and live server, and the
//! text logs [`export`]ed from it; the interactive [`viewer`] (feature `viewer`).
//! [`output_error`] names the file that failed.

pub mod animation;
pub mod crossings;
pub mod decimated;
pub mod export;
pub mod foxglove;
pub mod handoff;
pub mod log_writer;
pub mod metrics;
pub mod output_error;
pub mod plots;
pub mod recorder;
#[cfg(feature = "renderer")]
pub mod render;
pub mod summary;
pub mod telemetry;
pub mod telemetry_csv;
pub mod torques;
#[cfg(feature = "viewer")]
pub mod viewer;
