//! What the rejection tests share: the teleop's command and the controller's receiver.

use protocol::*;

use super::controller_session;

pub fn teleop(mode: TeleopMode) -> TeleopCommand {
    TeleopCommand {
        mode,
        body_height: BodyHeight::from_si(0.0).unwrap(),
        speed_scale: SpeedScale::from_si(100.0).unwrap(),
        speed: Default::default(),
        yaw_rate: Default::default(),
    }
}

/// The teleop's command with full counter `counter`, in the controller's session.
pub fn teleop_frame(counter: u32) -> Frame {
    encode(
        &teleop(TeleopMode::WheelForward),
        (),
        &controller_session(),
        counter,
    )
    .unwrap()
}

/// The controller's receiver.
pub fn controller() -> Receiver {
    Receiver::owner(controller_session())
}

/// Asserts that `rx` counted one rejection, under `cause`, and none under any other.
pub fn only_cause(rx: &Receiver, cause: RejectCause) {
    for other in RejectCause::ALL {
        let expected = u16::from(other == cause);
        assert_eq!(
            rx.counters().get(other).raw(),
            expected,
            "counter {other:?}"
        );
    }
}
