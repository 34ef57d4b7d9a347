//! A CAN bus inside one process: every endpoint receives every frame the others send, in send
//! order. Deterministic when all endpoints run on one thread (lockstep tests); thread-safe, with
//! blocking receive, when they do not (teleop beside the simulator).

use std::collections::VecDeque;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use protocol::Frame;

use crate::bus::{Bus, BusError};

#[derive(Debug, Default)]
struct Shared {
    queues: Vec<VecDeque<Frame>>,
    /// Endpoints waiting in `recv`: a send wakes them, and costs no wake-up call without.
    waiting: usize,
}

/// The bus; [`InprocBus::endpoint`] attaches a node.
#[derive(Debug, Clone, Default)]
pub struct InprocBus {
    shared: Arc<(Mutex<Shared>, Condvar)>,
}

/// One node's attachment to an [`InprocBus`].
#[derive(Debug)]
pub struct InprocEndpoint {
    shared: Arc<(Mutex<Shared>, Condvar)>,
    /// Its receive queue; `None` for a node that only sends.
    index: Option<usize>,
}

impl InprocBus {
    /// An empty bus.
    pub fn new() -> Self {
        Self::default()
    }

    /// Attaches a new node; it receives frames sent from now on.
    pub fn endpoint(&self) -> InprocEndpoint {
        let mut shared = lock(&self.shared.0);
        shared.queues.push(VecDeque::new());
        InprocEndpoint {
            shared: Arc::clone(&self.shared),
            index: Some(shared.queues.len() - 1),
        }
    }

    /// Attaches a node that only sends (a scripted operator, a tool): it has no receive queue,
    /// so frames do not pile up for a reader that never comes. Its `recv` never returns a frame.
    pub fn transmitter(&self) -> InprocEndpoint {
        InprocEndpoint {
            shared: Arc::clone(&self.shared),
            index: None,
        }
    }
}

/// A poisoned lock only means another endpoint's thread panicked mid-send; the queues are still
/// consistent (every push is a single operation), so keep using them.
fn lock(mutex: &Mutex<Shared>) -> MutexGuard<'_, Shared> {
    mutex
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

impl InprocEndpoint {
    /// Queues `frames` for every other endpoint under one lock, waking only those waiting.
    fn deliver(&self, frames: &[Frame]) {
        let (mutex, ready) = &*self.shared;
        let mut shared = lock(mutex);
        for (i, queue) in shared.queues.iter_mut().enumerate() {
            if Some(i) != self.index {
                queue.extend(frames.iter().copied());
            }
        }
        if shared.waiting > 0 {
            ready.notify_all();
        }
    }
}

impl Bus for InprocEndpoint {
    fn send(&mut self, frame: &Frame) -> Result<(), BusError> {
        self.deliver(std::slice::from_ref(frame));
        Ok(())
    }

    fn send_all(&mut self, frames: &[Frame]) -> Result<(), BusError> {
        self.deliver(frames);
        Ok(())
    }

    fn recv(&mut self, timeout: Duration) -> Result<Option<Frame>, BusError> {
        let Some(index) = self.index else {
            std::thread::sleep(timeout);
            return Ok(None);
        };
        let (mutex, ready) = &*self.shared;
        let mut shared = lock(mutex);
        // The clock is read only when there is something to wait for.
        let mut deadline = None;
        loop {
            if let Some(frame) = shared.queues.get_mut(index).and_then(VecDeque::pop_front) {
                return Ok(Some(frame));
            }
            if timeout.is_zero() {
                return Ok(None);
            }
            let now = Instant::now();
            let until = *deadline.get_or_insert(now + timeout);
            if now >= until {
                return Ok(None);
            }
            shared.waiting += 1;
            shared = ready
                .wait_timeout(shared, until - now)
                .map(|(guard, _)| guard)
                .unwrap_or_else(|poisoned| poisoned.into_inner().0);
            shared.waiting -= 1;
        }
    }

    fn name(&self) -> &str {
        "inproc"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(id: u16, byte: u8) -> Frame {
        Frame::new(id, &[byte; 8]).unwrap()
    }

    #[test]
    fn others_receive_in_send_order_and_the_sender_does_not() {
        let bus = InprocBus::new();
        let mut a = bus.endpoint();
        let mut b = bus.endpoint();
        let mut c = bus.endpoint();
        a.send(&frame(0x101, 1)).unwrap();
        b.send(&frame(0x180, 2)).unwrap();
        a.send(&frame(0x100, 3)).unwrap();
        let none = Duration::ZERO;
        let got: Vec<_> = std::iter::from_fn(|| c.recv(none).unwrap()).collect();
        assert_eq!(got, [frame(0x101, 1), frame(0x180, 2), frame(0x100, 3)]);
        assert_eq!(b.recv(none).unwrap(), Some(frame(0x101, 1)));
        assert_eq!(b.recv(none).unwrap(), Some(frame(0x100, 3)));
        assert_eq!(b.recv(none).unwrap(), None);
        assert_eq!(a.recv(none).unwrap(), Some(frame(0x180, 2)));
        assert_eq!(a.recv(none).unwrap(), None);
    }

    #[test]
    fn a_transmitter_sends_to_all_and_keeps_nothing() {
        let bus = InprocBus::new();
        let mut rx = bus.endpoint();
        let mut tx = bus.transmitter();
        let mut other = bus.endpoint();
        other.send(&frame(0x101, 1)).unwrap();
        tx.send(&frame(0x200, 2)).unwrap();
        assert_eq!(rx.recv(Duration::ZERO).unwrap(), Some(frame(0x101, 1)));
        assert_eq!(rx.recv(Duration::ZERO).unwrap(), Some(frame(0x200, 2)));
        assert_eq!(tx.recv(Duration::ZERO).unwrap(), None);
        assert_eq!(lock(&bus.shared.0).queues.len(), 2);
    }

    #[test]
    fn receive_waits_for_another_thread() {
        let bus = InprocBus::new();
        let mut rx = bus.endpoint();
        let mut tx = bus.endpoint();
        let sender = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(20));
            tx.send(&frame(0x010, 7)).unwrap();
        });
        let got = rx.recv(Duration::from_secs(5)).unwrap();
        sender.join().unwrap();
        assert_eq!(got, Some(frame(0x010, 7)));
        assert_eq!(rx.recv(Duration::from_millis(10)).unwrap(), None);
    }
}
