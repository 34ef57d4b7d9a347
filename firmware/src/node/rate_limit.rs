//! A per-tick budget: at most so many events are served between two control ticks.
//!
//! A babbling node can put thousands of valid frames on the bus every second (10 000 frames/s
//! is 40 per 4 ms tick). Handing each to the controller would let it spend its period on one
//! sender. The budget bounds that work: the first `per_tick` events of a tick are served, the
//! rest are refused (and counted by the caller), and the next tick starts afresh.

/// How many events are left to serve in the present tick.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TickBudget {
    per_tick: u8,
    left: u8,
}

impl TickBudget {
    /// A full budget of `per_tick` events per tick.
    pub const fn new(per_tick: u8) -> Self {
        Self {
            per_tick,
            left: per_tick,
        }
    }

    /// Takes one event from the budget: `true` if it may be served, `false` if this tick's
    /// budget is spent.
    pub fn take(&mut self) -> bool {
        match self.left.checked_sub(1) {
            Some(left) => {
                self.left = left;
                true
            }
            None => false,
        }
    }

    /// Starts a new tick with the full budget.
    pub fn refill(&mut self) {
        self.left = self.per_tick;
    }

    /// Events still to be served in this tick.
    pub const fn left(&self) -> u8 {
        self.left
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn serves_per_tick_events_then_refuses_until_refilled() {
        let mut budget = TickBudget::new(2);
        assert!(budget.take() && budget.take());
        assert!(!budget.take() && !budget.take());
        assert_eq!(budget.left(), 0);
        budget.refill();
        assert_eq!(budget.left(), 2);
        assert!(budget.take());
        // A refill does not accumulate what a quiet tick left over.
        budget.refill();
        budget.refill();
        assert_eq!(budget.left(), 2);
        let mut none = TickBudget::new(0);
        assert!(!none.take());
    }
}
