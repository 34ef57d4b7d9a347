//! The campaign's Markdown, for `docs/campaign.md`: success per scenario and overall, the
//! causes of failure, the worst runs with the command that reruns each, and the failure rate
//! by where each parameter was drawn in its range. Made from the results alone (no wall
//! times), so the same results give the same text: what `cargo xtask campaign --check` needs.

use std::collections::BTreeMap;
use std::fmt::Write;

use crate::campaign::draw::{parameters, Draws, Parameter, Scale};
use crate::campaign::judge::Outcome;
use crate::campaign::results::Results;
use crate::campaign::scenario::Scenario;
use crate::campaign::{rerun_command, RunResult};

/// How many of the worst runs the table lists.
pub const WORST: usize = 12;

/// The whole generated section.
pub fn markdown(results: &Results) -> String {
    let c = &results.campaign;
    let mut text = format!(
        "{} trials (seeds 0…{}) × {} scenarios on {} drives, {} runs \
         (`cargo xtask campaign --trials {}{}`).\n\n",
        c.trials,
        c.trials.saturating_sub(1),
        c.scenarios.len(),
        c.drives.name(),
        results.runs.len(),
        c.trials,
        match c.drives {
            crate::campaign::Drives::Rated => "",
            crate::campaign::Drives::Ideal => " --drives ideal",
        },
    );
    text.push_str(&rates(results));
    text.push_str(&causes(&results.runs));
    text.push_str(&worst(results));
    text.push_str(&by_parameter(&results.runs));
    text
}

fn percent(part: usize, whole: usize) -> String {
    if whole == 0 {
        "–".into()
    } else {
        format!("{:.1} %", 100.0 * part as f64 / whole as f64)
    }
}

/// Success per scenario, overall, and of whole plants.
fn rates(results: &Results) -> String {
    let mut text = String::from(
        "| scenario | runs | pass | safe abort | fell | limit | missed (silent) | missed, reported | panic, error | success |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
    );
    let row = |name: &str, runs: Vec<&RunResult>| {
        let n = |o: Outcome| runs.iter().filter(|r| r.verdict.outcome == o).count();
        let ok = runs.iter().filter(|r| r.verdict.outcome.success()).count();
        format!(
            "| {name} | {} | {} | {} | {} | {} | {} | {} | {} | **{}** |\n",
            runs.len(),
            n(Outcome::Pass),
            n(Outcome::Aborted),
            n(Outcome::Fell),
            n(Outcome::Limit),
            n(Outcome::Missed),
            n(Outcome::Reported),
            n(Outcome::Panic) + n(Outcome::Error),
            percent(ok, runs.len()),
        )
    };
    for scenario in &results.campaign.scenarios {
        let runs = results.runs.iter().filter(|r| r.scenario == *scenario);
        text.push_str(&row(scenario.name(), runs.collect()));
    }
    text.push_str(&row("**overall**", results.runs.iter().collect()));
    let mut per_seed: BTreeMap<u64, bool> = BTreeMap::new();
    for r in &results.runs {
        *per_seed.entry(r.seed).or_insert(true) &= r.verdict.outcome.success();
    }
    let whole = per_seed.values().filter(|ok| **ok).count();
    let _ = writeln!(
        text,
        "\nPlants that passed every scenario: {whole} of {} ({}).\n",
        per_seed.len(),
        percent(whole, per_seed.len())
    );
    text
}

/// Failed runs counted by scenario and the check that failed them, most first.
fn causes(runs: &[RunResult]) -> String {
    let mut counts: BTreeMap<(Scenario, Outcome, &str), usize> = BTreeMap::new();
    for r in runs.iter().filter(|r| r.verdict.outcome != Outcome::Pass) {
        *counts
            .entry((r.scenario, r.verdict.outcome, r.verdict.check.as_str()))
            .or_default() += 1;
    }
    if counts.is_empty() {
        return "Every run met every figure.\n\n".into();
    }
    let mut rows: Vec<_> = counts.into_iter().collect();
    rows.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    let mut text = String::from(
        "Runs that did not simply pass, by the check that decided them:\n\n\
         | scenario | outcome | check | runs |\n|---|---|---|---|\n",
    );
    for ((scenario, outcome, check), n) in rows {
        let _ = writeln!(text, "| {scenario} | {} | {check} | {n} |", outcome.name());
    }
    text.push('\n');
    text
}

/// The worst runs: failures by severity (panic, error, fall, limit, silent miss, reported miss), then by how
/// far they missed; safe aborts after them.
fn worst(results: &Results) -> String {
    let mut bad: Vec<&RunResult> = results
        .runs
        .iter()
        .filter(|r| r.verdict.outcome != Outcome::Pass)
        .collect();
    if bad.is_empty() {
        return String::new();
    }
    bad.sort_by(|a, b| {
        (a.verdict.outcome.cmp(&b.verdict.outcome))
            .then(b.verdict.shortfall.total_cmp(&a.verdict.shortfall))
            .then((a.seed, a.scenario).cmp(&(b.seed, b.scenario)))
    });
    let mut text = format!(
        "The worst runs ({} of {}), the parameter drawn nearest its hard end, and how to rerun \
         each:\n\n| seed | scenario | outcome | what failed | most extreme parameter | rerun |\n\
         |---|---|---|---|---|---|\n",
        bad.len().min(WORST),
        bad.len()
    );
    for r in bad.into_iter().take(WORST) {
        let (p, value, harsh) = Draws::of(r.seed).most_extreme();
        let _ = writeln!(
            text,
            "| {} | {} | {} | {}: {} | {} = {} ({:.0} % to its hard end) | `{}` |",
            r.seed,
            r.scenario,
            r.verdict.outcome.name(),
            r.verdict.check,
            r.verdict.detail.replace('|', "/"),
            p.name,
            with_unit(&significant(value), p.unit),
            100.0 * harsh,
            rerun_command(r.seed, r.scenario, results.campaign.drives),
        );
    }
    text.push('\n');
    text
}

/// A value to three decimals, or in scientific notation when small or large.
pub fn significant(value: f64) -> String {
    if value == 0.0 || (0.01..1000.0).contains(&value.abs()) {
        format!("{value:.3}")
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_owned()
    } else {
        format!("{value:.2e}")
    }
}

/// `text unit`, or `text` for a parameter without a unit.
pub fn with_unit(text: &str, unit: &str) -> String {
    if unit.is_empty() {
        text.to_owned()
    } else {
        format!("{text} {unit}")
    }
}

/// Per parameter, the failure rate of the runs whose draw lay in the mildest, middle and
/// hardest third of its range: a parameter that drives failures shows a rising row.
fn by_parameter(runs: &[RunResult]) -> String {
    let mut text = String::from(
        "Failure rate (runs not passing, safe aborts included) by the third of its range each \
         parameter was drawn in, mild to hard (the chip's offsets: by the third of the parts' \
         spread, nearest nominal to farthest):\n\n\
         | parameter | range | mildest third | middle | hardest third |\n|---|---|---|---|---|\n",
    );
    let draws: BTreeMap<u64, Draws> = runs.iter().map(|r| (r.seed, Draws::of(r.seed))).collect();
    for (i, p) in parameters().enumerate() {
        let mut bins = [(0usize, 0usize); 3];
        for r in runs {
            let Some(u) = draws.get(&r.seed).and_then(|d| d.unit.get(i)) else {
                continue;
            };
            let bin = ((p.harshness(*u) * 3.0) as usize).min(2);
            bins[bin].1 += 1;
            if r.verdict.outcome != Outcome::Pass {
                bins[bin].0 += 1;
            }
        }
        let [a, b, c] = bins.map(|(bad, all)| percent(bad, all));
        let _ = writeln!(text, "| {} | {} | {a} | {b} | {c} |", p.name, range_text(p));
    }
    text
}

/// A parameter's range for the tables: `lo … hi unit`, or for the chip's offsets their
/// spread, `normal, 1σ s unit`.
pub fn range_text(p: &Parameter) -> String {
    let text = match p.scale {
        Scale::Chip => format!("normal, 1σ {}", significant(p.range.1 / 2.0)),
        _ => format!("{} … {}", significant(p.range.0), significant(p.range.1)),
    };
    with_unit(&text, p.unit)
}
