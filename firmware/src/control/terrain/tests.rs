//! The terrain watch on synthetic ground: level, a riser, a flight, an edge and a 10° slope,
//! ranged as the rangefinder would from a robot backing over it.

#![allow(
    clippy::indexing_slicing,
    clippy::panic,
    clippy::default_numeric_fallback
)]

extern crate std;

use std::vec::Vec;

use super::*;

const CONFIG: TerrainConfig = TerrainConfig::ROBOT;

/// Ground height at `along_m` behind the start: flat up to `start_m`, then `kind`.
#[derive(Clone, Copy)]
enum Ground {
    Flat,
    Riser {
        at_m: f32,
        height_m: f32,
    },
    Slope {
        at_m: f32,
        grade: f32,
    },
    Stairs {
        at_m: f32,
        rise_m: f32,
        tread_m: f32,
    },
}

impl Ground {
    fn height_m(self, along_m: f32) -> f32 {
        match self {
            Ground::Flat => 0.0,
            Ground::Riser { at_m, height_m } => {
                if along_m >= at_m {
                    height_m
                } else {
                    0.0
                }
            }
            Ground::Slope { at_m, grade } => (along_m - at_m).max(0.0) * grade,
            Ground::Stairs {
                at_m,
                rise_m,
                tread_m,
            } => {
                let steps = ((along_m - at_m) / tread_m).floor() + 1.0;
                steps.clamp(0.0, 2.0) * rise_m
            }
        }
    }
}

/// What the beam measures with the robot `backed_m` back on level ground, pitched `pitch_rad`:
/// marched along the beam in millimetres until it is under the ground.
fn distance_m(ground: Ground, backed_m: f32, pitch_rad: f32) -> Option<f32> {
    (1..1300).map(|mm| mm as f32 * 1e-3).find(|&d| {
        let (height_m, behind_m) = TerrainWatch::spot_m(&CONFIG, d, pitch_rad);
        height_m <= ground.height_m(backed_m + behind_m)
    })
}

/// [`back_over_leaning`] with the robot's balance point level.
fn back_over(
    ground: Ground,
    run_m: f32,
    wobble_rad: f32,
    pitch_error_rad: f32,
    noise_m: f32,
) -> Vec<(f32, Feature)> {
    back_over_leaning(ground, run_m, 0.0, wobble_rad, pitch_error_rad, noise_m)
}

/// Backs the robot over `ground` at 0.4 m/s for `run_m`, rangings every 20 ms, the true pitch
/// `lean_rad` and wobbling by `wobble_rad` at 1.5 Hz about it, read `pitch_error_rad` off, the
/// distance `noise_m` off in a fixed pattern; the features the watch decides, with where the
/// robot was.
fn back_over_leaning(
    ground: Ground,
    run_m: f32,
    lean_rad: f32,
    wobble_rad: f32,
    pitch_error_rad: f32,
    noise_m: f32,
) -> Vec<(f32, Feature)> {
    let mut watch = TerrainWatch::default();
    let mut found = Vec::new();
    let steps = (run_m / (0.4 * 0.02)) as usize;
    for k in 0..steps {
        let t_s = k as f32 * 0.02;
        let backed_m = 0.4 * t_s;
        let pitch_rad =
            lean_rad + wobble_rad * crate::math::sin(2.0 * core::f32::consts::PI * 1.5 * t_s);
        let sign = if k % 3 == 0 { -1.0 } else { 0.5 };
        // The part averages its returns over the ranging's 20 ms: five cycles.
        let cycles: Vec<f32> = (0..5)
            .filter_map(|c| distance_m(ground, backed_m - 0.4 * 0.004 * c as f32, pitch_rad))
            .collect();
        let mean_m = (cycles.len() == 5).then(|| cycles.iter().sum::<f32>() / 5.0);
        let ranging = Ranging {
            distance_m: mean_m.map(|d| d + sign * noise_m),
            pitch_rad: pitch_rad + pitch_error_rad,
            backed_m,
        };
        if let Some(feature) = watch.update(&CONFIG, &ranging) {
            found.push((backed_m, feature));
        }
    }
    found
}

const DEG: f32 = core::f32::consts::PI / 180.0;

#[test]
fn level_ground_shows_nothing_under_pitch_wobble_offset_and_noise() {
    assert!(back_over(Ground::Flat, 4.0, 3.0 * DEG, 1.5 * DEG, 0.005).is_empty());
}

#[test]
fn a_riser_is_a_step_seen_before_the_wheels_reach_it() {
    for height_m in [0.05, 0.06, 0.08, 0.10] {
        let ground = Ground::Riser {
            at_m: 1.5,
            height_m,
        };
        let found = back_over(ground, 2.0, 2.0 * DEG, 1.0 * DEG, 0.005);
        let Some(&(backed_m, _)) = found.first() else {
            panic!("{height_m} m: nothing seen");
        };
        assert!(
            backed_m < 1.5 - 0.5,
            "seen {:.2} m before the riser",
            1.5 - backed_m
        );
        // Decided anew on the face or the plateau, it is a step each time.
        assert!(
            found
                .iter()
                .all(|(_, f)| matches!(f, Feature::Step { rise_m } if *rise_m > 0.0)),
            "{height_m} m: {found:?}"
        );
    }
}

#[test]
fn a_flight_of_two_risers_is_two_steps() {
    for rise_m in [0.05, 0.06, 0.07] {
        let ground = Ground::Stairs {
            at_m: 1.5,
            rise_m,
            tread_m: 0.6,
        };
        let found = back_over(ground, 2.0, 2.0 * DEG, 1.0 * DEG, 0.005);
        assert!(found.len() >= 2, "{rise_m} m: {found:?}");
        assert!(
            found
                .iter()
                .all(|(_, f)| matches!(f, Feature::Step { rise_m } if *rise_m > 0.0)),
            "{rise_m} m: {found:?}"
        );
    }
}

#[test]
fn an_edge_is_a_step_down() {
    let ground = Ground::Riser {
        at_m: 1.5,
        height_m: -0.06,
    };
    let found = back_over(ground, 2.0, 2.0 * DEG, 0.0, 0.005);
    assert!(!found.is_empty());
    assert!(
        found
            .iter()
            .all(|(_, f)| matches!(f, Feature::Step { rise_m } if *rise_m < 0.0)),
        "{found:?}"
    );
}

#[test]
fn a_ten_degree_ramp_is_a_slope_seen_before_the_wheels_reach_it() {
    let grade = crate::math::sin(10.0 * DEG) / crate::math::cos(10.0 * DEG);
    for (grade, up) in [(grade, true), (-grade, false)] {
        let ground = Ground::Slope { at_m: 1.5, grade };
        let found = back_over(ground, 1.4, 2.0 * DEG, 1.0 * DEG, 0.005);
        let Some(&(backed_m, _)) = found.first() else {
            panic!("grade {grade}: nothing seen");
        };
        assert!(
            backed_m < 1.5 - 0.4,
            "seen {:.2} m before the foot",
            1.5 - backed_m
        );
        // Decided anew further along the slope, it is the same slope each time.
        assert!(
            found
                .iter()
                .all(|(_, f)| matches!(f, Feature::Slope { rise_m } if (*rise_m > 0.0) == up)),
            "grade {grade}: {found:?}"
        );
    }
}

#[test]
fn nonsense_changes_nothing_and_no_return_forgets_the_level() {
    let mut watch = TerrainWatch::default();
    let ranging = |distance_m| Ranging {
        distance_m,
        pitch_rad: 0.0,
        backed_m: 0.0,
    };
    for _ in 0..10 {
        assert_eq!(watch.update(&CONFIG, &ranging(Some(0.5))), None);
    }
    let learned = watch;
    assert_ne!(learned, TerrainWatch::default(), "no level learned");
    for distance_m in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        assert_eq!(watch.update(&CONFIG, &ranging(Some(distance_m))), None);
        assert_eq!(watch, learned, "{distance_m} changed the watch");
    }
    assert_eq!(watch.update(&CONFIG, &ranging(None)), None);
    assert_eq!(watch, TerrainWatch::default());
}

#[test]
fn the_ground_back_in_range_after_no_return_is_a_new_level() {
    let mut watch = TerrainWatch::default();
    let ranging = |distance_m, backed_m| Ranging {
        distance_m,
        pitch_rad: 0.0,
        backed_m,
    };
    // Level ground, then the beam loses it, then meets ground 10 cm higher.
    for k in 0..10 {
        assert_eq!(
            watch.update(&CONFIG, &ranging(Some(0.5), 0.01 * k as f32)),
            None
        );
    }
    assert_eq!(watch.update(&CONFIG, &ranging(None, 0.1)), None);
    for k in 0..10 {
        let backed_m = 0.11 + 0.01 * k as f32;
        assert_eq!(watch.update(&CONFIG, &ranging(Some(0.3), backed_m)), None);
    }
}

#[test]
fn pitched_nose_down_or_up_an_edge_is_still_a_step_and_a_ramp_a_slope() {
    // A robot whose balance point leans it 6° either way: the beam meets the ground 6° less
    // (or more) steeply, and so does the spot's jump off an edge.
    for pitch_rad in [10.0 * DEG, 6.0 * DEG, -6.0 * DEG, -10.0 * DEG] {
        let edge = Ground::Riser {
            at_m: 1.5,
            height_m: -0.06,
        };
        let found = back_over_leaning(edge, 2.0, pitch_rad, 1.0 * DEG, 0.0, 0.005);
        assert!(!found.is_empty(), "pitch {pitch_rad}: edge not seen");
        assert!(
            found
                .iter()
                .all(|(_, f)| matches!(f, Feature::Step { rise_m } if *rise_m < 0.0)),
            "pitch {pitch_rad}: {found:?}"
        );
        let grade = crate::math::sin(10.0 * DEG) / crate::math::cos(10.0 * DEG);
        let ramp = Ground::Slope { at_m: 1.5, grade };
        let found = back_over_leaning(ramp, 1.4, pitch_rad, 1.0 * DEG, 0.0, 0.005);
        assert!(!found.is_empty(), "pitch {pitch_rad}: ramp not seen");
        assert!(
            found
                .iter()
                .all(|(_, f)| matches!(f, Feature::Slope { rise_m } if *rise_m > 0.0)),
            "pitch {pitch_rad}: {found:?}"
        );
    }
}

#[test]
fn looking_back_too_shallow_to_tell_a_ramp_from_a_riser_decides_nothing() {
    // Leaning 14° nose down, the beam meets the ground 11° down: a 10° ramp's grade is within
    // a tenth of the beam's, as an edge's would be.
    let grade = crate::math::sin(10.0 * DEG) / crate::math::cos(10.0 * DEG);
    let ramp = Ground::Slope { at_m: 1.5, grade };
    let found = back_over_leaning(ramp, 1.4, 14.0 * DEG, 0.5 * DEG, 0.0, 0.005);
    assert!(found.is_empty(), "{found:?}");
}

#[test]
fn looking_back_shallow_a_riser_is_still_a_step() {
    // The beam 12–13° down: a riser's face rises with the spot standing still, far faster
    // than any slope or edge changes the height.
    for lean_deg in [12.0, 13.0] {
        let riser = Ground::Riser {
            at_m: 1.5,
            height_m: 0.10,
        };
        let found = back_over_leaning(riser, 2.0, lean_deg * DEG, 0.5 * DEG, 0.0, 0.005);
        assert!(
            matches!(found.first(), Some((_, Feature::Step { rise_m })) if *rise_m > 0.0),
            "{lean_deg}°: {found:?}"
        );
    }
}
