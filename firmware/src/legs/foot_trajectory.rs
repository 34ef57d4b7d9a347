//! The Cartesian trot: each foot runs a stance line on the ground and a swing arc through the
//! air, in the leg frame, and the IK turns it into joint targets. This is the default walking
//! gait; unlike the report's sinusoids it puts the foot on a flat ground line during stance, so
//! the body is carried level and the stride length is a parameter in metres.
//!
//! ```text
//!   z      swing (the rest of the cycle): x from −L/2 to +L/2, z lifts by h·sin(πs)
//!   ^     .-----------.
//!   |    /             \
//!  −d  +L/2 <—————— −L/2    stance (the duty's share): x from +L/2 to −L/2 at z = −d
//! ```
//!
//! # Duty
//!
//! A foot is on the ground for a little more than half the cycle, so that at each change of
//! support both diagonal pairs stand for a moment. With exactly half, one pair lifted as the
//! other landed and the body tipped toward the unsupported side for the whole half cycle (the
//! trot runs at the report's 1 Hz, and a 0.38 m body tips with a time constant of 0.2 s): it
//! rocked ±5° in pitch and roll, the stance knees caught it at up to 33 N·m, and on drives
//! rated 20 % low with legs three times as heavy as drawn a knee gave way and the robot fell
//! over its front legs. At 0.55 the rocking is reset at each change of support; at 0.6 and
//! more the feet of a lifting pair left the ground at different moments often enough to put
//! the robot on two feet of one side (campaign over 100 trials, `L`, `K` and X after a trot:
//! 255 of 300 at 0.5, 287 at 0.55, 232 at 0.6).

use core::f32::consts::PI;

use crate::legs::phase::Phase;
use crate::math::{cos, sin};

/// Shape of the foot path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FootTrajectory {
    /// Stride length L, m: how far the foot travels along the ground per stance.
    pub step_length_m: f32,
    /// Peak lift h above the stance line during swing, m.
    pub clearance_m: f32,
    /// Forward offset of the stride's centre from the hip, m.
    pub centre_x_m: f32,
    /// Share of the cycle a foot is on the ground (0.5…0.9): above one half both pairs stand
    /// at each change of support.
    pub duty: f32,
}

impl FootTrajectory {
    /// 8 cm stride, 4 cm clearance, centred 3 cm ahead of the hip, on the ground 55 % of the
    /// cycle (module docs, "Duty"). Centred under the hip the robot trotted forward (1.3 m in
    /// 8 s) but not backward (0.09 m): its knees bend one way, so a leg pushes unevenly fore
    /// and aft of the hip. Measured in the simulator over 8 s,
    /// forward / backward: centre 0 → 1.30 / 0.09 m, +1.5 cm → 1.21 / 0.60 m, +3 cm → 0.96 /
    /// 0.88 m, +4.5 cm → 0.65 / 1.18 m; +3 cm walks both ways alike.
    pub const DEFAULT: Self = Self {
        step_length_m: 0.08,
        clearance_m: 0.04,
        centre_x_m: 0.03,
        duty: 0.55,
    };

    /// The foot position at `phase` for a stride of `along` full strides fore–aft and `across`
    /// full strides to the left (each −1…1; a turning trot's legs stride differently and
    /// sideways): stance carries the foot from `+(along, across)·L/2` to `−(along, across)·L/2`
    /// around the stride's centre, and swing back through the air. Stance takes the first
    /// [`FootTrajectory::duty`] of the cycle and pushes the foot backward (for a positive
    /// `along`), so the body moves forward; run the phase backward ([`Phase::reversed`]) to
    /// walk backward. A foot with no stride stays down.
    pub fn foot_on_stride(&self, phase: Phase, depth_m: f32, along: f32, across: f32) -> FootPoint {
        let half = 0.5 * self.step_length_m;
        let fraction = phase.fraction();
        let duty = crate::math::clamp(self.duty, 0.5, 0.9);
        // Where the foot is along its stride, +1 at touchdown to −1 at lift-off.
        let (u, lift) = if fraction < duty {
            (1.0 - 2.0 * fraction / duty, 0.0)
        } else {
            let s = (fraction - duty) / (1.0 - duty);
            let striding = along != 0.0 || across != 0.0;
            let lift = if striding {
                self.clearance_m * sin(PI * s)
            } else {
                0.0
            };
            (-cos(PI * s), lift)
        };
        FootPoint {
            x_m: self.centre_x_m + half * along * u,
            y_m: half * across * u,
            z_m: -depth_m + lift,
        }
    }
}

/// A foot position in the leg frame (x forward, y left, z up, origin at the hip), m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FootPoint {
    /// Forward.
    pub x_m: f32,
    /// Left.
    pub y_m: f32,
    /// Up (negative below the hip).
    pub z_m: f32,
}
