//! The controller's session clock heard through its announcements, and the counters a sender
//! slower than one frame a millisecond uses.

use protocol::e2e::MAX_LAG_MS;
use protocol::*;

use super::announce_frame_at;
use super::frames::{receive, OLD};

/// A clock of the controller's session: the controller's receiver reads it, and every member
/// hears it in the announcements, one every 20 ms.
pub struct Clock {
    pub ms: u32,
    pub announced: u32,
}

impl Clock {
    pub fn new(ms: u32) -> Clock {
        Clock { ms, announced: 0 }
    }

    /// Runs the clock to `ms`: the controller reads it, and `members` hear the announcement
    /// when one falls due.
    pub fn to(&mut self, ms: u32, controller: &mut Receiver, members: &mut [&mut Receiver]) {
        assert!(ms >= self.ms);
        if ms / 20 > self.ms / 20 {
            self.announce(ms / 20 * 20, members);
        }
        self.ms = ms;
        controller.set_time(SessionTime::from_ms(ms));
    }

    pub fn announce(&mut self, ms: u32, members: &mut [&mut Receiver]) {
        self.announced += 1;
        let frame = announce_frame_at(WireVersion::THIS, OLD, ms, self.announced);
        for member in members.iter_mut() {
            receive(member, &frame).unwrap();
            assert_eq!(member.session().time(), SessionTime::from_ms(ms));
        }
    }
}

/// The counter a sender slower than one frame a millisecond uses for its `k`-th frame on an
/// identifier, sealed at session time `times[k]`: from the time of its first frame, one per
/// frame, and the session time itself once the next would be more than `MAX_LAG_MS` behind.
pub fn slow_sender_counters(times: &[u32]) -> Vec<u32> {
    let mut next = times[0];
    times
        .iter()
        .map(|&now| {
            if next + MAX_LAG_MS < now {
                next = now;
            }
            next += 1;
            next - 1
        })
        .collect()
}
