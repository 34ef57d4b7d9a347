//! The node's service loop, written once for every target: frames in → [`Node::poll`] → frames
//! out, through any CAN port that implements `embedded-can`'s non-blocking [`Can`] trait with
//! the protocol's [`Frame`] as its frame type.
//!
//! The STM32 board's FDCAN, the processor-in-the-loop image's recorded bus, the host runner's
//! SocketCAN or in-process bus and the simulator's in-process controller are all such ports;
//! each only decides *when* to call [`receive`] and [`transmit`] (on its timer, on a SYNC, once
//! per simulated cycle) — what happens to a frame is decided here.
//!
//! A port hands out only frames this bus can carry (11-bit ids, CAN FD lengths: what
//! [`Frame`] can hold); it skips and counts anything else itself.

use embedded_can::nb::Can;
use protocol::{decode_frame, AnyMessage, Frame, MessageId};

use crate::control::controller::Output;
use crate::node::Node;
use crate::time::Tick;

/// How often one frame is offered to a port whose transmit queue is full before it is dropped
/// and counted. On the FDCAN each try is a register read, and a 64-byte frame takes ~140 µs on
/// the bus, so this waits out a few frames' worth of a busy bus and no more.
pub const TX_TRIES: u32 = 20_000;

/// Until when [`receive`] takes frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Drain {
    /// Until the port has none ([`nb::Error::WouldBlock`]) or the limit.
    All,
    /// As [`Drain::All`], but stop right after an accepted SYNC: in lockstep a SYNC closes the
    /// frames of its tick, and the tick it names is the one to compute next.
    ThroughSync,
}

/// What [`receive`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Received {
    /// Frames taken from the port.
    pub frames: u32,
    /// Of those, frames the node refused (counted by cause in [`Node::reject_counters`]).
    pub rejected: u32,
    /// The tick named by the last SYNC the node accepted, if one came.
    pub sync_tick: Option<u32>,
}

/// What [`transmit`] did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transmitted {
    /// The tick's output (commands, status).
    pub output: Output,
    /// Frames the port queued without losing another.
    pub sent: u32,
    /// Frames lost: one whose queue stayed full for [`TX_TRIES`] tries, or, for one the port
    /// queued in place of a lower-priority frame, the frame it displaced (either way one frame
    /// of this node does not reach the bus).
    pub dropped: u32,
}

/// Gives the frames waiting on `port` to `node` as frames of tick `now`: at most `limit` of
/// them (a bound for a flooded bus), fewer when the port runs dry or, with
/// [`Drain::ThroughSync`], after the first accepted SYNC. A port error ends the call; the
/// frames taken before it have been handled.
pub fn receive<P: Can<Frame = Frame>>(
    node: &mut Node,
    now: Tick,
    port: &mut P,
    drain: Drain,
    limit: u32,
) -> Result<Received, P::Error> {
    let mut received = Received::default();
    while received.frames < limit {
        let frame = match port.receive() {
            Ok(frame) => frame,
            Err(nb::Error::WouldBlock) => break,
            Err(nb::Error::Other(error)) => return Err(error),
        };
        received.frames = received.frames.saturating_add(1);
        if node.on_frame(now, frame.id(), frame.data()).is_err() {
            received.rejected = received.rejected.saturating_add(1);
            continue;
        }
        if let Some(tick) = sync_tick(&frame) {
            received.sync_tick = Some(tick);
            if drain == Drain::ThroughSync {
                break;
            }
        }
    }
    Ok(received)
}

/// Runs tick `now` on `node` and puts the frames due in it on `port`, highest priority first.
/// A port error ends the call after the frames before it went out.
pub fn transmit<P: Can<Frame = Frame>>(
    node: &mut Node,
    now: Tick,
    port: &mut P,
) -> Result<Transmitted, P::Error> {
    let (output, frames) = node.poll(now);
    let mut done = Transmitted {
        output,
        sent: 0,
        dropped: 0,
    };
    for frame in &frames {
        if offer(port, frame)? {
            done.sent = done.sent.saturating_add(1);
        } else {
            done.dropped = done.dropped.saturating_add(1);
        }
    }
    Ok(done)
}

/// Puts `frames` (e.g. [`Node::stop_frames`]) on `port`; returns how many it took.
pub fn send_all<P: Can<Frame = Frame>>(port: &mut P, frames: &[Frame]) -> Result<u32, P::Error> {
    let mut sent = 0_u32;
    for frame in frames {
        if offer(port, frame)? {
            sent = sent.saturating_add(1);
        }
    }
    Ok(sent)
}

/// Whether `port` took `frame` for good: `false` when its queue stayed full for [`TX_TRIES`]
/// tries, or when it took the frame in place of a queued one (that one is then lost).
fn offer<P: Can<Frame = Frame>>(port: &mut P, frame: &Frame) -> Result<bool, P::Error> {
    for _ in 0..TX_TRIES {
        match port.transmit(frame) {
            Ok(None) => return Ok(true),
            Ok(Some(_replaced)) => return Ok(false),
            Err(nb::Error::WouldBlock) => continue,
            Err(nb::Error::Other(error)) => return Err(error),
        }
    }
    Ok(false)
}

/// The tick a SYNC frame names (`None` for any other frame).
fn sync_tick(frame: &Frame) -> Option<u32> {
    if frame.id() != MessageId::Sync.raw() {
        return None;
    }
    match decode_frame(frame.id(), frame.data()).ok()?.message {
        AnyMessage::Sync(sync) => Some(sync.tick.raw()),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::indexing_slicing)]

    use super::*;
    use crate::config::Config;
    use core::convert::Infallible;
    use heapless::{Deque, Vec};
    use protocol::{Epoch, Sender, Session, Sync, TEST_KEY};

    /// The session of the node under test; the simulator's SYNC is sealed in it.
    const SESSION: Session = Session::owned(TEST_KEY, Epoch::new(1));

    fn node() -> Node {
        Node::new(Config::ROBOT, SESSION).unwrap()
    }

    /// A port over two queues; `full_for` tries answer "queue full" before it takes a frame.
    struct Queues {
        rx: Deque<Frame, 8>,
        tx: Vec<Frame, 8>,
        full_for: u32,
    }

    impl Can for Queues {
        type Frame = Frame;
        type Error = Infallible;

        fn transmit(&mut self, frame: &Frame) -> nb::Result<Option<Frame>, Infallible> {
            if self.full_for > 0 {
                self.full_for -= 1;
                return Err(nb::Error::WouldBlock);
            }
            self.tx.push(*frame).unwrap();
            Ok(None)
        }

        fn receive(&mut self) -> nb::Result<Frame, Infallible> {
            self.rx.pop_front().ok_or(nb::Error::WouldBlock)
        }
    }

    fn sync(tick: u32, sender: &mut Sender) -> Frame {
        let sync = AnyMessage::Sync(Sync {
            tick: protocol::Tick::from_raw(tick).unwrap(),
        });
        sender.seal(&SESSION, &sync).unwrap()
    }

    fn queues(frames: &[Frame]) -> Queues {
        let mut rx = Deque::new();
        for frame in frames {
            rx.push_back(*frame).unwrap();
        }
        Queues {
            rx,
            tx: Vec::new(),
            full_for: 0,
        }
    }

    #[test]
    fn through_sync_stops_after_the_sync_and_names_its_tick() {
        let mut node = node();
        let mut sender = Sender::new();
        let frames = [sync(7, &mut sender), sync(8, &mut sender)];
        let mut port = queues(&frames);
        let rx = receive(&mut node, Tick(0), &mut port, Drain::ThroughSync, 8).unwrap();
        assert_eq!((rx.frames, rx.rejected, rx.sync_tick), (1, 0, Some(7)));
        let rx = receive(&mut node, Tick(0), &mut port, Drain::All, 8).unwrap();
        assert_eq!((rx.frames, rx.sync_tick), (1, Some(8)));
        let rx = receive(&mut node, Tick(0), &mut port, Drain::All, 8).unwrap();
        assert_eq!(rx, Received::default());
    }

    #[test]
    fn a_refused_sync_is_counted_and_ticks_nothing() {
        let mut node = node();
        let mut sender = Sender::new();
        let good = sync(3, &mut sender);
        let mut data = [0_u8; 64];
        let len = good.data().len();
        data[..len].copy_from_slice(good.data());
        data[0] ^= 0xFF;
        let corrupted = Frame::new(good.id(), &data[..len]).unwrap();
        let mut port = queues(&[corrupted]);
        let rx = receive(&mut node, Tick(0), &mut port, Drain::ThroughSync, 8).unwrap();
        assert_eq!((rx.frames, rx.rejected, rx.sync_tick), (1, 1, None));
    }

    #[test]
    fn the_limit_bounds_a_flood() {
        let mut node = node();
        let mut sender = Sender::new();
        let frames: [Frame; 5] = core::array::from_fn(|k| sync(k as u32, &mut sender));
        let mut port = queues(&frames);
        let rx = receive(&mut node, Tick(0), &mut port, Drain::All, 2).unwrap();
        assert_eq!((rx.frames, rx.sync_tick), (2, Some(1)));
    }

    #[test]
    fn send_all_counts_the_frames_the_port_took() {
        let mut node = node();
        let stop = node.stop_frames();
        let mut port = queues(&[]);
        assert_eq!(send_all(&mut port, &stop).unwrap(), stop.len() as u32);
        assert_eq!(port.tx.as_slice(), stop.as_slice());
        let mut full = queues(&[]);
        full.full_for = TX_TRIES;
        assert_eq!(
            send_all(&mut full, &stop).unwrap(),
            stop.len() as u32 - 1,
            "the first waits out every try"
        );
    }

    #[test]
    fn transmit_sends_the_tick_s_frames_and_counts_a_full_queue() {
        let mut node = node();
        let mut port = queues(&[]);
        let done = transmit(&mut node, Tick(0), &mut port).unwrap();
        assert!(done.sent >= 2, "tick 0 sends at least legs and wheels");
        assert_eq!((done.dropped, port.tx.len()), (0, done.sent as usize));
        let mut full = queues(&[]);
        full.full_for = TX_TRIES;
        let done = transmit(&mut node, Tick(1), &mut full).unwrap();
        assert_eq!(done.dropped, 1, "the first frame waits out every try");
        assert_eq!(full.tx.len(), done.sent as usize);
    }
}
