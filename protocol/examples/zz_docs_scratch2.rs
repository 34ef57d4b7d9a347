use protocol::*;
fn hb() -> AnyMessage { AnyMessage::TeleopHeartbeat(TeleopHeartbeat { uptime: Millis::saturating_from_si(0.0) }) }
fn main() {
    // 1) teleop joins at 1 s, heartbeats every 20 ms; controller receives all, then loses N.
    for (lost, label) in [(10u32, "10 lost"), (0x8000 + 10, "2^15+10 lost")] {
        for join_ms in [1_000u32, 600_000] {
            let epoch = Epoch::new(3);
            let ctl = Session::owned(TEST_KEY, epoch);
            let mut rx = Receiver::owner(ctl);
            let mut tx = Sender::new();
            let mut t = join_ms;
            let mut last = None;
            for i in 0..(100 + lost + 1) {
                let s = ctl.at(SessionTime::from_ms(t));
                let f = tx.seal(&s, &hb()).unwrap();
                if i < 100 || i == 100 + lost {
                    rx.set_time(SessionTime::from_ms(t));
                    last = Some(rx.receive(f.id(), f.data()).map(|a| a.status));
                }
                t += 20;
            }
            println!("owner, teleop joined {join_ms} ms, {label}: last frame {:?} at t={} ms", last, t - 20);
        }
    }
    // 2) member drive joining late: controller's LegTargets at 250 Hz since time 0.
    for join_h in [1.0f64, 5.0, 7.0] {
        let ctl = Session::owned(TEST_KEY, Epoch::new(3));
        let mut tx = Sender::new();
        let join_ms = (join_h * 3600e3) as u32;
        // controller sends 1 frame / 4 ms from 0 to join: counter = join/4
        // simulate: first frame at 0 sets counters to 0, then jump
        let _ = tx.seal(&ctl.at(SessionTime::from_ms(0)), &AnyMessage::WheelCommand(WheelCommand { torque: [Torque::saturating_from_si(0.0); 2] })).unwrap();
        let counter = join_ms / 4;
        let ann = AnyMessage::Announce(Announce { version: WireVersion::THIS, epoch: Epoch::new(3), time: SessionTime::from_ms(join_ms) }).encode(&ctl, 0).unwrap();
        let f = AnyMessage::WheelCommand(WheelCommand { torque: [Torque::saturating_from_si(0.0); 2] }).encode(&ctl.at(SessionTime::from_ms(join_ms)), counter).unwrap();
        let mut rx = Receiver::member(TEST_KEY);
        let a = rx.receive(ann.id(), ann.data()).map(|a| a.status);
        let r = rx.receive(f.id(), f.data()).map(|a| a.status);
        println!("member joins at {join_h} h, 250 Hz command counter {counter}: announce {a:?}, command {r:?}");
    }
}
