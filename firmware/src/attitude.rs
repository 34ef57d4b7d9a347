//! Torso attitude from the IMU's orientation quaternion (world ← body, w x y z; x forward,
//! y left, z up).

use crate::math::{asin, atan2, clamp};

/// Pitch and roll of the torso, rad.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Attitude {
    /// About +y, positive leaning forward (nose down), −π/2…π/2.
    pub pitch_rad: f32,
    /// About +x, positive with the left side up, −π…π.
    pub roll_rad: f32,
}

impl Attitude {
    /// Z-Y-X Euler pitch and roll of `[w, x, y, z]`. The quaternion need not be normalised
    /// exactly (wire rounding); a zero or non-finite quaternion gives NaN, for the caller to
    /// reject.
    pub fn from_quaternion(q: [f32; 4]) -> Self {
        let [w, x, y, z] = q;
        let norm_sq = w * w + x * x + y * y + z * z;
        if !(norm_sq.is_finite() && norm_sq > 1e-6) {
            return Self {
                pitch_rad: f32::NAN,
                roll_rad: f32::NAN,
            };
        }
        let sin_pitch = clamp(2.0 * (w * y - z * x) / norm_sq, -1.0, 1.0);
        Self {
            pitch_rad: asin(sin_pitch),
            roll_rad: atan2(2.0 * (w * x + y * z), norm_sq - 2.0 * (x * x + y * y)),
        }
    }

    /// The larger of |pitch| and |roll| (NaN if either is).
    pub fn tilt_rad(&self) -> f32 {
        if self.pitch_rad.is_nan() || self.roll_rad.is_nan() {
            f32::NAN
        } else {
            self.pitch_rad.abs().max(self.roll_rad.abs())
        }
    }
}
