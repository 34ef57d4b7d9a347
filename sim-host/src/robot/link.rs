//! One emulated node's end of the bus session: a member receiver that joins the session the
//! controller announces (and checks everything addressed to the node), and the sender of the
//! node's own frames. Every emulated node has its own, as every real node joins on its own.

use protocol::{
    Accepted, AnyMessage, DecodeError, EncodeError, Frame, Key, Receiver, RejectCounters, Sender,
};

/// A node's session state.
#[derive(Debug, Clone)]
pub struct NodeLink {
    receiver: Receiver,
    sender: Sender,
}

impl NodeLink {
    /// A node with `key` that has not heard the controller yet.
    pub fn new(key: Key) -> Self {
        Self {
            receiver: Receiver::member(key),
            sender: Sender::new(),
        }
    }

    /// Verifies, sequence-checks and decodes a frame (see [`Receiver::receive`]).
    pub fn receive(&mut self, raw_id: u16, data: &[u8]) -> Result<Accepted, DecodeError> {
        self.receiver.receive(raw_id, data)
    }

    /// The frame for `message`, or `None` while the node has not joined a session.
    pub fn seal(&mut self, message: &AnyMessage) -> Result<Option<Frame>, EncodeError> {
        match self.sender.seal(self.receiver.session(), message) {
            Ok(frame) => Ok(Some(frame)),
            Err(EncodeError::NoSession) => Ok(None),
            Err(error) => Err(error),
        }
    }

    /// Whether the node has joined a session.
    pub fn joined(&self) -> bool {
        self.receiver.session().epoch().is_some()
    }

    /// Frames refused so far, by cause.
    pub fn counters(&self) -> &RejectCounters {
        self.receiver.counters()
    }
}
