//! The robustness campaign (`sim_host::campaign`) as an instrument: on the acceptance tests'
//! own plant (`Plant::default()`) its judge passes every scenario (so a failure in a campaign
//! is the plant's or the controller's doing, not the judge's), a seed reruns to the same
//! verdict whatever the number of workers, and
//! shards merged give the results and the table of one whole run.
//!
//! Run in release for speed: `cargo test --release -p sim-host --test campaign`.

use std::path::Path;

use host_can::fault_plan::Faults;
use sim_host::campaign::judge::{judge, Outcome};
use sim_host::campaign::pool::run_campaign;
use sim_host::campaign::results::{merge, Campaign, Results, Shard};
use sim_host::campaign::scenario::Scenario;
use sim_host::campaign::{observe, table, Drives};
use sim_host::robot::model::DEFAULT_MODEL;
use sim_host::robot::plant::Plant;

#[test]
fn the_acceptance_tests_plant_passes_every_scenario() {
    let model = Path::new(DEFAULT_MODEL);
    let mut failed = Vec::new();
    for scenario in Scenario::ALL {
        let obs = observe::run(model, scenario, Plant::default(), &Faults::default()).unwrap();
        let verdict = judge(scenario, &obs);
        println!("{scenario}: {verdict:?}");
        if verdict.outcome != Outcome::Pass {
            failed.push(format!("{scenario}: {verdict:?}"));
        }
    }
    assert!(failed.is_empty(), "{failed:#?}");
}

/// A small campaign: 6 trials of three short scenarios.
fn small() -> Campaign {
    Campaign {
        trials: 6,
        drives: Drives::Rated,
        scenarios: vec![Scenario::A, Scenario::Fold, Scenario::XFromL],
    }
}

fn run(campaign: &Campaign, shard: Shard, jobs: usize) -> Results {
    let model = Path::new(DEFAULT_MODEL);
    let (runs, _) = run_campaign(model, campaign.drives, &campaign.runs(shard), jobs, false);
    Results::new(campaign.clone(), shard, runs)
}

#[test]
fn shards_merged_give_the_table_of_one_run_whatever_the_workers() {
    let campaign = small();
    let whole = run(&campaign, Shard::WHOLE, 2);
    let dir = std::env::temp_dir().join(format!("campaign-test-{}", std::process::id()));
    let mut files = Vec::new();
    for index in 0..3 {
        let shard = Shard { index, count: 3 };
        let path = dir.join(format!("shard-{index}.json"));
        run(&campaign, shard, 1).write(&path).unwrap();
        files.push((path.clone(), Results::read(&path).unwrap()));
    }
    let merged = merge(files.clone()).unwrap();
    // (Not assert_eq!: a difference would print every run's plant.)
    assert!(merged == whole, "merged shards differ from the whole run");
    assert_eq!(table::markdown(&merged), table::markdown(&whole));
    println!("{}", table::markdown(&whole));
    // A shard missing, or given twice, is refused.
    assert!(merge(files[..2].to_vec()).is_err());
    let mut twice = files.clone();
    twice.push(files[0].clone());
    assert!(merge(twice).is_err());
    let _ = std::fs::remove_dir_all(&dir);
}
