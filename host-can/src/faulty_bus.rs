//! A [`Bus`] that breaks frames on purpose, between a node and its real bus (in-process or
//! SocketCAN), per a [`Faults`] plan: for fault-injection tests and for trying the robot on a
//! bad bus from the command line.
//!
//! Time is counted in control cycles: a cycle ends when a SYNC passes through the bus in either
//! direction (the simulator's clock), or when the owner calls [`Bus::end_cycle`] (a node
//! that sees no SYNC, such as a flooding teleop). Delays are in those cycles, and every random
//! choice comes from the plan's seed, so a lockstep run with faults is repeatable.
//!
//! Every fault is counted in [`FaultStats`], so a test can check that each corrupted,
//! duplicated or replayed frame was rejected by its receiver.

use std::collections::{BTreeMap, VecDeque};
use std::time::{Duration, Instant};

use protocol::e2e::HEADER_LEN;
use protocol::{decode_frame, protection_of, AnyMessage, Frame, Key, MessageId, Session, TEST_KEY};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};

use crate::bus::{Bus, BusError};
use crate::fault_plan::{faultable, FaultPlan, Faults};

/// Frames kept for replays.
const HISTORY: usize = 64;

/// What the faults did in one direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FaultStats {
    /// Frames that passed the layer (before faults).
    pub frames: u64,
    /// Dropped at random.
    pub dropped: u64,
    /// Dropped because their sender is silenced.
    pub silenced: u64,
    /// Held back by the delay (every frame when a delay is set).
    pub delayed: u64,
    /// Sent twice (a corrupted frame's copy counts as one more [`FaultStats::flipped`]).
    pub duplicated: u64,
    /// Held back behind the next frame.
    pub reordered: u64,
    /// Frames sent with one protected bit flipped.
    pub flipped: u64,
    /// Older frames sent again.
    pub replayed: u64,
    /// Extra TeleopCommand frames of a flood.
    pub flooded: u64,
}

/// One direction's faults: frames in, broken frames out.
#[derive(Debug)]
struct Injector {
    plan: FaultPlan,
    rng: SmallRng,
    /// Recent frames as they were before faults, newest last.
    history: VecDeque<Frame>,
    /// A frame held back behind the next one.
    held: Option<Frame>,
    /// Frames waiting for their cycle, in order.
    queue: VecDeque<(u64, Frame)>,
    /// Ids whose last frame was followed by a replay: the next replay waits for a genuine
    /// frame in between, or two old frames in a row would look like a restarted sender.
    replayed_last: Vec<u16>,
    flood_template: Option<AnyMessage>,
    flood_counter: Option<u32>,
    /// The session the flood's copies are sealed in: the one the node's bus announced.
    session: Session,
    /// With [`FaultPlan::burst_cycles`]: whether this cycle is inside a loss burst.
    in_burst: bool,
    stats: FaultStats,
    /// Per id: frames sent that any receiver must reject (flipped, duplicated, replayed).
    bad_by_id: BTreeMap<u16, u64>,
}

impl Injector {
    fn new(plan: FaultPlan, seed: u64) -> Self {
        Self {
            plan,
            rng: SmallRng::seed_from_u64(seed),
            history: VecDeque::with_capacity(HISTORY),
            held: None,
            queue: VecDeque::new(),
            replayed_last: Vec::new(),
            flood_template: None,
            flood_counter: None,
            session: Session::unjoined(TEST_KEY),
            in_burst: false,
            stats: FaultStats::default(),
            bad_by_id: BTreeMap::new(),
        }
    }

    fn chance(&mut self, p: f64) -> bool {
        p > 0.0 && self.rng.random_bool(p.min(1.0))
    }

    /// Takes one frame at `cycle`; what survives is queued for [`Injector::pop`].
    fn input(&mut self, frame: Frame, cycle: u64) {
        if !faultable(frame.id()) {
            self.queue.push_back((cycle, frame));
            return;
        }
        self.stats.frames += 1;
        let frame = self.flood_sequence(frame);
        let sender = MessageId::from_raw(frame.id()).map(MessageId::sender);
        if sender.is_some_and(|s| self.plan.silence.contains(&s)) {
            self.stats.silenced += 1;
            return;
        }
        let original = frame;
        self.remember(original);
        let lost = if self.plan.burst_cycles == 0 {
            self.chance(self.plan.drop)
        } else {
            self.in_burst
        };
        if lost {
            self.stats.dropped += 1;
            return;
        }
        let mut out = original;
        let flipped = self.chance(self.plan.flip);
        if flipped {
            out = self.flip(out);
        }
        let release = cycle + u64::from(self.plan.delay_cycles);
        if self.plan.delay_cycles > 0 {
            self.stats.delayed += 1;
        }
        if self.chance(self.plan.reorder) && self.held.is_none() {
            self.stats.reordered += 1;
            self.held = Some(out);
        } else {
            self.queue.push_back((release, out));
            if let Some(held) = self.held.take() {
                self.queue.push_back((release, held));
            }
        }
        let id = original.id();
        if out != original {
            self.count_bad(id);
        }
        if self.chance(self.plan.duplicate) {
            self.count_bad(id);
            // A copy of a corrupted frame is one more corrupted frame on the wire.
            if flipped && out != original {
                self.stats.flipped += 1;
            } else {
                self.stats.duplicated += 1;
            }
            self.queue.push_back((release, out));
        }
        let may_replay = !self.replayed_last.contains(&id);
        self.replayed_last.retain(|i| *i != id);
        if may_replay && self.chance(self.plan.replay) {
            if let Some(old) = self.older_frame(id) {
                self.stats.replayed += 1;
                self.count_bad(id);
                self.replayed_last.push(id);
                self.queue.push_back((release, old));
            }
        }
    }

    fn count_bad(&mut self, id: u16) {
        *self.bad_by_id.entry(id).or_default() += 1;
    }

    /// The first frame due at `cycle`, in queue order: a frame that is not delayed (SYNC, a
    /// flood) may overtake delayed ones.
    fn pop(&mut self, cycle: u64) -> Option<Frame> {
        let due = self
            .queue
            .iter()
            .position(|(release, _)| *release <= cycle)?;
        self.queue.remove(due).map(|(_, frame)| frame)
    }

    /// At the end of a cycle a held-back frame goes out: it waited behind everything this cycle.
    fn end_cycle(&mut self, cycle: u64) {
        if let Some(held) = self.held.take() {
            self.queue
                .push_back((cycle + u64::from(self.plan.delay_cycles), held));
        }
        self.next_burst_state();
    }

    /// The Gilbert–Elliott channel of [`FaultPlan::burst_cycles`]: a burst ends after each cycle
    /// with probability 1/N, so bursts last N cycles on average, and one starts with the
    /// probability that makes `drop` the long-run fraction of cycles inside one.
    fn next_burst_state(&mut self) {
        let p = self.plan.drop;
        if self.plan.burst_cycles == 0 || p <= 0.0 {
            return;
        }
        let n = f64::from(self.plan.burst_cycles);
        if self.in_burst {
            self.in_burst = !self.chance(1.0 / n);
        } else {
            let start = if p >= 1.0 { 1.0 } else { p / (n * (1.0 - p)) };
            self.in_burst = self.chance(start);
        }
    }

    fn remember(&mut self, frame: Frame) {
        if self.history.len() == HISTORY {
            self.history.pop_front();
        }
        self.history.push_back(frame);
    }

    /// An older frame of `id`, at least two of its frames back (one back would be a mere
    /// duplicate), chosen at random; `None` if there is none yet.
    fn older_frame(&mut self, id: u16) -> Option<Frame> {
        let same: Vec<Frame> = self
            .history
            .iter()
            .rev()
            .filter(|f| f.id() == id)
            .skip(2)
            .copied()
            .collect();
        if same.is_empty() {
            return None;
        }
        let pick = self.rng.random_range(0..same.len());
        same.get(pick).copied()
    }

    /// `frame` with one bit flipped inside the bytes its check value covers (the header and
    /// the covered payload), so that the flip is always detectable: a flip in the zero padding,
    /// or in an E-stop latch's token (its check covers action and source only), would not be.
    fn flip(&mut self, frame: Frame) -> Frame {
        let covered = MessageId::from_raw(frame.id())
            .map_or(frame.data().len(), |id| {
                HEADER_LEN + protection_of(id, frame.data()).1
            })
            .min(frame.data().len());
        if covered == 0 {
            return frame;
        }
        let mut data = frame.data().to_vec();
        let bit = self.rng.random_range(0..covered * 8);
        if let Some(byte) = data.get_mut(bit / 8) {
            *byte ^= 1 << (bit % 8);
        }
        match Frame::new(frame.id(), &data) {
            Some(flipped) => {
                self.stats.flipped += 1;
                flipped
            }
            None => frame,
        }
    }

    /// With a flood planned, the layer owns the TeleopCommand counter: the node's own commands
    /// and the flood's copies form one sequence, sealed with the node's key in the session the
    /// bus announced, as a babbling teleop's would.
    fn flood_sequence(&mut self, frame: Frame) -> Frame {
        if self.plan.flood_per_cycle == 0 || frame.id() != MessageId::TeleopCommand.raw() {
            return frame;
        }
        let Ok(decoded) = decode_frame(frame.id(), frame.data()) else {
            return frame;
        };
        let counter = self.flood_counter.get_or_insert(u32::from(decoded.counter));
        self.flood_template = Some(decoded.message);
        let sealed = decoded.message.encode(&self.session, *counter);
        *counter = counter.wrapping_add(1);
        sealed.unwrap_or(frame)
    }

    /// The flood's frames for one cycle.
    fn flood(&mut self, cycle: u64) {
        let (Some(message), Some(counter)) = (self.flood_template, self.flood_counter.as_mut())
        else {
            return;
        };
        for _ in 0..self.plan.flood_per_cycle {
            let sealed = message.encode(&self.session, *counter);
            *counter = counter.wrapping_add(1);
            if let Ok(frame) = sealed {
                self.stats.flooded += 1;
                self.queue.push_back((cycle, frame));
            }
        }
    }
}

/// A node's bus with faults in between. See the module docs.
#[derive(Debug)]
pub struct FaultyBus<B> {
    inner: B,
    tx: Injector,
    rx: Injector,
    cycle: u64,
    name: String,
    key: Key,
}

impl<B: Bus> FaultyBus<B> {
    /// `inner` with `faults` (a clean plan passes every frame untouched).
    pub fn new(inner: B, faults: &Faults) -> Self {
        let name = format!("{} (faults: {faults})", inner.name());
        Self {
            inner,
            tx: Injector::new(faults.tx.clone(), faults.seed),
            rx: Injector::new(faults.rx.clone(), faults.seed.wrapping_add(0x9E37_79B9)),
            cycle: 0,
            name,
            key: TEST_KEY,
        }
    }

    /// Seals the flood's copies with `key` (the test key by default).
    #[must_use]
    pub fn with_key(mut self, key: Key) -> Self {
        self.key = key;
        self
    }

    /// Follows the session the controller announces, for the flood's copies.
    fn observe(&mut self, frame: &Frame) {
        if frame.id() != MessageId::Announce.raw() {
            return;
        }
        if let Ok(decoded) = decode_frame(frame.id(), frame.data()) {
            if let AnyMessage::Announce(announce) = decoded.message {
                self.tx.session = Session::owned(self.key, announce.epoch);
            }
        }
    }

    /// Changes the plan from now on; frames already held back keep their release cycle, and the
    /// counts go on.
    pub fn set_faults(&mut self, faults: &Faults) {
        self.tx.plan = faults.tx.clone();
        self.rx.plan = faults.rx.clone();
    }

    /// What the faults did to sent frames.
    pub fn tx_stats(&self) -> FaultStats {
        self.tx.stats
    }

    /// What the faults did to received frames.
    pub fn rx_stats(&self) -> FaultStats {
        self.rx.stats
    }

    /// Frames on `raw_id` this node sent that every receiver of the id must reject: flipped,
    /// duplicated and replayed ones.
    pub fn tx_bad_frames(&self, raw_id: u16) -> u64 {
        self.tx.bad_by_id.get(&raw_id).copied().unwrap_or(0)
    }

    /// Frames on `raw_id` this node received flipped, duplicated or replayed (which it must
    /// reject).
    pub fn rx_bad_frames(&self, raw_id: u16) -> u64 {
        self.rx.bad_by_id.get(&raw_id).copied().unwrap_or(0)
    }

    /// Control cycles ended so far.
    pub fn cycle(&self) -> u64 {
        self.cycle
    }

    /// The bus underneath.
    pub fn inner_mut(&mut self) -> &mut B {
        &mut self.inner
    }

    fn close_cycle(&mut self) {
        self.tx.end_cycle(self.cycle);
        self.rx.end_cycle(self.cycle);
        self.cycle += 1;
    }

    fn flush_tx(&mut self) -> Result<(), BusError> {
        while let Some(frame) = self.tx.pop(self.cycle) {
            self.inner.send(&frame)?;
        }
        Ok(())
    }
}

impl<B: Bus> Bus for FaultyBus<B> {
    fn send(&mut self, frame: &Frame) -> Result<(), BusError> {
        if frame.id() == MessageId::Sync.raw() {
            // Everything of this cycle goes out before the SYNC that closes it.
            self.tx.end_cycle(self.cycle);
            self.flush_tx()?;
            self.inner.send(frame)?;
            self.rx.end_cycle(self.cycle);
            self.cycle += 1;
            return self.flush_tx();
        }
        self.tx.input(*frame, self.cycle);
        self.flush_tx()
    }

    fn recv(&mut self, timeout: Duration) -> Result<Option<Frame>, BusError> {
        // The clock is read only when there is something to wait for.
        let deadline = (!timeout.is_zero()).then(|| Instant::now() + timeout);
        loop {
            if let Some(frame) = self.rx.pop(self.cycle) {
                self.observe(&frame);
                if frame.id() == MessageId::Sync.raw() {
                    self.close_cycle();
                    self.flush_tx()?;
                }
                return Ok(Some(frame));
            }
            // Frames queued but not yet due do not count: wait for more, as long as asked.
            let left = deadline.map_or(Duration::ZERO, |d| {
                d.saturating_duration_since(Instant::now())
            });
            match self.inner.recv(left)? {
                Some(frame) => self.rx.input(frame, self.cycle),
                None => return Ok(None),
            }
        }
    }

    /// Ends a control cycle for a node that sees no SYNC: the flood's frames for this cycle go
    /// out, then held-back and delayed frames that are due.
    fn end_cycle(&mut self) -> Result<(), BusError> {
        self.tx.flood(self.cycle);
        self.close_cycle();
        self.flush_tx()
    }

    fn foreign_frames(&self) -> u64 {
        self.inner.foreign_frames()
    }

    fn name(&self) -> &str {
        &self.name
    }
}
