//! How the climb places the feet, how far it crawls, and which steps it takes.

use crate::legs::hips::HipLayout;
use crate::math::deg_to_rad;

/// How the climb places the feet and how far it crawls.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClimbConfig {
    /// Where the back feet go above the plateau: behind their hips, m.
    pub reach_x_m: f32,
    /// … and below their hips, m (above a step as high as the legs set a foot on).
    pub reach_depth_m: f32,
    /// How long the swings from the fold (the front feet's to the ground, the back feet's to
    /// above the plateau) take, ms.
    pub reach_ms: u32,
    /// Where the front feet go down: behind their hips, m.
    pub prop_x_m: f32,
    /// … starting this far below their hips, m.
    pub prop_depth_m: f32,
    /// How fast a foot is lowered toward the ground, m/s.
    pub probe_m_s: f32,
    /// Deepest a foot is lowered looking for ground, m below its hip.
    pub probe_depth_max_m: f32,
    /// A foot carrying this much is down, N, …
    pub touchdown_n: f32,
    /// … and standing this much higher than it is sent, m: stopped by the ground. The load
    /// alone reads 15–25 N on a foot in the air in the prop's and the reach's poses (the hip and
    /// knee torques also hold the leg's own weight and swing).
    pub touchdown_lag_m: f32,
    /// How much deeper than where it touched a foot is then held, m (its share of the weight).
    pub preload_m: f32,
    /// Where the hips are: the body's pitch moves each pair up or down by their distance
    /// from the torso's centre.
    pub hips: HipLayout,
    /// Where the front feet stand after the rise, m below their hips.
    pub front_depth_m: f32,
    /// Where the back feet stand after the rise, m below their hips: as deep as the legs
    /// still swing a foot from (a foot under its hip reaches no higher than 0.29 m below it),
    /// the body pitched nose down by what the step is higher than the two depths differ.
    pub back_depth_m: f32,
    /// How far each crawl cycle carries the body back, m.
    pub crawl_m: f32,
    /// How many crawl cycles carry the wheels over the plateau.
    pub crawl_cycles: u8,
    /// How long the body's shift over the planted feet takes, ms.
    pub shift_ms: u32,
    /// How long one foot's step takes (lift, carry, lower), ms.
    pub step_ms: u32,
    /// How high a stepping foot lifts, m.
    pub lift_m: f32,
    /// How long the lift, a retreat from it and the last lowering onto the wheels take, ms.
    pub rise_ms: u32,
    /// How far through the rise the step's height is first judged, 0…1: late enough that
    /// the feet carry the robot and the estimate has settled, early enough that a step too
    /// high has not yet pitched the body over its front feet (at 9–11 cm the last third of
    /// the rise tipped robots 10–15° further and rolled them, and the retreat from there
    /// put the torso down).
    pub rise_check_share: f32,
    /// How much the back legs shorten at the end, m, …
    pub lower_back_m: f32,
    /// … and the front legs (they stand ahead of their hips there, near their reach), m: the
    /// body comes down and tips back until the wheels stand on the plateau.
    pub lower_front_m: f32,
    /// Steps lower than this (m) the wheels roll: no climb.
    pub step_min_m: f32,
    /// Steps higher than this (m) are not climbed.
    pub step_max_m: f32,
    /// A body pitched further nose down than this when the back feet are down is not lifted,
    /// rad.
    pub pitch_max_rad: f32,
    /// A body that pitches further nose down than this while the legs lift it is stepped
    /// down from at once, rad: one robot of 50 that met a 10.7 cm riser slowly tipped 21°
    /// over its front feet by 60 % of the rise, where the height is judged, and 40° as the
    /// legs went back.
    pub rise_pitch_max_rad: f32,
    /// A body pitched further than this either way once the legs have set it down is not on
    /// its wheels on the plateau, rad: the crawl did not carry it over (the wheels stand on
    /// the plateau pitched a few degrees nose up; a robot whose wheels came down before the
    /// riser stood 26–28° nose down on its back feet, and climbed again).
    pub over_pitch_max_rad: f32,
}

impl ClimbConfig {
    /// The robot.
    pub const ROBOT: Self = Self {
        reach_x_m: -0.20,
        reach_depth_m: 0.12,
        reach_ms: 800,
        prop_x_m: -0.06,
        prop_depth_m: 0.18,
        probe_m_s: 0.06,
        probe_depth_max_m: 0.31,
        touchdown_n: 15.0,
        touchdown_lag_m: 0.01,
        preload_m: 0.01,
        hips: HipLayout::ROBOT,
        front_depth_m: 0.36,
        back_depth_m: 0.31,
        crawl_m: 0.09,
        crawl_cycles: 2,
        shift_ms: 1200,
        step_ms: 1200,
        lift_m: 0.03,
        rise_ms: 2000,
        rise_check_share: 0.6,
        lower_back_m: 0.10,
        lower_front_m: 0.045,
        step_min_m: 0.03,
        step_max_m: 0.085,
        pitch_max_rad: deg_to_rad(12.0),
        rise_pitch_max_rad: deg_to_rad(15.0),
        over_pitch_max_rad: deg_to_rad(15.0),
    };
}
