//! The operator's E-stop release: deliberate, answering the latch the controller reports, and
//! repeated until the controller confirms it left its E-stop.
//!
//! A release must echo the controller's release token, which names the latch in force. The
//! operator takes the token from a status that reports `EStop`, so a token heard before a latch
//! (when the controller was still running) never goes out. A release frame may be lost like any
//! frame, so it is sent again every [`RELEASE_REPEAT_MS`] until a status reports another mode,
//! and given up after [`RELEASE_TIMEOUT_MS`]; if the controller latches again meanwhile (a new
//! token), the release is abandoned: the new latch needs its own.

use protocol::{ControllerMode, ControllerStatus, EStop, NodeId, ReleaseToken};

/// How often a release is sent again until the controller reports it left its E-stop, ms.
pub const RELEASE_REPEAT_MS: u64 = 50;
/// How long a release is tried before it is given up (the controller kept its E-stop), ms:
/// the controller takes a release once its controlled stop is over, which may be up to the
/// SS1 deadline (2 s) after the latch, and the status that confirms it crosses the bus after.
pub const RELEASE_TIMEOUT_MS: u64 = 2_500;

/// How a release the operator asked for ended, as the controller reported it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReleaseOutcome {
    /// The controller left its E-stop.
    Released,
    /// The controller latched again (another E-stop) before it took this release: the new
    /// latch needs its own release.
    Superseded,
    /// The controller kept its E-stop for [`RELEASE_TIMEOUT_MS`].
    TimedOut,
    /// The controller reports no E-stop to release (not heard yet, or not latched).
    NothingToRelease,
}

/// A release on its way: the token of the latch it answers, when it started and was last sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Pending {
    token: ReleaseToken,
    since_ms: u64,
    sent_ms: Option<u64>,
}

/// The release state of one operator.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Release {
    /// The token of the latch the controller last reported it is in (`None` when its last
    /// authentic status was not `EStop`).
    estop_token: Option<ReleaseToken>,
    pending: Option<Pending>,
    outcome: Option<ReleaseOutcome>,
}

impl Release {
    /// Takes an authentic status of the controller.
    pub fn observe(&mut self, status: &ControllerStatus) {
        self.estop_token = (status.mode == ControllerMode::EStop).then_some(status.release_token);
        let Some(pending) = self.pending else {
            return;
        };
        let outcome = match self.estop_token {
            None => Some(ReleaseOutcome::Released),
            Some(token) if token != pending.token => Some(ReleaseOutcome::Superseded),
            Some(_) => None,
        };
        if outcome.is_some() {
            self.pending = None;
            self.outcome = outcome;
        }
    }

    /// The operator asked for a release at `now_ms` (the second `R`). Returns whether one
    /// started: only a latch the controller reports can be released.
    pub fn start(&mut self, now_ms: u64) -> bool {
        match self.estop_token {
            Some(token) => {
                self.outcome = None;
                self.pending = Some(Pending {
                    token,
                    since_ms: now_ms,
                    sent_ms: None,
                });
                true
            }
            None => {
                self.outcome = Some(ReleaseOutcome::NothingToRelease);
                false
            }
        }
    }

    /// The release to send at `now_ms`, if one is due. Call [`Release::sent`] once it went out.
    pub fn due(&mut self, now_ms: u64) -> Option<EStop> {
        let pending = self.pending?;
        if now_ms.saturating_sub(pending.since_ms) > RELEASE_TIMEOUT_MS {
            self.pending = None;
            self.outcome = Some(ReleaseOutcome::TimedOut);
            return None;
        }
        pending
            .sent_ms
            .is_none_or(|sent| now_ms.saturating_sub(sent) >= RELEASE_REPEAT_MS)
            .then(|| EStop::release(NodeId::Teleop, pending.token))
    }

    /// The release due went out at `now_ms`.
    pub fn sent(&mut self, now_ms: u64) {
        if let Some(pending) = &mut self.pending {
            pending.sent_ms = Some(now_ms);
        }
    }

    /// Drops a release on its way (the operator latched again: the release answered an older
    /// latch).
    pub fn abandon(&mut self) {
        self.pending = None;
    }

    /// Whether a release is on its way (the controller has not confirmed it yet).
    pub fn pending(&self) -> bool {
        self.pending.is_some()
    }

    /// Whether the controller's last authentic status reported its E-stop.
    pub fn controller_in_estop(&self) -> bool {
        self.estop_token.is_some()
    }

    /// How the last release ended, once.
    pub fn take_outcome(&mut self) -> Option<ReleaseOutcome> {
        self.outcome.take()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use protocol::{Angle, BodyHeight, FaultFlags, Tick};

    fn status(mode: ControllerMode, token: u16) -> ControllerStatus {
        ControllerStatus {
            mode,
            faults: FaultFlags::EMPTY,
            tick: Tick::from_raw(0).unwrap(),
            body_height: BodyHeight::saturating_from_si(0.0),
            pitch: Angle::saturating_from_si(0.0),
            roll: Angle::saturating_from_si(0.0),
            release_token: ReleaseToken::new(token),
        }
    }

    fn token_of(estop: Option<EStop>) -> Option<u16> {
        estop.map(|e| e.token.raw())
    }

    #[test]
    fn a_token_heard_before_the_latch_never_goes_out() {
        let mut release = Release::default();
        // The controller was running with token 4; the latch makes it 5.
        release.observe(&status(ControllerMode::WheelForward, 4));
        assert!(!release.start(0), "nothing reported latched yet");
        assert_eq!(
            release.take_outcome(),
            Some(ReleaseOutcome::NothingToRelease)
        );
        assert_eq!(release.due(0), None);
        release.observe(&status(ControllerMode::EStop, 5));
        assert!(release.start(10));
        assert_eq!(token_of(release.due(10)), Some(5));
    }

    #[test]
    fn a_release_repeats_until_the_controller_leaves_its_estop() {
        let mut release = Release::default();
        release.observe(&status(ControllerMode::EStop, 2));
        assert!(release.start(100));
        let mut sent = Vec::new();
        for now in 100..400 {
            if let Some(estop) = release.due(now) {
                assert_eq!(estop.token.raw(), 2);
                release.sent(now);
                sent.push(now);
            }
            // Every status before 350 ms still reports the E-stop (the releases were lost).
            if now < 350 {
                release.observe(&status(ControllerMode::EStop, 2));
            } else if now == 350 {
                release.observe(&status(ControllerMode::Stop, 2));
            }
        }
        assert_eq!(sent, [100, 150, 200, 250, 300, 350]);
        assert!(!release.pending());
        assert_eq!(release.take_outcome(), Some(ReleaseOutcome::Released));
        assert_eq!(release.take_outcome(), None);
    }

    #[test]
    fn a_new_latch_abandons_the_release_and_an_unanswered_one_times_out() {
        let mut release = Release::default();
        release.observe(&status(ControllerMode::EStop, 2));
        assert!(release.start(0));
        release.sent(0);
        release.observe(&status(ControllerMode::EStop, 3));
        assert!(!release.pending());
        assert_eq!(release.take_outcome(), Some(ReleaseOutcome::Superseded));
        assert_eq!(
            release.due(60),
            None,
            "the new latch is not released by the old R R"
        );
        assert!(release.start(100));
        for now in 100..=100 + RELEASE_TIMEOUT_MS {
            if release.due(now).is_some() {
                release.sent(now);
            }
        }
        assert!(release.pending());
        assert_eq!(release.due(101 + RELEASE_TIMEOUT_MS), None);
        assert_eq!(release.take_outcome(), Some(ReleaseOutcome::TimedOut));
    }
}
