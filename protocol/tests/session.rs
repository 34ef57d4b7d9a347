//! The bus session of wire version 2: replays from the same or an earlier session, frames
//! forged without the key, the announcement rules, the E-stop latch (classic and FD), burst
//! loss, the sender's counters and reading a key.

mod common;

use std::sync::OnceLock;

use common::{announce_frame, announce_frame_at, joined_member, member_at, owner_at};
use proptest::prelude::*;
use protocol::e2e::{HEADER_LEN, MAX_LAG_MS};
use protocol::*;

// ------------------------------------------------------------------------------------------
// A recorded bus.

/// Control ticks of the recorded run, one per millisecond of session time. The wheel command and
/// the wheel feedback go out every tick, so each of their ids carries more than 2^16 frames and
/// their low counters wrap.
const TICKS: u32 = 70_000;
/// The session the run is recorded in, and the one the controller opens when it restarts.
const OLD: Epoch = Epoch::new(1_000);
const NEW: Epoch = Epoch::new(1_001);
/// The E-stop panel's classic latch: one constant frame, counter and all.
const PANEL_COUNTER: u16 = 0x0BAD;

/// One frame of the recorded bus.
#[derive(Debug, Clone, Copy)]
struct Logged {
    frame: Frame,
    /// Who sent it.
    from: NodeId,
    /// The full counter its sender used.
    counter: u32,
    /// The session its sender was in (none for a panel's classic latch).
    epoch: Option<Epoch>,
}

impl Logged {
    fn id(&self) -> MessageId {
        MessageId::from_raw(self.frame.id()).unwrap()
    }

    fn is_latch(&self) -> bool {
        self.id() == MessageId::EStop && self.frame.data()[HEADER_LEN] == EStopAction::Latch.raw()
    }

    /// The refusal a check that does not hold gives this frame.
    fn check_failed(&self) -> DecodeError {
        check_failed(&self.frame)
    }
}

/// The refusal a check that does not hold gives `frame`: a CRC mismatch or, for a frame that
/// carries a CMAC, unauthentic.
fn check_failed(frame: &Frame) -> DecodeError {
    let id = frame.id();
    let check = protection_of(MessageId::from_raw(id).unwrap(), frame.data())
        .0
        .check;
    match check {
        Check::Crc => DecodeError::CrcMismatch { id },
        Check::Mac => DecodeError::Unauthentic { id },
    }
}

/// A node of the bus: what it receives with and what it sends with.
#[derive(Debug, Clone)]
struct Node {
    id: NodeId,
    rx: Receiver,
    tx: Sender,
    /// The session time of its first frame in the present session, where all its counters
    /// start.
    start: Option<u32>,
}

impl Node {
    fn member(id: NodeId) -> Node {
        Node {
            id,
            rx: Receiver::member(TEST_KEY),
            tx: Sender::new(),
            start: None,
        }
    }

    fn controller(epoch: Epoch) -> Node {
        Node {
            id: NodeId::Controller,
            rx: Receiver::owner(Session::owned(TEST_KEY, epoch)),
            tx: Sender::new(),
            start: None,
        }
    }
}

/// The controller, the teleop and the wheel drive (and whoever joins later) on one bus. Every
/// frame a node sends reaches every other node, which must accept it.
#[derive(Debug, Clone)]
struct Bus {
    nodes: Vec<Node>,
    /// The controller's session time, ms.
    time: u32,
    /// The next counter of each identifier in the present session (each has one sender), once
    /// it has sent on it.
    next: [Option<u32>; MessageId::ALL.len()],
    log: Vec<Logged>,
}

impl Bus {
    /// The controller opens `epoch` and announces it; the teleop and the wheel drive join.
    fn start(epoch: Epoch) -> Bus {
        let mut bus = Bus {
            nodes: vec![
                Node::controller(epoch),
                Node::member(NodeId::Teleop),
                Node::member(NodeId::WheelDrive),
            ],
            time: 0,
            next: [None; MessageId::ALL.len()],
            log: Vec::new(),
        };
        bus.announce();
        bus.assert_all_in(epoch);
        bus
    }

    /// The controller restarts into `epoch`: a new owner and sender at session time 0; the
    /// members hear the announcement and move.
    fn restart(&mut self, epoch: Epoch) {
        self.nodes[0] = Node::controller(epoch);
        for node in &mut self.nodes {
            node.start = None;
        }
        self.time = 0;
        self.next = [None; MessageId::ALL.len()];
        self.announce();
        self.assert_all_in(epoch);
    }

    /// A node joins a millisecond later: it hears the controller's next announcement.
    fn join(&mut self, id: NodeId) {
        self.nodes.push(Node::member(id));
        self.set_time(self.time + 1);
        self.announce();
        let epoch = self.nodes[0].rx.session().epoch();
        assert_eq!(self.nodes.last().unwrap().rx.session().epoch(), epoch);
    }

    /// The controller's clock reads `time`.
    fn set_time(&mut self, time: u32) {
        assert!(time >= self.time, "session time runs forward");
        self.time = time;
        self.nodes[0].rx.set_time(SessionTime::from_ms(time));
    }

    fn assert_all_in(&self, epoch: Epoch) {
        for node in &self.nodes {
            assert_eq!(node.rx.session().epoch(), Some(epoch), "{:?}", node.id);
        }
    }

    fn announce(&mut self) {
        let session = self.nodes[0].rx.session();
        assert_eq!(session.time().ms(), self.time);
        let announce = AnyMessage::Announce(Announce {
            version: WireVersion::THIS,
            epoch: session.epoch().unwrap(),
            time: session.time(),
        });
        self.send(NodeId::Controller, announce);
    }

    /// `from` seals `message` under its session and sends it.
    fn send(&mut self, from: NodeId, message: AnyMessage) {
        let node = self.nodes.iter_mut().find(|n| n.id == from).unwrap();
        let session = *node.rx.session();
        let frame = node.tx.seal(&session, &message).unwrap();
        let epoch = session.epoch();
        // A sender's counters all start at the session time of its first frame in the session
        // and count one per frame on each identifier; the E-stop's never falls behind the time,
        // and any other jumps to the time once it is more than `MAX_LAG_MS` behind it.
        let now = session.time().ms();
        let start = *node.start.get_or_insert(now);
        let slot = &mut self.next[message.id().index()];
        let mut counter = slot.unwrap_or(start);
        if message.id() == MessageId::EStop || counter + MAX_LAG_MS < now {
            counter = counter.max(now);
        }
        *slot = Some(counter + 1);
        assert_eq!(
            decode_frame(frame.id(), frame.data()).unwrap().counter,
            counter as u16,
            "the sender's counter on {:?}",
            message.id()
        );
        self.deliver(Logged {
            frame,
            from,
            counter,
            epoch,
        });
    }

    /// Puts a frame on the bus: every other node accepts it.
    fn deliver(&mut self, logged: Logged) {
        for node in self.nodes.iter_mut().filter(|n| n.id != logged.from) {
            let result = node.rx.receive(logged.frame.id(), logged.frame.data());
            assert!(
                result.is_ok(),
                "{:?} refused genuine {:?} (counter {}): {result:?}",
                node.id,
                logged.id(),
                logged.counter
            );
        }
        self.log.push(logged);
    }

    /// The robot's traffic of the next `ticks` control ticks, one a millisecond.
    fn run(&mut self, ticks: u32) {
        for t in self.time + 1..=self.time + ticks {
            self.tick(t);
        }
    }

    fn tick(&mut self, t: u32) {
        use NodeId::{Controller, Teleop, WheelDrive};
        self.set_time(t);
        let small = |x: u32| (x % 2000) as i16 - 1000;
        if t % 20 == 0 {
            self.announce();
        }
        self.send(
            Controller,
            AnyMessage::WheelCommand(WheelCommand {
                torque: [Torque::from_raw(small(t)).unwrap(); 2],
            }),
        );
        self.send(
            WheelDrive,
            AnyMessage::WheelFeedback(WheelFeedback {
                velocity: [WheelVelocity::from_raw(small(t * 3)).unwrap(); 2],
                effort: [Torque::from_raw(small(t)).unwrap(); 2],
            }),
        );
        if t % 4 == 1 {
            self.send(
                Controller,
                AnyMessage::LegTargets(LegTargets {
                    enable: DriveEnable::Enabled,
                    position: Joints::from_fn(|j| Angle::from_raw(small(t + j as u32)).unwrap()),
                }),
            );
        }
        if t % 20 == 7 {
            self.send(
                Teleop,
                AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
                    uptime: Millis::from_raw(t).unwrap(),
                }),
            );
        }
        if t % 20 == 11 {
            self.send(
                Controller,
                AnyMessage::ControllerStatus(ControllerStatus {
                    mode: ControllerMode::WheelForward,
                    faults: FaultFlags::EMPTY,
                    tick: Tick::from_raw(t).unwrap(),
                    body_height: BodyHeight::default(),
                    pitch: Angle::default(),
                    roll: Angle::default(),
                    release_token: ReleaseToken::new((t / 10_000) as u16),
                }),
            );
        }
        if t % 50 == 3 {
            self.send(
                Teleop,
                AnyMessage::TeleopCommand(TeleopCommand {
                    mode: TeleopMode::ALL[(t / 50) as usize % TeleopMode::ALL.len()],
                    body_height: BodyHeight::default(),
                    speed_scale: SpeedScale::from_raw(50).unwrap(),
                }),
            );
        }
        match t % 10_000 {
            5_000 => self.send(Teleop, AnyMessage::EStop(EStop::latch(Teleop))),
            5_001 => self.deliver(Logged {
                frame: classic_latch(NodeId::Tool, PANEL_COUNTER).unwrap(),
                from: NodeId::Tool,
                counter: u32::from(PANEL_COUNTER),
                epoch: None,
            }),
            5_100 => self.send(
                Teleop,
                AnyMessage::EStop(EStop::release(
                    Teleop,
                    ReleaseToken::new((t / 10_000) as u16),
                )),
            ),
            _ => {}
        }
    }
}

/// The recorded run and the bus at two points after it.
struct Recorded {
    /// Every frame of the run, in bus order.
    log: Vec<Logged>,
    /// The last counter of each identifier in the log, E-stop latches aside.
    last: [Option<u32>; MessageId::ALL.len()],
    /// The nodes right after the run: later in the session the log was recorded in.
    later: Bus,
    /// The same nodes after the controller restarted into a new session: the members moved,
    /// a node joined at the restart, 300 ticks of traffic ran, and one more node joined.
    next_session: Bus,
}

fn recorded() -> &'static Recorded {
    static RECORDED: OnceLock<Recorded> = OnceLock::new();
    RECORDED.get_or_init(|| {
        let mut bus = Bus::start(OLD);
        bus.run(TICKS);
        let log = std::mem::take(&mut bus.log);
        let mut last = [None; MessageId::ALL.len()];
        for logged in log.iter().filter(|l| !l.is_latch()) {
            last[logged.id().index()] = Some(logged.counter);
        }
        let later = bus.clone();

        bus.restart(NEW);
        bus.join(NodeId::LegDriveFl);
        bus.run(300);
        bus.join(NodeId::LegDriveFr);
        bus.log.clear();
        Recorded {
            log,
            last,
            later,
            next_session: bus,
        }
    })
}

/// The answer a node must give a frame of the log replayed after the whole run, in the same
/// session: it has heard every frame of the log not its own.
fn expected_later(logged: &Logged) -> Result<(), DecodeError> {
    if logged.is_latch() {
        return Ok(());
    }
    let id = logged.frame.id();
    let last = recorded().last[logged.id().index()].unwrap();
    if logged.id() == MessageId::Announce {
        // Announcements are ordered by their session time within the epoch. The latest one
        // again is taken and changes nothing (the controller repeats its announcement while
        // its clock stands); an earlier one is refused.
        let time = match decode_frame(id, logged.frame.data()).unwrap().message {
            AnyMessage::Announce(announce) => announce.time,
            other => panic!("{other:?}"),
        };
        let latest = recorded().later.nodes[1].rx.session().time();
        assert!(
            time <= latest,
            "fixture: the members heard every announcement"
        );
        return if time == latest {
            Ok(())
        } else {
            Err(DecodeError::WrongSequence { id })
        };
    }
    Err(match last - logged.counter {
        0 => DecodeError::Repeated { id },
        1..=0x8000 => DecodeError::WrongSequence { id },
        // From 2^15 + 1 frames back the low half places it ahead or on the last frame, at a
        // full counter it was not sealed with, and the search looks only ahead of the last.
        _ => logged.check_failed(),
    })
}

/// The answer a node of the new session must give a frame of the old one.
fn expected_next_session(logged: &Logged) -> Result<(), DecodeError> {
    if logged.is_latch() {
        Ok(())
    } else if logged.id() == MessageId::Announce {
        Err(DecodeError::StaleSession {
            id: logged.frame.id(),
        })
    } else {
        Err(logged.check_failed())
    }
}

/// Refusals by cause.
type Tally = [u32; RejectCause::ALL.len()];

/// Whether a node in `epoch` is given a replay of `logged`: every frame but those it sent
/// itself in that session (its receiver never tracked those, as the node does not consume
/// them).
fn hears(node: NodeId, epoch: Option<Epoch>, logged: &Logged) -> bool {
    logged.from != node || logged.epoch != epoch
}

/// Replays `frames` to every node of `bus` as [`hears`] says. Each answer must be the
/// expected one (a refusal, or for a latch and the latest announcement, an acceptance that
/// moves nothing); each refusal must be counted under its cause, and nothing counted as lost.
/// Returns the refusals by cause over all nodes.
fn replay(
    bus: &mut Bus,
    frames: &[Logged],
    expected: impl Fn(&Logged) -> Result<(), DecodeError>,
) -> Tally {
    let mut all: Tally = [0; RejectCause::ALL.len()];
    for node in &mut bus.nodes {
        let epoch = node.rx.session().epoch();
        let heard: Vec<&Logged> = frames.iter().filter(|l| hears(node.id, epoch, l)).collect();
        // In chunks, so that no 16-bit counter wraps between two readings.
        for chunk in heard.chunks(20_000) {
            let before = *node.rx.counters();
            let mut tally: Tally = [0; RejectCause::ALL.len()];
            let mut taken = 0;
            for logged in chunk {
                let session = *node.rx.session();
                let got = node.rx.receive(logged.frame.id(), logged.frame.data());
                match (got, expected(logged)) {
                    (Ok(accepted), Ok(())) => {
                        taken += 1;
                        assert_eq!(accepted.status, E2eStatus::Initial);
                        if logged.is_latch() {
                            assert!(matches!(
                                accepted.message,
                                AnyMessage::EStop(EStop {
                                    action: EStopAction::Latch,
                                    ..
                                })
                            ));
                        } else {
                            // The latest announcement again: nothing moves.
                            assert!(matches!(accepted.message, AnyMessage::Announce(_)));
                            assert_eq!(*node.rx.session(), session);
                        }
                    }
                    (Err(error), Err(want)) if error == want => {
                        tally[error.cause() as usize] += 1;
                    }
                    (got, want) => panic!(
                        "{:?} given a replay of {:?} (counter {}, from {:?}): {got:?}, \
                         expected {want:?}",
                        node.id,
                        logged.id(),
                        logged.counter,
                        logged.from
                    ),
                }
            }
            let after = node.rx.counters();
            for cause in RejectCause::ALL {
                let counted = after.get(cause).raw().wrapping_sub(before.get(cause).raw());
                assert_eq!(
                    u32::from(counted),
                    tally[cause as usize],
                    "{:?}: {cause:?}",
                    node.id
                );
            }
            let refused: u32 = tally.iter().sum();
            assert_eq!(refused as usize + taken, chunk.len());
            if before.total() + refused < u32::from(u16::MAX) {
                assert_eq!(after.total() - before.total(), refused, "{:?}", node.id);
            }
            assert_eq!(
                after.lost, before.lost,
                "{:?}: a replay is no loss",
                node.id
            );
            for (sum, n) in all.iter_mut().zip(tally) {
                *sum += n;
            }
        }
    }
    all
}

/// After a replay the genuine traffic goes on for `ticks` ticks: every node accepts every frame,
/// all in sequence (no loss counted, no refusal).
fn traffic_goes_on(bus: &mut Bus, ticks: u32) {
    let before: Vec<RejectCounters> = bus.nodes.iter().map(|n| *n.rx.counters()).collect();
    bus.run(ticks);
    for (node, before) in bus.nodes.iter().zip(before) {
        assert_eq!(*node.rx.counters(), before, "{:?}", node.id);
    }
}

#[test]
fn the_recorded_run_wraps_the_counter_and_carries_every_kind_of_frame() {
    let log = &recorded().log;
    let on = |id: MessageId| log.iter().filter(|l| l.id() == id).count();
    assert!(on(MessageId::WheelCommand) > 1 << 16);
    assert!(on(MessageId::WheelFeedback) > 1 << 16);
    for id in [
        MessageId::Announce,
        MessageId::LegTargets,
        MessageId::TeleopCommand,
        MessageId::TeleopHeartbeat,
        MessageId::ControllerStatus,
    ] {
        assert!(on(id) > 0, "{id:?}");
    }
    let latches = log.iter().filter(|l| l.is_latch()).count();
    assert_eq!(latches, 14, "7 sealed and 7 classic");
    assert_eq!(on(MessageId::EStop), 21, "and 7 releases");
    // The identifiers slower than one frame a millisecond fell `MAX_LAG_MS` behind the session
    // time and jumped to it, again and again; the 1 kHz ones never did.
    let jumps = |id: MessageId| {
        let counters: Vec<u32> = log
            .iter()
            .filter(|l| l.id() == id)
            .map(|l| l.counter)
            .collect();
        counters.windows(2).filter(|w| w[1] != w[0] + 1).count()
    };
    for id in [
        MessageId::LegTargets,
        MessageId::TeleopHeartbeat,
        MessageId::ControllerStatus,
        MessageId::TeleopCommand,
    ] {
        assert!(jumps(id) >= 2, "{id:?}: {}", jumps(id));
    }
    assert_eq!(jumps(MessageId::WheelCommand), 0);
    assert_eq!(jumps(MessageId::WheelFeedback), 0);
}

#[test]
fn the_whole_log_replayed_later_in_its_session_is_refused_but_for_the_latches() {
    // (And the latest announcement, which the members take again without effect.)
    let recorded = recorded();
    let mut bus = recorded.later.clone();
    let tally = replay(&mut bus, &recorded.log, expected_later);
    // Every way a replay in the same session fails occurred.
    for cause in [
        RejectCause::Repeated,
        RejectCause::WrongSequence,
        RejectCause::Crc,
        RejectCause::Unauthentic,
    ] {
        assert!(tally[cause as usize] > 0, "{cause:?}: {tally:?}");
    }
    assert_eq!(tally[RejectCause::Session as usize], 0);
    traffic_goes_on(&mut bus, 200);
}

#[test]
fn the_whole_log_replayed_in_a_new_session_is_refused_but_for_the_latches() {
    let recorded = recorded();
    let mut bus = recorded.next_session.clone();
    // Every node hears every frame of the old session: the one that joined last (no sequence
    // on any identifier) and each node its own identifiers too, which it has no sequence on.
    // A receiver with no sequence looks only near its session time (300 ms into the new
    // session): the old session's frames fail their check there, and everywhere else.
    let tally = replay(&mut bus, &recorded.log, expected_next_session);
    for cause in [
        RejectCause::Crc,
        RejectCause::Unauthentic,
        RejectCause::Session,
    ] {
        assert!(tally[cause as usize] > 0, "{cause:?}: {tally:?}");
    }
    assert_eq!(tally[RejectCause::Repeated as usize], 0);
    assert_eq!(tally[RejectCause::WrongSequence as usize], 0);
    traffic_goes_on(&mut bus, 200);
}

/// A pick of frames from the log: `at` places it, `len` frames long.
fn slice(at: prop::sample::Index, len: usize) -> &'static [Logged] {
    let log = &recorded().log;
    let start = at.index(log.len() - len + 1);
    &log[start..start + len]
}

/// Two consecutive frames of one identifier, as the old resynchronisation rule wanted.
fn consecutive_on_one_id(id: prop::sample::Index, at: prop::sample::Index) -> [Logged; 2] {
    let log = &recorded().log;
    let ids = [
        MessageId::Announce,
        MessageId::WheelCommand,
        MessageId::WheelFeedback,
        MessageId::LegTargets,
        MessageId::TeleopCommand,
        MessageId::TeleopHeartbeat,
        MessageId::ControllerStatus,
        MessageId::EStop,
    ];
    let id = ids[id.index(ids.len())];
    let on_id: Vec<&Logged> = log
        .iter()
        .filter(|l| l.id() == id && !l.is_latch())
        .collect();
    let i = at.index(on_id.len() - 1);
    [*on_id[i], *on_id[i + 1]]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn any_frame_replayed_later_in_its_session_is_refused(at in any::<prop::sample::Index>()) {
        let mut bus = recorded().later.clone();
        replay(&mut bus, slice(at, 1), expected_later);
        traffic_goes_on(&mut bus, 5);
    }

    #[test]
    fn any_frame_replayed_in_a_new_session_is_refused(at in any::<prop::sample::Index>()) {
        let mut bus = recorded().next_session.clone();
        replay(&mut bus, slice(at, 1), expected_next_session);
        traffic_goes_on(&mut bus, 5);
    }

    #[test]
    fn any_two_consecutive_frames_replayed_are_refused(
        at in any::<prop::sample::Index>(),
        id in any::<prop::sample::Index>(),
        on_id in any::<prop::sample::Index>(),
        twice in any::<bool>(),
    ) {
        let mut pairs = vec![slice(at, 2).to_vec(), consecutive_on_one_id(id, on_id).to_vec()];
        if twice {
            for pair in &mut pairs {
                pair.extend(pair.clone());
            }
        }
        for pair in &pairs {
            let mut bus = recorded().later.clone();
            replay(&mut bus, pair, expected_later);
            traffic_goes_on(&mut bus, 5);
            let mut bus = recorded().next_session.clone();
            replay(&mut bus, pair, expected_next_session);
            traffic_goes_on(&mut bus, 5);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn any_slice_of_the_log_replayed_is_refused(
        at in any::<prop::sample::Index>(),
        len in prop_oneof![3_usize..50, 50_usize..3_000],
    ) {
        let frames = slice(at, len);
        let mut bus = recorded().later.clone();
        replay(&mut bus, frames, expected_later);
        traffic_goes_on(&mut bus, 5);
        let mut bus = recorded().next_session.clone();
        replay(&mut bus, frames, expected_next_session);
        traffic_goes_on(&mut bus, 5);
    }
}

// ------------------------------------------------------------------------------------------
// Forgery.

/// `message` as an attacker without the key makes it for `epoch` and full counter `counter`:
/// the documented layout, the right counter, and a CRC-32C it computes itself over exactly
/// what the receiver's check covers (data id, epoch, full counter, payload).
fn forged(message: &AnyMessage, epoch: Epoch, counter: u32) -> Frame {
    // The layout is public: any key gives the right bytes after the check value.
    let template = message
        .encode(&Session::owned(Key([0; 16]), epoch), counter)
        .unwrap();
    let mut data = template.data().to_vec();
    let (protection, covered) = protection_of(message.id(), &data);
    let counter = if protection.sequenced {
        counter
    } else {
        counter & 0xFFFF
    };
    let mut fields = message.id().data_id().to_le_bytes().to_vec();
    let epoch = if protection.bound { epoch.raw() } else { 0 };
    fields.extend_from_slice(&epoch.to_le_bytes());
    fields.extend_from_slice(&counter.to_le_bytes());
    fields.extend_from_slice(&data[HEADER_LEN..HEADER_LEN + covered]);
    let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISCSI).checksum(&fields);
    data[..4].copy_from_slice(&crc.to_le_bytes());
    Frame::new(template.id(), &data).unwrap()
}

/// The messages that carry a CMAC and take part in a sequence (the operator's), each with the
/// controller's receiver and a member's.
fn authenticated_messages() -> Vec<(AnyMessage, fn() -> Receiver)> {
    let owner: fn() -> Receiver = || Receiver::owner(common::controller_session());
    let member: fn() -> Receiver = || joined_member(common::EPOCH);
    let messages = [
        AnyMessage::TeleopCommand(TeleopCommand {
            mode: TeleopMode::TrotForward,
            body_height: BodyHeight::default(),
            speed_scale: SpeedScale::from_raw(100).unwrap(),
        }),
        AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
            uptime: Millis::from_raw(99).unwrap(),
        }),
        AnyMessage::EStop(EStop::release(NodeId::Teleop, ReleaseToken::new(2))),
    ];
    let all: Vec<_> = messages
        .into_iter()
        .flat_map(|message| [(message, owner), (message, member)])
        .collect();
    for (message, _) in &all {
        let frame = message.encode(&common::controller_session(), 0).unwrap();
        assert_eq!(
            check_failed(&frame),
            DecodeError::Unauthentic { id: frame.id() }
        );
    }
    all
}

#[test]
fn a_command_forged_without_the_key_is_unauthentic_and_the_same_with_the_key_passes() {
    for (message, receiver) in authenticated_messages() {
        for counter in [0, 1, 1234] {
            let mut rx = receiver();
            let fake = forged(&message, common::EPOCH, counter);
            assert_eq!(
                rx.receive(fake.id(), fake.data()),
                Err(DecodeError::Unauthentic { id: fake.id() }),
                "{message:?}"
            );
            assert_eq!(rx.counters().get(RejectCause::Unauthentic).raw(), 1);
            assert_eq!(rx.counters().total(), 1);
            // With the key, the same message at the same counter: the forgery took nothing.
            let genuine = message
                .encode(&common::controller_session(), counter)
                .unwrap();
            assert_eq!(
                fake.data()[4..],
                genuine.data()[4..],
                "only the check differs"
            );
            let accepted = rx.receive(genuine.id(), genuine.data()).unwrap();
            assert_eq!(accepted.message, message);
            assert_eq!(accepted.status, E2eStatus::Initial);
        }
    }
}

#[test]
fn the_forger_computes_the_crc_right_a_crc_frame_it_forges_passes() {
    // The threat model: feedback and status carry a CRC, which anyone can compute. This pins
    // the forger above to the receiver's own computation, so that the refusals above come from
    // the missing key and not from a wrong CRC.
    let status = AnyMessage::DriveStatus(
        Drive::Wheel,
        DriveStatus {
            flags: DriveFlags::ENABLED,
            rejected: Count::ZERO,
            commands: Count::ZERO,
        },
    );
    let fake = forged(&status, common::EPOCH, 77);
    let genuine = status.encode(&common::controller_session(), 77).unwrap();
    assert_eq!(fake, genuine);
    // So do the drive commands, which carry a CRC (a CMAC is too dear for the drives at 1 kHz):
    // a forger on the bus can command the drives, though not replay the controller's frames.
    let command = AnyMessage::WheelCommand(WheelCommand {
        torque: [Torque::from_raw(-2500).unwrap(); 2],
    });
    let fake = forged(&command, common::EPOCH, 5);
    assert_eq!(
        fake,
        command.encode(&common::controller_session(), 5).unwrap()
    );
    let mut drive = joined_member(common::EPOCH);
    assert_eq!(receive(&mut drive, &fake).unwrap().message, command);
    let latch = AnyMessage::EStop(EStop::latch(NodeId::Tool));
    let mut rx = Receiver::member(TEST_KEY);
    let fake = forged(&latch, common::EPOCH, 5);
    assert!(
        rx.receive(fake.id(), fake.data()).is_ok(),
        "anyone may latch"
    );
}

#[test]
fn a_command_sealed_with_another_key_is_unauthentic() {
    let other = Session::owned(
        Key::from_hex("00112233445566778899aabbccddeeff").unwrap(),
        common::EPOCH,
    );
    for (message, receiver) in authenticated_messages() {
        let mut rx = receiver();
        let frame = message.encode(&other, 0).unwrap();
        assert_eq!(
            rx.receive(frame.id(), frame.data()),
            Err(DecodeError::Unauthentic { id: frame.id() }),
            "{message:?}"
        );
    }
}

#[test]
fn an_announcement_forged_without_the_key_opens_no_session() {
    let announce = AnyMessage::Announce(Announce {
        version: WireVersion::THIS,
        epoch: Epoch::new(u32::MAX),
        time: SessionTime::from_ms(u32::MAX),
    });
    for mut rx in [Receiver::member(TEST_KEY), joined_member(OLD)] {
        let epoch = rx.session().epoch();
        for frame in [
            forged(&announce, Epoch::new(0), 0),
            announce
                .encode(&Session::unjoined(Key([7; 16])), 0)
                .unwrap(),
        ] {
            assert_eq!(
                rx.receive(frame.id(), frame.data()),
                Err(DecodeError::Unauthentic { id: 0x020 })
            );
            assert_eq!(rx.session().epoch(), epoch, "not moved");
        }
    }
}

// ------------------------------------------------------------------------------------------
// Announcements.

fn wheel_command(counter: u32, epoch: Epoch) -> Frame {
    AnyMessage::WheelCommand(WheelCommand {
        torque: [Torque::from_raw(counter as i16).unwrap(); 2],
    })
    .encode(&Session::owned(TEST_KEY, epoch), counter)
    .unwrap()
}

fn receive(rx: &mut Receiver, frame: &Frame) -> Result<Accepted, DecodeError> {
    rx.receive(frame.id(), frame.data())
}

#[test]
fn a_member_joins_on_the_announcement() {
    let mut member = Receiver::member(TEST_KEY);
    let mut tx = Sender::new();
    assert_eq!(member.session().epoch(), None);
    // Before it: bound frames neither go out nor come in; the latch does both.
    let command = AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
        uptime: Millis::from_raw(1).unwrap(),
    });
    assert_eq!(
        tx.seal(member.session(), &command),
        Err(EncodeError::NoSession)
    );
    assert_eq!(
        receive(&mut member, &wheel_command(0, OLD)),
        Err(DecodeError::NoSession { id: 0x101 })
    );
    let latch = tx
        .seal(
            member.session(),
            &AnyMessage::EStop(EStop::latch(NodeId::Teleop)),
        )
        .unwrap();
    assert!(receive(&mut Receiver::member(TEST_KEY), &latch).is_ok());

    let announce = announce_frame(WireVersion::THIS, OLD, 3);
    let accepted = receive(&mut member, &announce).unwrap();
    assert_eq!(accepted.status, E2eStatus::Initial);
    assert_eq!(
        accepted.message,
        AnyMessage::Announce(Announce {
            version: WireVersion::THIS,
            epoch: OLD,
            time: SessionTime::from_ms(300),
        })
    );
    assert_eq!(member.session().epoch(), Some(OLD));
    assert_eq!(member.session().time(), SessionTime::from_ms(300));
    assert_eq!(*member.session().key(), TEST_KEY);
    assert_eq!(
        receive(&mut member, &wheel_command(0, OLD)).unwrap().status,
        E2eStatus::Initial
    );
    // Its first bound frame starts its counter on that id at the session time it joined at:
    // the refused attempt above used none.
    let frame = tx.seal(member.session(), &command).unwrap();
    assert_eq!(decode_frame(frame.id(), frame.data()).unwrap().counter, 300);
    let mut owner = owner_at(OLD, 320);
    assert_eq!(
        receive(&mut owner, &frame).unwrap().status,
        E2eStatus::Initial
    );
}

#[test]
fn a_greater_epoch_moves_the_member_and_restarts_every_counter() {
    let mut member = joined_member(OLD);
    let mut tx = Sender::new();
    for counter in 0..=5000 {
        receive(&mut member, &wheel_command(counter, OLD)).unwrap();
    }
    let heartbeat = AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
        uptime: Millis::from_raw(1).unwrap(),
    });
    for expected in 0..10 {
        let frame = tx.seal(member.session(), &heartbeat).unwrap();
        assert_eq!(
            decode_frame(frame.id(), frame.data()).unwrap().counter,
            expected
        );
    }

    // The restarted controller opens its session at time 0 and announces it; a member hears
    // the announcement 200 ms in.
    let announce = announce_frame(WireVersion::THIS, NEW, 2);
    assert!(receive(&mut member, &announce).is_ok());
    assert_eq!(member.session().epoch(), Some(NEW));
    assert_eq!(member.session().time(), SessionTime::from_ms(200));
    // The controller's counters started at its session time, 0, and the member follows.
    assert_eq!(
        receive(&mut member, &wheel_command(0, NEW)).unwrap().status,
        E2eStatus::Initial
    );
    assert_eq!(
        receive(&mut member, &wheel_command(1, NEW)).unwrap().status,
        E2eStatus::Ok
    );
    // The old session's frames, before and after the point the member had reached, are dead.
    for counter in [0, 1, 2, 4999, 5000, 5001, 5002] {
        assert_eq!(
            receive(&mut member, &wheel_command(counter, OLD)),
            Err(DecodeError::CrcMismatch { id: 0x101 }),
            "old-session counter {counter}"
        );
    }
    // The member's own sender starts again too, at the session time it is in.
    let frame = tx.seal(member.session(), &heartbeat).unwrap();
    assert_eq!(decode_frame(frame.id(), frame.data()).unwrap().counter, 200);
    let mut owner = owner_at(NEW, 230);
    assert_eq!(
        receive(&mut owner, &frame).unwrap().status,
        E2eStatus::Initial
    );
    assert_eq!(member.counters().get(RejectCause::Crc).raw(), 7);
    assert_eq!(member.counters().total(), 7);
}

#[test]
fn a_smaller_epoch_is_refused_as_stale() {
    let mut member = joined_member(NEW);
    receive(&mut member, &wheel_command(0, NEW)).unwrap();
    for counter in [0, 1, 7, 0xFFFF] {
        let old = announce_frame(WireVersion::THIS, OLD, counter);
        assert_eq!(
            receive(&mut member, &old),
            Err(DecodeError::StaleSession { id: 0x020 })
        );
    }
    assert_eq!(
        receive(
            &mut member,
            &announce_frame(WireVersion::THIS, Epoch::new(0), 0)
        ),
        Err(DecodeError::StaleSession { id: 0x020 })
    );
    assert_eq!(member.session().epoch(), Some(NEW));
    assert_eq!(member.counters().get(RejectCause::Session).raw(), 5);
    // The session goes on.
    assert_eq!(
        receive(&mut member, &wheel_command(1, NEW)).unwrap().status,
        E2eStatus::Ok
    );
    // The controller refuses an announcement of any session but its own.
    let mut owner = Receiver::owner(Session::owned(TEST_KEY, OLD));
    for epoch in [Epoch::new(OLD.raw() - 1), NEW] {
        let frame = announce_frame(WireVersion::THIS, epoch, 0);
        assert_eq!(
            receive(&mut owner, &frame),
            Err(DecodeError::StaleSession { id: 0x020 }),
            "{epoch:?}"
        );
        assert_eq!(owner.session().epoch(), Some(OLD));
    }
}

#[test]
fn an_announcement_of_the_same_epoch_replayed_is_refused() {
    let mut member = Receiver::member(TEST_KEY);
    let announces: Vec<Frame> = (0..5)
        .map(|counter| announce_frame(WireVersion::THIS, OLD, counter))
        .collect();
    for frame in &announces[..4] {
        assert!(receive(&mut member, frame).is_ok());
    }
    receive(&mut member, &wheel_command(0, OLD)).unwrap();
    // The latest again (as the controller repeats it while its clock stands) is taken and
    // moves nothing; the earlier ones are refused.
    assert!(receive(&mut member, &announces[3]).is_ok());
    assert_eq!(member.session().time(), SessionTime::from_ms(300));
    for frame in &announces[..3] {
        assert_eq!(
            receive(&mut member, frame),
            Err(DecodeError::WrongSequence { id: 0x020 })
        );
    }
    assert_eq!(member.counters().get(RejectCause::Repeated).raw(), 0);
    assert_eq!(member.counters().get(RejectCause::WrongSequence).raw(), 3);
    assert_eq!(member.counters().total(), 3);
    // The next genuine one is taken, a gap is no matter, and none of this reset the session.
    assert!(receive(&mut member, &announces[4]).is_ok());
    assert!(receive(&mut member, &announce_frame(WireVersion::THIS, OLD, 40)).is_ok());
    assert_eq!(
        receive(&mut member, &wheel_command(1, OLD)).unwrap().status,
        E2eStatus::Ok
    );
    assert_eq!(member.session().time(), SessionTime::from_ms(4000));
}

/// In its epoch a member orders announcements by their session time, not their counter: it
/// moves to a time after the last it heard, takes the same time again without effect (the
/// controller repeats its announcement while its clock stands), and refuses an earlier one.
#[test]
fn a_member_takes_an_announcement_only_with_a_later_time() {
    let at = |ms, counter| announce_frame_at(WireVersion::THIS, OLD, ms, counter);
    let mut member = member_at(OLD, 5_000);
    receive(&mut member, &wheel_command(4_990, OLD)).unwrap();
    // The same time under another counter is taken and moves nothing; an earlier time is
    // stale, whatever its counter.
    assert!(receive(&mut member, &at(5_000, 77)).is_ok());
    assert_eq!(member.session().time(), SessionTime::from_ms(5_000));
    assert_eq!(
        receive(&mut member, &wheel_command(4_991, OLD))
            .unwrap()
            .status,
        E2eStatus::Ok,
        "the sequences stand"
    );
    assert_eq!(
        receive(&mut member, &at(4_999, 1_000)),
        Err(DecodeError::WrongSequence { id: 0x020 })
    );
    assert_eq!(
        receive(&mut member, &at(0, 0)),
        Err(DecodeError::WrongSequence { id: 0x020 })
    );
    assert_eq!(member.session().time(), SessionTime::from_ms(5_000));
    // A later time under a smaller counter moves it, however long after.
    let accepted = receive(&mut member, &at(5_001, 0)).unwrap();
    assert_eq!(accepted.status, E2eStatus::Initial);
    assert_eq!(member.session().time(), SessionTime::from_ms(5_001));
    assert!(receive(&mut member, &at(4_000_000_000, 3)).is_ok());
    assert_eq!(member.session().time(), SessionTime::from_ms(4_000_000_000));
    assert_eq!(member.counters().get(RejectCause::WrongSequence).raw(), 2);
    assert_eq!(member.counters().total(), 2);
    // A greater epoch moves it to that session's time, even an earlier one.
    assert!(receive(
        &mut member,
        &announce_frame_at(WireVersion::THIS, NEW, 10, 0)
    )
    .is_ok());
    assert_eq!(member.session().epoch(), Some(NEW));
    assert_eq!(member.session().time(), SessionTime::from_ms(10));
}

/// The controller hears its own announcements on the bus: in its epoch it takes them at any
/// time (its clock is its own, not the announcements'), and moves nowhere.
#[test]
fn the_controller_takes_its_own_announcements_whatever_their_time() {
    let mut owner = owner_at(OLD, 7_000);
    for (ms, counter) in [(7_000, 70), (7_000, 70), (100, 1), (9_000_000, 2)] {
        let frame = announce_frame_at(WireVersion::THIS, OLD, ms, counter);
        assert!(receive(&mut owner, &frame).is_ok(), "{ms} ms");
        assert_eq!(owner.session().time(), SessionTime::from_ms(7_000));
        assert_eq!(owner.session().epoch(), Some(OLD));
    }
    assert_eq!(owner.counters().total(), 0);
    // Its time is set by its clock alone; a member's is not.
    owner.set_time(SessionTime::from_ms(8_000));
    assert_eq!(owner.session().time(), SessionTime::from_ms(8_000));
    let mut member = member_at(OLD, 7_000);
    member.set_time(SessionTime::from_ms(8_000));
    assert_eq!(member.session().time(), SessionTime::from_ms(7_000));
}

#[test]
fn an_announcement_of_another_wire_version_is_refused_and_joins_nothing() {
    for theirs in [0, 1, WIRE_VERSION + 1, u8::MAX] {
        let version = WireVersion::from_raw(theirs).unwrap();
        let expected = Err(DecodeError::WireVersion { theirs });
        let mut unjoined = Receiver::member(TEST_KEY);
        assert_eq!(
            receive(&mut unjoined, &announce_frame(version, OLD, 0)),
            expected
        );
        assert_eq!(unjoined.session().epoch(), None);
        // Not even a newer controller moves a member to a session it cannot read.
        let mut member = joined_member(OLD);
        assert_eq!(
            receive(&mut member, &announce_frame(version, NEW, 0)),
            expected
        );
        assert_eq!(member.session().epoch(), Some(OLD));
        assert_eq!(member.counters().get(RejectCause::Session).raw(), 1);
        let mut owner = Receiver::owner(Session::owned(TEST_KEY, OLD));
        assert_eq!(
            receive(&mut owner, &announce_frame(version, OLD, 0)),
            expected
        );
    }
}

// ------------------------------------------------------------------------------------------
// The E-stop latch.

#[test]
fn a_classic_latch_is_accepted_by_anyone_again_and_again() {
    for source in NodeId::ALL {
        let frame = classic_latch(source, PANEL_COUNTER).unwrap();
        assert_eq!(frame.id(), 0);
        assert_eq!(frame.data().len(), CLASSIC_LATCH_LEN);
        assert_eq!(CLASSIC_LATCH_LEN, 8);
        for mut rx in [
            Receiver::member(TEST_KEY),
            joined_member(OLD),
            Receiver::owner(Session::owned(TEST_KEY, OLD)),
            Receiver::member(Key([9; 16])),
        ] {
            for _ in 0..5 {
                let accepted = receive(&mut rx, &frame).unwrap();
                assert_eq!(accepted.message, AnyMessage::EStop(EStop::latch(source)));
                assert_eq!(accepted.status, E2eStatus::Initial);
            }
            assert_eq!(rx.counters().total(), 0);
        }
        let decoded = decode_frame(frame.id(), frame.data()).unwrap();
        assert_eq!(decoded.counter, PANEL_COUNTER);
    }
}

#[test]
fn a_classic_frame_that_is_not_a_latch_is_refused() {
    let release = AnyMessage::EStop(EStop::release(NodeId::Teleop, ReleaseToken::new(0)))
        .encode(&Session::owned(TEST_KEY, OLD), 0)
        .unwrap();
    let classic = &release.data()[..CLASSIC_LATCH_LEN];
    let wrong_length = Err(DecodeError::WrongLength {
        id: 0,
        expected: 12,
        got: 8,
    });
    for mut rx in [
        joined_member(OLD),
        Receiver::owner(Session::owned(TEST_KEY, OLD)),
    ] {
        assert_eq!(rx.receive(0, classic), wrong_length);
        assert_eq!(rx.counters().get(RejectCause::WrongLength).raw(), 1);
        // The full frame is a release like any other.
        assert!(receive(&mut rx, &release).is_ok());
    }
    assert!(Receiver::member(TEST_KEY).receive(0, classic).is_err());
    assert!(matches!(
        decode_frame(0, classic),
        Err(DecodeError::WrongLength { got: 8, .. })
    ));
    // A latch's eight bytes on any other identifier, and a corrupted classic latch.
    let latch = classic_latch(NodeId::Tool, 0).unwrap();
    let mut rx = joined_member(OLD);
    assert!(matches!(
        rx.receive(0x200, latch.data()),
        Err(DecodeError::WrongLength { got: 8, .. })
    ));
    let mut corrupted = latch.data().to_vec();
    corrupted[7] ^= 0x01;
    assert_eq!(
        rx.receive(0, &corrupted),
        Err(DecodeError::CrcMismatch { id: 0 })
    );
}

proptest! {
    /// Whatever its counter, session or sender, a latch with a valid CRC acts.
    #[test]
    fn a_latch_acts_whatever_its_counter_and_session(
        source in proptest::sample::select(&NodeId::ALL[..]),
        counter in any::<u32>(),
        epoch in proptest::option::of(any::<u32>()),
        classic in any::<bool>(),
    ) {
        let session = match epoch {
            Some(epoch) => Session::owned(Key([3; 16]), Epoch::new(epoch)),
            None => Session::unjoined(Key([3; 16])),
        };
        let frame = if classic {
            classic_latch(source, counter as u16).unwrap()
        } else {
            AnyMessage::EStop(EStop::latch(source)).encode(&session, counter).unwrap()
        };
        for mut rx in [
            Receiver::member(TEST_KEY),
            joined_member(OLD),
            Receiver::owner(Session::owned(TEST_KEY, NEW)),
        ] {
            let accepted = rx.receive(frame.id(), frame.data()).unwrap();
            prop_assert_eq!(accepted.message, AnyMessage::EStop(EStop::latch(source)));
        }
    }
}

// ------------------------------------------------------------------------------------------
// Loss.

#[test]
fn a_burst_of_5000_lost_frames_is_accepted_and_counted() {
    // Across the wrap of the low half: 63 000 → 68 001.
    let mut member = member_at(OLD, 62_900);
    for counter in 62_990..=63_000 {
        receive(&mut member, &wheel_command(counter, OLD)).unwrap();
    }
    // The burst lasts 5 s; the member hears the announcements meanwhile.
    receive(&mut member, &announce_frame(WireVersion::THIS, OLD, 680)).unwrap();
    let after_burst = wheel_command(63_000 + 5_001, OLD);
    assert_eq!(
        receive(&mut member, &after_burst).unwrap().status,
        E2eStatus::OkSomeLost { lost: 5_000 }
    );
    assert_eq!(member.counters().lost.raw(), 5_000);
    assert_eq!(member.counters().total(), 0);
    assert_eq!(
        receive(&mut member, &wheel_command(68_002, OLD))
            .unwrap()
            .status,
        E2eStatus::Ok
    );
    // A frame from inside the burst, arriving late, is stale and adds no loss.
    assert_eq!(
        receive(&mut member, &wheel_command(65_000, OLD)),
        Err(DecodeError::WrongSequence { id: 0x101 })
    );
    assert_eq!(member.counters().lost.raw(), 5_000);
}

#[test]
fn the_longest_burst_in_sequence_is_just_under_half_the_counter_range() {
    // One frame a millisecond; the member hears the announcements through the burst.
    let heard = |member: &mut Receiver, ms: u32| {
        receive(
            member,
            &announce_frame_at(WireVersion::THIS, OLD, ms, ms / 20),
        )
        .unwrap();
    };
    let mut member = member_at(OLD, 100);
    receive(&mut member, &wheel_command(100, OLD)).unwrap();
    heard(&mut member, 100 + 0x7FFF - 10);
    let frame = wheel_command(100 + 0x7FFF, OLD);
    assert_eq!(
        receive(&mut member, &frame).unwrap().status,
        E2eStatus::OkSomeLost { lost: 0x7FFE }
    );
    assert_eq!(member.counters().lost.raw(), 0x7FFE);
    // 2^15 − 1 lost: the frame reads as behind, where its check fails; the search near the
    // member's time finds it and the sequence starts again there. The loss is not counted:
    // the receiver cannot tell how many periods of 2^16 it skipped.
    let mut member = member_at(OLD, 100);
    receive(&mut member, &wheel_command(100, OLD)).unwrap();
    heard(&mut member, 100 + 0x8000 - 10);
    let frame = wheel_command(100 + 0x8000, OLD);
    assert_eq!(
        receive(&mut member, &frame).unwrap().status,
        E2eStatus::Initial
    );
    assert_eq!(member.counters().lost.raw(), 0);
    assert_eq!(member.counters().total(), 0);
    assert_eq!(
        receive(&mut member, &wheel_command(101 + 0x8000, OLD))
            .unwrap()
            .status,
        E2eStatus::Ok
    );
}

#[test]
fn a_late_joiner_finds_a_crc_sender_past_the_first_wrap() {
    // The status went out every millisecond since the session opened: its counter is about
    // the session time, which the member learns from the announcement it joins on.
    let status = |counter: u32| {
        AnyMessage::Sync(Sync {
            tick: Tick::from_raw(counter).unwrap(),
        })
        .encode(&Session::owned(TEST_KEY, OLD), counter)
        .unwrap()
    };
    let first = 200 << 16 | 0x1234;
    let mut member = member_at(OLD, first - 40);
    assert_eq!(
        receive(&mut member, &status(first)).unwrap().status,
        E2eStatus::Initial
    );
    assert_eq!(
        receive(&mut member, &status(first + 1)).unwrap().status,
        E2eStatus::Ok
    );
}

// ------------------------------------------------------------------------------------------
// The sender.

#[test]
fn the_sender_counts_per_identifier_from_the_session_time() {
    let session = Session::owned(TEST_KEY, OLD).at(SessionTime::from_ms(5_000));
    let mut tx = Sender::new();
    let counter = |frame: Frame| decode_frame(frame.id(), frame.data()).unwrap().counter;
    let wheel = AnyMessage::WheelCommand(WheelCommand {
        torque: [Torque::default(); 2],
    });
    let legs = AnyMessage::LegTargets(LegTargets {
        enable: DriveEnable::Disabled,
        position: [Angle::default(); 16].into(),
    });
    for expected in 5_000..5_003 {
        assert_eq!(counter(tx.seal(&session, &wheel).unwrap()), expected);
    }
    // Every identifier started at the session time of the sender's first frame in the
    // session; later frames count on from there, whatever the time.
    let later = session.at(SessionTime::from_ms(9_000));
    assert_eq!(counter(tx.seal(&later, &legs).unwrap()), 5_000);
    assert_eq!(counter(tx.seal(&later, &wheel).unwrap()), 5_003);
    // The E-stop counts with the session time: the greater of its next counter and the time.
    let release = AnyMessage::EStop(EStop::release(NodeId::Teleop, ReleaseToken::new(1)));
    let latch = AnyMessage::EStop(EStop::latch(NodeId::Teleop));
    assert_eq!(counter(tx.seal(&later, &release).unwrap()), 9_000);
    assert_eq!(counter(tx.seal(&later, &latch).unwrap()), 9_001);
    assert_eq!(counter(tx.seal(&later, &release).unwrap()), 9_002);
    let later = session.at(SessionTime::from_ms(20_000));
    assert_eq!(counter(tx.seal(&later, &release).unwrap()), 20_000);
    assert_eq!(counter(tx.seal(&later, &wheel).unwrap()), 5_004);
    // Another session starts every counter again, at that session's time.
    let next = Session::owned(TEST_KEY, NEW).at(SessionTime::from_ms(250));
    assert_eq!(counter(tx.seal(&next, &wheel).unwrap()), 250);
    assert_eq!(counter(tx.seal(&next, &legs).unwrap()), 250);
    assert_eq!(counter(tx.seal(&next, &release).unwrap()), 250);
}

/// A clock of the controller's session: the controller's receiver reads it, and every member
/// hears it in the announcements, one every 20 ms.
struct Clock {
    ms: u32,
    announced: u32,
}

impl Clock {
    fn new(ms: u32) -> Clock {
        Clock { ms, announced: 0 }
    }

    /// Runs the clock to `ms`: the controller reads it, and `members` hear the announcement
    /// when one falls due.
    fn to(&mut self, ms: u32, controller: &mut Receiver, members: &mut [&mut Receiver]) {
        assert!(ms >= self.ms);
        if ms / 20 > self.ms / 20 {
            self.announce(ms / 20 * 20, members);
        }
        self.ms = ms;
        controller.set_time(SessionTime::from_ms(ms));
    }

    fn announce(&mut self, ms: u32, members: &mut [&mut Receiver]) {
        self.announced += 1;
        let frame = announce_frame_at(WireVersion::THIS, OLD, ms, self.announced);
        for member in members.iter_mut() {
            receive(member, &frame).unwrap();
            assert_eq!(member.session().time(), SessionTime::from_ms(ms));
        }
    }
}

fn heartbeat(ms: u32) -> AnyMessage {
    AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
        uptime: Millis::from_raw(ms).unwrap(),
    })
}

/// Wire version 2 first refused a teleop restarted within the session until it resumed its
/// counters from a state file. Now a node restarted within the session starts its counters at
/// the session time it joins at, past everything it sent before: the controller and every
/// member take it from its first frame, and the frames of its previous life stay refused.
#[test]
fn a_sender_restarted_within_the_session_is_taken_from_its_first_frame() {
    for down_for in [30, 150_000] {
        let mut clock = Clock::new(1_000);
        let mut controller = owner_at(OLD, 1_000);
        let mut drive = member_at(OLD, 1_000);
        // First life: the teleop joins at 1 s and sends a heartbeat every 20 ms for 10 s.
        let mut teleop = member_at(OLD, 1_000);
        let mut tx = Sender::new();
        let mut first_life = Vec::new();
        for k in 0..500 {
            let ms = 1_000 + 20 * k;
            clock.to(ms, &mut controller, &mut [&mut drive, &mut teleop]);
            let frame = tx.seal(teleop.session(), &heartbeat(ms)).unwrap();
            for rx in [&mut controller, &mut drive] {
                assert!(receive(rx, &frame).is_ok());
            }
            first_life.push(frame);
        }
        // The teleop restarts: a new receiver joins on the next announcement, a new sender.
        let back = clock.ms + down_for;
        clock.to(back, &mut controller, &mut [&mut drive]);
        let mut teleop = Receiver::member(TEST_KEY);
        clock.announce(back / 20 * 20 + 20, &mut [&mut drive, &mut teleop]);
        let rejoined = teleop.session().time().ms();
        clock.to(rejoined + 5, &mut controller, &mut []);
        let mut tx = Sender::new();
        let frame = tx.seal(teleop.session(), &heartbeat(rejoined)).unwrap();
        assert_eq!(
            decode_frame(frame.id(), frame.data()).unwrap().counter,
            rejoined as u16,
            "it starts at the session time it joined at"
        );
        // Its counter jumped further than the session time moved since its last frame (it
        // sent one frame every 20 ms): a restart, not a loss.
        for rx in [&mut controller, &mut drive] {
            let lost_before = rx.counters().lost;
            assert_eq!(receive(rx, &frame).unwrap().status, E2eStatus::Initial);
            assert_eq!(rx.counters().lost, lost_before);
        }
        // Its previous life, replayed now, is refused by both, in any order.
        for frame in first_life.iter().rev().chain(&first_life) {
            for rx in [&mut controller, &mut drive] {
                let refused = receive(rx, frame).unwrap_err();
                assert!(
                    matches!(
                        refused,
                        DecodeError::WrongSequence { .. } | DecodeError::Unauthentic { .. }
                    ),
                    "{refused:?}"
                );
            }
        }
        // And its new life goes on in sequence.
        let frame = tx.seal(teleop.session(), &heartbeat(rejoined)).unwrap();
        for rx in [&mut controller, &mut drive] {
            assert_eq!(receive(rx, &frame).unwrap().status, E2eStatus::Ok);
        }
    }
}

fn wheel_message(ms: u32) -> AnyMessage {
    AnyMessage::WheelCommand(WheelCommand {
        torque: [Torque::from_raw((ms % 1000) as i16).unwrap(); 2],
    })
}

fn wheel_feedback(ms: u32) -> AnyMessage {
    AnyMessage::WheelFeedback(WheelFeedback {
        velocity: [WheelVelocity::from_raw((ms % 1000) as i16).unwrap(); 2],
        effort: [Torque::default(); 2],
    })
}

/// Wire version 2 first looked for a sender's first CMAC frame at high half zero only, so a
/// node that joined after the sender's counter passed 2^16 never accepted it. Now the senders
/// count from the session time and the late joiner looks around its own.
#[test]
fn a_member_that_joins_after_the_counter_wrapped_takes_the_next_frame() {
    // The controller's wheel command (CRC), the wheel drive's feedback (CRC) and the teleop's
    // heartbeat (CMAC), each every millisecond since the session opened: 70 000 of each
    // before the member joins. The drive and the teleop seal at the announced time.
    let at = |ms| Session::owned(TEST_KEY, OLD).at(SessionTime::from_ms(ms));
    let mut controller = Sender::new();
    let mut wheel_drive = Sender::new();
    let mut teleop = Sender::new();
    let mut sent: [Vec<Frame>; 3] = Default::default();
    for ms in 0..70_002 {
        let announced = at(ms / 20 * 20);
        sent[0].push(controller.seal(&at(ms), &wheel_message(ms)).unwrap());
        sent[1].push(wheel_drive.seal(&announced, &wheel_feedback(ms)).unwrap());
        sent[2].push(teleop.seal(&announced, &heartbeat(ms)).unwrap());
    }
    assert_eq!(
        decode_frame(0x101, sent[0][69_999].data()).unwrap().counter,
        (69_999_u32 - 0x1_0000) as u16,
        "the low counter wrapped"
    );
    let mut member = member_at(OLD, 70_000);
    for stream in &sent {
        let frame = |ms: u32| &stream[ms as usize];
        let id = frame(0).id();
        assert_eq!(
            receive(&mut member, frame(70_000)).unwrap().status,
            E2eStatus::Initial,
            "{id:#x}"
        );
        assert_eq!(
            receive(&mut member, frame(70_001)).unwrap().status,
            E2eStatus::Ok
        );
        // Replays of frames older than the last accepted are refused: within 2^15 as out of
        // sequence, further back as failing their check (the search looks only ahead).
        let check_failed = check_failed(frame(0));
        for (ms, refused) in [
            (70_001, DecodeError::Repeated { id }),
            (70_000, DecodeError::WrongSequence { id }),
            (69_999, DecodeError::WrongSequence { id }),
            (70_001 - 0x8000, DecodeError::WrongSequence { id }),
            (70_001 - 0x8001, check_failed),
            (70_001 - 0x1_0000, check_failed),
            (70_002 - 0x1_0000, check_failed),
            (0, check_failed),
        ] {
            assert_eq!(
                receive(&mut member, frame(ms)),
                Err(refused),
                "{id:#x} {ms}"
            );
        }
    }
    assert_eq!(member.counters().total(), 24);
    assert_eq!(member.counters().get(RejectCause::Unauthentic).raw(), 4);
    assert_eq!(member.counters().lost.raw(), 0);
}

/// Wire version 2 first could not place a frame 2^15 or more ahead of the last it accepted:
/// after such a gap a receiver refused the sender for the rest of the session. Now the frame is
/// found by the search, nearest the receiver's session time.
#[test]
fn a_gap_of_40_000_lost_frames_is_recovered() {
    let mut clock = Clock::new(1_000);
    let mut controller = owner_at(OLD, 1_000);
    let mut drive = member_at(OLD, 1_000);
    let mut teleop = member_at(OLD, 1_000);
    let controller_session = *controller.session();
    let mut controller_tx = Sender::new();
    let mut drive_tx = Sender::new();
    let mut teleop_tx = Sender::new();
    let command = AnyMessage::TeleopCommand(TeleopCommand {
        mode: TeleopMode::WheelForward,
        body_height: BodyHeight::default(),
        speed_scale: SpeedScale::from_raw(50).unwrap(),
    });
    // Each sender sends one frame a millisecond: the controller's wheel command (CRC) to the
    // drive, the drive's feedback (CRC) and the teleop's command (CMAC) to the controller. The
    // frames of 41 000…80 999 ms are lost (the announcements get through).
    let mut statuses = Vec::new();
    for ms in 1_000..81_003 {
        clock.to(ms, &mut controller, &mut [&mut drive, &mut teleop]);
        let lost = (41_000..81_000).contains(&ms);
        let frames = [
            controller_tx.seal(
                &controller_session.at(SessionTime::from_ms(ms)),
                &wheel_message(ms),
            ),
            drive_tx.seal(drive.session(), &wheel_feedback(ms)),
            teleop_tx.seal(teleop.session(), &command),
        ];
        let [wheel, feedback, command] = frames.map(Result::unwrap);
        if lost {
            continue;
        }
        let got = [
            receive(&mut drive, &wheel),
            receive(&mut controller, &feedback),
            receive(&mut controller, &command),
        ];
        if ms >= 81_000 {
            statuses.push(got.map(|got| got.unwrap().status));
        } else {
            assert!(got.iter().all(Result::is_ok), "{ms}: {got:?}");
        }
    }
    assert_eq!(
        statuses,
        [
            [E2eStatus::Initial; 3],
            [E2eStatus::Ok; 3],
            [E2eStatus::Ok; 3],
        ]
    );
    assert_eq!(controller.counters().total(), 0);
    assert_eq!(drive.counters().total(), 0);
}

/// A member that has just joined has no sequence to hold a frame against: it takes the first
/// genuine frame its search finds, and so takes a frame replayed from earlier in the session if
/// its counter is one of the search's two candidates: the counter with the frame's low half
/// nearest the member's session time (within ±2^15 ms), and the one 2^16 below that. So a
/// replay is taken back to 2^15 + 2^16 ms (98.3 s) before the member's time and refused from
/// further back, CMAC and CRC alike; which end of the window is closed depends on the low half
/// of the member's time (the candidate 2^15 away on either side is the one in the same period of
/// 2^16). Every genuine sender is well inside: its counter is at most `MAX_LAG_MS` (16.4 s)
/// behind the session time.
///
/// Wire version 2 first looked through 2^8 periods of 2^16 ms for a CMAC (4.66 h) and 2^12 for
/// a CRC (74.6 h): a frame recorded two minutes or an hour before was taken.
#[test]
fn a_freshly_joined_member_refuses_a_replay_from_beyond_its_search() {
    let sync = |counter: u32| {
        AnyMessage::Sync(Sync {
            tick: Tick::from_raw(counter).unwrap(),
        })
        .encode(&Session::owned(TEST_KEY, OLD), counter)
        .unwrap()
    };
    let command = |counter: u32| {
        AnyMessage::TeleopCommand(TeleopCommand {
            mode: TeleopMode::WheelForward,
            body_height: BodyHeight::default(),
            speed_scale: SpeedScale::from_raw(40).unwrap(),
        })
        .encode(&Session::owned(TEST_KEY, OLD), counter)
        .unwrap()
    };
    type Seal = fn(u32) -> Frame;
    let cases: [(Seal, DecodeError); 2] = [
        (command, DecodeError::Unauthentic { id: 0x200 }),
        (sync, DecodeError::CrcMismatch { id: 0x010 }),
    ];
    const WINDOW: u32 = 0x8000 + 0x1_0000;
    assert_eq!(WINDOW, 98_304);
    for (seal, check_failed) in cases {
        // The member joins at `now`, 5.5 h into the session, low half below or above 2^15.
        for now in [300 << 16 | 0x1234, 300 << 16 | 0x9234] {
            // The oldest counter its search reaches.
            let oldest = if now & 0xFFFF < 0x8000 {
                now - WINDOW + 1
            } else {
                now - WINDOW
            };
            for (recorded, taken) in [
                (now, true),
                (now - 10, true),
                (now - MAX_LAG_MS, true),
                (now - 0x8000, true),
                (now - 60_000, true),
                (oldest, true),
                (oldest - 1, false),
                (now - 0x2_0000, false),
                (now - 120_000, false),
                (now - 3_600_000, false),
                (now - (1 << 24), false),
                (now - ((1 << 12) << 16).min(now), false),
            ] {
                let mut member = member_at(OLD, now);
                let got = receive(&mut member, &seal(recorded));
                if taken {
                    assert_eq!(got.unwrap().status, E2eStatus::Initial, "{now} {recorded}");
                } else {
                    assert_eq!(got, Err(check_failed), "{now} {recorded}");
                }
                // Either way the genuine sender's next frame is taken, and the replay is then
                // behind it.
                let genuine = now + 10;
                assert!(receive(&mut member, &seal(genuine))
                    .unwrap()
                    .status
                    .is_accepted());
                assert!(receive(&mut member, &seal(recorded)).is_err());
            }
        }
    }
}

/// Wire version 2 first looked for a first frame from the period of 2^16 ms after the
/// receiver's time's downward, the controller in two periods: a teleop that joined on an
/// announcement just below a boundary (65 500 ms) sealed its first frames there, while the
/// controller's time had passed the boundary (65 540 ms), so the controller refused it until
/// its counter passed 65 536. Now every receiver looks first at the counter nearest its time.
#[test]
fn a_teleop_joining_just_below_a_period_boundary_is_taken_from_its_first_frame() {
    let mut controller = owner_at(OLD, 65_540);
    let mut drive = member_at(OLD, 65_540);
    let teleop = member_at(OLD, 65_500);
    let mut tx = Sender::new();
    let command = AnyMessage::TeleopCommand(TeleopCommand {
        mode: TeleopMode::WheelForward,
        body_height: BodyHeight::default(),
        speed_scale: SpeedScale::from_raw(50).unwrap(),
    });
    for (message, status) in [
        (heartbeat(1), E2eStatus::Initial),
        (command, E2eStatus::Initial),
        (heartbeat(2), E2eStatus::Ok),
        (command, E2eStatus::Ok),
    ] {
        let frame = tx.seal(teleop.session(), &message).unwrap();
        let counter = decode_frame(frame.id(), frame.data()).unwrap().counter;
        assert!((65_500..65_502).contains(&u32::from(counter)), "{counter}");
        for rx in [&mut controller, &mut drive] {
            let accepted = receive(rx, &frame).unwrap();
            assert_eq!(accepted.message, message);
            assert_eq!(accepted.status, status, "{message:?}");
        }
    }
    assert_eq!(*controller.counters(), *drive.counters());
    assert_eq!(controller.counters().total(), 0);
    assert_eq!(controller.counters().lost.raw(), 0);
}

/// The counter a sender slower than one frame a millisecond uses for its `k`-th frame on an
/// identifier, sealed at session time `times[k]`: from the time of its first frame, one per
/// frame, and the session time itself once the next would be more than `MAX_LAG_MS` behind.
fn slow_sender_counters(times: &[u32]) -> Vec<u32> {
    let mut next = times[0];
    times
        .iter()
        .map(|&now| {
            if next + MAX_LAG_MS < now {
                next = now;
            }
            next += 1;
            next - 1
        })
        .collect()
}

/// Wire version 2 first let a slow sender's counter fall ever further behind the session time:
/// after a long gap in its frames (here 15 minutes) the controller, which looks near its own
/// time, never found it again. Now its counter stays within `MAX_LAG_MS` of the session time,
/// and the first frame after the gap restarts the sequence.
#[test]
fn a_50_hz_sender_is_taken_again_at_its_first_frame_after_15_minutes_lost() {
    let mut clock = Clock::new(1_000);
    let mut controller = owner_at(OLD, 1_000);
    let mut drive = member_at(OLD, 1_000);
    let mut teleop = member_at(OLD, 1_000);
    let mut tx = Sender::new();
    let lost = 61_000..61_000 + 15 * 60_000;
    let times: Vec<u32> = (1_000..lost.end + 100).step_by(20).collect();
    let expected = slow_sender_counters(&times);
    let mut after_gap = Vec::new();
    for (&ms, &counter) in times.iter().zip(&expected) {
        clock.to(ms, &mut controller, &mut [&mut drive, &mut teleop]);
        let frame = tx.seal(teleop.session(), &heartbeat(ms)).unwrap();
        let decoded = decode_frame(frame.id(), frame.data()).unwrap();
        assert_eq!(decoded.counter, counter as u16, "{ms}");
        assert!(ms - counter <= MAX_LAG_MS + 1, "{ms}: {counter}");
        if lost.contains(&ms) {
            continue;
        }
        let statuses = [&mut controller, &mut drive].map(|rx| receive(rx, &frame).unwrap().status);
        assert_eq!(statuses[0], statuses[1], "{ms}");
        if ms >= lost.end {
            after_gap.push(statuses[0]);
        }
    }
    assert_eq!(after_gap[..2], [E2eStatus::Initial, E2eStatus::Ok]);
    assert!(after_gap[1..].iter().all(|s| *s == E2eStatus::Ok));
    for rx in [&controller, &drive] {
        assert_eq!(rx.counters().total(), 0);
        // A gap the sequence cannot span restarts it: the frames in it are not counted.
        assert_eq!(rx.counters().lost.raw(), 0);
    }
}

/// Wire version 2 first let a 50 Hz sender's counter fall behind the session time by 19 ms a
/// frame: a member that joined 6 h into the session looked for it within 2^8 periods of 2^16 ms
/// below its time (4.66 h) and never found it. Now its counter is within `MAX_LAG_MS`.
#[test]
fn a_member_joining_6_hours_in_takes_a_50_hz_sender_at_its_first_frame() {
    const JOIN: u32 = 6 * 3_600_000;
    // The teleop's heartbeat (CMAC), sealed at each announced time since the session opened.
    let mut tx = Sender::new();
    let times: Vec<u32> = (0..JOIN + 100).step_by(20).collect();
    let expected = slow_sender_counters(&times);
    let frames: Vec<Frame> = times
        .iter()
        .map(|&ms| {
            let session = Session::owned(TEST_KEY, OLD).at(SessionTime::from_ms(ms));
            tx.seal(&session, &heartbeat(ms)).unwrap()
        })
        .collect();
    let at_join = times.iter().position(|&ms| ms == JOIN).unwrap();
    assert!(JOIN - expected[at_join] <= MAX_LAG_MS);
    let mut member = member_at(OLD, JOIN);
    for (k, frame) in frames.iter().enumerate().skip(at_join) {
        let decoded = decode_frame(frame.id(), frame.data()).unwrap();
        assert_eq!(decoded.counter, expected[k] as u16);
        let status = receive(&mut member, frame).unwrap().status;
        let want = if k == at_join {
            E2eStatus::Initial
        } else {
            E2eStatus::Ok
        };
        assert_eq!(status, want, "{}", times[k]);
    }
    assert_eq!(member.counters().total(), 0);
    assert_eq!(member.counters().lost.raw(), 0);
}

/// Loss of a 50 Hz sender over 10 minutes, at the controller and at a member. Every
/// `MAX_LAG_MS` (863 frames) its counter jumps to the session time: further than the time
/// elapsed since its previous frame, so the sequence restarts there (`Initial`) and the jump
/// is no loss. With every 10th frame dropped, every dropped frame counts as lost but those
/// next to a jump (the jump frame itself, or the frame just before it): there the receiver
/// sees the jump and no loss. (Wire version 2 first had no jumps, and a member that joined
/// late never took such a sender at all.)
#[test]
fn a_50_hz_sender_loses_exactly_the_frames_dropped() {
    let times: Vec<u32> = (1_000..1_000 + 10 * 60_000 + 20).step_by(20).collect();
    let expected = slow_sender_counters(&times);
    let jump: Vec<bool> = (0..times.len())
        .map(|k| k > 0 && expected[k] != expected[k - 1] + 1)
        .collect();
    let jumps = jump.iter().filter(|j| **j).count();
    assert_eq!(jumps, times.len() / 863);
    assert_eq!(jump.iter().position(|j| *j), Some(863));
    for every in [None, Some(10)] {
        let dropped = |k: usize| every.is_some_and(|n| k % n == n - 1);
        let mut clock = Clock::new(1_000);
        let mut controller = owner_at(OLD, 1_000);
        let mut drive = member_at(OLD, 1_000);
        let mut teleop = member_at(OLD, 1_000);
        let mut tx = Sender::new();
        let mut initial = 0;
        for (k, &ms) in times.iter().enumerate() {
            clock.to(ms, &mut controller, &mut [&mut drive, &mut teleop]);
            let frame = tx.seal(teleop.session(), &heartbeat(ms)).unwrap();
            let decoded = decode_frame(frame.id(), frame.data()).unwrap();
            assert_eq!(decoded.counter, expected[k] as u16, "{ms}");
            if dropped(k) {
                continue;
            }
            let statuses =
                [&mut controller, &mut drive].map(|rx| receive(rx, &frame).unwrap().status);
            assert_eq!(statuses[0], statuses[1], "{ms}");
            let after_drop = k > 0 && dropped(k - 1);
            let want = match (k == 0 || jump[k] || (after_drop && jump[k - 1]), after_drop) {
                (true, _) => E2eStatus::Initial,
                (false, true) => E2eStatus::OkSomeLost { lost: 1 },
                (false, false) => E2eStatus::Ok,
            };
            assert_eq!(statuses[0], want, "frame {k} at {ms} ms");
            initial += usize::from(want == E2eStatus::Initial);
        }
        let dropped_all = (0..times.len()).filter(|&k| dropped(k)).count();
        let dropped_at_jump = (0..times.len())
            .filter(|&k| dropped(k) && (jump[k] || jump.get(k + 1) == Some(&true)))
            .count();
        match every {
            None => {
                assert_eq!(dropped_all, 0);
                assert_eq!(initial, 1 + jumps);
            }
            Some(_) => {
                assert_eq!(dropped_all, times.len() / 10);
                // The jumps fall on frames 863·i: frame 863·i is dropped for i = 3, 13, 23, 33,
                // and the one before it for i = 10, 20, 30.
                assert_eq!(dropped_at_jump, 7);
            }
        }
        for rx in [&controller, &drive] {
            assert_eq!(rx.counters().total(), 0);
            assert_eq!(
                usize::from(rx.counters().lost.raw()),
                dropped_all - dropped_at_jump,
                "{every:?}"
            );
        }
    }
}

/// An E-stop release counts with the session time, so two releases 10 s apart are 10 000
/// counters apart: in sequence, but not 9 999 lost frames. Wire version 2 first counted them.
#[test]
fn two_releases_10_s_apart_count_no_loss() {
    let mut clock = Clock::new(1_000);
    let mut controller = owner_at(OLD, 1_000);
    let mut drive = member_at(OLD, 1_000);
    let mut teleop = member_at(OLD, 1_000);
    let mut tx = Sender::new();
    let release = AnyMessage::EStop(EStop::release(NodeId::Teleop, ReleaseToken::new(1)));
    let latch = AnyMessage::EStop(EStop::latch(NodeId::Teleop));
    let mut statuses = Vec::new();
    for ms in [2_000, 12_000] {
        clock.to(ms, &mut controller, &mut [&mut drive, &mut teleop]);
        let frame = tx.seal(teleop.session(), &release).unwrap();
        assert_eq!(
            decode_frame(frame.id(), frame.data()).unwrap().counter,
            ms as u16
        );
        for rx in [&mut controller, &mut drive] {
            statuses.push(receive(rx, &frame).unwrap().status);
        }
        // And a latch in between, which takes no part in the sequence.
        let frame = tx.seal(teleop.session(), &latch).unwrap();
        for rx in [&mut controller, &mut drive] {
            receive(rx, &frame).unwrap();
        }
    }
    let gap = E2eStatus::OkSomeLost { lost: 9_999 };
    assert_eq!(statuses, [E2eStatus::Initial, E2eStatus::Initial, gap, gap]);
    for rx in [&controller, &drive] {
        assert_eq!(rx.counters().lost.raw(), 0);
        assert_eq!(rx.counters().total(), 0);
    }
    // Any other identifier's gap of the same length is counted.
    let mut member = member_at(OLD, 2_000);
    receive(&mut member, &wheel_command(2_000, OLD)).unwrap();
    receive(
        &mut member,
        &announce_frame_at(WireVersion::THIS, OLD, 12_000, 600),
    )
    .unwrap();
    assert_eq!(
        receive(&mut member, &wheel_command(12_000, OLD))
            .unwrap()
            .status,
        gap
    );
    assert_eq!(member.counters().lost.raw(), 9_999);
}

/// Wire version 2 first counted E-stop releases like any identifier, from zero per sender, so
/// that two operators releasing on the one E-stop identifier (the teleop and a tool) collided
/// and the second was refused as a repeat. Now a release counts with the session time.
#[test]
fn two_operators_releasing_in_turn_are_both_taken() {
    let mut clock = Clock::new(1_000);
    let mut controller = owner_at(OLD, 1_000);
    let mut teleop = member_at(OLD, 1_000);
    let mut tool = member_at(OLD, 1_000);
    let mut teleop_tx = Sender::new();
    let mut tool_tx = Sender::new();
    let release = |source| AnyMessage::EStop(EStop::release(source, ReleaseToken::new(3)));
    let latch = |source| AnyMessage::EStop(EStop::latch(source));
    let mut statuses = Vec::new();
    // Among them times just past a 2^16 ms boundary of the controller's time (65 536,
    // 131 072), where the operator seals at the last announced time, just before it.
    for (ms, source) in [
        (10_020, NodeId::Teleop),
        (12_040, NodeId::Tool),
        (12_150, NodeId::Teleop),
        (30_010, NodeId::Teleop),
        (31_000, NodeId::Tool),
        (65_538, NodeId::Teleop),
        (65_600, NodeId::Tool),
        (100_000, NodeId::Tool),
        (100_130, NodeId::Teleop),
        (131_075, NodeId::Tool),
        (131_190, NodeId::Teleop),
        (190_500, NodeId::Teleop),
        (190_610, NodeId::Tool),
    ] {
        clock.to(ms, &mut controller, &mut [&mut teleop, &mut tool]);
        let (tx, rx) = match source {
            NodeId::Teleop => (&mut teleop_tx, &teleop),
            _ => (&mut tool_tx, &tool),
        };
        // Each operator latches first, then releases.
        let frame = tx.seal(rx.session(), &latch(source)).unwrap();
        assert!(receive(&mut controller, &frame).is_ok());
        let frame = tx.seal(rx.session(), &release(source)).unwrap();
        let accepted = receive(&mut controller, &frame)
            .unwrap_or_else(|e| panic!("{source:?} at {ms} ms: {e:?}"));
        assert_eq!(accepted.message, release(source));
        statuses.push(accepted.status);
    }
    assert_eq!(statuses[0], E2eStatus::Initial);
    assert!(statuses.iter().all(|s| s.is_accepted()));
    assert_eq!(controller.counters().total(), 0);
}

// ------------------------------------------------------------------------------------------
// Keys.

#[test]
fn a_key_reads_from_32_hex_digits() {
    let key = Key::from_hex("000102030405060708090a0b0c0d0e0f").unwrap();
    assert_eq!(key, Key(core::array::from_fn(|i| i as u8)));
    assert_eq!(
        Key::from_hex("  000102030405060708090A0B0C0D0E0F\n"),
        Ok(key),
        "upper case, surrounding whitespace"
    );
    let test_hex: String = TEST_KEY.0.iter().map(|b| format!("{b:02x}")).collect();
    assert_eq!(Key::from_hex(&test_hex), Ok(TEST_KEY));
    assert_eq!(
        Key::from_hex("ffffffffffffffffffffffffffffffff"),
        Ok(Key([0xFF; 16]))
    );
}

#[test]
fn a_key_of_the_wrong_length_is_refused_with_its_length() {
    let digits = "0123456789abcdef0123456789abcdef";
    for len in [0, 1, 2, 16, 30, 31] {
        assert_eq!(
            Key::from_hex(&digits[..len]),
            Err(KeyError::Length { digits: len }),
            "{len}"
        );
    }
    for extra in ["0", "00", "0123456789abcdef"] {
        let text = format!("{digits}{extra}");
        assert_eq!(
            Key::from_hex(&text),
            Err(KeyError::Length { digits: text.len() })
        );
    }
    assert_eq!(Key::from_hex("   \n"), Err(KeyError::Length { digits: 0 }));
    let text = KeyError::Length { digits: 31 }.to_string();
    assert!(text.contains("32") && text.contains("31"), "{text}");
}

#[test]
fn a_key_with_a_character_that_is_not_hex_is_refused_where_it_is() {
    let digits = "0123456789abcdef0123456789abcdef";
    for at in [0, 1, 2, 15, 30, 31] {
        for bad in ['g', 'x', ' ', '-', 'G'] {
            let mut text: Vec<char> = digits.chars().collect();
            text[at] = bad;
            let text: String = text.into_iter().collect();
            if bad == ' ' && (at == 0 || at == 31) {
                continue; // trimmed away: a length error instead
            }
            assert_eq!(
                Key::from_hex(&text),
                Err(KeyError::NotHex { at }),
                "{text:?}"
            );
        }
    }
    // "0x" in front of 30 digits: 32 characters, the second not hex.
    assert_eq!(
        Key::from_hex(&format!("0x{}", &digits[..30])),
        Err(KeyError::NotHex { at: 1 })
    );
    // Two bytes of UTF-8 in place of the last two digits.
    assert_eq!(
        Key::from_hex(&format!("{}é", &digits[..30])),
        Err(KeyError::NotHex { at: 30 })
    );
    let text = KeyError::NotHex { at: 5 }.to_string();
    assert!(text.contains('5'), "{text}");
}

#[test]
fn a_key_is_never_printed() {
    let key = Key::from_hex("0123456789abcdef0123456789abcdef").unwrap();
    let shown = format!("{key:?} {:?}", Session::owned(key, OLD));
    assert!(!shown.contains("01") && !shown.contains("[1,"), "{shown}");
    assert_eq!(format!("{TEST_KEY:?}"), "Key(test key)");
}
