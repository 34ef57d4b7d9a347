//! Why writing a telemetry output (the CSV, the plots, the MCAP, the animation) failed, naming
//! the file concerned.

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
    /// The model has no body the robot's transforms can hang from.
    #[error("the model has no body named `{body}`: the Foxglove transforms hang from it (the robot's free-joint body)")]
    NoRootBody {
        /// The body looked for.
        body: &'static str,
    },
    /// The MCAP file could not be created, written or closed.
    #[error("cannot write the MCAP file {path}: {source}")]
    Mcap {
        /// The file.
        path: PathBuf,
        /// What the Foxglove SDK said.
        #[source]
        source: foxglove::FoxgloveError,
    },
    /// The model has more coordinates than the Foxglove log's samples hold.
    #[error("the model has {coordinates} position coordinates; the Foxglove log holds at most {max} (a scene with fewer free bodies, or run without an output folder and without --foxglove-port)")]
    TooManyCoordinates {
        /// The model's `nq`.
        coordinates: usize,
        /// What a sample holds.
        max: usize,
    },
    /// The live Foxglove server could not start.
    #[error("cannot serve Foxglove on 127.0.0.1:{port}: {source} (is the port taken? give another with --foxglove-port, or 0 for any)")]
    LiveServer {
        /// The port asked for.
        port: u16,
        /// What the Foxglove SDK said.
        #[source]
        source: foxglove::FoxgloveError,
    },
    /// A Foxglove channel could not be made.
    #[error("cannot make the Foxglove channel {topic}: {source}")]
    Channel {
        /// Its topic.
        topic: String,
        /// What the Foxglove SDK said.
        #[source]
        source: foxglove::FoxgloveError,
    },
    /// Encoding the animation failed.
    #[error("cannot write the animation {path}: {source}")]
    Gif {
        /// The GIF file.
        path: PathBuf,
        /// What the encoder said.
        #[source]
        source: gif::EncodingError,
    },
    /// A frame handed to the animation is not the size it was made for.
    #[error("a frame of {bytes} bytes for the animation {path} is not {width} × {height} RGB")]
    FrameSize {
        /// The GIF file.
        path: PathBuf,
        /// Bytes given.
        bytes: usize,
        /// Width expected, px.
        width: u32,
        /// Height expected, px.
        height: u32,
    },
    /// There are no telemetry rows, so there is nothing to plot.
    #[error("no telemetry rows were recorded, so there is nothing to plot")]
    NoRows,
}
