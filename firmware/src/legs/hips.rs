//! Where the legs attach to the torso: what a turning trot and the crawl's body frame both need
//! to know about the body.

use protocol::Leg;

/// The hips' positions in the torso's frame (x forward, y left, origin at the torso's centre),
/// symmetric fore–aft and left–right.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HipLayout {
    /// The hips' distance ahead of and behind the torso's centre, m.
    pub x_m: f32,
    /// The hips' distance left and right of the torso's centre, m.
    pub y_m: f32,
}

impl HipLayout {
    /// The robot: hips at ±0.22 m, ±0.15 m (`sim-host/models/hybrid_robot.xml`).
    pub const ROBOT: Self = Self {
        x_m: 0.22,
        y_m: 0.15,
    };

    /// `leg`'s hip in the torso's frame, m.
    pub const fn offset_m(&self, leg: Leg) -> (f32, f32) {
        match leg {
            Leg::Fl => (self.x_m, self.y_m),
            Leg::Fr => (self.x_m, -self.y_m),
            Leg::Bl => (-self.x_m, self.y_m),
            Leg::Br => (-self.x_m, -self.y_m),
        }
    }
}
