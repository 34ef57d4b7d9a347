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
    Crawl::new(RATE, PerLeg::from_fn(under))
}

/// What the test plant does besides following the targets.
#[derive(Default)]
struct Plant<'a> {
    /// The ground's height under x (none: no ground within reach).
    ground_z_m: Option<&'a dyn Fn(f32) -> f32>,
    /// A wall no foot passes forward of below its top: (x, top z).
    wall: Option<(f32, f32)>,
    /// A foot that slipped along the ground: its measured x is this far off its target.
    slip: Option<(Leg, f32)>,
    /// Each foot's load, N, as its drives' torques report it, from the body's sideways
    /// position and whether the ground stopped the foot (none: no load).
    load_n: Option<&'a dyn Fn(Leg, f32, bool) -> f32>,
    /// The crawl's configuration (none: the robot's).
    config: Option<CrawlConfig>,
}

/// Runs the crawl's move on a plant whose feet follow their targets, but for the `plant`.
fn run_on(crawl: &mut Crawl, plant: &Plant<'_>) -> Option<Outcome> {
    let config = plant.config.unwrap_or(CrawlConfig::ROBOT);
    let geometry = LegGeometry::ROBOT;
    let limits = JointLimits::REPORT;
    // A target out of reach holds the leg where it was, as the controller holds its goal.
    let mut held = crawl.targets(&config, &geometry, &limits).map(|t| t.ok());
    for _ in 0..5_000_u32 {
        let targets = crawl.targets(&config, &geometry, &limits);
        let mut measured = Joints::splat(0.0);
        let mut effort = Joints::splat(0.0);
        for ((leg, target), hold) in Leg::ALL.into_iter().zip(targets).zip(held.iter_mut()) {
            let joints = match (target, *hold) {
                (Ok(joints), _) => joints,
                (Err(_), Some(joints)) => joints,
                (Err(_), None) => return None,
            };
            *hold = Some(joints);
            let mut foot = config
                .geometry
                .foot_of(&geometry, &crawl.body(), leg, &joints);
            if let Some((wall_x_m, top_z_m)) = plant.wall {
                if foot.z_m < top_z_m && foot.x_m > wall_x_m {
                    foot.x_m = wall_x_m;
                }
            }
            let mut grounded = false;
            if let Some(ground) = plant.ground_z_m {
                let ground_z_m = ground(foot.x_m);
                grounded = foot.z_m <= ground_z_m;
                foot.z_m = foot.z_m.max(ground_z_m);
            }
            if let Some((slipped, dx_m)) = plant.slip {
                if slipped == leg {
                    foot.x_m += dx_m;
                }
            }
            let solved = config
                .geometry
                .solve(&geometry, &limits, &crawl.body(), leg, &foot)
                .unwrap_or(joints);
            *measured.leg_mut(leg) = solved.to_array();
            let load_n = plant
                .load_n
                .map_or(0.0, |load| load(leg, crawl.body().centre.y_m, grounded));
            *effort.leg_mut(leg) = preload::holding_torques_nm(&geometry, &solved, load_n);
        }
        if let Some(outcome) = crawl.tick(&config, &geometry, &limits, &measured, &effort) {
            return Some(outcome);
        }
    }
    None
}

/// [`run_on`] a plant with the ground at `ground_z_m(x)` and maybe a wall.
fn run(
    crawl: &mut Crawl,
    ground_z_m: &dyn Fn(f32) -> f32,
    wall: Option<(f32, f32)>,
) -> Option<Outcome> {
    run_on(
        crawl,
        &Plant {
            ground_z_m: Some(ground_z_m),
            wall,
            ..Plant::default()
        },
    )
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
    let outcome = run(&mut crawl, &step, None);
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
        run(&mut crawl, &|_| -1.0, wall),
        Some(Outcome::Blocked { leg: Leg::Fr })
    );
    let back = crawl.feet().fr;
    assert!(
        (back.x_m - start.x_m).abs() < 1e-4 && back.z_m == start.z_m,
        "{back:?}"
    );
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
        run(&mut crawl, &|_| -1.0, None),
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
    assert_eq!(run(&mut crawl, &|_| -1.0, None), Some(Outcome::Moved));
    assert_eq!(crawl.body(), to);
    // Re-anchored where the encoders put them: within rounding of where they stood.
    for leg in Leg::ALL {
        let (a, b) = (crawl.feet().get(leg), feet.get(leg));
        assert!((a.x_m - b.x_m).abs() < 1e-4 && (a.y_m - b.y_m).abs() < 1e-4 && a.z_m == b.z_m);
    }
}

#[test]
fn an_unload_sways_away_from_the_foot_until_it_carries_little() {
    // No torque reported: the sway goes its whole length, away from the left front foot
    // (sideways, and back by half as much), and says the foot is still loaded.
    let mut crawl = standing();
    crawl.start(Move::Unload {
        leg: Leg::Fl,
        max_m: 0.04,
    });
    assert_eq!(
        run(&mut crawl, &|_| -1.0, None),
        Some(Outcome::StillLoaded { leg: Leg::Fl })
    );
    let body = crawl.body();
    assert!((body.centre.y_m + 0.04 * 0.894).abs() < 1e-4, "{body:?}");
    assert!((body.centre.x_m + 0.04 * 0.447).abs() < 1e-4, "{body:?}");
    // The back right foot sheds 3 kN per metre of sway from 100 N; the others share the rest.
    let shed = |leg: Leg, body_y_m: f32, _: bool| {
        let right = (100.0 - 3000.0 * body_y_m).max(0.0);
        if leg == Leg::Br {
            right
        } else {
            (400.0 - right) / 3.0
        }
    };
    let mut crawl = standing();
    crawl.start(Move::Unload {
        leg: Leg::Br,
        max_m: 0.06,
    });
    let plant = Plant {
        ground_z_m: Some(&|_| -1.0),
        load_n: Some(&shed),
        ..Plant::default()
    };
    assert_eq!(
        run_on(&mut crawl, &plant),
        Some(Outcome::Freed { leg: Leg::Br })
    );
    // Freed at 40 N of 400: 2 cm of sway.
    let body = crawl.body();
    assert!((body.centre.y_m - 0.02).abs() < 0.002, "{body:?}");
    // A length that is no length sways nowhere.
    let mut crawl = standing();
    crawl.start(Move::Unload {
        leg: Leg::Br,
        max_m: f32::NAN,
    });
    assert_eq!(
        run(&mut crawl, &|_| -1.0, None),
        Some(Outcome::StillLoaded { leg: Leg::Br })
    );
    assert_eq!(crawl.body(), BodyPose::default());
}

#[test]
fn a_lowered_foot_whose_knee_takes_the_load_has_landed() {
    // Only the knee's torque can tell: the lag rule is set out of reach.
    let config = CrawlConfig {
        touchdown_lag_m: 1.0,
        ..CrawlConfig::ROBOT
    };
    let mut crawl = standing();
    let start = crawl.feet().fl;
    crawl.start(Move::Swing {
        leg: Leg::Fl,
        to: start,
        lift_m: 0.03,
    });
    let ground_z_m = start.z_m - 0.01;
    let plant = Plant {
        ground_z_m: Some(&move |_| ground_z_m),
        load_n: Some(&|_, _, grounded| if grounded { 100.0 } else { 0.0 }),
        config: Some(config),
        ..Plant::default()
    };
    let outcome = run_on(&mut crawl, &plant);
    assert!(
        matches!(
            outcome,
            Some(Outcome::Landed { leg: Leg::Fl, z_m }) if (z_m - ground_z_m).abs() < 0.005
        ),
        "{outcome:?}"
    );
}

#[test]
fn a_carry_out_of_the_legs_reach_goes_back_down_and_says_so() {
    let mut crawl = standing();
    let start = crawl.feet().fr;
    crawl.start(Move::Swing {
        leg: Leg::Fr,
        to: Point {
            x_m: start.x_m + 0.4,
            ..start
        },
        lift_m: 0.03,
    });
    assert_eq!(
        run(&mut crawl, &|_| -1.0, None),
        Some(Outcome::OutOfReach { leg: Leg::Fr })
    );
    let back = crawl.feet().fr;
    assert!(
        (back.x_m - start.x_m).abs() < 1e-4 && back.z_m == start.z_m,
        "{back:?}"
    );
}

#[test]
fn a_foot_that_slipped_is_taken_where_the_encoders_put_it() {
    let mut crawl = standing();
    let before = crawl.feet();
    crawl.start(Move::Body {
        to: BodyPose::default(),
        ms: 100,
    });
    let plant = Plant {
        ground_z_m: Some(&|_| -1.0),
        slip: Some((Leg::Bl, -0.02)),
        ..Plant::default()
    };
    assert_eq!(run_on(&mut crawl, &plant), Some(Outcome::Moved));
    let after = crawl.feet();
    assert!(
        (after.bl.x_m - (before.bl.x_m - 0.02)).abs() < 1e-3,
        "{after:?}"
    );
    assert_eq!(after.bl.z_m, before.bl.z_m, "the height stays the target's");
    assert!((after.fl.x_m - before.fl.x_m).abs() < 1e-4);
}

#[test]
fn the_targets_lead_by_the_planned_loads_and_a_swinging_foot_carries_none() {
    let config = CrawlConfig::ROBOT;
    let (geometry, limits) = (LegGeometry::ROBOT, JointLimits::REPORT);
    let kp = [180.0, 200.0, 260.0, 160.0];
    let differs = |crawl: &Crawl, leg: Leg| {
        let index = leg as usize;
        let plain = crawl.targets(&config, &geometry, &limits);
        let led = crawl.preloaded_targets(&config, &geometry, &limits, 400.0, &kp);
        match (plain.get(index), led.get(index)) {
            (Some(Ok(a)), Some(Ok(b))) => (a.knee_rad - b.knee_rad).abs() > 1e-3,
            _ => false,
        }
    };
    let mut crawl = standing();
    assert!(Leg::ALL.into_iter().all(|leg| differs(&crawl, leg)));
    let start = crawl.feet().fl;
    crawl.start(Move::Swing {
        leg: Leg::Fl,
        to: start,
        lift_m: 0.02,
    });
    assert!(!differs(&crawl, Leg::Fl));
    // The mass over the diagonal of the other three: the front right and back left carry it.
    assert!(differs(&crawl, Leg::Fr) && differs(&crawl, Leg::Bl));
}
