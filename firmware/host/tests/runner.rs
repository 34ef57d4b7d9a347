//! The runner answers SYNC with the firmware's commands, keeps time on the wall clock, and stops
//! the drives when it stops.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use firmware_host::runner::{self, Clock, RunnerConfig};
use host_can::bus::{Bus, BusError};
use host_can::inproc_bus::InprocBus;
use protocol::{
    AnyMessage, DriveEnable, Epoch, MessageId, Receiver, Sender, Session, Sync, Tick, TEST_KEY,
};

/// The session the runner under test opens.
const SESSION: Session = Session::owned(TEST_KEY, Epoch::new(1));

/// A runner configuration in [`SESSION`], nothing latched.
fn config(clock: Clock, max_ticks: Option<u64>, idle_timeout: Option<Duration>) -> RunnerConfig {
    RunnerConfig {
        session: SESSION,
        latched: false,
        clock,
        control_hz: 250,
        max_ticks,
        idle_timeout,
    }
}

fn sync(tick: u32, sender: &mut Sender, session: &Session) -> protocol::Frame {
    let sync = AnyMessage::Sync(Sync {
        tick: Tick::from_raw(tick).unwrap(),
    });
    sender.seal(session, &sync).unwrap()
}

#[test]
fn lockstep_answers_every_sync_with_a_wheel_command_then_stops_the_drives() {
    let bus = InprocBus::new();
    let mut sim = bus.endpoint();
    let mut firmware_bus = bus.endpoint();
    let stop = Arc::new(AtomicBool::new(false));
    let runner_stop = Arc::clone(&stop);
    let runner = std::thread::spawn(move || {
        runner::run(
            &mut firmware_bus,
            config(Clock::Lockstep, Some(50), Some(Duration::from_secs(10))),
            &runner_stop,
            None,
        )
    });
    // The simulator joins the session the runner announces while it waits for SYNC.
    let mut rx = Receiver::member(TEST_KEY);
    let announce = sim
        .recv(Duration::from_secs(5))
        .unwrap()
        .expect("the session announced");
    let accepted = rx.receive(announce.id(), announce.data()).unwrap();
    assert!(matches!(accepted.message, AnyMessage::Announce(_)));
    assert_eq!(rx.session().epoch(), SESSION.epoch());
    let session = *rx.session();
    let mut clock = Sender::new();
    let mut commands = 0;
    for tick in 0..50 {
        sim.send(&sync(tick, &mut clock, &session)).unwrap();
        // Each SYNC is answered with a wheel command before the next one is sent.
        loop {
            let frame = sim
                .recv(Duration::from_secs(5))
                .unwrap()
                .expect("an answer");
            let message = rx.receive(frame.id(), frame.data()).unwrap().message;
            if frame.id() == MessageId::WheelCommand.raw() {
                commands += 1;
                break;
            }
            let _ = message;
        }
    }
    let stats = runner.join().unwrap().unwrap();
    assert_eq!((commands, stats.ticks), (50, 50));
    assert_eq!(stats.rejected, [0; 10]);
    // The last frames: legs torque-free and zero wheel torque, accepted in sequence.
    let mut last_legs = None;
    while let Some(frame) = sim.recv(Duration::from_millis(100)).unwrap() {
        let accepted = rx.receive(frame.id(), frame.data()).expect("in sequence");
        if let AnyMessage::LegTargets(targets) = accepted.message {
            last_legs = Some(targets.enable);
        }
    }
    assert_eq!(last_legs, Some(DriveEnable::Disabled));
    assert!(!stop.load(Ordering::Relaxed));
}

#[test]
fn a_quiet_bus_in_lockstep_is_an_error_naming_the_simulator() {
    let bus = InprocBus::new();
    let mut firmware_bus = bus.endpoint();
    let err = runner::run(
        &mut firmware_bus,
        config(Clock::Lockstep, None, Some(Duration::from_millis(200))),
        &AtomicBool::new(false),
        None,
    )
    .unwrap_err();
    assert!(err.to_string().contains("simulator"), "{err}");
}

#[test]
fn heartbeats_without_sync_still_end_in_the_idle_timeout_and_a_stop_is_heard() {
    // A teleop keeps talking (heartbeats at 50 Hz), but no simulator sends SYNC: the idle
    // timeout must still fire; it used to be reset by any frame.
    let bus = InprocBus::new();
    let mut firmware_bus = bus.endpoint();
    let mut teleop = bus.endpoint();
    let done = Arc::new(AtomicBool::new(false));
    let talking = Arc::clone(&done);
    let talker = std::thread::spawn(move || {
        let mut sender = Sender::new();
        let mut uptime_ms = 0;
        while !talking.load(Ordering::Relaxed) {
            let beat = AnyMessage::TeleopHeartbeat(protocol::TeleopHeartbeat {
                uptime: protocol::Millis::from_raw(uptime_ms).unwrap(),
            });
            teleop.send(&sender.seal(&SESSION, &beat).unwrap()).unwrap();
            uptime_ms += 20;
            std::thread::sleep(Duration::from_millis(20));
        }
    });
    let started = Instant::now();
    let result = runner::run(
        &mut firmware_bus,
        config(Clock::Lockstep, None, Some(Duration::from_millis(300))),
        &AtomicBool::new(false),
        None,
    );
    let waited = started.elapsed();
    done.store(true, Ordering::Relaxed);
    talker.join().unwrap();
    let err = result.unwrap_err();
    assert!(err.to_string().contains("no SYNC"), "{err}");
    assert!(waited < Duration::from_secs(2), "took {waited:?}");

    // And a stop request is heard within the lockstep wait, traffic or not.
    let stop = Arc::new(AtomicBool::new(false));
    let later = Arc::clone(&stop);
    let stopper = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(200));
        later.store(true, Ordering::Relaxed);
        Instant::now()
    });
    let stats = runner::run(
        &mut bus.endpoint(),
        config(Clock::Lockstep, None, None),
        &stop,
        None,
    )
    .unwrap();
    let asked = stopper.join().unwrap();
    assert!(
        asked.elapsed() < Duration::from_millis(500),
        "stopped {:?} late",
        asked.elapsed()
    );
    assert_eq!(stats.ticks, 0);
}

#[test]
fn on_the_wall_clock_it_keeps_its_own_time() {
    let bus = InprocBus::new();
    let mut listener = bus.endpoint();
    let mut firmware_bus = bus.endpoint();
    let stats = runner::run(
        &mut firmware_bus,
        config(Clock::Wall, Some(25), None),
        &AtomicBool::new(false),
        None,
    )
    .unwrap();
    assert_eq!(stats.ticks, 25);
    let mut wheel_commands = 0;
    while let Some(frame) = listener.recv(Duration::ZERO).unwrap() {
        wheel_commands += usize::from(frame.id() == MessageId::WheelCommand.raw());
    }
    // One per tick, plus the stop.
    assert_eq!(wheel_commands, 26);
}

/// A bus whose owner is descheduled for `stall` once, after `stall_after` cycles, and that
/// notes when each wheel command went out.
struct StallingBus<B> {
    inner: B,
    cycles: u32,
    stall_after: u32,
    stall: Duration,
    wheel_commands_at: Vec<Instant>,
}

impl<B: Bus> Bus for StallingBus<B> {
    fn send(&mut self, frame: &protocol::Frame) -> Result<(), BusError> {
        if frame.id() == MessageId::WheelCommand.raw() {
            self.wheel_commands_at.push(Instant::now());
        }
        self.inner.send(frame)
    }
    fn recv(&mut self, timeout: Duration) -> Result<Option<protocol::Frame>, BusError> {
        self.inner.recv(timeout)
    }
    fn end_cycle(&mut self) -> Result<(), BusError> {
        self.cycles += 1;
        if self.cycles == self.stall_after {
            std::thread::sleep(self.stall);
        }
        Ok(())
    }
    fn name(&self) -> &str {
        self.inner.name()
    }
}

#[test]
fn a_stalled_wall_clock_runner_loses_the_missed_ticks_instead_of_bunching_them_up() {
    let bus = InprocBus::new();
    let mut stalling = StallingBus {
        inner: bus.endpoint(),
        cycles: 0,
        stall_after: 5,
        stall: Duration::from_millis(60),
        wheel_commands_at: Vec::new(),
    };
    let stats = runner::run(
        &mut stalling,
        config(Clock::Wall, Some(20), None),
        &AtomicBool::new(false),
        None,
    )
    .unwrap();
    assert_eq!(stats.ticks, 20);
    // 60 ms is 15 periods: the one due at once runs, at least 14 are lost.
    assert!(stats.overruns >= 14, "{} ticks lost", stats.overruns);
    // Never three commands within 2 ms: bunched catch-up ticks would send 15 at once (the last
    // command is the stop, sent right after the last tick, so it is left out).
    let sent = &stalling.wheel_commands_at[..20];
    let bunched = sent
        .windows(3)
        .filter(|w| w[2].duration_since(w[0]) < Duration::from_millis(2))
        .count();
    assert_eq!(
        bunched,
        0,
        "{:?}",
        sent.windows(2).map(|w| w[1] - w[0]).collect::<Vec<_>>()
    );
}

#[test]
fn the_wall_clock_schedule_keeps_going_past_two_to_the_32_periods() {
    use firmware_host::runner::{current_slot, slot_start};
    let period = Duration::from_millis(1);
    let wrap = 1_u64 << 32;
    // Each period begins one period after the last, on both sides of 2^32 (49.7 days at 1 kHz):
    // a schedule that stops there would run every later tick back to back.
    for slot in [wrap - 2, wrap - 1, wrap, wrap + 1, 3 * wrap] {
        assert_eq!(
            slot_start(period, slot + 1) - slot_start(period, slot),
            period,
            "slot {slot}"
        );
    }
    assert_eq!(slot_start(period, wrap), Duration::from_millis(wrap));
    // Waking in the period after 2^32 runs there and counts the one missed tick.
    let mut lost = 0;
    let elapsed = slot_start(period, wrap + 1) + Duration::from_micros(10);
    assert_eq!(current_slot(wrap, elapsed, period, &mut lost), wrap + 1);
    assert_eq!(lost, 1);
    // A huge slot saturates instead of overflowing.
    assert_eq!(
        slot_start(Duration::from_secs(1), u64::MAX).as_secs(),
        u64::MAX
    );
}

#[test]
fn the_state_file_gives_each_start_a_greater_epoch_and_keeps_a_latch_across_restarts() {
    use firmware_host::state::StateFile;
    use protocol::{EStop, NodeId};
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("runner-state");
    let _ = std::fs::remove_dir_all(&dir);
    let path = dir.join("firmware-host.toml");
    let (_, first, latched) = StateFile::start(&path, None).unwrap();
    assert_eq!((first.raw(), latched), (1, false));
    let (_, second, _) = StateFile::start(&path, None).unwrap();
    assert_eq!(second.raw(), 2);
    // After a lost state file, `--epoch` sets a floor.
    let (mut state, third, _) = StateFile::start(&path, Some(Epoch::new(10))).unwrap();
    assert_eq!(third.raw(), 10);

    // A latch heard in this run is written to the file...
    let bus = InprocBus::new();
    let mut firmware_bus = bus.endpoint();
    let mut panel = bus.endpoint();
    let latch = Sender::new()
        .seal(
            &Session::unjoined(TEST_KEY),
            &AnyMessage::EStop(EStop::latch(NodeId::Tool)),
        )
        .unwrap();
    panel.send(&latch).unwrap();
    let session = Session::owned(TEST_KEY, third);
    let wall = |latched| RunnerConfig {
        session,
        latched,
        ..config(Clock::Wall, Some(5), None)
    };
    runner::run(
        &mut firmware_bus,
        wall(false),
        &AtomicBool::new(false),
        Some(&mut state),
    )
    .unwrap();
    // ...and the next start, in a new session, begins latched.
    let (_, fourth, latched) = StateFile::start(&path, None).unwrap();
    assert_eq!((fourth.raw(), latched), (11, true));
    while panel.recv(Duration::ZERO).unwrap().is_some() {}
    let mut rx = Receiver::member(TEST_KEY);
    runner::run(
        &mut firmware_bus,
        RunnerConfig {
            session: Session::owned(TEST_KEY, fourth),
            max_ticks: Some(25),
            ..wall(true)
        },
        &AtomicBool::new(false),
        None,
    )
    .unwrap();
    let mut modes = Vec::new();
    while let Some(frame) = panel.recv(Duration::ZERO).unwrap() {
        if let AnyMessage::ControllerStatus(status) =
            rx.receive(frame.id(), frame.data()).unwrap().message
        {
            modes.push(status.mode);
        }
    }
    assert_eq!(rx.session().epoch(), Some(fourth));
    assert!(
        !modes.is_empty() && modes.iter().all(|m| *m == protocol::ControllerMode::EStop),
        "{modes:?}"
    );
}
