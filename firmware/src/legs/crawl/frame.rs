//! Where the crawl keeps the body and the feet: a ground frame fixed where the crawl began
//! (x forward, y left, z up; the origin at the torso's centre then), the body's commanded pose
//! in it, and each foot's centre in it. The legs' targets follow from the two by rotating the
//! hip-to-foot vector into the pitched body.

use protocol::Leg;

use crate::legs::hips::HipLayout;
use crate::legs::kinematics::{leg_fk, leg_ik, FootTarget, IkError, LegGeometry, LegJoints};
use crate::limits::JointLimits;
use crate::math::{cos, deg_to_rad, sin};

/// A point of the ground frame, m.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Point {
    /// Forward, m.
    pub x_m: f32,
    /// Left, m.
    pub y_m: f32,
    /// Up, m.
    pub z_m: f32,
}

/// The torso's commanded pose in the ground frame: its centre, and its pitch (nose up
/// positive). Roll and yaw are not commanded.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BodyPose {
    /// The torso's centre, m.
    pub centre: Point,
    /// Nose up, rad.
    pub pitch_rad: f32,
}

impl BodyPose {
    /// The pose `share` (0…1) of the way from `self` to `to`.
    pub fn toward(&self, to: &BodyPose, share: f32) -> BodyPose {
        let s = crate::math::clamp(share, 0.0, 1.0);
        let mix = |a: f32, b: f32| a + (b - a) * s;
        BodyPose {
            centre: Point {
                x_m: mix(self.centre.x_m, to.centre.x_m),
                y_m: mix(self.centre.y_m, to.centre.y_m),
                z_m: mix(self.centre.z_m, to.centre.z_m),
            },
            pitch_rad: mix(self.pitch_rad, to.pitch_rad),
        }
    }
}

/// One value per leg, by name (no index to get wrong).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PerLeg<T> {
    /// Front left.
    pub fl: T,
    /// Front right.
    pub fr: T,
    /// Back left.
    pub bl: T,
    /// Back right.
    pub br: T,
}

impl<T: Copy> PerLeg<T> {
    /// The same value for every leg.
    pub const fn splat(value: T) -> Self {
        Self {
            fl: value,
            fr: value,
            bl: value,
            br: value,
        }
    }

    /// `f` of each leg.
    pub fn from_fn(mut f: impl FnMut(Leg) -> T) -> Self {
        Self {
            fl: f(Leg::Fl),
            fr: f(Leg::Fr),
            bl: f(Leg::Bl),
            br: f(Leg::Br),
        }
    }

    /// `leg`'s value.
    pub fn get(&self, leg: Leg) -> T {
        match leg {
            Leg::Fl => self.fl,
            Leg::Fr => self.fr,
            Leg::Bl => self.bl,
            Leg::Br => self.br,
        }
    }

    /// `leg`'s value, to change.
    pub fn get_mut(&mut self, leg: Leg) -> &mut T {
        match leg {
            Leg::Fl => &mut self.fl,
            Leg::Fr => &mut self.fr,
            Leg::Bl => &mut self.bl,
            Leg::Br => &mut self.br,
        }
    }
}

/// The body's dimensions and the foot-pitch schedule the crawl solves its legs with.
///
/// The climb's poses reach where the trot's schedule ([`crate::legs::posture::Posture`]) has
/// no solution: feet lifted 10–14 cm behind a pitched hip. Fitted by a grid search over every
/// foot position 0.22–0.37 m below the hip and 0.16 m behind to 0.08 m ahead of it that some
/// foot pitch reaches with 8° to spare on every joint: `φ = −96° + 175°/m · x + 300°/m ·
/// (depth − 0.33 m)` keeps every joint 5.9° inside its range over all of them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrawlGeometry {
    /// Where the hips are on the torso.
    pub hips: HipLayout,
    /// Foot sphere radius, m.
    pub foot_radius_m: f32,
    /// φ at x = 0 and the reference depth, rad.
    pub pitch_base_rad: f32,
    /// dφ/dx, rad/m.
    pub pitch_per_x_rad_m: f32,
    /// dφ/d(depth), rad/m.
    pub pitch_per_depth_rad_m: f32,
    /// The schedule's reference depth, m.
    pub pitch_reference_depth_m: f32,
}

impl CrawlGeometry {
    /// The robot (hips at ±0.22 m, ±0.15 m; foot radius 0.035 m).
    pub const ROBOT: Self = Self {
        hips: HipLayout::ROBOT,
        foot_radius_m: 0.035,
        pitch_base_rad: deg_to_rad(-96.0),
        pitch_per_x_rad_m: deg_to_rad(175.0),
        pitch_per_depth_rad_m: deg_to_rad(300.0),
        pitch_reference_depth_m: 0.33,
    };

    /// `leg`'s hip in the torso's frame (x forward, y left), m.
    pub fn hip_offset_m(&self, leg: Leg) -> (f32, f32) {
        self.hips.offset_m(leg)
    }

    /// `leg`'s hip in the ground frame for the body at `body`.
    pub fn hip(&self, body: &BodyPose, leg: Leg) -> Point {
        let (hx, hy) = self.hip_offset_m(leg);
        Point {
            x_m: body.centre.x_m + hx * cos(body.pitch_rad),
            y_m: body.centre.y_m + hy,
            z_m: body.centre.z_m + hx * sin(body.pitch_rad),
        }
    }

    /// The foot at `foot` (ground frame) in `leg`'s leg frame for the body at `body`.
    pub fn to_leg(&self, body: &BodyPose, leg: Leg, foot: &Point) -> Point {
        let hip = self.hip(body, leg);
        let (vx, vz) = (foot.x_m - hip.x_m, foot.z_m - hip.z_m);
        let (s, c) = (sin(body.pitch_rad), cos(body.pitch_rad));
        Point {
            x_m: vx * c + vz * s,
            y_m: foot.y_m - hip.y_m,
            z_m: -vx * s + vz * c,
        }
    }

    /// A leg-frame foot position in the ground frame for the body at `body`.
    pub fn to_ground(&self, body: &BodyPose, leg: Leg, foot: &Point) -> Point {
        let hip = self.hip(body, leg);
        let (s, c) = (sin(body.pitch_rad), cos(body.pitch_rad));
        Point {
            x_m: hip.x_m + foot.x_m * c - foot.z_m * s,
            y_m: hip.y_m + foot.y_m,
            z_m: hip.z_m + foot.x_m * s + foot.z_m * c,
        }
    }

    /// Joint angles that put `leg`'s foot at `foot` (ground frame) with the body at `body`.
    pub fn solve(
        &self,
        geometry: &LegGeometry,
        limits: &JointLimits,
        body: &BodyPose,
        leg: Leg,
        foot: &Point,
    ) -> Result<LegJoints, IkError> {
        let local = self.to_leg(body, leg, foot);
        let depth_m = -local.z_m;
        let pitch_rad = self.pitch_base_rad
            + self.pitch_per_x_rad_m * local.x_m
            + self.pitch_per_depth_rad_m * (depth_m - self.pitch_reference_depth_m);
        leg_ik(
            geometry,
            limits,
            &FootTarget {
                x_m: local.x_m,
                y_m: local.y_m,
                z_m: local.z_m,
                pitch_rad,
            },
            crate::legs::kinematics::KneeBranch::Down,
        )
    }

    /// Where `joints` put `leg`'s foot in the ground frame with the body at `body`.
    pub fn foot_of(
        &self,
        geometry: &LegGeometry,
        body: &BodyPose,
        leg: Leg,
        joints: &LegJoints,
    ) -> Point {
        let local = leg_fk(geometry, joints);
        self.to_ground(
            body,
            leg,
            &Point {
                x_m: local.x_m,
                y_m: local.y_m,
                z_m: local.z_m,
            },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_foot_goes_to_the_leg_frame_and_back_unchanged_at_any_pitch() {
        let g = CrawlGeometry::ROBOT;
        let foot = Point {
            x_m: 0.31,
            y_m: 0.12,
            z_m: -0.33,
        };
        for pitch_deg in [-10.0_f32, 0.0, 15.0] {
            let body = BodyPose {
                centre: Point {
                    x_m: 0.05,
                    y_m: -0.02,
                    z_m: 0.01,
                },
                pitch_rad: deg_to_rad(pitch_deg),
            };
            for leg in Leg::ALL {
                let back = g.to_ground(&body, leg, &g.to_leg(&body, leg, &foot));
                assert!((back.x_m - foot.x_m).abs() < 1e-5);
                assert!((back.y_m - foot.y_m).abs() < 1e-5);
                assert!((back.z_m - foot.z_m).abs() < 1e-5);
            }
        }
    }

    #[test]
    fn a_nose_up_body_puts_a_foot_below_the_front_hip_behind_it() {
        let g = CrawlGeometry::ROBOT;
        let body = BodyPose {
            centre: Point::default(),
            pitch_rad: deg_to_rad(15.0),
        };
        let hip = g.hip(&body, Leg::Fl);
        let below = Point {
            z_m: hip.z_m - 0.35,
            ..hip
        };
        let local = g.to_leg(&body, Leg::Fl, &below);
        assert!(local.x_m < -0.08, "{local:?}");
    }

    #[test]
    fn the_schedule_solves_a_foot_lifted_high_behind_a_level_hip() {
        let g = CrawlGeometry::ROBOT;
        let body = BodyPose::default();
        let hip = g.hip(&body, Leg::Fl);
        let limits = JointLimits::REPORT;
        for (x_m, depth_m) in [(-0.12, 0.24), (-0.06, 0.28), (0.0, 0.35), (0.06, 0.34)] {
            let foot = Point {
                x_m: hip.x_m + x_m,
                y_m: hip.y_m,
                z_m: hip.z_m - depth_m,
            };
            let joints = g.solve(&LegGeometry::ROBOT, &limits, &body, Leg::Fl, &foot);
            assert!(joints.is_ok(), "({x_m}, {depth_m}): {joints:?}");
            let back = g.foot_of(
                &LegGeometry::ROBOT,
                &body,
                Leg::Fl,
                &joints.unwrap_or_default(),
            );
            assert!((back.x_m - foot.x_m).abs() < 1e-4 && (back.z_m - foot.z_m).abs() < 1e-4);
        }
    }

    /// The smallest distance of the pitch joints from their range's ends for the foot at
    /// `(x_m, depth_m)` with foot pitch `pitch_rad`, rad (negative: outside, or unreachable).
    fn margin_rad(x_m: f32, depth_m: f32, pitch_rad: f32) -> f32 {
        use crate::legs::kinematics::{planar_ik, KneeBranch, PlanarPose};
        use crate::limits::Joint;
        let pose = PlanarPose {
            x_m,
            z_m: -depth_m,
            pitch_rad,
        };
        let Ok(angles) = planar_ik(&LegGeometry::ROBOT, &pose, KneeBranch::Down) else {
            return -1.0;
        };
        let limits = JointLimits::REPORT;
        [
            (
                Joint::HipPitch,
                angles.q1_rad + core::f32::consts::FRAC_PI_2,
            ),
            (Joint::Knee, angles.q2_rad),
            (Joint::Ankle, angles.q3_rad),
        ]
        .into_iter()
        .map(|(joint, angle)| {
            let range = limits.range(joint);
            (angle - range.min_rad).min(range.max_rad - angle)
        })
        .fold(f32::INFINITY, f32::min)
    }

    #[test]
    fn the_schedule_keeps_every_joint_inside_its_range_where_some_pitch_does_by_8_degrees() {
        let g = CrawlGeometry::ROBOT;
        let (mut checked, mut worst) = (0_u32, f32::INFINITY);
        for i in 0..13_u8 {
            let x_m = -0.16 + 0.02 * f32::from(i);
            for j in 0..16_u8 {
                let depth_m = 0.22 + 0.01 * f32::from(j);
                let best = (0..180_u8)
                    .map(|k| margin_rad(x_m, depth_m, deg_to_rad(-180.0 + f32::from(k))))
                    .fold(f32::NEG_INFINITY, f32::max);
                if best < deg_to_rad(8.0) {
                    continue;
                }
                let pitch_rad = g.pitch_base_rad
                    + g.pitch_per_x_rad_m * x_m
                    + g.pitch_per_depth_rad_m * (depth_m - g.pitch_reference_depth_m);
                worst = worst.min(margin_rad(x_m, depth_m, pitch_rad));
                checked += 1;
            }
        }
        assert!(checked > 100, "{checked} poses");
        assert!(worst > deg_to_rad(5.5), "{} degrees", worst.to_degrees());
    }
}
