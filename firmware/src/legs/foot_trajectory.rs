//! The Cartesian trot: each foot runs a stance line on the ground and a swing arc through the
//! air, in the leg frame, and the IK turns it into joint targets. This is the default walking
//! gait; unlike the report's sinusoids it puts the foot on a flat ground line during stance, so
//! the body is carried level and the stride length is a parameter in metres.
//!
//! ```text
//!   z      swing (second half): x from −L/2 to +L/2, z lifts by h·sin(πs)
//!   ^     .-----------.
//!   |    /             \
//!  −d  +L/2 <—————— −L/2    stance (first half): x from +L/2 to −L/2 at z = −d
//! ```

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
}

impl FootTrajectory {
    /// 8 cm stride, 4 cm clearance, centred 3 cm ahead of the hip. Centred under the hip the
    /// robot trotted forward (1.3 m in 8 s) but not backward (0.09 m): its knees bend one way,
    /// so a leg pushes unevenly fore and aft of the hip. Measured in the simulator over 8 s,
    /// forward / backward: centre 0 → 1.30 / 0.09 m, +1.5 cm → 1.21 / 0.60 m, +3 cm → 0.96 /
    /// 0.88 m, +4.5 cm → 0.65 / 1.18 m; +3 cm walks both ways alike.
    pub const DEFAULT: Self = Self {
        step_length_m: 0.08,
        clearance_m: 0.04,
        centre_x_m: 0.03,
    };

    /// The foot position `(x_m, z_m)` at `phase` for a stance line `depth_m` below the hip,
    /// with the stride scaled by `scale` (0…1, clamped). Stance takes the first half of the
    /// cycle and pushes the foot backward, so the body moves forward; run the phase backward
    /// ([`Phase::reversed`]) to walk backward.
    pub fn foot(&self, phase: Phase, depth_m: f32, scale: f32) -> (f32, f32) {
        let scale = crate::math::clamp(scale, 0.0, 1.0);
        let half = 0.5 * self.step_length_m * scale;
        let fraction = phase.fraction();
        if fraction < 0.5 {
            let s = fraction * 2.0;
            (self.centre_x_m + half - 2.0 * half * s, -depth_m)
        } else {
            let s = (fraction - 0.5) * 2.0;
            let x = self.centre_x_m - half + 2.0 * half * 0.5 * (1.0 - cos(PI * s));
            let lift = if scale > 0.0 {
                self.clearance_m * sin(PI * s)
            } else {
                0.0
            };
            (x, -depth_m + lift)
        }
    }
}
