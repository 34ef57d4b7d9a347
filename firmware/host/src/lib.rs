//! The firmware on a host: the runner that puts the firmware's control core on a CAN bus
//! (`firmware-host`, see `src/main.rs` and [`runner`]). The bus itself — SocketCAN, the
//! in-process bus, fault injection — comes from the `host-can` crate.
// Functions stay short enough to read whole (clippy.toml: 80 lines); tests may run longer.
#![cfg_attr(not(test), warn(clippy::too_many_lines))]
#![deny(missing_docs, clippy::unwrap_used, clippy::expect_used, clippy::panic)]
#![cfg_attr(test, allow(clippy::unwrap_used, clippy::expect_used, clippy::panic))]

pub mod runner;
pub mod state;
