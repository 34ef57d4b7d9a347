//! Hardware-in-the-loop suite over SocketCAN `vcan`.
//!
//! The firmware and the simulator run as separate processes that share nothing but a kernel CAN
//! interface. The scenarios land with the vcan issue; this crate holds them.
