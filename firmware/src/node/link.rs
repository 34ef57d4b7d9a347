//! The link monitor: is the bus losing so many of the controller's inbound frames that it
//! should stop?
//!
//! The per-drive watchdogs (50 ms) catch a silent bus, not a lossy one: at 20 % random loss a
//! drive's feedback still arrives every few milliseconds, so no watchdog trips, yet one frame in
//! five of everything — operator commands and E-stop clears included — is gone. The monitor
//! measures the loss from the E2E sequence gaps the receiver reports
//! ([`E2eStatus::OkSomeLost`]) against the frames received, over consecutive windows of a fixed
//! number of ticks, and calls the link degraded when a window's loss ratio is above the degrade
//! threshold. It recovers only when a later window is at or below the recover threshold, which is
//! lower, so a loss ratio near one threshold does not make the state flicker.
//!
//! Integer arithmetic only: counts per window and thresholds in per mille (‰). What the monitor
//! cannot see is an identifier that falls silent altogether (no frame, no gap): that is what the
//! watchdogs are for. A window in which nothing arrived leaves the state as it was.

use protocol::E2eStatus;

use crate::time::Tick;

/// Inbound loss ratio over consecutive windows, with hysteresis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LinkMonitor {
    window_ticks: u32,
    degrade_permille: u32,
    recover_permille: u32,
    /// Start of the window being counted (`None` until the first [`LinkMonitor::update`]).
    window_start: Option<Tick>,
    /// Frames received in this window.
    received: u32,
    /// Frames missing from sequences in this window.
    lost: u32,
    /// Loss of the last judged window, ‰ (rounded down).
    last_loss_permille: Option<u32>,
    degraded: bool,
}

impl LinkMonitor {
    /// A monitor judging windows of `window_ticks` ticks: degraded when a window loses more than
    /// `degrade_permille` ‰ of its frames, recovered when one loses at most `recover_permille`
    /// ‰. `None` unless `window_ticks ≥ 1` and `recover_permille ≤ degrade_permille ≤ 1000`.
    pub const fn new(
        window_ticks: u32,
        degrade_permille: u32,
        recover_permille: u32,
    ) -> Option<Self> {
        if window_ticks == 0 || recover_permille > degrade_permille || degrade_permille > 1000 {
            return None;
        }
        Some(Self {
            window_ticks,
            degrade_permille,
            recover_permille,
            window_start: None,
            received: 0,
            lost: 0,
            last_loss_permille: None,
            degraded: false,
        })
    }

    /// Records one frame the receiver accepted with `status`: one frame received, plus the
    /// frames its sequence gap says were lost before it.
    pub fn record(&mut self, status: E2eStatus) {
        self.received = self.received.saturating_add(1);
        if let E2eStatus::OkSomeLost { lost } = status {
            self.lost = self.lost.saturating_add(lost);
        }
    }

    /// Called once per control tick: when the window that started `window_ticks` ago is
    /// complete at `now`, judges it and starts the next. Returns whether the link is degraded.
    pub fn update(&mut self, now: Tick) -> bool {
        let start = *self.window_start.get_or_insert(now);
        if now.since(start) >= self.window_ticks {
            self.judge();
            self.window_start = Some(now);
            self.received = 0;
            self.lost = 0;
        }
        self.degraded
    }

    /// Whether the link is degraded.
    pub const fn degraded(&self) -> bool {
        self.degraded
    }

    /// Loss of the last judged window that had traffic, ‰ (rounded down); `None` before the
    /// first.
    pub const fn last_loss_permille(&self) -> Option<u32> {
        self.last_loss_permille
    }

    fn judge(&mut self) {
        // Products in u64: a u32 count times 1000 cannot overflow it.
        let expected = u64::from(self.received) + u64::from(self.lost);
        if expected == 0 {
            return;
        }
        let lost_permille_scaled = u64::from(self.lost) * 1000;
        let loss_permille = lost_permille_scaled / expected;
        self.last_loss_permille = Some(u32::try_from(loss_permille).unwrap_or(u32::MAX));
        if lost_permille_scaled > u64::from(self.degrade_permille) * expected {
            self.degraded = true;
        } else if lost_permille_scaled <= u64::from(self.recover_permille) * expected {
            self.degraded = false;
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::default_numeric_fallback)]

    use super::*;

    /// 250 ticks (1 s at 250 Hz), degrade above 10 %, recover at or below 3 %.
    fn monitor() -> LinkMonitor {
        LinkMonitor::new(250, 100, 30).unwrap()
    }

    /// Runs `ticks` ticks from `*now`, receiving `per_tick` frames on each of which one in
    /// `drop_every` (if any) was lost before it arrived, in the style of a sender whose every
    /// `drop_every`-th frame goes missing. Returns the state after the last tick.
    fn run(
        link: &mut LinkMonitor,
        now: &mut u32,
        ticks: u32,
        per_tick: u32,
        drop_every: Option<u32>,
    ) -> bool {
        let mut sent = 0_u32;
        let mut degraded = link.degraded();
        for _ in 0..ticks {
            for _ in 0..per_tick {
                sent += 1;
                let lost_here = drop_every.is_some_and(|n| sent % n == 0);
                if lost_here {
                    // The next frame arrives after the gap.
                    sent += 1;
                    link.record(E2eStatus::OkSomeLost { lost: 1 });
                } else {
                    link.record(E2eStatus::Ok);
                }
            }
            degraded = link.update(Tick(*now));
            *now += 1;
        }
        degraded
    }

    #[test]
    fn a_clean_link_is_never_degraded() {
        let mut link = monitor();
        let mut now = 0;
        assert!(!run(&mut link, &mut now, 2_500, 7, None));
        assert_eq!(link.last_loss_permille(), Some(0));
    }

    #[test]
    fn five_percent_loss_is_tolerated() {
        let mut link = monitor();
        let mut now = 0;
        // One frame in 20 lost: 5 % of the frames sent.
        assert!(!run(&mut link, &mut now, 2_500, 7, Some(20)));
        let loss = link.last_loss_permille().unwrap();
        assert!((45..=55).contains(&loss), "{loss} ‰");
    }

    #[test]
    fn twenty_percent_loss_degrades_within_two_windows_and_recovery_needs_a_clean_window() {
        let mut link = monitor();
        let mut now = 0;
        run(&mut link, &mut now, 100, 7, None);
        // One frame in 5 lost from tick 100: the window ending at tick 250 has 150 lossy ticks
        // of 250 (12 %), already above 10 %; at the latest the next full window degrades.
        let mut ticks = 0;
        while !run(&mut link, &mut now, 1, 7, Some(5)) {
            ticks += 1;
            assert!(ticks <= 2 * 250, "not degraded after {ticks} ticks");
        }
        assert!(link.degraded());
        let loss = link.last_loss_permille().unwrap();
        assert!(loss > 100, "{loss} ‰");
        // Hysteresis: 5 % loss is below the degrade threshold but above the recover one, so
        // the link stays degraded.
        assert!(run(&mut link, &mut now, 1_000, 7, Some(20)));
        // A clean window recovers it (within two windows of the loss stopping).
        assert!(!run(&mut link, &mut now, 2 * 250, 7, None));
        assert_eq!(link.last_loss_permille(), Some(0));
    }

    #[test]
    fn a_window_without_traffic_keeps_the_state() {
        let mut link = monitor();
        let mut now = 0;
        assert!(run(&mut link, &mut now, 500, 7, Some(4)));
        assert!(
            run(&mut link, &mut now, 1_000, 0, None),
            "silence is not a recovery"
        );
        assert!(!run(&mut link, &mut now, 500, 7, None));
        let mut quiet = monitor();
        assert!(
            !run(&mut quiet, &mut now, 1_000, 0, None),
            "nor a degradation"
        );
        assert_eq!(quiet.last_loss_permille(), None);
    }

    #[test]
    fn the_thresholds_are_exclusive_for_degrade_and_inclusive_for_recover() {
        let mut link = monitor();
        // Exactly 10 %: 1 lost per 9 received.
        for _ in 0..100 {
            for _ in 0..8 {
                link.record(E2eStatus::Ok);
            }
            link.record(E2eStatus::OkSomeLost { lost: 1 });
        }
        link.update(Tick(0));
        assert!(!link.update(Tick(250)), "10 % is not above 10 %");
        link.record(E2eStatus::OkSomeLost { lost: 2 });
        assert!(link.update(Tick(500)), "2 of 3 frames lost");
        // Exactly 3 %: 3 lost, 97 received.
        for _ in 0..94 {
            link.record(E2eStatus::Ok);
        }
        for _ in 0..3 {
            link.record(E2eStatus::OkSomeLost { lost: 1 });
        }
        assert!(!link.update(Tick(750)), "3 % recovers");
    }

    #[test]
    fn invalid_settings_are_refused() {
        assert!(LinkMonitor::new(0, 100, 30).is_none());
        assert!(LinkMonitor::new(250, 30, 100).is_none());
        assert!(LinkMonitor::new(250, 1001, 30).is_none());
        assert!(LinkMonitor::new(250, 100, 100).is_some());
    }
}
