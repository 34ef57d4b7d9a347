//! The operator's end of the bus session: it joins the session the controller announces, seals
//! its commands in it (authenticated with the key), and resumes its counters after a restart
//! from what it persisted, so that its first frames are fresh to a controller that kept
//! running.

use protocol::{AnyMessage, EncodeError, Epoch, Frame, Key, MessageId, Receiver, Sender, Session};

/// How far ahead of the counters in use a teleop persists its resume point: it rewrites its
/// state file once per this many frames on its busiest identifier, and after a restart resumes
/// past every counter it can have used.
pub const RESUME_RESERVE: u32 = 4_096;

/// The operator's session state: a member receiver for the controller's announcement and
/// status, and the sender of its own frames.
#[derive(Debug, Clone)]
pub struct OperatorLink {
    receiver: Receiver,
    sender: Sender,
    resume: Option<(Epoch, u32)>,
}

impl OperatorLink {
    /// A link with `key` that has not heard the controller yet.
    pub fn new(key: Key) -> Self {
        Self {
            receiver: Receiver::member(key),
            sender: Sender::new(),
            resume: None,
        }
    }

    /// A link that, on joining session `epoch`, starts every counter at `counter` (a resume
    /// point this teleop persisted in that session).
    pub fn resuming(key: Key, epoch: Epoch, counter: u32) -> Self {
        Self {
            resume: Some((epoch, counter)),
            ..Self::new(key)
        }
    }

    /// Takes a frame heard on the bus. Returns the controller's announcement or status when it
    /// is authentic and fresh; every other frame is left to the nodes it is for.
    pub fn observe(&mut self, frame: &Frame) -> Option<AnyMessage> {
        let id = frame.id();
        if id != MessageId::Announce.raw() && id != MessageId::ControllerStatus.raw() {
            return None;
        }
        let before = self.receiver.session().epoch();
        let accepted = self.receiver.receive(id, frame.data()).ok()?;
        let now = self.receiver.session().epoch();
        if now != before {
            if let Some((epoch, counter)) = self.resume.filter(|(epoch, _)| Some(*epoch) == now) {
                self.sender = Sender::resuming(&Session::owned(*self.key(), epoch), counter);
            }
        }
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

    /// What to persist so that a restarted teleop resumes fresh: the session and a counter
    /// past every one used so far.
    pub fn resume_point(&self) -> Option<(Epoch, u32)> {
        Some((self.epoch()?, self.sender.high_water()))
    }
}
