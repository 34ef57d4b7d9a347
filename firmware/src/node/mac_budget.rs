//! One CMAC per control tick: the authenticated frames a tick may verify or seal.
//!
//! A CMAC costs the Cortex-M4F about a thousand instructions per AES block. A tick verifies the
//! operator's frames and, at 50 Hz, seals the session announcement; left unbounded, a tick that
//! met a command, a heartbeat and the announcement at once would spend three, and a flood of
//! forged operator frames one each. So each tick has one: the announcement takes it when it is
//! due, otherwise the first authenticated frame of the tick; later ones wait in a short queue
//! for the next ticks (the operator sends two frames per 20 ms, the queue drains at one per
//! tick), and a frame that finds the queue full is refused and counted as rate-limited. E-stop
//! latches carry a CRC, not a CMAC, and are never held back.

use heapless::Deque;
use protocol::Frame;

/// Authenticated frames kept for later ticks.
pub const DEFERRED_MAX: usize = 4;

/// This tick's CMAC and the frames waiting for one.
#[derive(Debug, Clone)]
pub struct MacBudget {
    spent: bool,
    deferred: Deque<Frame, DEFERRED_MAX>,
}

impl Default for MacBudget {
    fn default() -> Self {
        Self::new()
    }
}

impl MacBudget {
    /// A whole budget and no frame waiting.
    pub const fn new() -> Self {
        Self {
            spent: false,
            deferred: Deque::new(),
        }
    }

    /// A new tick: its CMAC is free again.
    pub fn refill(&mut self) {
        self.spent = false;
    }

    /// Takes this tick's CMAC: `true` if it was still free.
    pub fn take(&mut self) -> bool {
        !core::mem::replace(&mut self.spent, true)
    }

    /// Keeps `frame` for a later tick; `false` if the queue is full.
    pub fn defer(&mut self, frame: Frame) -> bool {
        self.deferred.push_back(frame).is_ok()
    }

    /// The oldest frame waiting, if any.
    pub fn next_deferred(&mut self) -> Option<Frame> {
        self.deferred.pop_front()
    }

    /// Frames waiting.
    pub fn waiting(&self) -> usize {
        self.deferred.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_cmac_per_tick_and_the_rest_wait_in_order_up_to_the_queue() {
        let mut budget = MacBudget::new();
        assert!(budget.take());
        assert!(!budget.take(), "one per tick");
        let frames: [Frame; 5] =
            core::array::from_fn(|n| Frame::new(0x200, &[n as u8; 12]).unwrap());
        for frame in &frames[..DEFERRED_MAX] {
            assert!(budget.defer(*frame));
        }
        assert!(!budget.defer(frames[4]), "the queue is full");
        budget.refill();
        assert!(budget.take());
        assert_eq!(budget.next_deferred(), Some(frames[0]));
        assert_eq!(budget.waiting(), DEFERRED_MAX - 1);
    }
}
