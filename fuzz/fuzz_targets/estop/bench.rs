//! The `estop` target's bench: the controller node under test with the nodes around it — the
//! operator (teleop), a tool on the bus (`cansend`, an E-stop panel), the plant's drives and
//! IMU, the simulator's SYNC, a forger without the key — the clock, and a record of the frames
//! delivered for replays. Every frame and every tick goes through the [`Oracle`].

use firmware::time::TickRate;
use firmware::{Config, Node, Tick};
use protocol::e2e::HEADER_LEN;
use protocol::{
    classic_latch, decode_frame, protection_of, AnyMessage, BodyHeight, EStop, Epoch, Frame, Key,
    MessageId, Millis, NodeId, ReleaseToken, Sender, Session, SpeedScale, Sync, TeleopCommand,
    TeleopHeartbeat, TeleopMode, TEST_KEY,
};

use crate::oracle::{Oracle, Origin};
use crate::plant::Plant;
use crate::script::{HEADER_LEN as SCRIPT_HEADER, RATES_HZ};

/// Most ticks one input computes: bounds the time of an execution (about 1.5 ms), and leaves
/// room for a motion, a latch and its SS1 deadline at 250 Hz and 100 Hz.
pub const MAX_POLLS: u32 = 1024;

/// Frames kept for replays (the most recent).
const KEPT: usize = 512;

/// The controller and everything around it.
pub struct Bench {
    config: Config,
    node: Node,
    oracle: Oracle,
    epoch: u32,
    teleop: Sender,
    tool: Sender,
    plant_tx: Sender,
    sim: Sender,
    forger: Sender,
    /// The tick frames are delivered at, and the next tick of the node's own clock.
    now: Tick,
    /// The tick last computed.
    last: Option<Tick>,
    polls: u32,
    /// The frames delivered (not replays), the latest [`KEPT`] of them, and how many in all.
    kept: Vec<Kept>,
    delivered: usize,
    /// A release held back, and the epoch it was sealed in.
    withheld: Option<(Frame, u32)>,
    /// Every token the node published.
    tokens: Vec<ReleaseToken>,
    plant: Plant,
    /// The operator's last command.
    last_command: Option<TeleopCommand>,
    /// Ticks between two rounds of the plant's and the operator's periodic frames (20 ms: half
    /// the feedback watchdog's timeout, the teleop's period), and the tick of the last round.
    period: u32,
    last_round: Option<Tick>,
    latches: u16,
}

impl Bench {
    /// The bench a script's header describes (see [`crate::script`]).
    pub fn new(header: &[u8; SCRIPT_HEADER]) -> Option<Bench> {
        let [setup, start, epoch] = *header;
        let hz = RATES_HZ[usize::from(setup & 0x7F) % RATES_HZ.len()];
        let config = Config::ROBOT.at_rate(TickRate::new(hz)?);
        let start = u32::from(start) * 4;
        let now = Tick(if setup & 0x80 != 0 {
            u32::MAX - start
        } else {
            start
        });
        let epoch = 1 + 257 * u32::from(epoch);
        let node = Node::new(config, Session::owned(TEST_KEY, Epoch::new(epoch))).ok()?;
        Some(Bench {
            config,
            oracle: Oracle::new(&node, epoch),
            tokens: vec![node.release_token()],
            node,
            epoch,
            teleop: Sender::new(),
            tool: Sender::new(),
            plant_tx: Sender::new(),
            sim: Sender::new(),
            forger: Sender::new(),
            now,
            last: None,
            polls: 0,
            kept: Vec::with_capacity(KEPT),
            delivered: 0,
            withheld: None,
            plant: Plant::SILENT,
            last_command: None,
            period: config.rate.ticks_from_ms(20).max(1),
            last_round: None,
            latches: 0,
        })
    }

    /// Whether the input has used its ticks.
    pub fn exhausted(&self) -> bool {
        self.polls >= MAX_POLLS
    }

    /// Hands `frame` to the node (through the oracle) and keeps it for replays.
    fn send(&mut self, frame: Frame, origin: Origin) {
        self.deliver_once(frame, origin);
        let kept = Kept {
            frame,
            sealed: match origin {
                Origin::Fresh { epoch } => Some(epoch),
                Origin::Forged | Origin::Replay => None,
            },
            heard: self.epoch,
        };
        if self.kept.len() < KEPT {
            self.kept.push(kept);
        } else if let Some(slot) = self.kept.get_mut(self.delivered % KEPT) {
            *slot = kept;
        }
        self.delivered += 1;
    }

    /// Hands `frame` to the node (through the oracle), and notes the token it publishes.
    fn deliver_once(&mut self, frame: Frame, origin: Origin) {
        let _ = self
            .oracle
            .deliver(&mut self.node, self.now, &frame, origin);
        let token = self.node.release_token();
        if self.tokens.last() != Some(&token) {
            self.tokens.push(token);
        }
    }

    /// `message` sealed fresh by `who` in the node's session, delivered.
    fn seal_and_send(&mut self, who: Who, message: &AnyMessage) {
        let session = *self.node.session();
        let sender = match who {
            Who::Teleop => &mut self.teleop,
            Who::Tool => &mut self.tool,
            Who::Plant => &mut self.plant_tx,
            Who::Sim => &mut self.sim,
        };
        if let Ok(frame) = sender.seal(&session, message) {
            self.send(frame, Origin::Fresh { epoch: self.epoch });
        }
    }

    /// Computes tick `at` (the plant's feedback and a SYNC naming it, if any, delivered
    /// before), and moves the clock after it.
    fn compute(&mut self, at: Tick, sync: bool) {
        // A round is due 20 ms after the last, or when the tick went back.
        if self
            .last_round
            .is_none_or(|last| at.since(last) >= self.period)
        {
            self.last_round = Some(at);
            self.feedback();
            self.operator();
        }
        if sync {
            let tick =
                protocol::Tick::from_raw(at.0).unwrap_or(protocol::Tick::saturating_from_si(0.0));
            self.seal_and_send(Who::Sim, &AnyMessage::Sync(Sync { tick }));
        }
        let output = self.oracle.poll(&mut self.node, at);
        self.plant.observe(&output);
        self.last = Some(at);
        self.now = at.plus(1);
        self.polls += 1;
    }

    /// `ticks` ticks of the node's own clock.
    pub fn ticks(&mut self, ticks: u32) {
        for _ in 0..ticks {
            if self.exhausted() {
                return;
            }
            self.compute(self.now, false);
        }
    }

    /// A SYNC naming the next tick: advancing, frozen, backward, or a jump (see the script).
    pub fn sync(&mut self, kind: u8, n: u8) {
        let last = self.last.unwrap_or(Tick(self.now.0.wrapping_sub(1)));
        let n = u32::from(n);
        let at = match kind % 4 {
            0 => last.plus(1 + n % 4),
            1 => last,
            2 => Tick(last.0.wrapping_sub(1 + n)),
            _ => last.plus(n * 4096),
        };
        self.compute(at, true);
    }

    /// The operator's periodic frames: its heartbeat, its last command repeated.
    fn operator(&mut self) {
        if self.plant.heartbeats {
            self.heartbeat();
        }
        if let Some(command) = self.last_command.filter(|_| self.plant.repeats) {
            self.seal_and_send(Who::Teleop, &AnyMessage::TeleopCommand(command));
        }
    }

    /// Sets what the plant reports every 20 ms, and what the operator sends every 20 ms.
    pub fn set_plant(&mut self, mode: u8, wheel: u8, pitch: u8) {
        self.plant.set(&self.config, mode, wheel, pitch);
    }

    /// One round of the plant's feedback.
    fn feedback(&mut self) {
        for message in self.plant.messages() {
            self.seal_and_send(Who::Plant, &message);
        }
    }

    /// A fresh operator command.
    pub fn command(&mut self, mode: u8, height: u8, speed: u8) {
        let command = TeleopCommand {
            mode: TeleopMode::from_raw(mode % 8).unwrap_or(TeleopMode::Stop),
            body_height: BodyHeight::saturating_from_si(f32::from(height as i8) * 1e-3),
            speed_scale: SpeedScale::saturating_from_si(f32::from(speed % 101)),
            speed: Default::default(),
            yaw_rate: Default::default(),
        };
        self.last_command = Some(command);
        self.seal_and_send(Who::Teleop, &AnyMessage::TeleopCommand(command));
    }

    /// A fresh operator heartbeat.
    pub fn heartbeat(&mut self) {
        let uptime = Millis::saturating_from_si(self.now.0 as f32);
        self.seal_and_send(
            Who::Teleop,
            &AnyMessage::TeleopHeartbeat(TeleopHeartbeat { uptime }),
        );
    }

    /// Any message the controller hears, read from `payload`, sealed fresh by its sender.
    pub fn message(&mut self, id: u8, payload: &[u8]) {
        let heard = MessageId::heard_by(NodeId::Controller);
        let ids: Vec<MessageId> = MessageId::ALL
            .into_iter()
            .filter(|i| heard.contains(*i))
            .collect();
        let Some(id) = ids.get(usize::from(id) % ids.len().max(1)).copied() else {
            return;
        };
        let mut data = vec![0_u8; id.layout().wire_len];
        for (slot, byte) in data.iter_mut().skip(HEADER_LEN).zip(payload) {
            *slot = *byte;
        }
        let Ok(decoded) = decode_frame(id.raw(), &data) else {
            return;
        };
        let who = match id {
            MessageId::EStop => Who::Tool,
            MessageId::TeleopCommand | MessageId::TeleopHeartbeat => Who::Teleop,
            MessageId::Sync => Who::Sim,
            _ => Who::Plant,
        };
        self.seal_and_send(who, &decoded.message);
    }

    /// An E-stop latch in one of its forms (see the script).
    pub fn latch(&mut self, form: u8) {
        self.latches = self.latches.wrapping_add(1);
        let frame = match form % 4 {
            0 => classic_latch(NodeId::Tool, self.latches),
            1 => classic_latch(NodeId::Teleop, self.latches),
            2 => {
                let latch = AnyMessage::EStop(EStop::latch(NodeId::Teleop));
                self.teleop.seal(&*self.node.session(), &latch).ok()
            }
            _ => AnyMessage::EStop(EStop::latch(NodeId::Tool))
                .encode(&Session::unjoined(TEST_KEY), u32::from(self.latches))
                .ok(),
        };
        if let Some(frame) = frame {
            self.send(frame, Origin::Fresh { epoch: self.epoch });
        }
    }

    /// A release of the published token sealed now by the teleop (`source` even) or a tool.
    fn fresh_release(&mut self, source: u8) -> Option<Frame> {
        let session = *self.node.session();
        let token = self.node.release_token();
        let (sender, node) = if source % 2 == 0 {
            (&mut self.teleop, NodeId::Teleop)
        } else {
            (&mut self.tool, NodeId::Tool)
        };
        sender
            .seal(&session, &AnyMessage::EStop(EStop::release(node, token)))
            .ok()
    }

    /// A fresh authenticated release of the published token.
    pub fn release(&mut self, source: u8) {
        if let Some(frame) = self.fresh_release(source) {
            self.send(frame, Origin::Fresh { epoch: self.epoch });
        }
    }

    /// A forged release (see the script).
    pub fn forge(&mut self, kind: u8, n: u8) {
        let current = self.node.release_token();
        let fresh = Origin::Fresh { epoch: self.epoch };
        let sealed = match kind % 5 {
            0 => {
                let wrong = ReleaseToken::new(current.raw().wrapping_add(1 + u16::from(n)));
                self.sealed_release(self.epoch, TEST_KEY, wrong)
                    .map(|f| (f, fresh))
            }
            1 => {
                let mut earlier = self.tokens.iter().rev().copied().filter(|t| *t != current);
                let stale = earlier
                    .nth(usize::from(n) % self.tokens.len())
                    .unwrap_or(current.next());
                self.sealed_release(self.epoch, TEST_KEY, stale)
                    .map(|f| (f, fresh))
            }
            2 => {
                let other = match self.epoch.checked_sub(1) {
                    Some(before) if n % 2 == 0 && before > 0 => before,
                    _ => self.epoch.saturating_add(1 + u32::from(n)),
                };
                let origin = Origin::Fresh { epoch: other };
                self.sealed_release(other, TEST_KEY, current)
                    .map(|f| (f, origin))
            }
            3 => {
                let key = Key([0x5A ^ n; 16]);
                self.sealed_release(self.epoch, key, current)
                    .map(|f| (f, Origin::Forged))
            }
            _ => self
                .fresh_release(1)
                .and_then(|frame| flip(&frame, n))
                .map(|f| (f, Origin::Forged)),
        };
        if let Some((frame, origin)) = sealed {
            self.send(frame, origin);
        }
    }

    /// A release of `token` from a tool sealed by the forger under `key` in `epoch`.
    fn sealed_release(&mut self, epoch: u32, key: Key, token: ReleaseToken) -> Option<Frame> {
        let session = Session::owned(key, Epoch::new(epoch)).at(self.node.session().time());
        let release = AnyMessage::EStop(EStop::release(NodeId::Tool, token));
        self.forger.seal(&session, &release).ok()
    }

    /// Seals a fresh release and holds it back.
    pub fn withhold(&mut self, source: u8) {
        self.withheld = self.fresh_release(source).map(|frame| (frame, self.epoch));
    }

    /// Delivers the release held back, for the first time.
    pub fn deliver(&mut self) {
        if let Some((frame, epoch)) = self.withheld.take() {
            self.send(frame, Origin::Fresh { epoch });
        }
    }

    /// Replays `count` consecutive frames delivered before, from the one `back` before the last.
    pub fn replay(&mut self, back: u8, count: u8) {
        let kept = self.kept.len();
        if kept == 0 {
            return;
        }
        let back = usize::from(back) % kept;
        for k in 0..usize::from(count).min(back + 1) {
            let index = (self.delivered - 1 - back + k) % KEPT;
            let epoch = self.epoch;
            let Some(kept) = self.kept.get_mut(index) else {
                continue;
            };
            // A frame sealed ahead for this session (a release sealed in a later epoch, then
            // restarts) that this session never heard is new to it, not a replay: the node
            // cannot tell it from one sealed now, and the oracle judges it as fresh.
            let origin = if kept.sealed == Some(epoch) && kept.heard != epoch {
                Origin::Fresh { epoch }
            } else {
                Origin::Replay
            };
            kept.heard = epoch;
            let frame = kept.frame;
            self.deliver_once(frame, origin);
        }
    }

    /// The controller restarts in the next epoch and restores its latch as firmware-host does
    /// (its state file: `Node::estop_latched` after every receive, `Node::restore_latch(Tick(0))`
    /// after the start); `kind` odd: its clock restarts at 0 (the wall-clock runner).
    pub fn restart(&mut self, kind: u8) {
        let latched = self.node.estop_latched();
        self.epoch = self.epoch.saturating_add(1);
        let session = Session::owned(TEST_KEY, Epoch::new(self.epoch));
        let Ok(mut node) = Node::new(self.config, session) else {
            return;
        };
        if latched {
            node.restore_latch(Tick(0));
        }
        if kind % 2 == 1 {
            self.now = Tick(0);
            self.last = None;
        }
        self.node = node;
        self.oracle.restart(&self.node, self.epoch);
        self.tokens.push(self.node.release_token());
    }
}

/// A frame delivered, kept for replays.
#[derive(Debug, Clone, Copy)]
struct Kept {
    frame: Frame,
    /// The epoch it was sealed in under the key, if it was.
    sealed: Option<u32>,
    /// The epoch of the session that last heard it.
    heard: u32,
}

/// Who seals a frame.
#[derive(Debug, Clone, Copy)]
enum Who {
    Teleop,
    Tool,
    Plant,
    Sim,
}

/// `frame` with bit `n` (modulo those its check covers) flipped.
fn flip(frame: &Frame, n: u8) -> Option<Frame> {
    let mut data = frame.data().to_vec();
    let id = MessageId::from_raw(frame.id())?;
    let (_, covered) = protection_of(id, &data);
    let bits = (HEADER_LEN + covered).min(data.len()) * 8;
    let bit = usize::from(n) % bits.max(1);
    *data.get_mut(bit / 8)? ^= 1 << (bit % 8);
    Frame::new(frame.id(), &data)
}
