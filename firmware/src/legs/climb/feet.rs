//! A climb's feet: where a leg's joints put its foot, the joints that put it somewhere, and
//! the paths of a step and a blend.

use super::{ClimbConfig, Foot};
use crate::legs::kinematics::{leg_fk, leg_ik, FootTarget, KneeBranch, LegGeometry, LegJoints};
use crate::limits::JointLimits;
use crate::math::{clamp, deg_to_rad, smoothstep};

/// Where `joints` put the foot in its leg's sagittal plane.
pub fn foot_of(geometry: &LegGeometry, joints: &LegJoints) -> Foot {
    let foot = leg_fk(geometry, joints);
    Foot {
        x_m: foot.x_m,
        depth_m: -foot.z_m,
    }
}

/// Joint angles that put the foot at `foot`, with the foot pitch nearest `pitch_rad` that the
/// joints reach (tried in 5° steps to either side, up to 90°).
pub fn solve(
    geometry: &LegGeometry,
    limits: &JointLimits,
    foot: Foot,
    pitch_rad: f32,
) -> Option<LegJoints> {
    const STEPS: i32 = 18;
    let step_rad = deg_to_rad(5.0);
    (0..=2 * STEPS).find_map(|i: i32| {
        let offset: i32 = if i % 2_i32 == 0_i32 {
            i / 2_i32
        } else {
            -(i + 1_i32) / 2_i32
        };
        let target = FootTarget {
            x_m: foot.x_m,
            y_m: 0.0,
            z_m: -foot.depth_m,
            pitch_rad: pitch_rad + offset as f32 * step_rad,
        };
        leg_ik(geometry, limits, &target, KneeBranch::Down).ok()
    })
}

/// A foot stepping `config.crawl_m` back from `from`, `share` of the way through: lifted in
/// the first third, carried in the second, set down at its depth again in the last.
pub(super) fn step_foot(from: Foot, config: &ClimbConfig, share: f32) -> Foot {
    let third = |k: f32| clamp(3.0 * share - k, 0.0, 1.0);
    let lift_m = config.lift_m * (smoothstep(third(0.0)) - smoothstep(third(2.0)));
    Foot {
        x_m: from.x_m - config.crawl_m * smoothstep(third(1.0)),
        depth_m: from.depth_m - lift_m,
    }
}

pub(super) fn blend(from: Foot, to: Foot, share: f32) -> Foot {
    let s = smoothstep(clamp(share, 0.0, 1.0));
    Foot {
        x_m: from.x_m + (to.x_m - from.x_m) * s,
        depth_m: from.depth_m + (to.depth_m - from.depth_m) * s,
    }
}
