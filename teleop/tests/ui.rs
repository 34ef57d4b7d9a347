//! The terminal UI on ratatui's test backend: keys in, frames out, the bus status on screen.

use protocol::{
    Angle, Announce, AnyMessage, BodyHeight, ControllerMode, ControllerStatus, Count, Drive,
    DriveFlags, DriveStatus, EStop, EStopAction, Epoch, FaultFlags, Frame, MessageId, Receiver,
    RejectCause, RejectCounters, ReleaseToken, Sender, Session, TeleopCommand, TeleopMode, Tick,
    Torque, WheelFeedback, WheelVelocity, WireVersion, TEST_KEY,
};
use ratatui::backend::TestBackend;
use ratatui::Terminal;
use teleop::app::{App, SimView};
use teleop_core::keys::Key;

fn screen(app: &App, now_ms: u64) -> String {
    let mut terminal = Terminal::new(TestBackend::new(110, 40)).unwrap();
    terminal
        .draw(|frame| teleop::ui::draw(frame, app, now_ms))
        .unwrap();
    let buffer = terminal.backend().buffer();
    let width = buffer.area.width as usize;
    buffer
        .content()
        .chunks(width)
        .map(|row| row.iter().map(|cell| cell.symbol()).collect::<String>())
        .collect::<Vec<_>>()
        .join("\n")
}

/// The rest of the bus as the operator hears it: the controller's session (its announcement
/// and status, and its receiver for what the operator sends) and the drives' feedback.
struct Robot {
    session: Session,
    sender: Sender,
    rx: Receiver,
}

impl Robot {
    fn new() -> Self {
        let session = Session::owned(TEST_KEY, Epoch::new(1));
        Self {
            session,
            sender: Sender::new(),
            rx: Receiver::owner(session),
        }
    }

    fn seal(&mut self, message: AnyMessage) -> Frame {
        self.sender.seal(&self.session, &message).unwrap()
    }

    fn announce(&mut self) -> Frame {
        self.seal(AnyMessage::Announce(Announce {
            version: WireVersion::THIS,
            epoch: Epoch::new(1),
            time: self.session.time(),
        }))
    }

    /// The controller's status; a release must echo token 4.
    fn status(&mut self, mode: ControllerMode, faults: FaultFlags) -> Frame {
        self.seal(AnyMessage::ControllerStatus(ControllerStatus {
            mode,
            faults,
            tick: Tick::from_raw(100).unwrap(),
            body_height: BodyHeight::saturating_from_si(-0.02),
            pitch: Angle::saturating_from_si(0.05),
            roll: Angle::saturating_from_si(-0.01),
            release_token: ReleaseToken::new(4),
        }))
    }

    fn wheels(&mut self, left: f32, right: f32) -> Frame {
        self.seal(AnyMessage::WheelFeedback(WheelFeedback {
            velocity: [
                WheelVelocity::saturating_from_si(left),
                WheelVelocity::saturating_from_si(right),
            ],
            effort: [Torque::saturating_from_si(0.0); 2],
        }))
    }

    /// What the controller makes of the operator's frames (every one must be accepted).
    fn decode_all(&mut self, frames: &[Frame]) -> Vec<AnyMessage> {
        frames
            .iter()
            .map(|f| self.rx.receive(f.id(), f.data()).unwrap().message)
            .collect()
    }
}

#[test]
fn keys_go_out_as_frames_and_the_estop_shows_until_released() {
    let mut app = App::new("vcan0");
    let mut robot = Robot::new();
    app.observe(0, &robot.announce());
    let first = robot.decode_all(&app.poll(0).unwrap());
    assert!(matches!(
        first.as_slice(),
        [
            AnyMessage::TeleopCommand(TeleopCommand {
                mode: TeleopMode::Stop,
                ..
            }),
            AnyMessage::TeleopHeartbeat(_)
        ]
    ));
    app.key(5, Key::Char('l'));
    let sent = robot.decode_all(&app.poll(5).unwrap());
    assert!(
        matches!(
            sent.as_slice(),
            [AnyMessage::TeleopCommand(TeleopCommand {
                mode: TeleopMode::TrotForward,
                ..
            })]
        ),
        "L goes out at once: {sent:?}"
    );
    let shown = screen(&app, 5);
    assert!(shown.contains("command L trot forward"), "{shown}");

    app.key(9, Key::Up);
    app.key(9, Key::Char('['));
    let sent = robot.decode_all(&app.poll(9).unwrap());
    let AnyMessage::TeleopCommand(command) = sent[0] else {
        panic!("{sent:?}")
    };
    assert!((command.body_height.si() - 0.01).abs() < 1e-3);
    assert!((command.speed_scale.si() - 90.0).abs() < 0.5);
    assert!(screen(&app, 9).contains("height +0.01 m   speed 90 %"));

    app.key(12, Key::Char(' '));
    let sent = robot.decode_all(&app.poll(12).unwrap());
    assert!(matches!(
        sent.first(),
        Some(AnyMessage::EStop(EStop {
            action: EStopAction::Latch,
            ..
        }))
    ));
    // Not confirmed yet: the screen says so, and the latch goes out again every 4 ms.
    let shown = screen(&app, 12);
    assert!(shown.contains("E-STOP SENT, not yet confirmed"), "{shown}");
    assert!(shown.contains("command X stop"), "{shown}");
    let again = robot.decode_all(&app.poll(16).unwrap());
    assert!(
        again.iter().any(|m| matches!(
            m,
            AnyMessage::EStop(EStop {
                action: EStopAction::Latch,
                ..
            })
        )),
        "{again:?}"
    );
    // The controller reports it: the screen shows the controller's state, and the latch stops.
    app.observe(
        18,
        &robot.status(ControllerMode::EStop, FaultFlags::ESTOP_LATCHED),
    );
    let shown = screen(&app, 18);
    assert!(shown.contains("E-STOP LATCHED, confirmed"), "{shown}");
    for t in 19..60 {
        let frames = robot.decode_all(&app.poll(t).unwrap());
        assert!(
            !frames.iter().any(|m| matches!(m, AnyMessage::EStop(_))),
            "t {t}: {frames:?}"
        );
    }

    app.key(100, Key::Char('r'));
    assert!(screen(&app, 100).contains("press R again within 2 s"));
    app.key(200, Key::Char('R'));
    let sent = robot.decode_all(&app.poll(200).unwrap());
    assert!(
        matches!(
            sent.first(),
            Some(AnyMessage::EStop(EStop {
                action: EStopAction::Clear,
                token,
                ..
            })) if token.raw() == 4
        ),
        "the release echoes the controller's token: {sent:?}"
    );
    app.observe(
        201,
        &robot.status(ControllerMode::Stop, FaultFlags::AWAITING_STOP),
    );
    app.poll(201).unwrap();
    let shown = screen(&app, 201);
    assert!(
        !shown.contains("E-STOP LATCHED") && !shown.contains("E-STOP SENT"),
        "{shown}"
    );
    assert!(shown.contains("E-stop released"), "{shown}");

    app.key(300, Key::Char('z'));
    assert!(screen(&app, 300).contains("`z` does nothing"));
    app.key(300, Key::Char('q'));
    assert!(app.quit_requested());
    let farewell = robot.decode_all(&app.farewell(301).unwrap());
    assert!(
        farewell.iter().any(|m| matches!(
            m,
            AnyMessage::TeleopCommand(TeleopCommand {
                mode: TeleopMode::Stop,
                ..
            })
        )),
        "quitting sends STOP: {farewell:?}"
    );
}

#[test]
fn the_heartbeat_keeps_going_at_50_hz_without_keys() {
    let mut app = App::new("vcan0");
    // Nothing goes out before the controller's session is joined, not even a heartbeat.
    assert!((0..100).all(|t| app.poll(t).unwrap().is_empty()));
    app.observe(100, &Robot::new().announce());
    let beats: usize = (100..1_100)
        .map(|t| {
            app.poll(t)
                .unwrap()
                .iter()
                .filter(|f| f.id() == MessageId::TeleopHeartbeat.raw())
                .count()
        })
        .sum();
    assert_eq!(beats, 50);
    assert!(screen(&app, 1_100).contains("heartbeat sent"));
}

#[test]
fn the_bus_status_is_rendered_and_silence_gets_a_banner() {
    let mut app = App::new("vcan0");
    let mut robot = Robot::new();
    let shown = screen(&app, 0);
    assert!(shown.contains("CONTROLLER SILENT (never heard)"), "{shown}");
    assert!(shown.contains("DRIVES SILENT (never heard)"), "{shown}");

    app.observe(
        1_000,
        &robot.status(ControllerMode::WheelForward, FaultFlags::TELEOP_TIMEOUT),
    );
    app.observe(1_002, &robot.wheels(4.0, -1.5));
    let wheel_status = DriveStatus {
        flags: DriveFlags::ENABLED,
        rejected: Count::default(),
        commands: Count::default(),
    };
    app.observe(
        1_003,
        &robot.seal(AnyMessage::DriveStatus(Drive::Wheel, wheel_status)),
    );
    let fl_status = DriveStatus {
        flags: DriveFlags::TIMED_OUT,
        ..wheel_status
    };
    app.observe(
        1_003,
        &robot.seal(AnyMessage::DriveStatus(Drive::LegFl, fl_status)),
    );
    let mut counters = RejectCounters::default();
    for _ in 0..3 {
        counters.record(RejectCause::Crc);
    }
    counters.record(RejectCause::Repeated);
    counters.record(RejectCause::RateLimited);
    counters.record(RejectCause::RateLimited);
    app.observe(1_004, &robot.seal(AnyMessage::RejectCounters(counters)));
    app.set_sim(SimView {
        time_s: 12.5,
        position_m: [1.234, -0.05],
        yaw_deg: 30.0,
        height_m: 0.27,
        tilt_deg: 3.0,
    });

    let shown = screen(&app, 1_010);
    for needle in [
        "mode   WheelForward",
        "faults teleop_timeout",
        "pitch +2.9°",
        "height -0.020 m",
        "speed  L +4.00  R -1.50 rad/s",
        "FL     timed_out",
        "wheels enabled",
        "BR     no status",
        "crc 3",
        "repeated 1",
        "rate limited 2",
        "controller lost 0",
        "5 frames/s",
        "x +1.23 m",
        "yaw +30°",
    ] {
        assert!(shown.contains(needle), "`{needle}` missing from\n{shown}");
    }
    assert!(!shown.contains("SILENT"), "{shown}");

    // 300 ms later nothing more came: both get their banner, with the age.
    let shown = screen(&app, 1_310);
    assert!(
        shown.contains("CONTROLLER SILENT (silent for 310 ms)"),
        "{shown}"
    );
    assert!(
        shown.contains("DRIVES SILENT (silent for 308 ms)"),
        "{shown}"
    );
}
