//! The sending side of the bus: one counter per identifier, restarted with every session.

use crate::codec::EncodeError;
use crate::frame::Frame;
use crate::id::MessageId;
use crate::message::AnyMessage;
use crate::msg::{EStop, CLASSIC_LATCH_LEN};
use crate::node::NodeId;
use crate::session::{Epoch, Session, TEST_KEY};

/// Seals a node's messages: hands out each identifier's full counter and protects the frame
/// under the node's session. When the session changes (the controller restarted), every
/// counter starts again at zero, as the receivers expect.
#[derive(Debug, Clone)]
pub struct Sender {
    epoch: Option<Epoch>,
    counters: [u32; MessageId::ALL.len()],
}

impl Default for Sender {
    fn default() -> Self {
        Self::new()
    }
}

impl Sender {
    /// A sender that has sent nothing.
    pub const fn new() -> Self {
        Self {
            epoch: None,
            counters: [0; MessageId::ALL.len()],
        }
    }

    /// A sender whose next frame on every identifier carries `counter`, in `session`: for a
    /// node that resumes a session it was in before (the teleop's state file).
    pub const fn resuming(session: &Session, counter: u32) -> Self {
        Self {
            epoch: session.epoch(),
            counters: [counter; MessageId::ALL.len()],
        }
    }

    /// The frame for `message` under `session`, with the next counter of its identifier.
    /// A message bound to a session fails with [`EncodeError::NoSession`] until the node has
    /// joined one, and uses up no counter.
    pub fn seal(&mut self, session: &Session, message: &AnyMessage) -> Result<Frame, EncodeError> {
        if session.epoch() != self.epoch {
            self.epoch = session.epoch();
            self.counters = [0; MessageId::ALL.len()];
        }
        let slot = self
            .counters
            .get_mut(message.id().index())
            .ok_or(EncodeError::TooLarge)?;
        let frame = message.encode(session, *slot)?;
        *slot = slot.wrapping_add(1);
        Ok(frame)
    }

    /// The highest counter handed out so far on any identifier, for a node that persists it.
    pub fn high_water(&self) -> u32 {
        self.counters.iter().copied().max().unwrap_or(0)
    }
}

/// An E-stop latch from `source` as a classic CAN frame of [`CLASSIC_LATCH_LEN`] bytes, as an
/// E-stop panel sends it. Bound to no session: the same bytes work on any robot at any time.
pub fn classic_latch(source: NodeId, counter: u16) -> Option<Frame> {
    let full = AnyMessage::EStop(EStop::latch(source))
        .encode(&Session::unjoined(TEST_KEY), u32::from(counter))
        .ok()?;
    Frame::new(full.id(), full.data().get(..CLASSIC_LATCH_LEN)?)
}
