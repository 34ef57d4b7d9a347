//! The path of a swinging foot: up, across, and down at a steady speed until it finds the
//! ground (see [`super`], "A swing").

use super::frame::Point;
use super::CrawlConfig;
use crate::math::{clamp, cos};
use crate::time::TickRate;

/// Where a swing is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum SwingStage {
    Lift,
    Carry,
    Lower,
    /// Going back down where it stood, from where the swing had got to.
    Retreat {
        /// Where the foot was sent when the swing gave up.
        at: Point,
        /// Why it gave up.
        cause: RetreatCause,
    },
}

/// Why a swing goes back down where it stood.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum RetreatCause {
    /// The carried foot fell behind its target: a riser taller than the lift.
    Riser,
    /// The path left the legs' reach.
    OutOfReach,
}

/// The foot's point in a swing at `stage`, `stage_ticks` in.
pub(super) fn swing_point(
    config: &CrawlConfig,
    rate: TickRate,
    from: &Point,
    to: &Point,
    top_z_m: f32,
    stage: SwingStage,
    stage_ticks: u32,
) -> Point {
    let share = |ms: u32| {
        let ticks = rate.ticks_from_ms(ms).max(1);
        smooth(stage_ticks as f32 / ticks as f32)
    };
    match stage {
        SwingStage::Lift => Point {
            z_m: from.z_m + (top_z_m - from.z_m) * share(config.lift_ms),
            ..*from
        },
        SwingStage::Carry => {
            let s = share(config.carry_ms);
            Point {
                x_m: from.x_m + (to.x_m - from.x_m) * s,
                y_m: from.y_m + (to.y_m - from.y_m) * s,
                z_m: top_z_m,
            }
        }
        SwingStage::Lower => Point {
            z_m: top_z_m - config.lower_m_s * stage_ticks as f32 * rate.period_s(),
            ..*to
        },
        SwingStage::Retreat { at, .. } => {
            let s = share(config.lift_ms);
            Point {
                x_m: at.x_m + (from.x_m - at.x_m) * s,
                y_m: at.y_m + (from.y_m - at.y_m) * s,
                z_m: at.z_m + (from.z_m - at.z_m) * s,
            }
        }
    }
}

/// A smooth start and stop over a share 0…1 (half a cosine).
pub(super) fn smooth(share: f32) -> f32 {
    let s = clamp(share, 0.0, 1.0);
    0.5 * (1.0 - cos(core::f32::consts::PI * s))
}
