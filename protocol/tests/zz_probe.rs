mod common;
use protocol::*;

fn ann(epoch: Epoch, ms: u32, counter: u32) -> Frame {
    let time = SessionTime::from_ms(ms);
    AnyMessage::Announce(Announce {
        version: WireVersion::THIS,
        epoch,
        time,
    })
    .encode(&Session::owned(TEST_KEY, epoch).at(time), counter)
    .unwrap()
}
fn hb() -> AnyMessage {
    AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
        uptime: Millis::from_raw(1).unwrap(),
    })
}

#[test]
fn probe_owner_half_boundary() {
    let e = Epoch::new(5);
    let mut owner = Receiver::owner(Session::owned(TEST_KEY, e));
    let mut teleop = Receiver::member(TEST_KEY);
    let a = ann(e, 65_500, 1);
    teleop.receive(a.id(), a.data()).unwrap();
    owner.set_time(SessionTime::from_ms(65_540));
    let mut tx = Sender::new();
    let f = tx.seal(teleop.session(), &hb()).unwrap();
    println!(
        "boundary first frame: {:?}",
        owner.receive(f.id(), f.data())
    );
}

#[test]
fn probe_slow_sender_gap_at_owner() {
    let e = Epoch::new(5);
    let mut owner = Receiver::owner(Session::owned(TEST_KEY, e));
    let mut teleop = Receiver::member(TEST_KEY);
    let a = ann(e, 1_000, 1);
    teleop.receive(a.id(), a.data()).unwrap();
    let mut tx = Sender::new();
    // 20 Hz heartbeats for 10 s, delivered.
    let mut t = 1_000;
    for _ in 0..200 {
        owner.set_time(SessionTime::from_ms(t));
        let f = tx.seal(teleop.session(), &hb()).unwrap();
        owner.receive(f.id(), f.data()).unwrap();
        t += 50;
    }
    // 40_000 heartbeats lost (2000 s at 20 Hz), teleop keeps hearing announcements.
    for i in 0..40_000 {
        if i % 2 == 0 {
            let a = ann(e, t, 2 + i);
            teleop.receive(a.id(), a.data()).unwrap();
        }
        tx.seal(teleop.session(), &hb()).unwrap();
        t += 50;
    }
    owner.set_time(SessionTime::from_ms(t));
    for _ in 0..3 {
        let f = tx.seal(teleop.session(), &hb()).unwrap();
        println!(
            "slow gap: {:?}",
            owner.receive(f.id(), f.data()).map(|a| a.status)
        );
    }
    let mut m = Receiver::member(TEST_KEY);
    let a = ann(e, t, 100_000);
    m.receive(a.id(), a.data()).unwrap();
    let f = tx.seal(teleop.session(), &hb()).unwrap();
    println!(
        "slow gap member: {:?}",
        m.receive(f.id(), f.data()).map(|a| a.status)
    );
}

#[test]
fn probe_release_lost() {
    let e = Epoch::new(5);
    let mut owner = Receiver::owner(Session::owned(TEST_KEY, e));
    let mut teleop = Receiver::member(TEST_KEY);
    let mut tx = Sender::new();
    for (i, t) in [10_000u32, 20_000, 30_000].into_iter().enumerate() {
        let a = ann(e, t, i as u32 + 1);
        teleop.receive(a.id(), a.data()).unwrap();
        owner.set_time(SessionTime::from_ms(t + 5));
        let f = tx
            .seal(
                teleop.session(),
                &AnyMessage::EStop(EStop::release(NodeId::Teleop, ReleaseToken::new(1))),
            )
            .unwrap();
        println!(
            "release: {:?} lost {}",
            owner.receive(f.id(), f.data()).map(|a| a.status),
            owner.counters().lost.raw()
        );
    }
}

#[test]
fn probe_late_member_slow_mac_id() {
    let e = Epoch::new(5);
    let legs = AnyMessage::LegTargets(LegTargets {
        enable: DriveEnable::Enabled,
        position: [Angle::default(); 16].into(),
    });
    for hours in [1u32, 6, 7] {
        let t = hours * 3_600_000;
        let mut m = Receiver::member(TEST_KEY);
        let a = ann(e, t, 1);
        m.receive(a.id(), a.data()).unwrap();
        // The controller's LegTargets at 250 Hz since time 0: counter t / 4.
        let f = legs.encode(&Session::owned(TEST_KEY, e), t / 4).unwrap();
        println!(
            "late member after {hours} h, LegTargets 250 Hz: {:?}",
            m.receive(f.id(), f.data()).map(|a| a.status)
        );
    }
}

#[test]
fn probe_equal_time() {
    let e = Epoch::new(5);
    let mut m = Receiver::member(TEST_KEY);
    let a = ann(e, 5000, 50);
    println!("{:?}", m.receive(a.id(), a.data()).map(|a| a.status));
    println!("time {:?}", m.session().time());
    let b = ann(e, 5000, 77);
    println!("{:?}", m.receive(b.id(), b.data()));
    println!("{:?}", m.receive(a.id(), a.data()));
    let c = ann(e, 4000, 77);
    println!("{:?}", m.receive(c.id(), c.data()));
}
