//! The firmware on a host: the runner that puts the firmware's control core on a CAN bus
//! (`firmware-host`, see `src/main.rs` and [`runner`]). The bus itself — SocketCAN, the
//! in-process bus, fault injection — comes from the `host-can` crate.

#![deny(missing_docs, clippy::unwrap_used, clippy::expect_used, clippy::panic)]
#![cfg_attr(test, allow(clippy::unwrap_used, clippy::expect_used, clippy::panic))]

pub mod runner;
