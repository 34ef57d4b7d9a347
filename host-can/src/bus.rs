//! One CAN bus abstraction for every node on the host: the simulator, the host firmware runner,
//! teleop. Two implementations: [`crate::inproc_bus`] (deterministic, in one process) and
//! [`crate::socketcan_bus`] (Linux SocketCAN: `vcan0`, `can0`).
//!
//! Semantics follow SocketCAN's defaults: a node receives every frame the *other* nodes send,
//! in the order they were sent, and not its own.

use std::time::Duration;

use protocol::Frame;

/// Why a bus operation failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BusError {
    /// The named CAN interface does not exist.
    #[error(
        "CAN interface `{ifname}` does not exist. For a virtual bus run:\n  \
         sudo modprobe vcan && sudo ip link add {ifname} type vcan && sudo ip link set up {ifname}"
    )]
    NoSuchInterface {
        /// The interface asked for.
        ifname: String,
    },
    /// The interface exists but is down.
    #[error("CAN interface `{ifname}` is down: sudo ip link set up {ifname}")]
    InterfaceDown {
        /// The interface.
        ifname: String,
    },
    /// The interface cannot carry CAN FD frames (MTU 72).
    #[error(
        "CAN interface `{ifname}` does not carry CAN FD frames: sudo ip link set {ifname} mtu 72"
    )]
    NotFd {
        /// The interface.
        ifname: String,
    },
    /// The kernel has no SocketCAN support at all.
    #[error(
        "this kernel has no SocketCAN support (opening `{ifname}`: {source}); load it with \
         `sudo modprobe can can-raw vcan`"
    )]
    NoCanSupport {
        /// The interface.
        ifname: String,
        /// The OS error.
        source: std::io::Error,
    },
    /// The interface's transmit queue stayed full (`ENOBUFS`) for the whole send deadline.
    #[error(
        "CAN interface `{ifname}` took no frame for {waited:?}: its transmit queue stays full. Is \
         the bus off or unplugged? (`ip -details -statistics link show {ifname}`)"
    )]
    TxQueueFull {
        /// The interface.
        ifname: String,
        /// How long the send waited.
        waited: std::time::Duration,
    },
    /// Any other I/O error.
    #[error("CAN interface `{ifname}`: {source}")]
    Io {
        /// The interface.
        ifname: String,
        /// The OS error.
        source: std::io::Error,
    },
}

impl BusError {
    /// Whether the interface could not be opened at all (missing, or no CAN in the kernel):
    /// a program that also runs on the in-process bus may say so (`--bus inproc`).
    pub fn is_missing_interface(&self) -> bool {
        matches!(
            self,
            BusError::NoSuchInterface { .. } | BusError::NoCanSupport { .. }
        )
    }
}

/// A node's connection to a CAN bus.
pub trait Bus {
    /// Puts `frame` on the bus.
    fn send(&mut self, frame: &Frame) -> Result<(), BusError>;

    /// Puts `frames` on the bus in order, as one call where the bus can (SocketCAN:
    /// `sendmmsg`): a node that sends a cycle's frames together wakes its peers once, not
    /// once per frame. On an error the frames before it went out.
    fn send_all(&mut self, frames: &[Frame]) -> Result<(), BusError> {
        frames.iter().try_for_each(|frame| self.send(frame))
    }

    /// The next frame from another node, waiting at most `timeout` (zero: do not wait). `None`
    /// when nothing arrived in time. Frames that are not CAN FD data frames with an 11-bit id
    /// (error frames, remote frames, extended ids) are skipped and counted in
    /// [`Bus::foreign_frames`].
    fn recv(&mut self, timeout: Duration) -> Result<Option<Frame>, BusError>;

    /// How many received frames this project's protocol cannot represent (see [`Bus::recv`]).
    fn foreign_frames(&self) -> u64 {
        0
    }

    /// Marks the end of a control cycle for a node that sees no SYNC (a real-time simulator, a
    /// firmware on its own timer). Buses without a notion of cycles ignore it; the fault layer
    /// releases delayed frames by it ([`crate::faulty_bus`]).
    fn end_cycle(&mut self) -> Result<(), BusError> {
        Ok(())
    }

    /// A name for logs (`vcan0`, `inproc`).
    fn name(&self) -> &str;
}

/// A boxed bus is a bus, so that one code path can drive whichever bus the user chose.
impl<B: Bus + ?Sized> Bus for Box<B> {
    fn send(&mut self, frame: &Frame) -> Result<(), BusError> {
        (**self).send(frame)
    }

    fn send_all(&mut self, frames: &[Frame]) -> Result<(), BusError> {
        (**self).send_all(frames)
    }

    fn recv(&mut self, timeout: Duration) -> Result<Option<Frame>, BusError> {
        (**self).recv(timeout)
    }

    fn foreign_frames(&self) -> u64 {
        (**self).foreign_frames()
    }

    fn end_cycle(&mut self) -> Result<(), BusError> {
        (**self).end_cycle()
    }

    fn name(&self) -> &str {
        (**self).name()
    }
}
