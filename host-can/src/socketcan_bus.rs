//! The bus over Linux SocketCAN (`vcan0`, `can0`), through the `socketcan` crate, in CAN FD mode.
//! Classic CAN data frames are accepted too (a `cansend 123#…` from a shell); error, remote and
//! extended-id frames are counted as foreign and skipped.

use std::path::Path;
use std::time::{Duration, Instant};

use std::io::IoSlice;
use std::os::fd::{AsFd, AsRawFd, RawFd};

use nix::errno::Errno;
use nix::poll::{poll, PollFd, PollFlags, PollTimeout};
use nix::sys::socket::{recv, sendmmsg, MsgFlags, MultiHeaders};
use socketcan::{CanFdSocket, CanFilter, Socket, SocketOptions};

use protocol::Frame;

use crate::bus::{Bus, BusError};
use crate::kernel_frame::{self, FD_BYTES};

/// A node on a SocketCAN interface.
#[derive(Debug)]
pub struct SocketCanBus {
    socket: CanFdSocket,
    ifname: String,
    foreign: u64,
}

impl SocketCanBus {
    /// Opens `ifname` for CAN FD frames. A missing, down or classic-only interface is a
    /// [`BusError`] that says how to fix it.
    pub fn open(ifname: &str) -> Result<Self, BusError> {
        let sys = Path::new("/sys/class/net").join(ifname);
        if !sys.exists() {
            return Err(BusError::NoSuchInterface {
                ifname: ifname.to_owned(),
            });
        }
        let read = |file: &str| std::fs::read_to_string(sys.join(file)).unwrap_or_default();
        // 16 = classic CAN only; 72 = CAN FD.
        if read("mtu").trim() == "16" {
            return Err(BusError::NotFd {
                ifname: ifname.to_owned(),
            });
        }
        if !read("flags").trim().is_empty() {
            let flags =
                u32::from_str_radix(read("flags").trim().trim_start_matches("0x"), 16).unwrap_or(1);
            // IFF_UP
            if flags & 1 == 0 {
                return Err(BusError::InterfaceDown {
                    ifname: ifname.to_owned(),
                });
            }
        }
        let socket = CanFdSocket::open(ifname).map_err(|source| classify(ifname, source))?;
        reserve_receive_buffer(&socket, ifname);
        Ok(Self {
            socket,
            ifname: ifname.to_owned(),
            foreign: 0,
        })
    }

    /// This node, hearing only the standard identifiers `ids` (the kernel drops the rest before
    /// they reach the socket): for a node that sends much and listens to little, such as the
    /// scripted operator inside `sim-host`, which needs only the controller's announcement and
    /// status and would otherwise read every frame of the bus each cycle.
    pub fn only(self, ids: &[u16]) -> Result<Self, BusError> {
        /// Identifier bits, and the extended-frame and remote-request flags: an exact match
        /// on a standard data frame.
        const EXACT: u32 = 0xC000_07FF;
        let filters: Vec<CanFilter> = ids
            .iter()
            .map(|&id| CanFilter::new(u32::from(id), EXACT))
            .collect();
        self.socket
            .set_filters(&filters)
            .map_err(|source| classify(&self.ifname, source))?;
        Ok(self)
    }
}

/// Receive buffer asked of the kernel, bytes. A host process can be descheduled for tens of
/// milliseconds, and every frame that arrives meanwhile must wait in the socket: at the 10 000
/// frames/s of a flood a 100 ms stall is 1 000 frames, each of which costs the kernel about 1 KiB
/// of buffer. The default (`net.core.rmem_default`, some 200 KiB) would drop frames from every
/// node, the drives' feedback included; 4 MiB holds some 400 ms of such a flood.
pub const RECEIVE_BUFFER_BYTES: usize = 4 << 20;

/// Asks for [`RECEIVE_BUFFER_BYTES`]; the kernel caps the request at `net.core.rmem_max`, and a
/// smaller buffer is only a warning (the node still works, it loses frames sooner in a stall).
fn reserve_receive_buffer(socket: &CanFdSocket, ifname: &str) {
    let raw = socket.as_raw_socket();
    let _ = raw.set_recv_buffer_size(RECEIVE_BUFFER_BYTES);
    // Linux reports twice the size it was asked for, the bookkeeping included.
    let granted = raw.recv_buffer_size().unwrap_or(0) / 2;
    if granted < RECEIVE_BUFFER_BYTES {
        tracing::warn!(
            ifname,
            granted,
            wanted = RECEIVE_BUFFER_BYTES,
            "small socket receive buffer: a stall under heavy traffic will drop frames; \
             raise the cap with `sudo sysctl -w net.core.rmem_max={}`",
            RECEIVE_BUFFER_BYTES
        );
    }
}

// Linux errno values (x86_64 and arm share them).
const ENODEV: i32 = 19;
const EPROTONOSUPPORT: i32 = 93;
const EAFNOSUPPORT: i32 = 97;
const ENETDOWN: i32 = 100;
const ENOBUFS: i32 = 105;

fn classify(ifname: &str, source: std::io::Error) -> BusError {
    let ifname = ifname.to_owned();
    match source.raw_os_error() {
        Some(ENODEV) => BusError::NoSuchInterface { ifname },
        Some(EAFNOSUPPORT | EPROTONOSUPPORT) => BusError::NoCanSupport { ifname, source },
        Some(ENETDOWN) => BusError::InterfaceDown { ifname },
        _ => BusError::Io { ifname, source },
    }
}

/// Longest a frame waits for room in the interface's transmit queue (`ENOBUFS`) before `send`
/// gives up: a queue that stays full this long belongs to a bus that is off, unplugged or
/// starved, and a caller blocked here could not even hear Ctrl-C.
pub const SEND_DEADLINE: Duration = Duration::from_millis(100);

/// Calls `write` until it succeeds, fails with anything but `ENOBUFS`, or `deadline` has
/// passed since the first call (then the last `ENOBUFS` error is returned), sleeping 100 µs
/// between tries.
pub fn write_within(
    deadline: Duration,
    mut write: impl FnMut() -> std::io::Result<()>,
) -> std::io::Result<()> {
    let start = Instant::now();
    loop {
        match write() {
            Err(e) if e.raw_os_error() == Some(ENOBUFS) && start.elapsed() < deadline => {
                std::thread::sleep(Duration::from_micros(100));
            }
            other => return other,
        }
    }
}

impl Bus for SocketCanBus {
    fn send(&mut self, frame: &Frame) -> Result<(), BusError> {
        self.send_all(std::slice::from_ref(frame))
    }

    fn send_all(&mut self, frames: &[Frame]) -> Result<(), BusError> {
        let records: Vec<[u8; FD_BYTES]> = frames.iter().map(kernel_frame::encode_fd).collect();
        let fd = self.socket.as_raw_fd();
        let mut left = records.as_slice();
        let result = write_within(SEND_DEADLINE, || {
            while !left.is_empty() {
                let sent = send_batch(fd, left)?;
                left = left.get(sent..).unwrap_or_default();
            }
            Ok(())
        });
        result.map_err(|e| {
            if e.raw_os_error() == Some(ENOBUFS) {
                BusError::TxQueueFull {
                    ifname: self.ifname.clone(),
                    waited: SEND_DEADLINE,
                }
            } else {
                classify(&self.ifname, e)
            }
        })
    }

    fn recv(&mut self, timeout: Duration) -> Result<Option<Frame>, BusError> {
        // One deadline for the whole call: skipping foreign frames or an interrupted wait does
        // not restart it, so a babbling foreign node cannot hold the caller here. A frame
        // already queued is taken without polling first (one system call, not two).
        let deadline = Instant::now() + timeout;
        loop {
            match self.read_queued()? {
                Read::Frame(frame) => return Ok(Some(frame)),
                Read::Foreign => {
                    self.foreign += 1;
                    continue;
                }
                Read::Empty => {}
            }
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Ok(None);
            }
            if !self.wait_readable(left)? {
                return Ok(None);
            }
        }
    }

    fn foreign_frames(&self) -> u64 {
        self.foreign
    }

    fn name(&self) -> &str {
        &self.ifname
    }
}

/// What one non-blocking read found.
enum Read {
    Frame(Frame),
    Foreign,
    Empty,
}

impl SocketCanBus {
    /// Takes one queued record without waiting.
    fn read_queued(&mut self) -> Result<Read, BusError> {
        let mut record = [0_u8; FD_BYTES];
        match recv(self.socket.as_raw_fd(), &mut record, MsgFlags::MSG_DONTWAIT) {
            Ok(len) => Ok(match kernel_frame::decode(&record, len) {
                Some(frame) => Read::Frame(frame),
                None => Read::Foreign,
            }),
            Err(Errno::EAGAIN | Errno::EINTR) => Ok(Read::Empty),
            Err(errno) => Err(classify(&self.ifname, errno.into())),
        }
    }

    /// Waits at most `left` for a record; whether one may be there (see [`wait_step`]).
    fn wait_readable(&self, left: Duration) -> Result<bool, BusError> {
        let timeout = match wait_step(left) {
            WaitStep::Sleep(wait) => {
                std::thread::sleep(wait);
                return Ok(true);
            }
            WaitStep::Poll(timeout) => timeout,
        };
        let mut fds = [PollFd::new(self.socket.as_fd(), PollFlags::POLLIN)];
        match poll(&mut fds, timeout) {
            Ok(ready) => Ok(ready > 0),
            Err(Errno::EINTR) => Ok(true),
            Err(errno) => Err(classify(&self.ifname, errno.into())),
        }
    }
}

/// How [`SocketCanBus::recv`] waits for a record with `left` to its deadline.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum WaitStep {
    /// Sleep this long, then look once more.
    Sleep(Duration),
    /// poll(2) the socket with this timeout.
    Poll(PollTimeout),
}

/// poll(2) counts whole milliseconds: a wait under one would poll with timeout 0, return at
/// once and poll again until the deadline, spinning a core. Such a wait sleeps instead (and
/// then says "look once more"); a longer one polls for its whole milliseconds, never past the
/// deadline, and the rest is again under a millisecond.
fn wait_step(left: Duration) -> WaitStep {
    if left < Duration::from_millis(1) {
        WaitStep::Sleep(left)
    } else {
        WaitStep::Poll(PollTimeout::try_from(left).unwrap_or(PollTimeout::MAX))
    }
}

/// Writes `records` with one `sendmmsg`; how many the kernel took (at least one, or an error).
fn send_batch(fd: RawFd, records: &[[u8; FD_BYTES]]) -> std::io::Result<usize> {
    let slices: Vec<[IoSlice<'_>; 1]> = records.iter().map(|r| [IoSlice::new(r)]).collect();
    let addresses: Vec<Option<()>> = vec![None; records.len()];
    let mut headers = MultiHeaders::<()>::preallocate(records.len(), None);
    let results = sendmmsg(fd, &mut headers, &slices, &addresses, [], MsgFlags::empty())?;
    Ok(results.count())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_interface_says_how_to_create_it() {
        let err = SocketCanBus::open("vcan-missing7").unwrap_err();
        assert!(matches!(err, BusError::NoSuchInterface { .. }), "{err:?}");
        let text = err.to_string();
        assert!(text.contains("sudo modprobe vcan"), "{text}");
        assert!(
            text.contains("ip link add vcan-missing7 type vcan"),
            "{text}"
        );
    }

    #[test]
    fn a_full_transmit_queue_gives_up_at_the_deadline() {
        let full = || Err(std::io::Error::from_raw_os_error(ENOBUFS));
        let started = Instant::now();
        let error = write_within(Duration::from_millis(30), full).unwrap_err();
        let waited = started.elapsed();
        assert_eq!(error.raw_os_error(), Some(ENOBUFS));
        assert!(waited >= Duration::from_millis(30), "{waited:?}");
        assert!(waited < Duration::from_secs(1), "{waited:?}");
        // A queue that drains after a few tries takes the frame.
        let mut tries = 0;
        let draining = || {
            tries += 1;
            if tries < 4 {
                Err(std::io::Error::from_raw_os_error(ENOBUFS))
            } else {
                Ok(())
            }
        };
        assert!(write_within(Duration::from_millis(30), draining).is_ok());
        // Any other error is returned at once.
        let started = Instant::now();
        let down = || Err(std::io::Error::from_raw_os_error(100));
        assert!(write_within(Duration::from_secs(10), down).is_err());
        assert!(started.elapsed() < Duration::from_secs(1));
    }

    /// How long a wait step takes when no record comes: a sleep its length, a poll its
    /// timeout.
    fn spent(step: WaitStep) -> Duration {
        match step {
            WaitStep::Sleep(wait) => wait,
            WaitStep::Poll(timeout) => timeout.duration().unwrap_or(Duration::MAX),
        }
    }

    /// Waits from a microsecond to far beyond poll(2)'s range, and around its millisecond.
    const WAITS: [Duration; 10] = [
        Duration::from_nanos(1),
        Duration::from_micros(1),
        Duration::from_micros(250),
        Duration::from_nanos(999_999),
        Duration::from_millis(1),
        Duration::from_micros(1_500),
        Duration::from_micros(2_999),
        Duration::from_millis(20),
        Duration::from_secs(3),
        Duration::from_secs(100_000_000),
    ];

    #[test]
    fn no_wait_polls_with_a_zero_timeout_or_past_its_deadline() {
        for left in WAITS {
            let step = wait_step(left);
            assert_ne!(step, WaitStep::Poll(PollTimeout::ZERO), "{left:?}");
            assert!(spent(step) > Duration::ZERO, "{left:?}: {step:?}");
            assert!(spent(step) <= left, "{left:?}: {step:?}");
        }
        assert_eq!(
            wait_step(Duration::from_micros(300)),
            WaitStep::Sleep(Duration::from_micros(300))
        );
    }

    /// `recv` on a socket that stays empty, on a clock that moves only by what the waits spend
    /// (a poll with timeout 0 returns at once and costs nothing): the deadline comes after a
    /// couple of waits. A wait that spends nothing would loop here, as it spun a core for real.
    #[test]
    fn a_receive_deadline_is_reached_in_two_waits_at_most_not_by_spinning() {
        for timeout in WAITS.iter().take(9) {
            let mut left = *timeout;
            let mut waits = 0;
            while !left.is_zero() {
                waits += 1;
                assert!(
                    waits <= 2,
                    "{timeout:?}: {waits} waits, {left:?} still left"
                );
                left -= spent(wait_step(left));
            }
        }
    }
}
