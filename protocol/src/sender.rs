//! The sending side of the bus: one counter per identifier, started at the session time.

use crate::codec::EncodeError;
use crate::e2e::{PreparedKey, MAX_LAG_MS};
use crate::frame::Frame;
use crate::id::MessageId;
use crate::message::AnyMessage;
use crate::msg::{EStop, CLASSIC_LATCH_LEN};
use crate::node::NodeId;
use crate::session::{Epoch, Key, Session, TEST_KEY};

/// Seals a node's messages: hands out each identifier's full counter and protects the frame
/// under the node's session. In every session it is in, a sender starts all its counters at the
/// session time of its first frame there (see [`crate::session`]), so that a node restarted in
/// the same session sends counters above those of its previous life, and moves a counter up to
/// the session time when it has fallen [`MAX_LAG_MS`] behind.
#[derive(Debug, Clone)]
pub struct Sender {
    key: Option<(Key, PreparedKey)>,
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
            key: None,
            epoch: None,
            counters: [0; MessageId::ALL.len()],
        }
    }

    /// The frame for `message` under `session`, with the next counter of its identifier.
    /// A message bound to a session fails with [`EncodeError::NoSession`] until the node has
    /// joined one, and uses up no counter.
    pub fn seal(&mut self, session: &Session, message: &AnyMessage) -> Result<Frame, EncodeError> {
        let now = session.time().ms();
        if session.epoch() != self.epoch {
            self.epoch = session.epoch();
            self.counters = [now; MessageId::ALL.len()];
        }
        let slot = self
            .counters
            .get_mut(message.id().index())
            .ok_or(EncodeError::TooLarge)?;
        if message.id() == MessageId::EStop || slot.saturating_add(MAX_LAG_MS) < now {
            *slot = (*slot).max(now);
        }
        let key = match &self.key {
            Some((key, prepared)) if key == session.key() => prepared,
            _ => {
                let prepared = PreparedKey::new(session.key());
                &self.key.insert((*session.key(), prepared)).1
            }
        };
        let frame = message.encode_keyed(session, key, *slot)?;
        *slot = slot.wrapping_add(1);
        Ok(frame)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Epoch, Millis, Receiver, TeleopHeartbeat};

    fn heartbeat() -> AnyMessage {
        AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
            uptime: Millis::saturating_from_si(1.0),
        })
    }

    #[test]
    fn a_sender_whose_session_changes_key_seals_with_the_new_key() {
        let old = Session::owned(TEST_KEY, Epoch::new(4));
        let new = Session::owned(Key([7; 16]), Epoch::new(4));
        let mut sender = Sender::new();
        let first = sender.seal(&old, &heartbeat()).unwrap();
        assert!(Receiver::owner(old)
            .receive(first.id(), first.data())
            .is_ok());
        // The key cached for the old session must not seal frames of the new one.
        let second = sender.seal(&new, &heartbeat()).unwrap();
        assert!(Receiver::owner(new)
            .receive(second.id(), second.data())
            .is_ok());
        assert!(Receiver::owner(old)
            .receive(second.id(), second.data())
            .is_err());
    }

    #[test]
    fn a_key_other_than_the_test_key_shows_nothing_of_itself() {
        assert_eq!(format!("{:?}", Key([7; 16])), "Key(…)");
        assert_eq!(format!("{TEST_KEY:?}"), "Key(test key)");
        assert_ne!(Key([7; 16]), TEST_KEY);
    }
}
