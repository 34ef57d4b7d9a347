//! A bus of nodes that seal, send and receive every frame, logging each one.

use protocol::e2e::{HEADER_LEN, MAX_LAG_MS};
use protocol::*;

use super::frames::{check_failed, PANEL_COUNTER};

/// One frame of the recorded bus.
#[derive(Debug, Clone, Copy)]
pub struct Logged {
    pub frame: Frame,
    /// Who sent it.
    pub from: NodeId,
    /// The full counter its sender used.
    pub counter: u32,
    /// The session its sender was in (none for a panel's classic latch).
    pub epoch: Option<Epoch>,
}

impl Logged {
    pub fn id(&self) -> MessageId {
        MessageId::from_raw(self.frame.id()).unwrap()
    }

    pub fn is_latch(&self) -> bool {
        self.id() == MessageId::EStop && self.frame.data()[HEADER_LEN] == EStopAction::Latch.raw()
    }

    /// The refusal a check that does not hold gives this frame.
    pub fn check_failed(&self) -> DecodeError {
        check_failed(&self.frame)
    }
}

/// A node of the bus: what it receives with and what it sends with.
#[derive(Debug, Clone)]
pub struct Node {
    pub id: NodeId,
    pub rx: Receiver,
    pub tx: Sender,
    /// The session time of its first frame in the present session, where all its counters
    /// start.
    pub start: Option<u32>,
}

impl Node {
    pub fn member(id: NodeId) -> Node {
        Node {
            id,
            rx: Receiver::member(TEST_KEY),
            tx: Sender::new(),
            start: None,
        }
    }

    pub fn controller(epoch: Epoch) -> Node {
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
pub struct Bus {
    pub nodes: Vec<Node>,
    /// The controller's session time, ms.
    pub time: u32,
    /// The next counter of each identifier in the present session (each has one sender), once
    /// it has sent on it.
    pub next: [Option<u32>; MessageId::ALL.len()],
    pub log: Vec<Logged>,
}

impl Bus {
    /// The controller opens `epoch` and announces it; the teleop and the wheel drive join.
    pub fn start(epoch: Epoch) -> Bus {
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
    pub fn restart(&mut self, epoch: Epoch) {
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
    pub fn join(&mut self, id: NodeId) {
        self.nodes.push(Node::member(id));
        self.set_time(self.time + 1);
        self.announce();
        let epoch = self.nodes[0].rx.session().epoch();
        assert_eq!(self.nodes.last().unwrap().rx.session().epoch(), epoch);
    }

    /// The controller's clock reads `time`.
    pub fn set_time(&mut self, time: u32) {
        assert!(time >= self.time, "session time runs forward");
        self.time = time;
        self.nodes[0].rx.set_time(SessionTime::from_ms(time));
    }

    pub fn assert_all_in(&self, epoch: Epoch) {
        for node in &self.nodes {
            assert_eq!(node.rx.session().epoch(), Some(epoch), "{:?}", node.id);
        }
    }

    pub fn announce(&mut self) {
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
    pub fn send(&mut self, from: NodeId, message: AnyMessage) {
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
    pub fn deliver(&mut self, logged: Logged) {
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
    pub fn run(&mut self, ticks: u32) {
        for t in self.time + 1..=self.time + ticks {
            self.tick(t);
        }
    }

    pub fn tick(&mut self, t: u32) {
        use NodeId::{Controller, Teleop, WheelDrive};
        self.set_time(t);
        let small = |x: u32| (x % 2000) as i16 - 1000;
        if t % 20 == 0 {
            self.announce();
        }
        self.send(
            Controller,
            AnyMessage::WheelCommand(WheelCommand {
                enable: DriveEnable::Enabled,
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
                    speed: Default::default(),
                    yaw_rate: Default::default(),
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
