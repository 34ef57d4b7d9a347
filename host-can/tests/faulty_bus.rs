//! The fault layer on the in-process bus: each fault does what the plan says, is counted, and
//! the protocol's receiver rejects every corrupted, duplicated and replayed frame.

use std::time::Duration;

use host_can::bus::Bus;
use host_can::fault_plan::Faults;
use host_can::faulty_bus::FaultyBus;
use host_can::inproc_bus::{InprocBus, InprocEndpoint};
use protocol::SessionTime;
use protocol::{
    decode_frame, Announce, AnyMessage, BodyHeight, EStop, Epoch, Frame, NodeId, Receiver,
    RejectCause, Sender, Session, SpeedScale, Sync, TeleopCommand, TeleopMode, Tick, WireVersion,
    TEST_KEY,
};

/// The controller's session, in which every frame of these tests is sealed.
const SESSION: Session = Session::owned(TEST_KEY, Epoch::new(3));

/// A teleop command with full counter `counter`.
fn command(counter: u32) -> Frame {
    AnyMessage::TeleopCommand(TeleopCommand {
        mode: TeleopMode::TrotForward,
        body_height: BodyHeight::saturating_from_si(0.0),
        speed_scale: SpeedScale::saturating_from_si(1.0),
        speed: Default::default(),
        yaw_rate: Default::default(),
    })
    .encode(&SESSION, counter)
    .unwrap()
}

fn sync(tick: u32) -> Frame {
    AnyMessage::Sync(Sync {
        tick: Tick::from_raw(tick).unwrap(),
    })
    .encode(&SESSION, tick)
    .unwrap()
}

/// The low counter a frame carries.
fn counter(frame: &Frame) -> u16 {
    decode_frame(frame.id(), frame.data()).unwrap().counter
}

fn rig(faults: &str) -> (FaultyBus<InprocEndpoint>, InprocEndpoint) {
    let bus = InprocBus::new();
    let faulty = FaultyBus::new(bus.endpoint(), &faults.parse::<Faults>().unwrap());
    (faulty, bus.endpoint())
}

fn drain(bus: &mut dyn Bus) -> Vec<Frame> {
    std::iter::from_fn(|| bus.recv(Duration::ZERO).unwrap()).collect()
}

/// Sends `cycles` cycles of one command and a SYNC each; returns what the other side received.
fn run(
    faulty: &mut FaultyBus<InprocEndpoint>,
    other: &mut InprocEndpoint,
    cycles: u32,
) -> Vec<Frame> {
    let mut got = Vec::new();
    for cycle in 0..cycles {
        faulty.send(&command(cycle + 1)).unwrap();
        faulty.send(&sync(cycle)).unwrap();
        got.extend(drain(other));
    }
    got
}

#[test]
fn a_clean_plan_changes_nothing() {
    let (mut faulty, mut other) = rig("");
    let got = run(&mut faulty, &mut other, 50);
    assert_eq!(got.len(), 100);
    assert_eq!(faulty.tx_stats().frames, 50);
}

#[test]
fn drops_about_the_planned_share_and_never_the_sync() {
    let (mut faulty, mut other) = rig("tx.drop=0.2,seed=3");
    let got = run(&mut faulty, &mut other, 2000);
    let syncs = got.iter().filter(|f| f.id() == sync(0).id()).count();
    let commands = got.len() - syncs;
    assert_eq!(syncs, 2000);
    let dropped = faulty.tx_stats().dropped;
    assert_eq!(commands as u64 + dropped, 2000);
    assert!((320..480).contains(&dropped), "dropped {dropped} of 2000");
}

#[test]
fn burst_loss_drops_whole_runs_of_cycles_at_the_planned_share() {
    let (mut faulty, mut other) = rig("tx.drop=0.2,tx.burst=5,seed=3");
    let cycles = 10_000_u32;
    let got = run(&mut faulty, &mut other, cycles);
    let received: std::collections::BTreeSet<u16> = got
        .iter()
        .filter(|f| f.id() == command(0).id())
        .map(counter)
        .collect();
    let lost: Vec<bool> = (1..=cycles)
        .map(|c| !received.contains(&(c as u16)))
        .collect();
    let dropped = lost.iter().filter(|&&l| l).count();
    let runs = lost.windows(2).filter(|w| !w[0] && w[1]).count() + usize::from(lost[0]);
    let mean_run = dropped as f64 / runs.max(1) as f64;
    assert_eq!(dropped as u64, faulty.tx_stats().dropped);
    assert!(
        (1600..2400).contains(&dropped),
        "dropped {dropped} of {cycles}"
    );
    assert!(
        (4.0..6.0).contains(&mean_run),
        "bursts of {mean_run:.2} cycles"
    );
}

#[test]
fn delay_holds_frames_for_whole_cycles_in_order() {
    let (mut faulty, mut other) = rig("tx.delay=3");
    let mut arrival = Vec::new();
    for cycle in 0..10_u32 {
        // What the other side has at the start of the cycle, before this cycle's frames.
        for frame in drain(&mut other) {
            if frame.id() == command(1).id() {
                arrival.push((cycle, frame));
            }
        }
        faulty.send(&command(cycle + 1)).unwrap();
        faulty.send(&sync(cycle)).unwrap();
    }
    let expected: Vec<_> = (3..10).map(|c| (c, command(c - 2))).collect();
    assert_eq!(arrival, expected);
}

#[test]
fn flips_duplicates_and_replays_are_each_rejected_by_the_receiver() {
    let (mut faulty, mut other) = rig("tx.flip=0.1,tx.duplicate=0.1,tx.replay=0.1,seed=11");
    let got = run(&mut faulty, &mut other, 3000);
    let mut receiver = Receiver::owner(SESSION);
    let mut accepted_counters = Vec::new();
    for frame in got.iter().filter(|f| f.id() == command(1).id()) {
        if receiver.receive(frame.id(), frame.data()).is_ok() {
            accepted_counters.push(counter(frame));
        }
    }
    let stats = faulty.tx_stats();
    let counters = receiver.counters();
    assert!(
        stats.flipped > 200 && stats.duplicated > 200 && stats.replayed > 200,
        "{stats:?}"
    );
    // The command is authenticated: a flipped bit anywhere in it fails its MAC.
    assert_eq!(
        u64::from(counters.get(RejectCause::Unauthentic).raw()),
        stats.flipped
    );
    let sequence = u64::from(counters.get(RejectCause::Repeated).raw())
        + u64::from(counters.get(RejectCause::WrongSequence).raw());
    assert_eq!(sequence, stats.duplicated + stats.replayed);
    // Nothing old was ever accepted: the accepted counters only go up.
    assert!(accepted_counters.windows(2).all(|w| w[1] > w[0]));
}

#[test]
fn every_flipped_latch_is_rejected() {
    // An E-stop latch's check covers its action and source, not the token after them: the
    // layer flips only bits a receiver can detect.
    let (mut faulty, mut other) = rig("tx.flip=1,seed=4");
    let mut teleop = Sender::new();
    for _ in 0..200 {
        let latch = teleop
            .seal(&SESSION, &AnyMessage::EStop(EStop::latch(NodeId::Teleop)))
            .unwrap();
        faulty.send(&latch).unwrap();
    }
    let mut receiver = Receiver::owner(SESSION);
    let got = drain(&mut other);
    assert_eq!((got.len(), faulty.tx_stats().flipped), (200, 200));
    for frame in &got {
        assert!(
            receiver.receive(frame.id(), frame.data()).is_err(),
            "{frame:?}"
        );
    }
}

#[test]
fn silencing_a_node_drops_all_of_its_frames() {
    let (mut faulty, mut other) = rig("tx.silence=Teleop");
    let got = run(&mut faulty, &mut other, 20);
    assert!(got.iter().all(|f| f.id() == sync(0).id()));
    assert_eq!(faulty.tx_stats().silenced, 20);
}

#[test]
fn a_flood_keeps_one_valid_sequence() {
    let (mut faulty, mut other) = rig("tx.flood=40");
    // Nothing to seal the flood in before the controller's announcement is heard.
    faulty.send(&command(0)).unwrap();
    faulty.end_cycle().unwrap();
    assert_eq!(drain(&mut other), [command(0)]);
    assert_eq!(faulty.tx_stats().flooded, 0);
    let announce = AnyMessage::Announce(Announce {
        version: WireVersion::THIS,
        epoch: SESSION.epoch().unwrap(),
        time: SessionTime::from_ms(0),
    });
    other
        .send(&Sender::new().seal(&SESSION, &announce).unwrap())
        .unwrap();
    assert_eq!(drain(&mut faulty).len(), 1);
    let mut receiver = Receiver::owner(SESSION);
    for _ in 0..25 {
        // The teleop's own counter stands still; the layer owns the sequence.
        faulty.send(&command(1)).unwrap();
        faulty.end_cycle().unwrap();
    }
    let got = drain(&mut other);
    assert_eq!(got.len(), 25 * 41);
    for frame in &got {
        receiver.receive(frame.id(), frame.data()).unwrap();
    }
    assert_eq!(faulty.tx_stats().flooded, 25 * 40);
}

#[test]
fn reorder_swaps_a_frame_behind_the_next() {
    let (mut faulty, mut other) = rig("tx.reorder=1");
    faulty.send(&command(1)).unwrap();
    faulty.send(&command(2)).unwrap();
    faulty.send(&sync(0)).unwrap();
    let got = drain(&mut other);
    assert_eq!(got, [command(2), command(1), sync(0)]);
}

#[test]
fn received_frames_can_be_faulted_too() {
    let bus = InprocBus::new();
    let mut faulty = FaultyBus::new(bus.endpoint(), &"rx.delay=2".parse().unwrap());
    let mut other = bus.endpoint();
    let mut seen = Vec::new();
    for cycle in 0..6_u32 {
        other.send(&command(cycle + 1)).unwrap();
        other.send(&sync(cycle)).unwrap();
        for frame in drain(&mut faulty) {
            if frame.id() == command(1).id() {
                seen.push((cycle, frame));
            }
        }
    }
    // Sent before SYNC c, received after SYNC c + 1: two cycle boundaries later.
    let expected: Vec<_> = (1..6).map(|c| (c, command(c))).collect();
    assert_eq!(seen, expected);
}
