//! A fixed set of buffers going round between the simulation's thread and the log writer's:
//! full ones to the writer, emptied ones back. Nothing is allocated after [`Handoff::new`] —
//! not by a wait either (the standard channels grow a list of waiters the first time a thread
//! waits on one), so a lockstep cycle allocates nothing whichever side runs ahead.
//!
//! Either side hanging up (the recorder finishing, the writer stopping on an error or a panic)
//! wakes the other: neither waits for a peer that is gone.

use std::collections::VecDeque;
use std::sync::{Condvar, Mutex, MutexGuard, PoisonError};
use std::time::Duration;

/// The buffers and who is still there.
#[derive(Debug)]
struct State<T> {
    full: VecDeque<T>,
    empty: Vec<T>,
    /// The filling side hung up: the writer finishes what is queued and stops.
    filler_gone: bool,
    /// The writer stopped: nothing will come back.
    writer_gone: bool,
}

/// The exchange.
#[derive(Debug)]
pub struct Handoff<T> {
    state: Mutex<State<T>>,
    changed: Condvar,
}

/// What the writer gets when it asks for the next full buffer.
#[derive(Debug, PartialEq, Eq)]
pub enum Next<T> {
    /// A buffer to write out and give back.
    Full(T),
    /// None came within the wait.
    Timeout,
    /// The filling side hung up and everything is written.
    Finished,
}

impl<T> Handoff<T> {
    /// An exchange of `spares`, all empty to begin with: at least one, or the filling side
    /// waits until the writer stops.
    pub fn new(spares: Vec<T>) -> Self {
        let count = spares.len();
        let mut empty = Vec::with_capacity(count);
        empty.extend(spares);
        Self {
            state: Mutex::new(State {
                full: VecDeque::with_capacity(count + 1),
                empty,
                filler_gone: false,
                writer_gone: false,
            }),
            changed: Condvar::new(),
        }
    }

    fn lock(&self) -> MutexGuard<'_, State<T>> {
        // A panic on the other side leaves the buffers as they were: still usable.
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Queues `full` for the writer and returns an empty buffer, waiting for the writer to
    /// give one back if none is spare; `Err` with `full` back if the writer has stopped.
    pub fn exchange(&self, full: T) -> Result<T, T> {
        let mut state = self.lock();
        loop {
            if state.writer_gone {
                return Err(full);
            }
            // Every other buffer is queued or being written: one comes back.
            if let Some(empty) = state.empty.pop() {
                state.full.push_back(full);
                self.changed.notify_all();
                return Ok(empty);
            }
            state = self
                .changed
                .wait(state)
                .unwrap_or_else(PoisonError::into_inner);
        }
    }

    /// The filling side is done: the writer writes what is queued and then finishes.
    pub fn hang_up(&self) {
        self.lock().filler_gone = true;
        self.changed.notify_all();
    }

    /// The next full buffer, waiting up to `wait`.
    pub fn next(&self, wait: Duration) -> Next<T> {
        let mut state = self.lock();
        if state.full.is_empty() && !state.filler_gone {
            state = self
                .changed
                .wait_timeout_while(state, wait, |s| s.full.is_empty() && !s.filler_gone)
                .unwrap_or_else(PoisonError::into_inner)
                .0;
        }
        match state.full.pop_front() {
            Some(full) => Next::Full(full),
            None if state.filler_gone => Next::Finished,
            None => Next::Timeout,
        }
    }

    /// Gives back a buffer the writer has emptied.
    pub fn give_back(&self, empty: T) {
        self.lock().empty.push(empty);
        self.changed.notify_all();
    }

    /// The writer has stopped (done, failed or panicked): the filling side waits no more.
    pub fn writer_stopped(&self) {
        self.lock().writer_gone = true;
        self.changed.notify_all();
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;

    #[test]
    fn buffers_go_round_in_order_and_the_writer_finishes_after_the_last() {
        let handoff = Arc::new(Handoff::new(vec![Vec::new(), Vec::new()]));
        let writer = {
            let handoff = Arc::clone(&handoff);
            std::thread::spawn(move || {
                let mut seen = Vec::new();
                loop {
                    match handoff.next(Duration::from_millis(10)) {
                        Next::Full(mut batch) => {
                            seen.append(&mut batch);
                            handoff.give_back(batch);
                        }
                        Next::Timeout => {}
                        Next::Finished => return seen,
                    }
                }
            })
        };
        let mut batch = Vec::new();
        for n in 0..1000 {
            batch.push(n);
            if batch.len() == 7 {
                batch = handoff.exchange(batch).unwrap();
            }
        }
        batch = handoff.exchange(batch).unwrap();
        assert!(batch.is_empty());
        handoff.hang_up();
        assert_eq!(writer.join().unwrap(), (0..1000).collect::<Vec<_>>());
    }

    #[test]
    fn a_stopped_writer_hands_the_batch_back_instead_of_leaving_the_filler_waiting() {
        let handoff = Arc::new(Handoff::new(vec![Vec::new()]));
        assert_eq!(handoff.exchange(vec![1]), Ok(Vec::new()));
        let stopper = {
            let handoff = Arc::clone(&handoff);
            std::thread::spawn(move || {
                std::thread::sleep(Duration::from_millis(20));
                handoff.writer_stopped();
            })
        };
        // The only spare is queued and nothing is written: this waits until the writer stops,
        // then gets its batch back.
        assert_eq!(handoff.exchange(vec![2]), Err(vec![2]));
        stopper.join().unwrap();
        assert_eq!(handoff.exchange(vec![3]), Err(vec![3]));
    }

    #[test]
    fn the_writer_times_out_when_idle_and_finishes_when_hung_up() {
        let handoff = Handoff::new(vec![Vec::<u8>::new()]);
        assert_eq!(handoff.next(Duration::from_millis(1)), Next::Timeout);
        handoff.hang_up();
        assert_eq!(handoff.next(Duration::from_secs(10)), Next::Finished);
    }
}
