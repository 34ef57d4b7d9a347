//! Why writing a telemetry output (the CSV, the plots) failed, naming the file concerned.

use std::io;
use std::path::PathBuf;

/// Why a telemetry output could not be written. Every variant that concerns a file names it.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OutputError {
    /// Creating, writing or flushing a file or directory failed.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// What the operating system said.
        #[source]
        source: io::Error,
    },
    /// The CSV writer failed while writing a record.
    #[error("cannot write the CSV file {path}: {source}")]
    Csv {
        /// The file.
        path: PathBuf,
        /// What the CSV writer said.
        #[source]
        source: csv::Error,
    },
    /// Drawing a plot or encoding it as PNG failed.
    #[error("cannot draw the plot {path}: {message}")]
    Plot {
        /// The PNG file.
        path: PathBuf,
        /// What the plotting library said.
        message: String,
    },
    /// The Foxglove SDK refused: the MCAP file (empty for the live server) and what it said.
    #[error("Foxglove output {path}: {message}")]
    Foxglove {
        /// The MCAP file, or empty for the live server.
        path: PathBuf,
        /// What failed.
        message: String,
    },
    /// There are no telemetry rows, so there is nothing to plot.
    #[error("no telemetry rows were recorded, so there is nothing to plot")]
    NoRows,
}
