//! The recorded bus, built once per test binary, and the replay of its frames to the nodes
//! later in the session and in a new one.

use std::sync::OnceLock;

use protocol::*;

use super::bus::{Bus, Logged};
use super::frames::{NEW, OLD};

/// Control ticks of the recorded run, one per millisecond of session time. The wheel command and
/// the wheel feedback go out every tick, so each of their ids carries more than 2^16 frames and
/// their low counters wrap.
pub const TICKS: u32 = 70_000;

/// The recorded run and the bus at two points after it.
pub struct Recorded {
    /// Every frame of the run, in bus order.
    pub log: Vec<Logged>,
    /// The last counter of each identifier in the log, E-stop latches aside.
    pub last: [Option<u32>; MessageId::ALL.len()],
    /// The nodes right after the run: later in the session the log was recorded in.
    pub later: Bus,
    /// The same nodes after the controller restarted into a new session: the members moved,
    /// a node joined at the restart, 300 ticks of traffic ran, and one more node joined.
    pub next_session: Bus,
}

pub fn recorded() -> &'static Recorded {
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
pub fn expected_later(logged: &Logged) -> Result<(), DecodeError> {
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
pub fn expected_next_session(logged: &Logged) -> Result<(), DecodeError> {
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
pub type Tally = [u32; RejectCause::ALL.len()];

/// Whether a node in `epoch` is given a replay of `logged`: every frame but those it sent
/// itself in that session (its receiver never tracked those, as the node does not consume
/// them).
pub fn hears(node: NodeId, epoch: Option<Epoch>, logged: &Logged) -> bool {
    logged.from != node || logged.epoch != epoch
}

/// Replays `frames` to every node of `bus` as [`hears`] says. Each answer must be the
/// expected one (a refusal, or for a latch and the latest announcement, an acceptance that
/// moves nothing); each refusal must be counted under its cause, and nothing counted as lost.
/// Returns the refusals by cause over all nodes.
pub fn replay(
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
pub fn traffic_goes_on(bus: &mut Bus, ticks: u32) {
    let before: Vec<RejectCounters> = bus.nodes.iter().map(|n| *n.rx.counters()).collect();
    bus.run(ticks);
    for (node, before) in bus.nodes.iter().zip(before) {
        assert_eq!(*node.rx.counters(), before, "{:?}", node.id);
    }
}
