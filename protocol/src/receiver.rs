//! The receiving side of the bus: decode, sequence-check and count every rejection.

use crate::e2e::{E2eChecker, E2eStatus};
use crate::error::{DecodeError, RejectCause};
use crate::id::MessageId;
use crate::message::{decode_frame, AnyMessage};
use crate::msg::{EStop, RejectCounters};
use crate::units::EStopAction;

/// A frame the receiver accepted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Accepted {
    /// The message.
    pub message: AnyMessage,
    /// Its E2E status: `Ok`, `OkSomeLost` or `Initial`; for an E-stop latch also `Repeated` or
    /// `WrongSequence` (see [`Receiver`]: a latch acts whatever its counter).
    pub status: E2eStatus,
}

/// Decodes frames, checks each identifier's rolling counter, and counts every rejection by
/// cause. Nothing rejected reaches the caller as a message.
///
/// One exception is deliberate: an E-stop **latch** with a valid CRC is accepted whatever its
/// counter (its status still says `Repeated` or `WrongSequence`), because acting on a stale or
/// repeated latch can only stop the robot, while dropping a genuine one — say from an
/// operator's `cansend` that cannot know the counter — could hurt someone. An E-stop **clear**
/// passes every check.
#[derive(Debug, Clone)]
pub struct Receiver {
    checkers: [E2eChecker; MessageId::ALL.len()],
    counters: RejectCounters,
}

impl Default for Receiver {
    fn default() -> Self {
        Self::new(crate::e2e::DEFAULT_MAX_DELTA)
    }
}

impl Receiver {
    /// A receiver that accepts counter steps of 1…`max_delta` on every identifier.
    pub const fn new(max_delta: u16) -> Self {
        Self {
            checkers: [E2eChecker::new(max_delta); MessageId::ALL.len()],
            counters: RejectCounters {
                rejected: [crate::units::Count::ZERO; RejectCause::ALL.len()],
                lost: crate::units::Count::ZERO,
            },
        }
    }

    /// Accepts or rejects one frame. A rejection is counted before it is returned.
    pub fn receive(&mut self, raw_id: u16, data: &[u8]) -> Result<Accepted, DecodeError> {
        let result = self.check(raw_id, data);
        match &result {
            Ok(Accepted {
                status: E2eStatus::OkSomeLost { lost },
                ..
            }) => self.counters.record_lost(*lost),
            Ok(_) => {}
            Err(error) => self.counters.record(error.cause()),
        }
        result
    }

    /// Counts the refusal of a frame this receiver accepted but its caller will not act on
    /// (say [`DecodeError::RateLimited`]: a flood of valid frames), so that every frame not
    /// acted on is counted by cause. The frame's sequence step stands: the sender's next frame
    /// is still in sequence.
    pub fn refuse(&mut self, error: DecodeError) {
        self.counters.record(error.cause());
    }

    fn check(&mut self, raw_id: u16, data: &[u8]) -> Result<Accepted, DecodeError> {
        let decoded = decode_frame(raw_id, data)?;
        let checker = self
            .checkers
            .get_mut(decoded.id.index())
            .ok_or(DecodeError::UnknownId(raw_id))?;
        let skipped = checker.skipped_ahead(decoded.counter);
        let status = checker.check_counter(decoded.counter);
        if status == E2eStatus::WrongSequence {
            // A burst of loss longer than the window: the frames are lost all the same, and
            // the link's loss must count them (the frame itself is refused until the
            // sequence resynchronises on the next one).
            if let Some(lost) = skipped {
                self.counters.record_lost(lost);
            }
        }
        let fail_safe = matches!(
            decoded.message,
            AnyMessage::EStop(EStop {
                action: EStopAction::Latch,
                ..
            })
        );
        match DecodeError::from_e2e(raw_id, status) {
            Some(error) if !fail_safe => Err(error),
            _ => Ok(Accepted {
                message: decoded.message,
                status,
            }),
        }
    }

    /// Rejections so far, by cause, and frames lost.
    pub const fn counters(&self) -> &RejectCounters {
        &self.counters
    }
}
