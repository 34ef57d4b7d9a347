//! The operator's frames: what goes out when, the latch and its confirmation, the release.

use super::*;
use crate::keys::{action, Key};
use protocol::{
    decode_frame, Angle, Announce, BodyHeight, ControllerStatus, Epoch, FaultFlags, MessageId,
    Receiver, ReleaseToken, Sender, Session, Tick, WireVersion,
};

/// The controller's side of the session, as far as an operator hears and is heard.
struct FakeController {
    session: Session,
    sender: Sender,
    rx: Receiver,
}

impl FakeController {
    fn new() -> Self {
        Self::with_epoch(7)
    }

    fn with_epoch(epoch: u32) -> Self {
        let session = Session::owned(TEST_KEY, Epoch::new(epoch));
        Self {
            session,
            sender: Sender::new(),
            rx: Receiver::owner(session),
        }
    }

    fn announce(&mut self) -> Frame {
        let announce = AnyMessage::Announce(Announce {
            version: WireVersion::THIS,
            epoch: self.session.epoch().unwrap(),
            time: self.session.time(),
        });
        self.sender.seal(&self.session, &announce).unwrap()
    }

    fn status(&mut self, mode: ControllerMode) -> Frame {
        let status = AnyMessage::ControllerStatus(ControllerStatus {
            mode,
            faults: FaultFlags::EMPTY,
            tick: Tick::from_raw(0).unwrap(),
            body_height: BodyHeight::saturating_from_si(0.0),
            pitch: Angle::saturating_from_si(0.0),
            roll: Angle::saturating_from_si(0.0),
            release_token: ReleaseToken::new(3),
        });
        self.sender.seal(&self.session, &status).unwrap()
    }

    fn decode(&mut self, frames: &[Frame]) -> Vec<AnyMessage> {
        frames
            .iter()
            .map(|f| self.rx.receive(f.id(), f.data()).unwrap().message)
            .collect()
    }
}

#[test]
fn nothing_but_a_latch_goes_out_before_the_controller_is_heard() {
    let mut op = Operator::new();
    assert!(op.poll(0).unwrap().is_empty());
    op.press(1, Action::EStop);
    let frames = op.poll(1).unwrap();
    assert_eq!(frames.len(), 1);
    assert_eq!(frames[0].id(), MessageId::EStop.raw());
    let mut ctl = FakeController::new();
    op.observe(&ctl.announce());
    assert!(op.joined());
    assert!(!ctl.decode(&op.poll(20).unwrap()).is_empty());
}

#[test]
fn a_key_goes_out_at_once_and_the_command_and_heartbeat_every_20_ms() {
    let mut op = Operator::new();
    let mut ctl = FakeController::new();
    op.observe(&ctl.announce());
    let first = ctl.decode(&op.poll(0).unwrap());
    assert_eq!(first.len(), 2, "command and heartbeat at start: {first:?}");
    assert!(op.poll(5).unwrap().is_empty(), "nothing between periods");
    op.press(7, action(Key::Char('w')).unwrap());
    let now = ctl.decode(&op.poll(7).unwrap());
    assert!(matches!(
        now.as_slice(),
        [AnyMessage::TeleopCommand(TeleopCommand {
            mode: TeleopMode::WheelForward,
            ..
        })]
    ));
    let periodic = op.poll(20).unwrap();
    let ids: Vec<u16> = periodic.iter().map(Frame::id).collect();
    assert_eq!(
        ids,
        [
            MessageId::TeleopCommand.raw(),
            MessageId::TeleopHeartbeat.raw()
        ]
    );
    // One second of polling every ms: 50 heartbeats.
    let beats = (21..1021)
        .flat_map(|t| op.poll(t).unwrap())
        .filter(|f| f.id() == MessageId::TeleopHeartbeat.raw())
        .count();
    assert_eq!(beats, 50);
}

#[test]
fn space_latches_at_once_and_only_r_twice_within_2_s_releases() {
    let mut op = Operator::new();
    let mut ctl = FakeController::new();
    op.observe(&ctl.announce());
    op.poll(0).unwrap();
    op.press(1, action(Key::Char('l')).unwrap());
    op.press(2, action(Key::Char(' ')).unwrap());
    let frames = ctl.decode(&op.poll(2).unwrap());
    assert!(matches!(
        frames.first(),
        Some(AnyMessage::EStop(EStop {
            action: EStopAction::Latch,
            ..
        }))
    ));
    assert_eq!(
        op.mode(),
        TeleopMode::Stop,
        "motion must be asked for again"
    );
    // R, then too late: nothing; R, R in time: released.
    op.press(100, Action::Release);
    op.press(100 + RELEASE_WINDOW_MS + 1, Action::Release);
    assert!(op.estop_latched() && op.release_armed(100 + RELEASE_WINDOW_MS + 1));
    op.press(3_000, action(Key::Char('w')).unwrap());
    op.press(3_001, Action::Release);
    assert!(
        op.estop_latched(),
        "a key between the two R disarms the release"
    );
    op.observe(&ctl.status(ControllerMode::EStop));
    op.press(3_500, Action::Release);
    assert!(!op.estop_latched());
    let frames = ctl.decode(&op.poll(3_500).unwrap());
    assert!(
        matches!(
            frames.first(),
            Some(AnyMessage::EStop(EStop {
                action: EStopAction::Clear,
                token,
                ..
            })) if token.raw() == 3
        ),
        "the release echoes the controller's token: {frames:?}"
    );
}

#[test]
fn the_latch_repeats_until_a_status_heard_after_it_confirms_it() {
    let mut op = Operator::new();
    let mut ctl = FakeController::new();
    op.observe(&ctl.announce());
    let latches = |frames: &[Frame]| {
        frames
            .iter()
            .filter(|f| f.id() == MessageId::EStop.raw())
            .count()
    };
    op.poll(0).unwrap();
    op.press(10, Action::EStop);
    // A status heard before the latch went out (the controller still in its old E-stop,
    // say) confirms nothing.
    op.observe(&ctl.status(ControllerMode::EStop));
    assert!(!op.estop_confirmed());
    assert_eq!(latches(&op.poll(10).unwrap()), 1);
    assert_eq!(latches(&op.poll(12).unwrap()), 0, "not before 4 ms");
    assert_eq!(latches(&op.poll(14).unwrap()), 1, "again after 4 ms");
    op.observe(&ctl.status(ControllerMode::Stop));
    assert_eq!(
        latches(&op.poll(18).unwrap()),
        1,
        "another mode confirms nothing"
    );
    op.observe(&ctl.status(ControllerMode::EStop));
    assert!(op.estop_confirmed());
    assert_eq!(
        (19..100)
            .map(|t| latches(&op.poll(t).unwrap()))
            .sum::<usize>(),
        0
    );
}

#[test]
fn height_and_speed_stay_in_their_wire_ranges() {
    let mut op = Operator::new();
    for _ in 0..30 {
        op.press(0, Action::Height(0.01));
        op.press(0, Action::Speed(10.0));
    }
    assert_eq!((op.body_height_m(), op.speed_scale_pct()), (0.12, 100.0));
    for _ in 0..30 {
        op.press(0, Action::Height(-0.01));
        op.press(0, Action::Speed(-10.0));
    }
    assert_eq!((op.body_height_m(), op.speed_scale_pct()), (-0.10, 0.0));
    assert_eq!(op.press(0, Action::Quit), Outcome::Quit);
}

#[test]
fn a_new_latch_or_a_new_session_drops_a_release_on_its_way() {
    let releases = |frames: &[Frame]| {
        frames
            .iter()
            .filter(|f| {
                matches!(
                    decode_frame(f.id(), f.data()).map(|d| d.message),
                    Ok(AnyMessage::EStop(EStop {
                        action: EStopAction::Clear,
                        ..
                    }))
                )
            })
            .count()
    };
    let mut op = Operator::new();
    let mut ctl = FakeController::new();
    op.observe(&ctl.announce());
    op.press(0, Action::EStop);
    op.poll(0).unwrap();
    op.observe(&ctl.status(ControllerMode::EStop));
    op.press(100, Action::Release);
    op.press(200, Action::Release);
    assert_eq!(releases(&op.poll(200).unwrap()), 1);
    // Latched again before the controller confirmed: the release stops.
    op.press(210, Action::EStop);
    let later: usize = (211..400).map(|t| releases(&op.poll(t).unwrap())).sum();
    assert_eq!(later, 0, "no release after a new latch");
    // Released again, then the controller restarts (a new session): the release stops too.
    op.observe(&ctl.status(ControllerMode::EStop));
    op.press(500, Action::Release);
    op.press(600, Action::Release);
    assert_eq!(releases(&op.poll(600).unwrap()), 1);
    let mut restarted = FakeController::with_epoch(8);
    op.observe(&restarted.announce());
    let later: usize = (601..900).map(|t| releases(&op.poll(t).unwrap())).sum();
    assert_eq!(later, 0, "no release into a new session");
}

/// An operator in the controller's session who pressed `drive` at 1 ms and holds the sticks at
/// `forward` and `turn`.
fn driving(forward: f32, turn: f32) -> (Operator, FakeController) {
    let mut op = Operator::new();
    let mut ctl = FakeController::new();
    op.observe(&ctl.announce());
    ctl.decode(&op.poll(0).unwrap());
    op.press(1, Action::Mode(TeleopMode::Drive));
    op.press(1, Action::Sticks { forward, turn });
    (op, ctl)
}

#[test]
fn sticks_drive_at_the_modes_limits_and_ride_on_the_50_hz_command() {
    let (mut op, mut ctl) = driving(0.5, -1.0);
    let sent = ctl.decode(&op.poll(1).unwrap());
    let [AnyMessage::TeleopCommand(command)] = sent.as_slice() else {
        panic!("{sent:?}");
    };
    assert_eq!(command.mode, TeleopMode::Drive);
    assert!((command.speed.si() - 0.24).abs() < 1e-3, "{command:?}");
    assert!((command.yaw_rate.si() + 1.0).abs() < 1e-3, "{command:?}");
    // A stick moving every ms adds no frame: its position rides on the 50 Hz command.
    let mut commands = Vec::new();
    for t in 2..21 {
        op.press(
            t,
            Action::Sticks {
                forward: t as f32 / 40.0,
                turn: 0.0,
            },
        );
        for message in ctl.decode(&op.poll(t).unwrap()) {
            if let AnyMessage::TeleopCommand(c) = message {
                commands.push((t, c.speed.si()));
            }
        }
    }
    assert_eq!(commands.len(), 1, "{commands:?}");
    assert_eq!(commands[0].0, 20);
    assert!((commands[0].1 - 20.0 / 40.0 * 0.48).abs() < 1e-3);
    // In walk the same stick asks for the trot's limits; in the report's keys, no speed.
    op.press(21, Action::Mode(TeleopMode::Walk));
    assert!((op.velocity().0 - 20.0 / 40.0 * 0.145).abs() < 1e-6);
    op.press(21, Action::Mode(TeleopMode::WheelForward));
    assert_eq!(op.velocity(), (0.0, 0.0));
}

#[test]
fn a_lost_pad_sends_stop_then_silence_and_its_return_resumes_the_heartbeat() {
    let (mut op, mut ctl) = driving(1.0, 0.0);
    ctl.decode(&op.poll(1).unwrap());
    op.press(5, Action::InputLost);
    let sent = ctl.decode(&op.poll(5).unwrap());
    assert!(
        matches!(
            sent.as_slice(),
            [AnyMessage::TeleopCommand(TeleopCommand {
                mode: TeleopMode::Stop,
                ..
            })]
        ),
        "{sent:?}"
    );
    assert!(op.silent());
    let quiet: Vec<Frame> = (6..600).flat_map(|t| op.poll(t).unwrap()).collect();
    assert!(quiet.is_empty(), "{} frames while silent", quiet.len());
    op.press(700, Action::InputFound);
    let back = ctl.decode(&op.poll(700).unwrap());
    assert!(
        back.iter()
            .any(|m| matches!(m, AnyMessage::TeleopHeartbeat(_))),
        "{back:?}"
    );
    assert_eq!(op.velocity(), (0.0, 0.0), "the sticks start centred");
    // Silent or not, an E-stop goes out at once.
    op.press(701, Action::InputLost);
    op.poll(701).unwrap();
    assert!(op.silent());
    op.press(702, Action::EStop);
    let latch = op.poll(702).unwrap();
    assert_eq!(latch.first().map(Frame::id), Some(MessageId::EStop.raw()));
}
