//! Runs on every core: a pool of worker threads, each taking the next run off a shared counter
//! (long and short runs balance themselves), each run its own MuJoCo instance. Results come
//! back in the order of the runs given, whatever the number of workers or which finished
//! first: the pool changes how fast, never what.

use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

use crate::campaign::scenario::Scenario;
use crate::campaign::{run_one, Drives, RunResult};

/// The workers' count when none is asked for: one per core.
pub fn default_jobs() -> usize {
    std::thread::available_parallelism().map_or(1, usize::from)
}

/// Runs `work` on each of `items` on `jobs` workers (at least one); a progress bar on stderr
/// when `progress` (indicatif hides it where stderr is no terminal), counting the results
/// `failed` says failed. Returns the results in the order of `items` and the wall time taken.
pub fn run_all<J, R>(
    items: &[J],
    jobs: usize,
    progress: bool,
    work: impl Fn(&J) -> R + Sync,
    failed: impl Fn(&R) -> bool + Sync,
) -> (Vec<R>, Duration)
where
    J: Sync,
    R: Send,
{
    let bar = progress_bar(items.len(), progress);
    let next = AtomicUsize::new(0);
    let failures = AtomicUsize::new(0);
    let done: Mutex<Vec<(usize, R)>> = Mutex::new(Vec::with_capacity(items.len()));
    let started = Instant::now();
    std::thread::scope(|scope| {
        for _ in 0..jobs.clamp(1, items.len().max(1)) {
            scope.spawn(|| loop {
                let index = next.fetch_add(1, Ordering::Relaxed);
                let Some(item) = items.get(index) else {
                    break;
                };
                let result = work(item);
                if failed(&result) {
                    let n = failures.fetch_add(1, Ordering::Relaxed) + 1;
                    bar.set_message(format!("{n} failed"));
                }
                done.lock()
                    .unwrap_or_else(|poisoned| poisoned.into_inner())
                    .push((index, result));
                bar.inc(1);
            });
        }
    });
    let elapsed = started.elapsed();
    bar.finish_and_clear();
    let mut done = done.into_inner().unwrap_or_else(|p| p.into_inner());
    done.sort_by_key(|(i, _)| *i);
    (done.into_iter().map(|(_, r)| r).collect(), elapsed)
}

fn progress_bar(len: usize, progress: bool) -> ProgressBar {
    let bar = if progress {
        ProgressBar::new(len as u64)
    } else {
        ProgressBar::hidden()
    };
    if let Ok(style) = ProgressStyle::with_template(
        "{elapsed_precise} [{bar:40}] {pos}/{len} runs ({per_sec}, {eta} left) {msg}",
    ) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}

/// The campaign's runs (seed, scenario) of a plant drawn around `drives`, on `jobs` workers.
pub fn run_campaign(
    model: &Path,
    drives: Drives,
    runs: &[(u64, Scenario)],
    jobs: usize,
    progress: bool,
) -> (Vec<RunResult>, Duration) {
    run_all(
        runs,
        jobs,
        progress,
        |&(seed, scenario)| run_one(model, drives, seed, scenario),
        |r| !r.verdict.outcome.success(),
    )
}

/// The pool's speed-up on this machine: `runs` with 1 worker, then with 2, in one process.
#[derive(Debug, Clone, PartialEq)]
pub struct Scaling {
    /// Runs measured (each count ran them all).
    pub runs: usize,
    /// Runs per second with one worker.
    pub one_per_s: f64,
    /// Runs per second with two workers.
    pub two_per_s: f64,
    /// Whether both gave the same results (they must).
    pub same_results: bool,
    /// CPU seconds this process got per wall second with one worker and with two (Linux;
    /// `None` elsewhere): below 2 with two workers, other processes had the cores.
    pub cpu_per_wall: Option<[f64; 2]>,
}

impl Scaling {
    /// Two workers' rate over one's.
    pub fn ratio(&self) -> f64 {
        self.two_per_s / self.one_per_s
    }
}

/// Measures [`Scaling`] on `runs`.
pub fn scaling(model: &Path, drives: Drives, runs: &[(u64, Scenario)]) -> Scaling {
    let c0 = cpu_seconds();
    let (one, t1) = run_campaign(model, drives, runs, 1, false);
    let c1 = cpu_seconds();
    let (two, t2) = run_campaign(model, drives, runs, 2, false);
    let c2 = cpu_seconds();
    let rate = |t: Duration| runs.len() as f64 / t.as_secs_f64().max(1e-9);
    let per_wall = |a: Option<f64>, b: Option<f64>, t: Duration| Some((b? - a?) / t.as_secs_f64());
    Scaling {
        runs: runs.len(),
        one_per_s: rate(t1),
        two_per_s: rate(t2),
        same_results: one == two,
        cpu_per_wall: per_wall(c0, c1, t1)
            .zip(per_wall(c1, c2, t2))
            .map(|(a, b)| [a, b]),
    }
}

/// CPU time (user and system) this process has used, s, from `/proc/self/stat` (fields 14
/// and 15, in the kernel's 100 Hz user ticks); `None` where there is no such file.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // The command name (field 2) is in parentheses and may hold spaces: count after it.
    let rest = stat.rsplit_once(')')?.1;
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| fields.get(i)?.parse::<f64>().ok();
    Some((ticks(11)? + ticks(12)?) / 100.0)
}
