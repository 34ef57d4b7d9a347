//! The chip model against its data sheet: noise density measured back from its output,
//! turn-on spread, latency, range and resolution.

use super::*;

/// The chip's own output stream (every ODR sample) of one sensor at rest, `seconds` long.
fn register_stream(spec: SensorSpec, seed: u64, seconds: f64) -> Vec<[f64; 3]> {
    let mut rng = SmallRng::seed_from_u64(seed);
    let mut channel = Channel::new(spec, &mut rng);
    channel.start(0.0, [0.0; 3]);
    let n = (seconds * spec.odr_hz) as usize;
    (0..n)
        .map(|_| {
            let filtered = channel.sample(&mut rng, [0.0; 3]);
            channel.quantised(filtered)
        })
        .collect()
}

/// Noise density per axis from the Allan deviation at `tau_s` (white noise of one-sided
/// density n has σ_A(τ)² = n² / 2τ).
fn allan_density(samples: &[[f64; 3]], odr_hz: f64, tau_s: f64) -> [f64; 3] {
    let m = (tau_s * odr_hz).round() as usize;
    std::array::from_fn(|axis| {
        let means: Vec<f64> = samples
            .chunks_exact(m)
            .map(|block| block.iter().map(|s| s[axis]).sum::<f64>() / m as f64)
            .collect();
        let avar = means.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum::<f64>()
            / (2.0 * (means.len() - 1) as f64);
        (avar * 2.0 * tau_s).sqrt()
    })
}

/// The measured density is within ±20 % of the data sheet's, on every axis of both sensors
/// (300 s at the ODR; τ = 0.25 s, where white noise dominates the walk by five orders).
#[test]
fn the_noise_density_measured_back_matches_the_data_sheet() {
    for (name, spec) in [
        ("gyro", ChipSpec::BMI088.gyro),
        ("accel", ChipSpec::BMI088.accel),
    ] {
        let samples = register_stream(spec, 11, 300.0);
        let measured = allan_density(&samples, spec.odr_hz, 0.25);
        for (axis, (got, sheet)) in measured.iter().zip(spec.noise_density).enumerate() {
            let ratio = got / sheet;
            println!("{name} axis {axis}: {got:.3e} measured, ratio {ratio:.3}");
            assert!(
                (0.8..=1.2).contains(&ratio),
                "{name} axis {axis}: ratio {ratio:.3}"
            );
        }
    }
}

/// The turn-on offsets repeat for a seed, differ between seeds, and spread as the data sheet's
/// 1σ (±20 % over 300 chips).
#[test]
fn turn_on_offsets_follow_the_seed_and_the_data_sheet_spread() {
    let spec = ChipSpec::BMI088;
    assert_eq!(ImuChip::new(spec, 5).bias(), ImuChip::new(spec, 5).bias());
    assert_ne!(ImuChip::new(spec, 5).bias(), ImuChip::new(spec, 6).bias());
    let (mut gyro, mut accel) = (Vec::new(), Vec::new());
    for seed in 0..300 {
        let (g, a) = ImuChip::new(spec, seed).bias();
        gyro.extend(g);
        accel.extend(a);
    }
    let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
    for (what, values, sigma) in [
        ("gyro", &gyro, spec.gyro.offset_sigma),
        ("accel", &accel, spec.accel.offset_sigma),
    ] {
        let ratio = rms(values) / sigma;
        assert!((0.8..=1.2).contains(&ratio), "{what}: {ratio:.3}");
    }
}

/// A step of the true rate reaches half its height after the filter's group delay plus at most
/// one ODR period: between 0.5 and 2 ms.
#[test]
fn a_step_arrives_after_the_filters_group_delay() {
    let mut spec = ChipSpec::BMI088;
    for sensor in [&mut spec.gyro, &mut spec.accel] {
        sensor.noise_density = [0.0; 3];
        sensor.offset_sigma = 0.0;
        sensor.drift_per_sqrt_s = 0.0;
    }
    let mut chip = ImuChip::new(spec, 1);
    let dt = 1e-4;
    chip.read(0.0, [0.0; 3], [0.0; 3]);
    let mut t = 0.0;
    let mut crossed = None;
    while t < 0.01 {
        t += dt;
        let (rate, _) = chip.read(0.001 + t, [1.0; 3], [0.0; 3]);
        if crossed.is_none() && rate[0] >= 0.5 {
            crossed = Some(t);
        }
    }
    let delay = crossed.unwrap();
    println!("half-height after {:.2} ms", delay * 1e3);
    assert!((0.0005..=0.002).contains(&delay), "{delay}");
    assert!((spec.gyro.group_delay_s() - 0.98e-3).abs() < 0.01e-3);
}

/// Beyond the range the output saturates at full scale; within it, it is a whole number of
/// LSBs.
#[test]
fn the_output_is_clamped_to_the_range_and_rounded_to_the_lsb() {
    let mut spec = ChipSpec::BMI088;
    spec.gyro.noise_density = [0.0; 3];
    spec.gyro.offset_sigma = 0.0;
    spec.gyro.drift_per_sqrt_s = 0.0;
    let mut chip = ImuChip::new(spec, 1);
    let (rate, force) = chip.read(0.0, [30.0, -30.0, 0.123_456], [0.0, 0.0, G]);
    assert_eq!(rate[0], spec.gyro.full_scale);
    assert_eq!(rate[1], -spec.gyro.full_scale);
    assert!((rate[0] - 17.45).abs() < 0.01);
    let counts = rate[2] / spec.gyro.lsb;
    assert!((counts - counts.round()).abs() < 1e-9);
    assert!((rate[2] - 0.123_456).abs() <= 0.5 * spec.gyro.lsb);
    assert!((force[2] - G).abs() < 4.0 * spec.accel.offset_sigma);
}
