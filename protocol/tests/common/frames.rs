//! The sessions, the frames and the messages the session tests share.

use protocol::*;

/// The session the run is recorded in, and the one the controller opens when it restarts.
pub const OLD: Epoch = Epoch::new(1_000);
pub const NEW: Epoch = Epoch::new(1_001);
/// The E-stop panel's classic latch: one constant frame, counter and all.
pub const PANEL_COUNTER: u16 = 0x0BAD;

/// The refusal a check that does not hold gives `frame`: a CRC mismatch or, for a frame that
/// carries a CMAC, unauthentic.
pub fn check_failed(frame: &Frame) -> DecodeError {
    let id = frame.id();
    let check = protection_of(MessageId::from_raw(id).unwrap(), frame.data())
        .0
        .check;
    match check {
        Check::Crc => DecodeError::CrcMismatch { id },
        Check::Mac => DecodeError::Unauthentic { id },
    }
}

pub fn wheel_command(counter: u32, epoch: Epoch) -> Frame {
    AnyMessage::WheelCommand(WheelCommand {
        enable: DriveEnable::Enabled,
        torque: [Torque::from_raw(counter as i16).unwrap(); 2],
    })
    .encode(&Session::owned(TEST_KEY, epoch), counter)
    .unwrap()
}

pub fn receive(rx: &mut Receiver, frame: &Frame) -> Result<Accepted, DecodeError> {
    rx.receive(frame.id(), frame.data())
}

pub fn heartbeat(ms: u32) -> AnyMessage {
    AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
        uptime: Millis::from_raw(ms).unwrap(),
    })
}

pub fn wheel_message(ms: u32) -> AnyMessage {
    AnyMessage::WheelCommand(WheelCommand {
        enable: DriveEnable::Enabled,
        torque: [Torque::from_raw((ms % 1000) as i16).unwrap(); 2],
    })
}

pub fn wheel_feedback(ms: u32) -> AnyMessage {
    AnyMessage::WheelFeedback(WheelFeedback {
        velocity: [WheelVelocity::from_raw((ms % 1000) as i16).unwrap(); 2],
        effort: [Torque::default(); 2],
    })
}
