//! The receiving side of the bus: verify, sequence-check, decode and count every rejection.

use crate::e2e::{self, E2eChecker, E2eStatus, Freshness, PreparedKey, Search, HEADER_LEN};
use crate::error::{DecodeError, RejectCause};
use crate::id::MessageId;
use crate::message::{decode_frame, protection_of, AnyMessage};
use crate::msg::{Announce, RejectCounters, CLASSIC_LATCH_LEN};
use crate::session::{Key, Session};
use crate::units::{Count, SessionTime, WireVersion};

/// A frame the receiver accepted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Accepted {
    /// The message.
    pub message: AnyMessage,
    /// Its E2E status: `Ok`, `OkSomeLost` or `Initial` (an E-stop latch and an announcement,
    /// which take no part in a sequence, are `Initial`).
    pub status: E2eStatus,
}

/// Verifies frames against the session (see [`crate::session`]), checks each identifier's
/// counter sequence, decodes, and counts every rejection by cause. Nothing rejected reaches the
/// caller as a message.
///
/// The controller's receiver **owns** the session; every other node's receiver is a
/// **member** that joins on the controller's announcement, moves to a newer one, and refuses an
/// older one. An E-stop **latch** with a valid CRC is accepted at any time, in any session or
/// none, whatever its counter: acting on a stale or repeated latch can only stop the robot,
/// while dropping a genuine one could hurt someone.
#[derive(Debug, Clone)]
pub struct Receiver {
    session: Session,
    key: PreparedKey,
    owner: bool,
    checkers: [E2eChecker; MessageId::ALL.len()],
    counters: RejectCounters,
}

impl Receiver {
    /// The controller's receiver: `session` is its own.
    pub fn owner(session: Session) -> Self {
        Self::new(session, true)
    }

    /// Any other node's receiver: it joins the session the controller announces.
    pub fn member(key: Key) -> Self {
        Self::new(Session::unjoined(key), false)
    }

    fn new(session: Session, owner: bool) -> Self {
        Self {
            key: PreparedKey::new(session.key()),
            session,
            owner,
            checkers: [E2eChecker::new(); MessageId::ALL.len()],
            counters: RejectCounters {
                rejected: [Count::ZERO; RejectCause::ALL.len()],
                lost: Count::ZERO,
            },
        }
    }

    /// The session this node is in (or not yet): what its own frames are sealed under.
    pub const fn session(&self) -> &Session {
        &self.session
    }

    /// The controller's receiver: its session time now, against which it places counters.
    /// A member's time comes from the announcements it hears.
    pub fn set_time(&mut self, time: SessionTime) {
        if self.owner {
            self.session.set_time(time);
        }
    }

    /// Accepts or rejects one frame. A rejection is counted before it is returned.
    pub fn receive(&mut self, raw_id: u16, data: &[u8]) -> Result<Accepted, DecodeError> {
        let result = self.check(raw_id, data);
        match &result {
            // E-stop releases count with the session time: their gaps are not losses.
            Ok(Accepted {
                status: E2eStatus::OkSomeLost { lost },
                ..
            }) if raw_id != MessageId::EStop.raw() => self.counters.record_lost(*lost),
            Ok(_) => {}
            Err(error) => self.counters.record(error.cause()),
        }
        result
    }

    /// Counts the refusal of a frame this receiver accepted but its caller will not act on
    /// (say [`DecodeError::RateLimited`]: a flood of valid frames, or
    /// [`DecodeError::StaleRelease`]), so that every frame not acted on is counted by cause.
    /// The frame's sequence step stands: the sender's next frame is still in sequence.
    pub fn refuse(&mut self, error: DecodeError) {
        self.counters.record(error.cause());
    }

    fn check(&mut self, raw_id: u16, data: &[u8]) -> Result<Accepted, DecodeError> {
        let id = MessageId::from_raw(raw_id).ok_or(DecodeError::UnknownId(raw_id))?;
        let layout = id.layout();
        let classic_latch = id == MessageId::EStop && data.len() == CLASSIC_LATCH_LEN;
        if data.len() != layout.wire_len && !classic_latch {
            return Err(DecodeError::WrongLength {
                id: raw_id,
                expected: layout.wire_len,
                got: data.len(),
            });
        }
        let (protection, covered) = protection_of(id, data);
        let epoch = match (protection.bound, self.session.epoch()) {
            (true, None) => return Err(DecodeError::NoSession { id: raw_id }),
            (true, Some(epoch)) => Some(epoch),
            (false, _) => None,
        };
        let wrong_length = DecodeError::WrongLength {
            id: raw_id,
            expected: layout.wire_len,
            got: data.len(),
        };
        let (sent, low) = e2e::header(data).ok_or(wrong_length)?;
        let payload = data
            .get(HEADER_LEN..HEADER_LEN + covered)
            .ok_or(wrong_length)?;
        let key = &self.key;
        let verify = |counter: u32| {
            let freshness = Freshness {
                data_id: id.data_id(),
                epoch,
                counter,
            };
            e2e::check_value(protection.check, key, &freshness, payload) == sent
        };
        let status = if protection.sequenced {
            let checker = self
                .checkers
                .get_mut(id.index())
                .ok_or(DecodeError::UnknownId(raw_id))?;
            let search = Search::new(self.session.time().ms());
            checker.check(low, search, verify)
        } else if verify(u32::from(low)) {
            E2eStatus::Initial
        } else {
            E2eStatus::CheckFailed
        };
        if let Some(error) = DecodeError::from_e2e(raw_id, protection.check, status) {
            return Err(error);
        }
        let message = decode_frame(raw_id, data)?.message;
        if let AnyMessage::Announce(announce) = message {
            self.on_announce(raw_id, &announce)?;
        }
        Ok(Accepted { message, status })
    }

    /// Joins, moves to, or refuses the session an authentic announcement opens.
    fn on_announce(&mut self, raw_id: u16, announce: &Announce) -> Result<(), DecodeError> {
        if announce.version != WireVersion::THIS {
            return Err(DecodeError::WireVersion {
                theirs: announce.version.raw(),
            });
        }
        match self.session.epoch() {
            Some(epoch) if announce.epoch < epoch => Err(DecodeError::StaleSession { id: raw_id }),
            Some(epoch) if announce.epoch == epoch => {
                // A controller waiting for its first tick repeats its announcement at one
                // time; only an earlier time is a replay.
                let last = self.session.time();
                if self.owner || announce.time == last {
                    Ok(())
                } else if announce.time > last {
                    self.session.set_time(announce.time);
                    Ok(())
                } else {
                    Err(DecodeError::WrongSequence { id: raw_id })
                }
            }
            _ if self.owner => Err(DecodeError::StaleSession { id: raw_id }),
            _ => {
                self.session.join(announce.epoch, announce.time);
                for checker in &mut self.checkers {
                    checker.reset();
                }
                Ok(())
            }
        }
    }

    /// Rejections so far, by cause, and frames lost.
    pub const fn counters(&self) -> &RejectCounters {
        &self.counters
    }
}
