//! Why a session failed: one variant per part that can fail.

use host_can::bus::BusError;

use crate::output::output_error::OutputError;
use crate::robot::model::ModelError;
use crate::session::run_stats::RunError;

/// Why a session failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SessionError {
    /// The model.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The bus.
    #[error(transparent)]
    Bus(#[from] BusError),
    /// The run.
    #[error(transparent)]
    Run(#[from] RunError),
    /// An output file.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The control rate is not one the firmware runs at.
    #[error("the firmware cannot run at {0} Hz (it needs 1…10000 Hz)")]
    ControlRate(u32),
    /// The firmware's configuration was rejected.
    #[error("the firmware rejected its configuration: {0:?}")]
    Firmware(firmware::control::controller::ConfigError),
    /// A fault cell could not set up its scenario (a bug in the cell).
    #[error("a fault cell could not set up {0} (a bug in the fault matrix)")]
    Internal(&'static str),
    /// Rendering frames.
    #[cfg(feature = "renderer")]
    #[error(transparent)]
    Render(#[from] crate::output::render::RenderError),
    /// The viewer.
    #[cfg(feature = "viewer")]
    #[error(transparent)]
    Viewer(#[from] crate::output::viewer::ViewerError),
    /// The configuration asks for a feature this build leaves out.
    #[error("{what} needs sim-host built with `--features {feature}` (cargo run -p sim-host --features {feature} -- run …)")]
    NotBuilt {
        /// What was asked for.
        what: &'static str,
        /// The cargo feature it needs.
        feature: &'static str,
    },
}
