//! `cargo xtask soak [--minutes N]`: a long in-process run of `sim-host` (firmware on the
//! in-process bus, lockstep, every output on) with the robot turning in place on its wheels,
//! its resident memory sampled from `/proc` as it goes. The contract: growth between simulated
//! minute 5 and the end ≤ 5 MB (a log kept in memory, a queue that never drains, would show
//! here). Default 24 simulated hours; `cargo xtask test` runs 10 minutes.
//!
//! The logs stream to `/dev/null` (the run's bus.log and telemetry.csv are symlinks to it): the
//! writers do all their work, a day's logs (some 20 GB) do not fill the disk. Simulated time
//! is placed against the samples' wall time by the run's total (lockstep in-process runs at a
//! steady rate once started).

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::util::{cargo, root, run as sh};

/// Growth allowed between simulated minute [`FROM_MIN`] and the end, bytes.
const MAX_GROWTH_BYTES: u64 = 5 << 20;
/// Where the growth is measured from, simulated minutes.
const FROM_MIN: f64 = 5.0;
const SAMPLE_EVERY: Duration = Duration::from_millis(100);

pub fn run(args: &[String]) -> Result<(), String> {
    let minutes = minutes(args)?;
    crate::setup::run()?;
    sh(cargo().args(["build", "--release", "-p", "sim-host"]))?;
    let out = root().join("target").join("soak");
    let _ = std::fs::remove_dir_all(&out);
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    for log in ["bus.log", "telemetry.csv"] {
        std::os::unix::fs::symlink("/dev/null", out.join(log))
            .map_err(|e| format!("{}: {e}", out.join(log).display()))?;
    }
    let samples = sample_run(&out, minutes)?;
    judge(&samples, minutes)
}

fn minutes(args: &[String]) -> Result<f64, String> {
    match args {
        [] => Ok(24.0 * 60.0),
        [flag, value] if flag == "--minutes" => value
            .parse::<f64>()
            .ok()
            .filter(|m| (2.0 * FROM_MIN..=1e5).contains(m))
            .ok_or_else(|| format!("--minutes {value}: give simulated minutes, 10…100000")),
        _ => Err("usage: cargo xtask soak [--minutes N] (simulated minutes, default 1440)".into()),
    }
}

/// Runs sim-host and samples its resident size: `(wall time since start, bytes)`.
fn sample_run(out: &Path, minutes: f64) -> Result<Vec<(Duration, u64)>, String> {
    let binary = root().join("target/release/sim-host");
    let duration_s = format!("{}", minutes * 60.0);
    let mut child = Command::new(&binary)
        .args(["run", "--bus", "inproc", "--no-plots", "--no-progress"])
        .args([
            "--duration-s",
            &duration_s,
            "--drive",
            "0:X",
            "--drive",
            "0.5:A",
        ])
        .arg("--out")
        .arg(out)
        .stdout(Stdio::null())
        .spawn()
        .map_err(|e| format!("cannot start {}: {e}", binary.display()))?;
    let status_file = format!("/proc/{}/status", child.id());
    let started = Instant::now();
    let mut samples = Vec::new();
    let mut reported = Instant::now();
    loop {
        if let Some(status) = child.try_wait().map_err(|e| e.to_string())? {
            if !status.success() {
                return Err(format!(
                    "sim-host failed ({status}); its logs: {}",
                    out.display()
                ));
            }
            break;
        }
        if let Some(rss) = std::fs::read_to_string(&status_file)
            .ok()
            .as_deref()
            .and_then(resident_bytes)
        {
            samples.push((started.elapsed(), rss));
            if reported.elapsed() >= Duration::from_secs(30) {
                eprintln!(
                    "soak: {:.0} s wall, resident {:.1} MB",
                    started.elapsed().as_secs_f64(),
                    rss as f64 / 1048576.0
                );
                reported = Instant::now();
            }
        }
        std::thread::sleep(SAMPLE_EVERY);
    }
    Ok(samples)
}

/// `VmRSS` of a `/proc/PID/status` text, bytes.
fn resident_bytes(status: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with("VmRSS:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

fn judge(samples: &[(Duration, u64)], minutes: f64) -> Result<(), String> {
    let total = samples
        .last()
        .map(|s| s.0)
        .ok_or("no sample of sim-host's memory")?;
    let from = total.mul_f64(FROM_MIN / minutes);
    let at_from = samples
        .iter()
        .find(|s| s.0 >= from)
        .map(|s| s.1)
        .ok_or("no sample after minute 5")?;
    let peak_after = samples
        .iter()
        .filter(|s| s.0 >= from)
        .map(|s| s.1)
        .max()
        .unwrap_or(at_from);
    let end = samples.last().map_or(at_from, |s| s.1);
    let growth = peak_after.saturating_sub(at_from);
    let mb = |b: u64| b as f64 / 1048576.0;
    println!(
        "MEASURED soak: {minutes} simulated minutes in {:.0} s; resident {:.1} MB at minute {FROM_MIN}, \
         {:.1} MB at the end, peak after minute {FROM_MIN} {:.1} MB: growth {:.2} MB (limit 5 MB); \
         {} samples",
        total.as_secs_f64(),
        mb(at_from),
        mb(end),
        mb(peak_after),
        mb(growth),
        samples.len()
    );
    if growth > MAX_GROWTH_BYTES {
        return Err(format!(
            "resident memory grew {:.2} MB after minute {FROM_MIN} (limit 5 MB)",
            mb(growth)
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_resident_size() {
        let status = "Name:\tsim-host\nVmPeak:\t  9000 kB\nVmRSS:\t   2048 kB\n";
        assert_eq!(resident_bytes(status), Some(2048 * 1024));
        assert_eq!(resident_bytes("Name: x\n"), None);
    }

    #[test]
    fn growth_after_minute_five_fails_the_soak() {
        let samples: Vec<(Duration, u64)> = (0..100)
            .map(|i| (Duration::from_secs(i), 50_000_000 + i * 200_000))
            .collect();
        assert!(judge(&samples, 10.0).is_err());
        let flat: Vec<(Duration, u64)> = (0..100)
            .map(|i| (Duration::from_secs(i), 50_000_000 + (i % 3) * 1000))
            .collect();
        assert!(judge(&flat, 10.0).is_ok());
    }
}
