//! The controller as a CAN node: frames in, frames out, still sans-IO.
//!
//! [`Node::on_frame`] runs every received frame through the protocol's
//! [`Receiver`] — check value (CRC-32C or CMAC) in the session, counter, decode — so that nothing rejected
//! reaches the controller, and every rejection is counted by cause. Two guards sit between the
//! receiver and the controller:
//!
//! - a per-tick budget of [`TELEOP_COMMANDS_PER_TICK`] operator commands, so that a babbling
//!   teleop node cannot take the controller's period; the excess is refused and counted as
//!   [`RejectCause::RateLimited`](protocol::RejectCause::RateLimited);
//! - the [`LinkMonitor`], which measures the inbound loss from the E2E sequence gaps and, when
//!   the bus loses too much, has the controller stop ([`Controller::set_link_degraded`]).
//!
//! [`Node::poll`] runs one control tick and encodes the frames due in it, following the
//! protocol's bus schedule ([`protocol::busload::SCHEDULE`]): wheel torques every tick, leg
//! targets at up to 250 Hz, status at 50 Hz, the reject counters at 10 Hz.

pub mod link;
pub mod persist;
pub mod rate_limit;
pub mod service;

use heapless::Vec;
use protocol::busload::slot_of;
use protocol::{
    Angle, Announce, AnyMessage, BodyHeight, ControllerStatus, DecodeError, DriveEnable, EStop,
    EStopAction, Frame, IdSet, LegTargets, MessageId, NodeId, Receiver, RejectCounters,
    ReleaseToken, Sender, Session, SessionTime, Torque, WheelCommand, WireVersion,
};

use crate::config::Config;
use crate::control::controller::{ConfigError, Controller, Output};
use crate::control::fsm::State;
use crate::time::Tick;
use link::LinkMonitor;
use rate_limit::TickBudget;

/// The identifiers the controller acts on: its acceptance filter.
const HEARD: IdSet = MessageId::heard_by(NodeId::Controller);
/// Most operator commands ([`MessageId::TeleopCommand`]) handed to the controller per control
/// tick; more are refused as [`DecodeError::RateLimited`]. The teleop sends one every 20 ms and
/// one at once when a key changes it, so a genuine operator needs at most 2 in a tick at any
/// supported rate, while a node babbling 10 000 frames/s (40 per 4 ms tick) costs the
/// controller 2. E-stops are never limited (they must always act), nor are heartbeats (they only
/// feed a watchdog, and their flood costs nothing more than the receive check; the link
/// monitor leaves them out, see [`Node::on_frame`]).
pub const TELEOP_COMMANDS_PER_TICK: u8 = 2;

/// Most frames the node sends in one tick.
pub const MAX_FRAMES_PER_TICK: usize = 5;

/// Frames to put on the bus this tick, highest priority first.
pub type TickFrames = Vec<Frame, MAX_FRAMES_PER_TICK>;

/// The controller with its receive checks and its transmit schedule.
#[derive(Debug, Clone)]
pub struct Node {
    receiver: Receiver,
    teleop_budget: TickBudget,
    link: LinkMonitor,
    controller: Controller,
    sender: Sender,
    release_token: ReleaseToken,
    /// The source of the last latch accepted while latched.
    latch_source: Option<NodeId>,
    announced: bool,
    /// Ticks the session has run (only ever counted forward) and the tick they were counted to.
    session_ticks: u32,
    /// The tick the session time was last moved to.
    advanced: Option<Tick>,
    polled: Option<Tick>,
    encode_failures: u32,
}

impl Node {
    /// A node running `config` in `session`, the one this controller opens: its epoch must
    /// be greater than any this controller announced before (see [`protocol::session`]).
    /// The node announces it on its first tick.
    pub fn new(config: Config, session: Session) -> Result<Self, ConfigError> {
        let link = LinkMonitor::new(
            config.rate.ticks_from_ms(config.link_window_ms),
            config.link_degrade_permille,
            config.link_recover_permille,
        )
        .ok_or(ConfigError::LinkMonitor)?;
        Ok(Self {
            receiver: Receiver::owner(session),
            teleop_budget: TickBudget::new(TELEOP_COMMANDS_PER_TICK),
            link,
            controller: Controller::new(config)?,
            sender: Sender::new(),
            // Seeded from the epoch, so that a latch restored after a restart does not take the
            // token a release sent before the restart carried.
            release_token: ReleaseToken::new(
                session.epoch().map_or(0, |e| (e.raw() & 0xFFFF) as u16),
            ),
            latch_source: None,
            announced: false,
            session_ticks: 0,
            advanced: None,
            polled: None,
            encode_failures: 0,
        })
    }

    /// Latches the E-stop as a frame would, for a controller that restarts with a latch it
    /// persisted (the latched E-stop survives a restart; only a fresh release clears it).
    pub fn restore_latch(&mut self, now: Tick) {
        self.act(now, &AnyMessage::EStop(EStop::latch(NodeId::Controller)));
    }

    /// Whether the E-stop is latched: what a board persists so that it survives a restart.
    pub fn estop_latched(&self) -> bool {
        self.controller.state() == State::EStop
    }

    /// The session this node owns.
    pub fn session(&self) -> &Session {
        self.receiver.session()
    }

    /// The token a release of the present latch must echo (published in the status).
    pub fn release_token(&self) -> ReleaseToken {
        self.release_token
    }

    /// The controller inside.
    pub fn controller(&self) -> &Controller {
        &self.controller
    }

    /// The link monitor (its state and last measured loss).
    pub fn link(&self) -> &LinkMonitor {
        &self.link
    }

    /// Frames rejected so far, by cause, and frames lost in sequence.
    pub fn reject_counters(&self) -> &RejectCounters {
        self.receiver.counters()
    }

    /// Messages that failed to encode (none should: sizes are checked at compile time).
    pub fn encode_failures(&self) -> u32 {
        self.encode_failures
    }

    /// Takes one received frame. A rejected frame is counted and returned as the error; it
    /// never reaches the controller. Frames of identifiers the controller does not act on
    /// ([`MessageId::receivers`]) are ignored, as a hardware acceptance filter would drop them.
    ///
    /// An operator command beyond this tick's budget ([`TELEOP_COMMANDS_PER_TICK`]) has passed
    /// the receiver's checks — its counter keeps the sequence in step — but is refused as
    /// [`DecodeError::RateLimited`] and counted like any other rejection.
    ///
    /// The link monitor counts the frames handed to the controller except heartbeats, so that a
    /// flood cannot dilute the loss it measures: heartbeats are not limited, and a babbler's
    /// lossless 10 000 frames/s would otherwise hide a lossy bus (the genuine heartbeat is 50 of
    /// some 1 650 frames/s, so leaving it out costs the measure nothing). Commands are limited,
    /// so their flood adds at most 2 frames per tick: at 20 % loss the measure still reads about
    /// 15 % at 250 Hz and 12 % at 1 kHz.
    pub fn on_frame(&mut self, now: Tick, raw_id: u16, data: &[u8]) -> Result<(), DecodeError> {
        self.advance(now);
        // The acceptance filter: a frame with another node's identifier that the controller
        // does not act on (its own, say, replayed) passes by unchecked and uncounted; the nodes
        // that act on it check and count it.
        if MessageId::from_raw(raw_id).is_some_and(|id| !HEARD.contains(id)) {
            return Ok(());
        }
        let accepted = self.receiver.receive(raw_id, data)?;
        if matches!(accepted.message, AnyMessage::TeleopCommand(_)) && !self.teleop_budget.take() {
            return Err(self.refuse(DecodeError::RateLimited { id: raw_id }));
        }
        if let AnyMessage::EStop(EStop {
            action: EStopAction::Clear,
            token,
            ..
        }) = accepted.message
        {
            if !self.estop_latched() || token != self.release_token {
                return Err(self.refuse(DecodeError::StaleRelease { id: raw_id }));
            }
        }
        // Heartbeats (see above) and E-stops (their counters jump with the session time) are
        // not counted in the link's loss.
        if !matches!(
            accepted.message,
            AnyMessage::TeleopHeartbeat(_) | AnyMessage::EStop(_)
        ) {
            self.link.record(accepted.status);
        }
        self.act(now, &accepted.message);
        Ok(())
    }

    /// A new tick moves the session time (what every sender's counters start at and the
    /// receiver places them against) by the ticks counted since the previous one. It only
    /// ever moves forward: a tick that goes back (a restarted simulator's SYNC in lockstep)
    /// adds nothing, and counting resumes from it.
    fn advance(&mut self, now: Tick) {
        match self.advanced.replace(now) {
            Some(previous) if previous == now => return,
            Some(previous) => {
                let ahead = now.since(previous);
                if ahead < 1_u32 << 31_u32 {
                    self.session_ticks = self.session_ticks.saturating_add(ahead);
                }
            }
            None => {}
        }
        let ms = self
            .controller
            .config()
            .rate
            .ms_from_ticks(self.session_ticks);
        self.receiver.set_time(SessionTime::from_ms(ms));
    }

    /// Whether the session announcement goes out in tick `now`.
    fn announce_due(&self, now: Tick) -> bool {
        let hz = self.controller.config().rate.hz();
        !self.announced || slot_of(MessageId::Announce).is_some_and(|slot| slot.sends_in(now.0, hz))
    }

    fn refuse(&mut self, error: DecodeError) -> DecodeError {
        self.receiver.refuse(error);
        error
    }

    /// Hands an accepted message to the controller. A latch that latches the E-stop gets a new
    /// release token, and so does a latch from another source while latched (a second
    /// operator, a panel): a release sent before it answers the older latch and is refused, so
    /// a later E-stop is never undone by an earlier release. A source repeating its own latch
    /// (the teleop does until the controller confirms it) keeps the token; the teleop drops
    /// its own pending release when it latches again.
    fn act(&mut self, now: Tick, message: &AnyMessage) {
        let latched_before = self.estop_latched();
        self.controller.on_message(now, message);
        if let AnyMessage::EStop(EStop {
            action: EStopAction::Latch,
            source,
            ..
        }) = message
        {
            if !latched_before || self.latch_source != Some(*source) {
                self.release_token = self.release_token.next();
            }
            self.latch_source = Some(*source);
        }
    }

    /// Runs one control tick and returns its output and the frames due. The frames received
    /// until the next call get a fresh operator-command budget, and the link monitor's verdict
    /// reaches the controller before its step.
    ///
    /// A tick that does not come after the previous one (a lockstep SYNC that froze or went
    /// back) faults the controller with `SYNC_LOST` ([`Controller::set_clock_stalled`]).
    ///
    /// Inlined into the service loop: out of line (as the compiler chose once the controller
    /// grew), its output and frames went back through a frame of their own, a kilobyte of the
    /// MCU's stack and a tenth of the control step's instructions (`cargo xtask pil`).
    #[inline(always)]
    pub fn poll(&mut self, now: Tick) -> (Output, TickFrames) {
        let ahead = self.polled.map(|previous| now.since(previous));
        self.controller
            .set_clock_stalled(ahead.is_some_and(|ticks| ticks == 0 || ticks >= 1_u32 << 31_u32));
        self.polled = Some(now);
        self.advance(now);
        self.teleop_budget.refill();
        let degraded = self.link.update(now);
        self.controller.set_link_degraded(degraded);
        let output = self.controller.step(now);
        let hz = self.controller.config().rate.hz();
        let due = |id: MessageId| slot_of(id).is_some_and(|slot| slot.sends_in(now.0, hz));
        let mut frames = TickFrames::new();
        if self.announce_due(now) {
            self.announced = true;
            self.push(&mut frames, &self.announcement());
        }
        if due(MessageId::LegTargets) {
            let message = AnyMessage::LegTargets(LegTargets {
                enable: if output.legs_enabled {
                    DriveEnable::Enabled
                } else {
                    DriveEnable::Disabled
                },
                position: output.leg_targets_rad.map(Angle::saturating_from_si),
            });
            self.push(&mut frames, &message);
        }
        if due(MessageId::WheelCommand) {
            // The wheel drive is enabled with the legs: both go torque-free together.
            let message = AnyMessage::WheelCommand(WheelCommand {
                enable: if output.legs_enabled {
                    DriveEnable::Enabled
                } else {
                    DriveEnable::Disabled
                },
                torque: output.wheel_torque_nm.map(Torque::saturating_from_si),
            });
            self.push(&mut frames, &message);
        }
        if due(MessageId::ControllerStatus) {
            let status = output.status;
            let message = AnyMessage::ControllerStatus(ControllerStatus {
                mode: status.mode,
                faults: status.faults,
                tick: wire_tick(status.tick),
                body_height: BodyHeight::saturating_from_si(status.body_height_m),
                pitch: Angle::saturating_from_si(status.pitch_rad),
                roll: Angle::saturating_from_si(status.roll_rad),
                release_token: self.release_token,
            });
            self.push(&mut frames, &message);
        }
        if due(MessageId::RejectCounters) {
            let message = AnyMessage::RejectCounters(*self.receiver.counters());
            self.push(&mut frames, &message);
        }
        (output, frames)
    }

    /// The frames that stop every drive now — legs torque-free, zero wheel torque — in sequence
    /// with this node's earlier commands, for a controller that is shutting down (the drives
    /// would otherwise wait out their command timeout).
    pub fn stop_frames(&mut self) -> TickFrames {
        let mut frames = TickFrames::new();
        let legs = AnyMessage::LegTargets(LegTargets {
            enable: DriveEnable::Disabled,
            position: self
                .controller
                .sensors()
                .joint_position_rad
                .map(Angle::saturating_from_si),
        });
        self.push(&mut frames, &legs);
        let wheels = AnyMessage::WheelCommand(WheelCommand {
            enable: DriveEnable::Disabled,
            torque: [Torque::saturating_from_si(0.0); 2],
        });
        self.push(&mut frames, &wheels);
        frames
    }

    /// The session announcement sealed for the bus, for a runner that announces while it
    /// waits for its first tick (in lockstep the node ticks only on SYNC, and the simulator
    /// sends no SYNC before it has joined the session).
    pub fn announce_frame(&mut self) -> Option<Frame> {
        let message = self.announcement();
        self.sender.seal(self.receiver.session(), &message).ok()
    }

    /// The session announcement: wire version and this controller's epoch.
    pub fn announcement(&self) -> AnyMessage {
        AnyMessage::Announce(Announce {
            version: WireVersion::THIS,
            epoch: self
                .receiver
                .session()
                .epoch()
                .unwrap_or(protocol::Epoch::new(0)),
            time: self.receiver.session().time(),
        })
    }

    fn push(&mut self, frames: &mut TickFrames, message: &AnyMessage) {
        match self.sender.seal(self.receiver.session(), message) {
            Ok(frame) => {
                if frames.push(frame).is_err() {
                    self.encode_failures = self.encode_failures.saturating_add(1);
                }
            }
            Err(_) => self.encode_failures = self.encode_failures.saturating_add(1),
        }
    }
}

/// The tick on the wire: the full `u32` range is valid, so this never saturates.
fn wire_tick(tick: Tick) -> protocol::Tick {
    protocol::Tick::from_raw(tick.0).unwrap_or(protocol::Tick::saturating_from_si(0.0))
}
