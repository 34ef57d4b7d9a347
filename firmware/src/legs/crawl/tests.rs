//! The crawl's moves on a plant whose feet follow their targets but stop on the ground.

use super::*;
use crate::legs::kinematics::LegGeometry;
use crate::limits::JointLimits;

const RATE: TickRate = TickRate::SIM_250_HZ;

/// Four feet 0.35 m under and 8 cm behind their hips (where a foot lifts high), the body
/// at the origin.
fn standing() -> Crawl {
    standing_at(0.35)
}

/// Four feet `depth_m` under and 8 cm behind their hips, the body at the origin.
fn standing_at(depth_m: f32) -> Crawl {
    let g = CrawlGeometry::ROBOT;
    let body = BodyPose::default();
    let under = |leg: Leg| {
        let hip = g.hip(&body, leg);
        Point {
            x_m: hip.x_m - 0.08,
            z_m: hip.z_m - depth_m,
            ..hip
        }
    };
    Crawl::new(
        RATE,
        PerLeg {
            fl: under(Leg::Fl),
            fr: under(Leg::Fr),
            bl: under(Leg::Bl),
            br: under(Leg::Br),
        },
    )
}

/// Runs the crawl's move on a plant whose feet follow their targets, except that a foot
/// cannot go below `ground_z_m(x)` nor pass forward of `wall_x_m` below `wall_top_z_m`.
fn run(
    crawl: &mut Crawl,
    ground_z_m: impl Fn(f32) -> f32,
    wall: Option<(f32, f32)>,
) -> Option<Outcome> {
    let config = CrawlConfig::ROBOT;
    let geometry = LegGeometry::ROBOT;
    let limits = JointLimits::REPORT;
    for _ in 0..5_000_u32 {
        let targets = crawl.targets(&config, &geometry, &limits);
        let mut measured = Joints::splat(0.0);
        for (leg, target) in Leg::ALL.into_iter().zip(targets) {
            let Ok(joints) = target else {
                return None;
            };
            let mut foot = config
                .geometry
                .foot_of(&geometry, &crawl.body(), leg, &joints);
            if let Some((wall_x_m, top_z_m)) = wall {
                if foot.z_m < top_z_m && foot.x_m > wall_x_m {
                    foot.x_m = wall_x_m;
                }
            }
            foot.z_m = foot.z_m.max(ground_z_m(foot.x_m));
            let local = config.geometry.to_leg(&crawl.body(), leg, &foot);
            let solved = crate::legs::kinematics::leg_ik(
                &geometry,
                &JointLimits::REPORT,
                &crate::legs::kinematics::FootTarget {
                    x_m: local.x_m,
                    y_m: local.y_m,
                    z_m: local.z_m,
                    pitch_rad: -1.6,
                },
                crate::legs::kinematics::KneeBranch::Down,
            )
            .or_else(|_| {
                config
                    .geometry
                    .solve(&geometry, &limits, &crawl.body(), leg, &foot)
            })
            .unwrap_or(joints);
            *measured.leg_mut(leg) = solved.to_array();
        }
        if let Some(outcome) =
            crawl.tick(&config, &geometry, &limits, &measured, &Joints::splat(0.0))
        {
            return Some(outcome);
        }
    }
    None
}

#[test]
fn a_swing_lands_on_a_step_and_the_foot_stays_there() {
    let mut crawl = standing();
    let start = crawl.feet().fl;
    let step_x_m = start.x_m + 0.03;
    let step = |x: f32| {
        if x > step_x_m {
            start.z_m + 0.04
        } else {
            start.z_m
        }
    };
    crawl.start(Move::Swing {
        leg: Leg::Fl,
        to: Point {
            x_m: start.x_m + 0.06,
            ..start
        },
        lift_m: 0.06,
    });
    let outcome = run(&mut crawl, step, None);
    assert!(
        matches!(outcome, Some(Outcome::Landed { leg: Leg::Fl, .. })),
        "{outcome:?}"
    );
    let Some(Outcome::Landed { z_m, .. }) = outcome else {
        return;
    };
    assert!((z_m - (start.z_m + 0.04)).abs() < 0.01, "{z_m}");
    assert!((crawl.feet().fl.x_m - (start.x_m + 0.06)).abs() < 1e-4);
    assert!(crawl.idle());
}

#[test]
fn a_swing_into_a_riser_taller_than_its_lift_is_blocked_and_goes_back_down() {
    let mut crawl = standing();
    let start = crawl.feet().fr;
    crawl.start(Move::Swing {
        leg: Leg::Fr,
        to: Point {
            x_m: start.x_m + 0.06,
            ..start
        },
        lift_m: 0.04,
    });
    let wall = Some((start.x_m + 0.02, start.z_m + 0.10));
    assert_eq!(
        run(&mut crawl, |_| -1.0, wall),
        Some(Outcome::Blocked { leg: Leg::Fr })
    );
    assert_eq!(crawl.feet().fr, start);
}

#[test]
fn a_swing_over_a_hole_finds_no_ground() {
    let mut crawl = standing_at(0.31);
    let start = crawl.feet().bl;
    crawl.start(Move::Swing {
        leg: Leg::Bl,
        to: Point {
            x_m: start.x_m - 0.02,
            ..start
        },
        lift_m: 0.03,
    });
    assert_eq!(
        run(&mut crawl, |_| -1.0, None),
        Some(Outcome::NoGround { leg: Leg::Bl })
    );
}

#[test]
fn a_body_move_keeps_the_feet_where_they_stand() {
    let mut crawl = standing();
    let feet = crawl.feet();
    let to = BodyPose {
        centre: Point {
            x_m: 0.05,
            y_m: -0.03,
            z_m: -0.02,
        },
        pitch_rad: 0.1,
    };
    crawl.start(Move::Body { to, ms: 400 });
    assert_eq!(run(&mut crawl, |_| -1.0, None), Some(Outcome::Moved));
    assert_eq!(crawl.body(), to);
    assert_eq!(crawl.feet(), feet);
}
