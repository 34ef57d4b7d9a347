//! The firmware on a host: the CAN adapters every host program shares — one [`bus::Bus`]
//! trait, an in-process bus and SocketCAN — and the runner that puts the firmware's control
//! core on a bus (`firmware-host`, see `src/main.rs` and [`runner`]); and [`faulty_bus`], which
//! breaks frames on purpose between a node and its bus, for fault-injection tests.

#![deny(missing_docs, clippy::unwrap_used, clippy::expect_used, clippy::panic)]
#![cfg_attr(test, allow(clippy::unwrap_used, clippy::expect_used, clippy::panic))]

pub mod bus;
pub mod fault_plan;
pub mod faulty_bus;
pub mod inproc_bus;
pub mod logging;
pub mod runner;
pub mod socketcan_bus;
