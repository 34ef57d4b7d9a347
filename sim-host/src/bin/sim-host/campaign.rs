//! `sim-host campaign`: its flags, and what each form prints. The Markdown table goes to
//! stdout (for `cargo xtask campaign` to put into docs/campaign.md), everything else to stderr
//! through `tracing`.

use std::path::PathBuf;

use sim_host::campaign::draw::{parameters, Draws};
use sim_host::campaign::pool::{self, default_jobs};
use sim_host::campaign::results::{self, Campaign, Results, Shard};
use sim_host::campaign::scenario::Scenario;
use sim_host::campaign::{judge, sweep, table, CampaignError, Drives};
use sim_host::robot::model::DEFAULT_MODEL;

use crate::run::DrivesArg;

#[derive(Debug, clap::Args)]
pub(crate) struct CampaignArgs {
    /// Trials, seeds 0…N−1; each trial's plant runs every scenario.
    #[arg(long, default_value_t = 500)]
    pub(crate) trials: u64,
    /// Worker threads, each running one MuJoCo instance at a time (default: one per core).
    #[arg(long)]
    pub(crate) jobs: Option<usize>,
    /// Only this scenario (repeat for several): W S A L K fold X-from-W X-from-L estop-W
    /// stand-up.
    #[arg(long = "scenario", value_name = "NAME")]
    pub(crate) scenarios: Vec<Scenario>,
    /// Rerun one trial alone and print its plant and every figure (with --scenario: only that
    /// scenario), instead of a campaign.
    #[arg(long, conflicts_with_all = ["shard", "merge", "scaling"])]
    pub(crate) seed: Option<u64>,
    /// Run only every N-th trial from I (`I/N`), for N machines sharing a campaign; writes
    /// the partial results to --results for `--merge`.
    #[arg(long, value_name = "I/N")]
    pub(crate) shard: Option<Shard>,
    /// Join shards' results files into the results of the whole campaign (runs nothing).
    #[arg(long, num_args = 1.., value_name = "FILE", conflicts_with_all = ["shard", "scaling"])]
    pub(crate) merge: Vec<PathBuf>,
    /// Measure the pool: the first N runs with one worker, then with two, in this process;
    /// prints runs per second and the ratio (runs no campaign).
    #[arg(long, value_name = "N")]
    pub(crate) scaling: Option<usize>,
    /// One parameter at a time instead: the robot as modelled, then each parameter alone at
    /// each end of its range, through the scenarios; prints a table of the verdicts.
    #[arg(long, conflicts_with_all = ["seed", "shard", "merge", "scaling"])]
    pub(crate) sweep: bool,
    /// The drives whose torque ratings are drawn down to −20 %: `rated` (real parts) or
    /// `ideal` (unlimited leg servos, flat 30 N·m wheels).
    #[arg(long, value_enum, default_value_t = DrivesArg::Rated)]
    pub(crate) drives: DrivesArg,
    /// The MJCF model.
    #[arg(long, default_value = DEFAULT_MODEL)]
    pub(crate) model: PathBuf,
    /// Where to write the results (JSON).
    #[arg(long, value_name = "FILE", default_value = "out/campaign/results.json")]
    pub(crate) results: PathBuf,
    /// No progress bar (for logs and scripts).
    #[arg(long)]
    pub(crate) no_progress: bool,
}

impl CampaignArgs {
    fn campaign(&self) -> Campaign {
        let scenarios = if self.scenarios.is_empty() {
            Scenario::ALL.to_vec()
        } else {
            let mut s = self.scenarios.clone();
            s.sort();
            s.dedup();
            s
        };
        Campaign {
            trials: self.trials,
            drives: match self.drives {
                DrivesArg::Rated => Drives::Rated,
                DrivesArg::Ideal => Drives::Ideal,
            },
            scenarios,
        }
    }
}

/// Runs the form `args` asks for.
pub(crate) fn run(args: CampaignArgs) -> Result<(), CampaignError> {
    let campaign = args.campaign();
    if let Some(seed) = args.seed {
        return one_trial(&args, &campaign, seed);
    }
    if let Some(n) = args.scaling {
        return scaling(&args, &campaign, n);
    }
    if args.sweep {
        check_setup(&args)?;
        let jobs = args.jobs.unwrap_or_else(default_jobs);
        let runs = sweep::run(
            &args.model,
            campaign.drives,
            &campaign.scenarios,
            jobs,
            !args.no_progress,
        );
        print!(
            "One parameter at a time on {} drives:\n\n{}",
            campaign.drives.name(),
            sweep::markdown(&runs, &campaign.scenarios)
        );
        return Ok(());
    }
    let results = if args.merge.is_empty() {
        run_campaign(&args, campaign)?
    } else {
        let mut files = Vec::new();
        for path in &args.merge {
            files.push((path.clone(), Results::read(path)?));
        }
        results::merge(files)?
    };
    results.write(&args.results)?;
    tracing::info!(results = %args.results.display(), "wrote the results");
    if results.shard == Shard::WHOLE {
        print!("{}", table::markdown(&results));
    }
    Ok(())
}

fn run_campaign(args: &CampaignArgs, campaign: Campaign) -> Result<Results, CampaignError> {
    check_setup(args)?;
    let shard = args.shard.unwrap_or(Shard::WHOLE);
    let runs = campaign.runs(shard);
    let jobs = args.jobs.unwrap_or_else(default_jobs);
    tracing::info!(runs = runs.len(), jobs, %shard, drives = campaign.drives.name(), "campaign");
    let (done, elapsed) =
        pool::run_campaign(&args.model, campaign.drives, &runs, jobs, !args.no_progress);
    let ok = done.iter().filter(|r| r.verdict.outcome.success()).count();
    tracing::info!(
        "{ok} of {} runs succeeded; {:.1} s wall, {:.2} runs/s on {jobs} workers",
        done.len(),
        elapsed.as_secs_f64(),
        done.len() as f64 / elapsed.as_secs_f64().max(1e-9)
    );
    Ok(Results::new(campaign, shard, done))
}

/// Fails early, with what to do, when the closed loop cannot start at all (every run would
/// fail the same way).
fn check_setup(args: &CampaignArgs) -> Result<(), CampaignError> {
    sim_host::faults::rig::Rig::new(
        &args.model,
        Vec::new(),
        &Default::default(),
        &Default::default(),
    )
    .map(drop)
    .map_err(|source| CampaignError::Setup {
        model: args.model.clone(),
        source,
    })
}

fn scaling(args: &CampaignArgs, campaign: &Campaign, n: usize) -> Result<(), CampaignError> {
    check_setup(args)?;
    let runs: Vec<_> = campaign.runs(Shard::WHOLE).into_iter().take(n).collect();
    let s = pool::scaling(&args.model, campaign.drives, &runs);
    let per_trial = campaign.scenarios.len() as f64;
    println!(
        "{} runs: 1 worker {:.2} runs/s ({:.3} trials/s), 2 workers {:.2} runs/s ({:.3} trials/s): \
         {:.2}x; same results: {}",
        s.runs,
        s.one_per_s,
        s.one_per_s / per_trial,
        s.two_per_s,
        s.two_per_s / per_trial,
        s.ratio(),
        if s.same_results { "yes" } else { "NO" }
    );
    if let Some([one, two]) = s.cpu_per_wall {
        // Runs per CPU second: equal for both counts when the pool adds no work of its own,
        // whatever share of the cores the other processes left.
        println!(
            "CPU seconds per wall second: {one:.2} with 1 worker, {two:.2} with 2 ({} cores; \
             below 2 with 2 workers, other processes had the cores); runs per CPU second: \
             {:.1} with 1 worker, {:.1} with 2",
            default_jobs(),
            s.one_per_s / one.max(1e-9),
            s.two_per_s / two.max(1e-9),
        );
    }
    Ok(())
}

/// Prints one trial's plant, and per scenario its verdict and segments' figures.
fn one_trial(args: &CampaignArgs, campaign: &Campaign, seed: u64) -> Result<(), CampaignError> {
    check_setup(args)?;
    let draws = Draws::of(seed);
    println!("seed {seed} on {} drives:", campaign.drives.name());
    for p in parameters() {
        println!("  {:<18} {:>12.6} {}", p.name, draws.value(p.name), p.unit);
    }
    println!(
        "  {:<18} {:>12} (the BMI088's part: its offsets above)\n  {:<18} {:>12} (each \
         joint's effort gain error)",
        "chip seed", draws.chip_seed, "sensing seed", draws.sensing_seed
    );
    for &scenario in &campaign.scenarios {
        let obs = sim_host::campaign::observe_one(&args.model, campaign.drives, &draws, scenario);
        let obs = match obs {
            Ok(obs) => obs,
            Err(e) => {
                println!("\n{scenario}: the closed loop failed: {e}");
                continue;
            }
        };
        let v = judge::judge(scenario, &obs);
        println!(
            "\n{scenario}: {} {} {}",
            v.outcome.name(),
            v.check,
            v.detail
        );
        for s in &obs.segments {
            println!(
                "  [{}] forward {:.3} m, lateral {:.3} m, yaw {:.1}°, tilt {:.1}°, \
                 moved after 1 s {:.3} m, joint excess {:.2}°, wheel {:.1} N·m",
                s.label,
                s.forward_m,
                s.lateral_m,
                s.dyaw_deg,
                s.max_tilt_deg,
                s.moved_after_1s_m,
                s.max_joint_excess_deg,
                s.max_wheel_torque_nm
            );
        }
        if let Some(stop) = obs.stop {
            println!("  E-stop: {stop:?}");
        }
        println!(
            "  fell at {:?} s, abort {:?}, balancing from {:?} s, final state {:?}, {} late commands",
            obs.fell_at_s,
            obs.abort.map(|a| (a.at_s, sim_host::campaign::flag_names(a.flags))),
            obs.balancing_at_s,
            obs.final_state,
            obs.missed_cycles
        );
    }
    Ok(())
}
