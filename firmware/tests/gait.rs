//! The trot: integer phase (ten hours = ten seconds), diagonal pairs in antiphase, backward as
//! time reversal, the Cartesian foot path on the ground line, and IK solutions over the whole
//! body-height band.

use firmware::attitude::Attitude;
use firmware::config::Config;
use firmware::control::fsm::Direction;
use firmware::legs::gait::{Generator, Trot, TrotParams};
use firmware::legs::kinematics::{leg_fk, LegJoints};
use firmware::legs::phase::{Phase, PhaseStep};
use firmware::legs::sine_gait::SineGait;
use firmware::time::TickRate;
use protocol::Leg;

const CONFIG: Config = Config::ROBOT;
const TEN_SECONDS: u64 = 10 * 250;
const TEN_HOURS: u64 = 10 * 3600 * 250;

fn targets(trot: &Trot, direction: Direction, depth_m: f32) -> [LegJoints; 4] {
    trot.targets(
        direction,
        depth_m,
        &firmware::legs::gait::TrotCommand::straight(1.0),
        &Attitude::default(),
        &CONFIG.geometry,
        &CONFIG.limits,
        &CONFIG.posture,
    )
    .map(|t| t.expect("IK solves every gait pose"))
}

fn one_cycle_after(ticks: u64, params: TrotParams) -> Vec<[LegJoints; 4]> {
    let mut trot = Trot::new(params, TickRate::SIM_250_HZ).unwrap();
    trot.set_phase(Phase::after(trot.step(), ticks));
    (0..250)
        .map(|_| {
            let out = targets(&trot, Direction::Forward, CONFIG.posture.depth_nominal_m);
            trot.advance();
            out
        })
        .collect()
}

#[test]
fn the_gait_after_ten_hours_is_the_gait_after_ten_seconds() {
    for params in [TrotParams::DEFAULT, TrotParams::REPORT] {
        assert_eq!(
            one_cycle_after(TEN_SECONDS, params),
            one_cycle_after(TEN_HOURS, params)
        );
    }
}

#[test]
fn stepping_ten_hours_tick_by_tick_lands_exactly_on_the_ideal_phase() {
    // 1 Hz and an awkward 1.3 Hz at 250 Hz: the Bresenham remainder keeps the phase exact.
    for frequency_millihz in [1000, 1300] {
        let step = PhaseStep::new(frequency_millihz, TickRate::SIM_250_HZ).unwrap();
        let mut phase = Phase::default();
        for _ in 0..TEN_HOURS {
            phase.advance(step);
        }
        assert_eq!(phase, Phase::after(step, TEN_HOURS));
        let ideal = (TEN_HOURS as u128 * frequency_millihz as u128 * (1u128 << 32) / (250 * 1000))
            % (1u128 << 32);
        assert_eq!(phase.count() as u128, ideal, "{frequency_millihz} mHz");
    }
    // What the integer phase avoids: the report's float time `t += dt` after ten hours.
    let mut t = 0.0f32;
    for _ in 0..TEN_HOURS {
        t += 0.004;
    }
    assert!((t - 36_000.0).abs() > 1.0, "f32 time drifts to {t}");
}

#[test]
fn diagonal_pairs_move_together_and_half_a_cycle_apart() {
    for params in [TrotParams::DEFAULT, TrotParams::REPORT] {
        let mut trot = Trot::new(params, TickRate::SIM_250_HZ).unwrap();
        let mut history = Vec::new();
        for _ in 0..250 {
            history.push(targets(&trot, Direction::Forward, 0.35));
            trot.advance();
        }
        for (tick, legs) in history.iter().enumerate() {
            let [fl, fr, bl, br] = *legs;
            assert_eq!(fl, br, "FL and BR pair at tick {tick}");
            assert_eq!(fr, bl, "FR and BL pair at tick {tick}");
            let half_later = history[(tick + 125) % 250][1];
            for (a, b) in fl.to_array().iter().zip(half_later.to_array()) {
                assert!(
                    (a - b).abs() < 1e-3,
                    "FR lags FL by half a cycle at tick {tick}"
                );
            }
        }
    }
}

fn foot_path(direction: Direction) -> Vec<(f32, f32)> {
    let mut trot = Trot::new(TrotParams::DEFAULT, TickRate::SIM_250_HZ).unwrap();
    (0..250)
        .map(|_| {
            let fl = targets(&trot, direction, 0.35)[0];
            trot.advance();
            let foot = leg_fk(&CONFIG.geometry, &fl);
            (foot.x_m, foot.z_m)
        })
        .collect()
}

#[test]
fn the_cartesian_foot_pushes_back_along_the_ground_and_swings_over_it() {
    let path = foot_path(Direction::Forward);
    // The stance takes the duty's share of the 250 ticks.
    let duty = match TrotParams::DEFAULT.generator {
        Generator::Cartesian(path) => path.duty,
        Generator::Sine(_) => 0.5,
    };
    let stance_ticks = (duty * 250.0).round() as usize;
    let (stance, swing) = path.split_at(stance_ticks);
    for window in stance.windows(2) {
        assert!(
            (window[0].1 + 0.35).abs() < 1e-4,
            "stance on the ground line"
        );
        assert!(window[1].0 < window[0].0, "stance pushes the foot backward");
    }
    let stride = stance[0].0 - stance[stance_ticks - 1].0;
    assert!((stride - 0.08).abs() < 2e-3, "stride {stride} m");
    let apex = swing.iter().map(|p| p.1).fold(f32::MIN, f32::max);
    assert!((apex - (-0.35 + 0.04)).abs() < 1e-3, "swing apex {apex} m");
}

#[test]
fn walking_backward_runs_the_foot_path_backward() {
    let forward = foot_path(Direction::Forward);
    let backward = foot_path(Direction::Backward);
    // Backward at tick k is forward at tick −k (mod one cycle).
    for (k, point) in backward.iter().enumerate() {
        let mirror = forward[(250 - k) % 250];
        assert!((point.0 - mirror.0).abs() < 1e-3 && (point.1 - mirror.1).abs() < 1e-3);
    }
    // And the stance (foot on the ground) now moves the foot forward: the body goes back.
    let on_ground: Vec<_> = backward
        .iter()
        .filter(|p| (p.1 + 0.35).abs() < 1e-4)
        .collect();
    assert!(on_ground.len() > 100);
    assert!(on_ground.windows(2).filter(|w| w[1].0 > w[0].0).count() > 100);
}

#[test]
fn the_reports_sinusoids_are_reproduced() {
    let mut trot = Trot::new(TrotParams::REPORT, TickRate::SIM_250_HZ).unwrap();
    // A quarter cycle in: sin = 1 for the leading pair.
    for _ in 0..(250 / 4) {
        trot.advance();
    }
    let [fl, fr, ..] = targets(&trot, Direction::Forward, 0.35);
    let expect = |joints: LegJoints, s: f32| {
        let report = SineGait::REPORT;
        assert!((joints.hip_pitch_rad - report.hip_amplitude_rad * s).abs() < 1e-4);
        assert!(
            (joints.knee_rad - (report.knee_base_rad + report.knee_amplitude_rad * s)).abs() < 1e-4
        );
        assert!((joints.ankle_rad - report.ankle_amplitude_rad * s).abs() < 1e-4);
        assert_eq!(joints.hip_abduction_rad, 0.0);
    };
    expect(fl, 1.0);
    expect(fr, -1.0);
}

#[test]
fn every_gait_pose_solves_across_the_body_height_band_and_speed_scales() {
    let posture = CONFIG.posture;
    let Generator::Cartesian(_) = TrotParams::DEFAULT.generator else {
        panic!("the default gait is the Cartesian one");
    };
    for height_step in 0..=20 {
        let offset = -0.10 + 0.22 * height_step as f32 / 20.0; // the whole wire range
        let depth = posture.depth_for(offset);
        assert!(depth >= posture.depth_min_m && depth <= posture.depth_max_m);
        posture
            .stance(&CONFIG.geometry, &CONFIG.limits, depth)
            .unwrap_or_else(|e| panic!("stance at {depth} m: {e:?}"));
        let depth = posture.trot_depth_for(offset);
        // Level, and rolled past the body levelling's limit either way (every stance line at
        // its deepest or shallowest).
        let rolls = [0.0, 1.0, -1.0].map(|roll_rad| Attitude {
            pitch_rad: 0.0,
            roll_rad,
        });
        for (scale, attitude) in [0.0, 0.5, 1.0]
            .into_iter()
            .flat_map(|scale| rolls.map(|attitude| (scale, attitude)))
        {
            let mut trot = Trot::new(TrotParams::DEFAULT, TickRate::SIM_250_HZ).unwrap();
            for tick in 0..250 {
                for (leg, result) in Leg::ALL.iter().zip(trot.targets(
                    Direction::Forward,
                    depth,
                    &firmware::legs::gait::TrotCommand::straight(scale),
                    &attitude,
                    &CONFIG.geometry,
                    &CONFIG.limits,
                    &posture,
                )) {
                    if let Err(e) = result {
                        panic!("{leg:?} at depth {depth} m, scale {scale}, tick {tick}: {e:?}");
                    }
                }
                trot.advance();
            }
        }
    }
}

/// The blocked-swing watch measures a leading foot at 70 % of its swing, so the swing's share
/// must run from lift-off to touchdown whichever way the robot walks (walking backward the
/// phase runs backward, and the share once ran from touchdown to lift-off).
#[test]
fn a_swing_is_counted_from_lift_off_in_both_directions() {
    for direction in [Direction::Forward, Direction::Backward] {
        let mut trot = Trot::new(TrotParams::DEFAULT, TickRate::SIM_250_HZ).unwrap();
        let (mut last, mut rises, mut falls, mut first) = (None, 0, 0, None);
        for _ in 0..2 * 250 {
            let share = trot.swing_share(Leg::Bl, direction);
            match (last, share) {
                (Some(a), Some(b)) if b > a => rises += 1,
                (Some(_), Some(_)) => falls += 1,
                (None, Some(b)) => {
                    first.get_or_insert(b);
                }
                _ => {}
            }
            last = share;
            trot.advance();
        }
        assert!(
            rises > 150 && falls == 0,
            "{direction:?}: {rises} up, {falls} down"
        );
        assert!(
            first.is_some_and(|f: f32| f < 0.05),
            "{direction:?}: starts at {first:?}"
        );
    }
}

/// A yaw rate strides each foot along its hip's path: turning left, the right feet stride
/// longer than the left, the front feet stride to the right and the back feet to the left
/// (seen from the body: the body turns left over them). Walking backward the same turn
/// reverses every stride's sense with the phase. No stride exceeds the full one, and shrinking
/// them keeps their proportions (the turn's radius).
#[test]
fn a_turning_trot_strides_each_foot_along_its_hips_path() {
    use firmware::legs::gait::TrotCommand;
    let trot = Trot::new(TrotParams::DEFAULT, TickRate::SIM_250_HZ).unwrap();
    let full_m_s = trot.full_speed_m_s().unwrap();
    assert!((full_m_s - 0.08 / 0.55).abs() < 1e-5, "{full_m_s}");
    let straight = trot.strides(Direction::Forward, &TrotCommand::straight(0.5));
    assert!(straight.iter().all(|s| s.along == 0.5 && s.across == 0.0));
    let left = TrotCommand {
        stride_share: 0.5,
        yaw_rate_rad_s: 0.2,
    };
    let [fl, fr, bl, br] = trot.strides(Direction::Forward, &left);
    // ω·y / v_full = 0.2 · 0.15 / 0.1455 ≈ 0.206; ω·x / v_full ≈ 0.302.
    assert!((fr.along - 0.706).abs() < 0.002 && (fl.along - 0.294).abs() < 0.002);
    assert_eq!((bl.along, br.along), (fl.along, fr.along));
    assert!((fl.across - 0.302).abs() < 0.002 && fl.across == fr.across);
    assert!(bl.across == -fl.across && br.across == bl.across);
    let [bfl, _, _, bbr] = trot.strides(Direction::Backward, &left);
    assert!((bfl.along - 0.706).abs() < 0.002 && (bbr.along - 0.294).abs() < 0.002);
    assert!(bfl.across == -fl.across);
    let fast = TrotCommand {
        stride_share: 1.0,
        yaw_rate_rad_s: 0.4,
    };
    let strides = trot.strides(Direction::Forward, &fast);
    let longest = strides
        .iter()
        .map(|s| s.along.hypot(s.across))
        .fold(0.0_f32, f32::max);
    assert!((longest - 1.0).abs() < 1e-5, "{longest}");
    let [sfl, sfr, ..] = strides;
    // Unshrunk: 1 − 0.412 and 1 + 0.412; the ratio holds after shrinking.
    assert!((sfl.along / sfr.along - 0.588 / 1.412).abs() < 1e-3);
    // Every turning pose solves: both ways, across the trot's depths, rolled as far as the
    // body levelling reaches, at full stride and turning on the spot.
    let on_the_spot = TrotCommand {
        stride_share: 0.0,
        yaw_rate_rad_s: -0.4,
    };
    let posture = &CONFIG.posture;
    for command in [fast, on_the_spot] {
        for direction in [Direction::Forward, Direction::Backward] {
            for depth_m in [
                posture.trot_depth_min_m,
                posture.depth_nominal_m,
                posture.depth_max_m,
            ] {
                for roll_rad in [-0.3, 0.0, 0.3] {
                    let attitude = Attitude {
                        roll_rad,
                        ..Attitude::default()
                    };
                    let mut turning = trot;
                    for _ in 0..250 {
                        for result in turning.targets(
                            direction,
                            depth_m,
                            &command,
                            &attitude,
                            &CONFIG.geometry,
                            &CONFIG.limits,
                            posture,
                        ) {
                            assert!(
                                result.is_ok(),
                                "{command:?} {direction:?} {depth_m} {roll_rad}: {result:?}"
                            );
                        }
                        turning.advance();
                    }
                }
            }
        }
    }
}

/// The feet stride when the trot travels or turns on the spot, and stay down marking time.
#[test]
fn a_trot_lifts_its_feet_when_it_travels_or_turns() {
    use firmware::legs::gait::TrotCommand;
    let still = TrotCommand::straight(0.0);
    assert!(!still.advances() && !still.lifts_feet());
    let walking = TrotCommand::straight(0.5);
    assert!(walking.advances() && walking.lifts_feet());
    let turning = TrotCommand {
        yaw_rate_rad_s: 0.3,
        ..still
    };
    assert!(!turning.advances() && turning.lifts_feet());
    let broken = TrotCommand {
        yaw_rate_rad_s: f32::NAN,
        ..still
    };
    assert!(!broken.lifts_feet());
}
