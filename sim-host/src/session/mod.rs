//! The closed-loop session: the simulator, the bus it joins, the nodes beside it (the firmware
//! in-process, a scripted operator), one run from start to outputs.
//!
//! - [`config`]: what a run is asked to do; [`error`]: why it failed;
//! - [`simulator`]: the model and its emulated hardware, one control cycle at a time;
//! - [`inproc_controller`]: the firmware's control core on the in-process bus;
//! - [`run`]: one run (bus, clock, observers, outputs), with [`nodes`], [`segments`] and
//!   [`watch`] as its parts; [`run_stats`]: its counters; [`resident`]: its memory.

pub mod config;
pub mod error;
pub mod inproc_controller;
pub(crate) mod nodes;
pub mod resident;
pub mod run;
pub mod run_stats;
pub(crate) mod segments;
pub mod simulator;
pub(crate) mod watch;

pub use config::{
    firmware_config, Attach, BusChoice, Clock, FrameSettings, SegmentSpec, SessionConfig,
};
pub use error::SessionError;
pub use run::{run, SessionReport};
