//! The bus session of wire version 2: replays from the same or an earlier session, frames
//! forged without the key, the announcement rules, the E-stop latch (classic and FD), burst
//! loss, the sender's counters and reading a key.

mod common;

use std::sync::OnceLock;

use common::{announce_frame, joined_member};
use proptest::prelude::*;
use protocol::e2e::HEADER_LEN;
use protocol::*;

// ------------------------------------------------------------------------------------------
// A recorded bus.

/// Control ticks of the recorded run. The wheel command and the wheel feedback go out every
/// tick, so each of their ids carries more than 2^16 frames and their low counters wrap.
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

    fn check(&self) -> Check {
        protection_of(self.id(), self.frame.data()).0.check
    }

    /// The refusal a check that does not hold gives this frame.
    fn check_failed(&self) -> DecodeError {
        let id = self.frame.id();
        match self.check() {
            Check::Crc => DecodeError::CrcMismatch { id },
            Check::Mac => DecodeError::Unauthentic { id },
        }
    }
}

/// A node of the bus: what it receives with and what it sends with.
#[derive(Debug, Clone)]
struct Node {
    id: NodeId,
    rx: Receiver,
    tx: Sender,
}

impl Node {
    fn member(id: NodeId) -> Node {
        Node {
            id,
            rx: Receiver::member(TEST_KEY),
            tx: Sender::new(),
        }
    }
}

/// The controller, the teleop and the wheel drive (and whoever joins later) on one bus. Every
/// frame a node sends reaches every other node, which must accept it.
#[derive(Debug, Clone)]
struct Bus {
    nodes: Vec<Node>,
    /// The next counter of each identifier in the present session (each has one sender).
    next: [u32; MessageId::ALL.len()],
    log: Vec<Logged>,
}

impl Bus {
    /// The controller opens `epoch` and announces it; the teleop and the wheel drive join.
    fn start(epoch: Epoch) -> Bus {
        let controller = Node {
            id: NodeId::Controller,
            rx: Receiver::owner(Session::owned(TEST_KEY, epoch)),
            tx: Sender::new(),
        };
        let mut bus = Bus {
            nodes: vec![
                controller,
                Node::member(NodeId::Teleop),
                Node::member(NodeId::WheelDrive),
            ],
            next: [0; MessageId::ALL.len()],
            log: Vec::new(),
        };
        bus.announce();
        bus.assert_all_in(epoch);
        bus
    }

    /// The controller restarts into `epoch`: a new owner and sender; the members hear the
    /// announcement and move.
    fn restart(&mut self, epoch: Epoch) {
        self.nodes[0] = Node {
            id: NodeId::Controller,
            rx: Receiver::owner(Session::owned(TEST_KEY, epoch)),
            tx: Sender::new(),
        };
        self.next = [0; MessageId::ALL.len()];
        self.announce();
        self.assert_all_in(epoch);
    }

    /// A node joins: it hears the controller's next announcement.
    fn join(&mut self, id: NodeId) {
        self.nodes.push(Node::member(id));
        self.announce();
        let epoch = self.nodes[0].rx.session().epoch();
        assert_eq!(self.nodes.last().unwrap().rx.session().epoch(), epoch);
    }

    fn assert_all_in(&self, epoch: Epoch) {
        for node in &self.nodes {
            assert_eq!(node.rx.session().epoch(), Some(epoch), "{:?}", node.id);
        }
    }

    fn announce(&mut self) {
        let epoch = self.nodes[0].rx.session().epoch().unwrap();
        self.send(
            NodeId::Controller,
            AnyMessage::Announce(Announce {
                version: WireVersion::THIS,
                epoch,
            }),
        );
    }

    /// `from` seals `message` under its session and sends it.
    fn send(&mut self, from: NodeId, message: AnyMessage) {
        let node = self.nodes.iter_mut().find(|n| n.id == from).unwrap();
        let session = *node.rx.session();
        let frame = node.tx.seal(&session, &message).unwrap();
        let epoch = session.epoch();
        let slot = &mut self.next[message.id().index()];
        let counter = *slot;
        *slot += 1;
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

    /// The robot's traffic of control ticks `ticks`.
    fn run(&mut self, ticks: std::ops::Range<u32>) {
        for t in ticks {
            self.tick(t);
        }
    }

    fn tick(&mut self, t: u32) {
        use NodeId::{Controller, Teleop, WheelDrive};
        let small = |x: u32| (x % 2000) as i16 - 1000;
        if t % 100 == 0 {
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
                position: [WheelAngle::from_raw(small(t * 7)).unwrap(); 2],
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
        bus.run(0..TICKS);
        let log = std::mem::take(&mut bus.log);
        let mut last = [None; MessageId::ALL.len()];
        for logged in log.iter().filter(|l| !l.is_latch()) {
            last[logged.id().index()] = Some(logged.counter);
        }
        let later = bus.clone();

        bus.restart(NEW);
        bus.join(NodeId::LegDriveFl);
        bus.run(0..300);
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
        // Announcements are ordered by their low counter within the epoch.
        let delta = (logged.counter as u16).wrapping_sub(last as u16);
        assert!(
            delta == 0 || delta >= 0x8000,
            "fixture: announcements within 2^15"
        );
        return Err(if delta == 0 {
            DecodeError::Repeated { id }
        } else {
            DecodeError::WrongSequence { id }
        });
    }
    Err(match last - logged.counter {
        0 => DecodeError::Repeated { id },
        1..=0x8000 => DecodeError::WrongSequence { id },
        // From 2^15 + 1 frames back the low half places it ahead or on the last frame, at a
        // full counter it was not sealed with.
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
/// expected one; each refusal must be counted under its cause, and nothing counted as lost.
/// Returns the refusals by cause over all nodes.
fn replay(
    bus: &mut Bus,
    frames: &[Logged],
    expected: impl Fn(&Logged) -> Result<(), DecodeError>,
) -> Tally {
    replay_heard(bus, frames, expected, hears)
}

fn replay_heard(
    bus: &mut Bus,
    frames: &[Logged],
    expected: impl Fn(&Logged) -> Result<(), DecodeError>,
    hears: impl Fn(NodeId, Option<Epoch>, &Logged) -> bool,
) -> Tally {
    let mut all: Tally = [0; RejectCause::ALL.len()];
    for node in &mut bus.nodes {
        let epoch = node.rx.session().epoch();
        let heard: Vec<&Logged> = frames.iter().filter(|l| hears(node.id, epoch, l)).collect();
        // In chunks, so that no 16-bit counter wraps between two readings.
        for chunk in heard.chunks(20_000) {
            let before = *node.rx.counters();
            let mut tally: Tally = [0; RejectCause::ALL.len()];
            for logged in chunk {
                let got = node.rx.receive(logged.frame.id(), logged.frame.data());
                match (got, expected(logged)) {
                    (Ok(accepted), Ok(())) => {
                        assert!(logged.is_latch());
                        assert_eq!(accepted.status, E2eStatus::Initial);
                        assert!(matches!(
                            accepted.message,
                            AnyMessage::EStop(EStop {
                                action: EStopAction::Latch,
                                ..
                            })
                        ));
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
            let latches = chunk.iter().filter(|l| l.is_latch()).count();
            assert_eq!(refused as usize + latches, chunk.len());
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

/// After a replay the genuine traffic goes on: every node accepts every frame, all in
/// sequence (no loss counted, no refusal).
fn traffic_goes_on(bus: &mut Bus, ticks: std::ops::Range<u32>) {
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
}

#[test]
fn the_whole_log_replayed_later_in_its_session_is_refused_but_for_the_latches() {
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
    traffic_goes_on(&mut bus, TICKS..TICKS + 200);
}

#[test]
fn the_whole_log_replayed_in_a_new_session_is_refused_but_for_the_latches() {
    let recorded = recorded();
    let mut bus = recorded.next_session.clone();
    // A receiver with no sequence on a CRC identifier looks for each frame in 256 high halves:
    // for the 2^16 and more frames of an identifier that takes long in a debug build. Those
    // are the node that joined last (no sequence on any identifier) and each node's own
    // identifiers; the proptests below replay slices of the log to them.
    bus.nodes.retain(|n| n.id != NodeId::LegDriveFr);
    let tally = replay_heard(
        &mut bus,
        &recorded.log,
        expected_next_session,
        |node, _, logged| logged.from != node,
    );
    for cause in [
        RejectCause::Crc,
        RejectCause::Unauthentic,
        RejectCause::Session,
    ] {
        assert!(tally[cause as usize] > 0, "{cause:?}: {tally:?}");
    }
    assert_eq!(tally[RejectCause::Repeated as usize], 0);
    assert_eq!(tally[RejectCause::WrongSequence as usize], 0);
    traffic_goes_on(&mut bus, 300..500);
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
        traffic_goes_on(&mut bus, TICKS..TICKS + 5);
    }

    #[test]
    fn any_frame_replayed_in_a_new_session_is_refused(at in any::<prop::sample::Index>()) {
        let mut bus = recorded().next_session.clone();
        replay(&mut bus, slice(at, 1), expected_next_session);
        traffic_goes_on(&mut bus, 300..305);
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
            traffic_goes_on(&mut bus, TICKS..TICKS + 5);
            let mut bus = recorded().next_session.clone();
            replay(&mut bus, pair, expected_next_session);
            traffic_goes_on(&mut bus, 300..305);
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
        traffic_goes_on(&mut bus, TICKS..TICKS + 5);
        let mut bus = recorded().next_session.clone();
        replay(&mut bus, frames, expected_next_session);
        traffic_goes_on(&mut bus, 300..305);
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

fn authenticated_messages() -> Vec<(AnyMessage, fn() -> Receiver)> {
    let owner: fn() -> Receiver = || Receiver::owner(common::controller_session());
    let member: fn() -> Receiver = || joined_member(common::EPOCH);
    vec![
        (
            AnyMessage::TeleopCommand(TeleopCommand {
                mode: TeleopMode::TrotForward,
                body_height: BodyHeight::default(),
                speed_scale: SpeedScale::from_raw(100).unwrap(),
            }),
            owner,
        ),
        (
            AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
                uptime: Millis::from_raw(99).unwrap(),
            }),
            owner,
        ),
        (
            AnyMessage::EStop(EStop::release(NodeId::Teleop, ReleaseToken::new(2))),
            owner,
        ),
        (
            AnyMessage::LegTargets(LegTargets {
                enable: DriveEnable::Enabled,
                position: [Angle::from_raw(3000).unwrap(); 16].into(),
            }),
            member,
        ),
        (
            AnyMessage::WheelCommand(WheelCommand {
                torque: [Torque::from_raw(-2500).unwrap(); 2],
            }),
            member,
        ),
    ]
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

    let announce = announce_frame(WireVersion::THIS, OLD, 0);
    let accepted = receive(&mut member, &announce).unwrap();
    assert_eq!(accepted.status, E2eStatus::Initial);
    assert_eq!(
        accepted.message,
        AnyMessage::Announce(Announce {
            version: WireVersion::THIS,
            epoch: OLD
        })
    );
    assert_eq!(member.session().epoch(), Some(OLD));
    assert_eq!(*member.session().key(), TEST_KEY);
    assert_eq!(
        receive(&mut member, &wheel_command(0, OLD)).unwrap().status,
        E2eStatus::Initial
    );
    // Its first bound frame starts its counter on that id at zero: the refused attempt above
    // used none.
    let frame = tx.seal(member.session(), &command).unwrap();
    assert_eq!(decode_frame(frame.id(), frame.data()).unwrap().counter, 0);
    let mut owner = Receiver::owner(Session::owned(TEST_KEY, OLD));
    assert!(receive(&mut owner, &frame).is_ok());
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
    for _ in 0..10 {
        tx.seal(member.session(), &heartbeat).unwrap();
    }
    assert_eq!(tx.high_water(), 10);

    let announce = announce_frame(WireVersion::THIS, NEW, 0);
    assert!(receive(&mut member, &announce).is_ok());
    assert_eq!(member.session().epoch(), Some(NEW));
    // The restarted controller counts from zero, and the member follows.
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
            Err(DecodeError::Unauthentic { id: 0x101 }),
            "old-session counter {counter}"
        );
    }
    // So does the member's own sender.
    let frame = tx.seal(member.session(), &heartbeat).unwrap();
    assert_eq!(decode_frame(frame.id(), frame.data()).unwrap().counter, 0);
    let mut owner = Receiver::owner(Session::owned(TEST_KEY, NEW));
    assert_eq!(
        receive(&mut owner, &frame).unwrap().status,
        E2eStatus::Initial
    );
    assert_eq!(member.counters().get(RejectCause::Unauthentic).raw(), 7);
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
    assert_eq!(
        receive(&mut member, &announces[3]),
        Err(DecodeError::Repeated { id: 0x020 })
    );
    for frame in &announces[..3] {
        assert_eq!(
            receive(&mut member, frame),
            Err(DecodeError::WrongSequence { id: 0x020 })
        );
    }
    assert_eq!(member.counters().get(RejectCause::Repeated).raw(), 1);
    assert_eq!(member.counters().get(RejectCause::WrongSequence).raw(), 3);
    // The next genuine one is taken, a gap is no matter, and none of this reset the session.
    receive(&mut member, &wheel_command(0, OLD)).unwrap();
    assert!(receive(&mut member, &announces[4]).is_ok());
    assert!(receive(&mut member, &announce_frame(WireVersion::THIS, OLD, 40)).is_ok());
    assert_eq!(
        receive(&mut member, &wheel_command(1, OLD)).unwrap().status,
        E2eStatus::Ok
    );
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
    let mut member = Receiver::member(TEST_KEY);
    receive(&mut member, &announce_frame(WireVersion::THIS, OLD, 0)).unwrap();
    for counter in 62_990..=63_000 {
        receive(&mut member, &wheel_command(counter, OLD)).unwrap();
    }
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
fn the_longest_burst_accepted_is_just_under_half_the_counter_range() {
    let mut member = joined_member(OLD);
    receive(&mut member, &wheel_command(100, OLD)).unwrap();
    let frame = wheel_command(100 + 0x8000, OLD);
    assert_eq!(
        receive(&mut member, &frame),
        Err(DecodeError::Unauthentic { id: 0x101 }),
        "2^15 − 1 lost: the frame reads as behind"
    );
    let frame = wheel_command(100 + 0x7FFF, OLD);
    assert_eq!(
        receive(&mut member, &frame).unwrap().status,
        E2eStatus::OkSomeLost { lost: 0x7FFE }
    );
    assert_eq!(member.counters().lost.raw(), 0x7FFE);
}

#[test]
fn a_late_joiner_finds_a_crc_sender_past_the_first_wrap() {
    // A CRC is tried at 256 high halves for the first frame of a sender.
    let status = |counter: u32| {
        AnyMessage::Sync(Sync {
            tick: Tick::from_raw(counter).unwrap(),
        })
        .encode(&Session::owned(TEST_KEY, OLD), counter)
        .unwrap()
    };
    let mut member = joined_member(OLD);
    let first = 200 << 16 | 0x1234;
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
fn the_sender_counts_per_identifier_and_resumes_where_told() {
    let session = Session::owned(TEST_KEY, OLD);
    let mut tx = Sender::new();
    let low = |frame: Frame| decode_frame(frame.id(), frame.data()).unwrap().counter;
    let wheel = AnyMessage::WheelCommand(WheelCommand {
        torque: [Torque::default(); 2],
    });
    let legs = AnyMessage::LegTargets(LegTargets {
        enable: DriveEnable::Disabled,
        position: [Angle::default(); 16].into(),
    });
    assert_eq!(tx.high_water(), 0);
    for expected in 0..3 {
        assert_eq!(low(tx.seal(&session, &wheel).unwrap()), expected);
    }
    assert_eq!(low(tx.seal(&session, &legs).unwrap()), 0);
    assert_eq!(tx.high_water(), 3);

    // The teleop restarts within the session. The controller heard its heartbeats 0…9.
    let heartbeat = AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
        uptime: Millis::from_raw(1).unwrap(),
    });
    let mut teleop = Sender::new();
    let mut controller = Receiver::owner(session);
    for _ in 0..10 {
        let frame = teleop.seal(&session, &heartbeat).unwrap();
        receive(&mut controller, &frame).unwrap();
    }
    let resume_at = teleop.high_water();
    assert_eq!(resume_at, 10);
    // Started afresh, its frames are behind the controller's sequence: refused.
    let frame = Sender::new().seal(&session, &heartbeat).unwrap();
    assert_eq!(
        receive(&mut controller, &frame),
        Err(DecodeError::WrongSequence { id: 0x201 })
    );
    // Resumed from what it persisted, it is in sequence.
    let mut resumed = Sender::resuming(&session, resume_at);
    let frame = resumed.seal(&session, &heartbeat).unwrap();
    assert_eq!(low(frame), 10);
    assert_eq!(
        receive(&mut controller, &frame).unwrap().status,
        E2eStatus::Ok
    );
    assert_eq!(resumed.high_water(), 11);
    // Resuming another session's counters is starting afresh.
    let mut moved = Sender::resuming(&session, 500);
    let frame = moved
        .seal(&Session::owned(TEST_KEY, NEW), &heartbeat)
        .unwrap();
    assert_eq!(low(frame), 0);
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
