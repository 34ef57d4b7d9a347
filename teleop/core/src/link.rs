//! The operator's end of the bus session: it joins the session the controller announces and
//! seals its commands in it (authenticated with the key). A restarted teleop needs no state:
//! its counters start at the session time it rejoins at, above everything it sent before (see
//! [`protocol::session`]).

use protocol::{AnyMessage, EncodeError, Epoch, Frame, Key, MessageId, Receiver, Sender};

/// The operator's session state: a member receiver for the controller's announcement and
/// status, and the sender of its own frames.
#[derive(Debug, Clone)]
pub struct OperatorLink {
    receiver: Receiver,
    sender: Sender,
}

impl OperatorLink {
    /// A link with `key` that has not heard the controller yet.
    pub fn new(key: Key) -> Self {
        Self {
            receiver: Receiver::member(key),
            sender: Sender::new(),
        }
    }

    /// Takes a frame heard on the bus. Returns the controller's announcement or status when it
    /// is authentic and fresh; every other frame is left to the nodes it is for.
    pub fn observe(&mut self, frame: &Frame) -> Option<AnyMessage> {
        let id = frame.id();
        if id != MessageId::Announce.raw() && id != MessageId::ControllerStatus.raw() {
            return None;
        }
        let accepted = self.receiver.receive(id, frame.data()).ok()?;
        Some(accepted.message)
    }

    /// The frame for `message`, or `None` while no session is joined (only an E-stop latch
    /// goes out before).
    pub fn seal(&mut self, message: &AnyMessage) -> Result<Option<Frame>, EncodeError> {
        match self.sender.seal(self.receiver.session(), message) {
            Ok(frame) => Ok(Some(frame)),
            Err(EncodeError::NoSession) => Ok(None),
            Err(error) => Err(error),
        }
    }

    /// The session, once the controller has been heard.
    pub fn epoch(&self) -> Option<Epoch> {
        self.receiver.session().epoch()
    }

    /// The key.
    pub fn key(&self) -> &Key {
        self.receiver.session().key()
    }
}
