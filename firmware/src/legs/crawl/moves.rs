//! What the crawl can be asked to do ([`Move`]) and how a move ends ([`Outcome`]).

use protocol::Leg;

use super::frame::{BodyPose, Point};

/// A move of the crawl.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Move {
    /// The body to a pose, all four feet where they stand, over `ms`.
    Body {
        /// Where the body goes.
        to: BodyPose,
        /// How long it takes, ms.
        ms: u32,
    },
    /// The body away from `leg`'s foot, at a steady speed, until that foot carries no more than
    /// [`super::CrawlConfig::unloaded_share`] of the weight ([`super::foot_loads_n`]) or the body has gone
    /// `max_m`. The legs' servos are compliant and the centre of mass is not where the
    /// drawing puts it, so a sway is judged by the loads it leaves on the feet, not by its
    /// commanded length.
    Unload {
        /// The foot to free.
        leg: Leg,
        /// The longest sway, m.
        max_m: f32,
    },
    /// One foot up by `lift_m` above where it stands, over to `to` (x, y), and down.
    Swing {
        /// The foot.
        leg: Leg,
        /// Where it goes; its height is found.
        to: Point,
        /// How high above where it stands it travels, m.
        lift_m: f32,
    },
}

/// How a move ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Outcome {
    /// The body arrived.
    Moved,
    /// The sway left the foot no more than [`super::CrawlConfig::unloaded_share`] of the weight: it
    /// is free to lift.
    Freed {
        /// The foot.
        leg: Leg,
    },
    /// The sway went its whole length and the foot still carries more than that share.
    StillLoaded {
        /// The foot.
        leg: Leg,
    },
    /// The foot stands on something at height `z_m` (its centre, ground frame).
    Landed {
        /// The foot.
        leg: Leg,
        /// Where its centre stopped, m.
        z_m: f32,
    },
    /// The carried foot met something taller than its lift: it went back down where it stood.
    Blocked {
        /// The foot.
        leg: Leg,
    },
    /// The lowered foot found nothing within reach of the search.
    NoGround {
        /// The foot.
        leg: Leg,
    },
    /// The lift or the carry left the legs' reach: the foot went back down where it stood.
    OutOfReach {
        /// The foot.
        leg: Leg,
    },
}
