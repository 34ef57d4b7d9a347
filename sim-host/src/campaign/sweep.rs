//! One parameter at a time: the tested default robot ([`crate::robot::plant::Plant::default`]:
//! its chip, its sensors, its delay, drives at their rating) with a single parameter at one end
//! of its campaign range, through every scenario.
//! Where the random trials show how often the controller fails, this shows which parameter
//! alone is enough to make it fail, and how: the campaign's causes, separated.

use std::fmt::Write;
use std::path::Path;

use host_can::fault_plan::Faults;
use serde::{Deserialize, Serialize};

use crate::campaign::draw::{parameters, plant_of, Parameter};
use crate::campaign::judge::{Outcome, Verdict};
use crate::campaign::pool::run_all;
use crate::campaign::scenario::Scenario;
use crate::campaign::table::{significant, with_unit};
use crate::campaign::{judged, Drives};

/// One setting: the robot as modelled, or one parameter at one end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setting {
    /// The parameter set, or `None` for the robot as modelled.
    pub parameter: Option<&'static Parameter>,
    /// Its value.
    pub value: f64,
}

impl Setting {
    /// The robot as modelled, then every parameter at the low end of its range and at the
    /// high end.
    pub fn all() -> Vec<Setting> {
        let mut settings = vec![Setting {
            parameter: None,
            value: 0.0,
        }];
        for p in parameters() {
            for value in [p.range.0, p.range.1] {
                settings.push(Setting {
                    parameter: Some(p),
                    value,
                });
            }
        }
        settings
    }

    /// `name = value unit`, or `as modelled`.
    pub fn label(&self) -> String {
        match self.parameter {
            None => "as modelled".into(),
            Some(p) => format!(
                "{} = {}",
                p.name,
                with_unit(&significant(self.value), p.unit)
            ),
        }
    }

    /// The default plant on `drives` with this setting.
    fn plant(&self, drives: Drives) -> crate::robot::plant::Plant {
        let name = self.parameter.map(|p| p.name);
        let value = |n: &str| (Some(n) == name).then_some(self.value);
        let mut plant = plant_of(&value, drives.ratings());
        if let Some(name) = name {
            crate::campaign::imu::set_offset(&mut plant, name, self.value);
        }
        plant
    }
}

/// One run of the sweep.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepRun {
    /// The setting's label.
    pub setting: String,
    /// The scenario.
    pub scenario: Scenario,
    /// Its verdict.
    pub verdict: Verdict,
}

/// Runs every setting through `scenarios` on `jobs` workers.
pub fn run(
    model: &Path,
    drives: Drives,
    scenarios: &[Scenario],
    jobs: usize,
    progress: bool,
) -> Vec<SweepRun> {
    let items: Vec<(Setting, Scenario)> = Setting::all()
        .into_iter()
        .flat_map(|setting| scenarios.iter().map(move |s| (setting, *s)))
        .collect();
    let work = |&(setting, scenario): &(Setting, Scenario)| {
        let plant = setting.plant(drives);
        SweepRun {
            setting: setting.label(),
            scenario,
            verdict: judged(scenario, || {
                crate::campaign::observe::run(model, scenario, plant, &Faults::default())
            }),
        }
    };
    run_all(&items, jobs, progress, work, |r| {
        !r.verdict.outcome.success()
    })
    .0
}

/// A cell: `pass`, or the outcome and the check that decided it.
fn cell(verdict: &Verdict) -> String {
    match verdict.outcome {
        Outcome::Pass => "pass".into(),
        Outcome::Limit | Outcome::Fell | Outcome::Panic | Outcome::Error => {
            format!("**{}**", verdict.outcome.name())
        }
        Outcome::Missed => format!("**missed**: {}", verdict.check),
        Outcome::Reported => format!("**missed, reported**: {}", verdict.check),
        Outcome::Aborted => format!("abort: {}", abort_flags(&verdict.detail)),
    }
}

/// The flags of "…; firmware stopped it at T s: FLAGS".
fn abort_flags(detail: &str) -> &str {
    detail.rsplit(": ").next().unwrap_or(detail)
}

/// The sweep as a Markdown table, a column per scenario: the robot as modelled, then each
/// setting whose verdicts differ from it (the others are listed after the table).
pub fn markdown(runs: &[SweepRun], scenarios: &[Scenario]) -> String {
    let mut text = String::from("| setting |");
    for s in scenarios {
        let _ = write!(text, " {s} |");
    }
    text.push_str("\n|---|");
    text.push_str(&"---|".repeat(scenarios.len()));
    text.push('\n');
    let rows: Vec<&[SweepRun]> = runs.chunks(scenarios.len().max(1)).collect();
    let cells = |row: &[SweepRun]| row.iter().map(|r| cell(&r.verdict)).collect::<Vec<_>>();
    let nominal = rows.first().map(|row| cells(row)).unwrap_or_default();
    let mut same = Vec::new();
    for (i, row) in rows.iter().enumerate() {
        let row_cells = cells(row);
        if i > 0 && row_cells == nominal {
            same.push(row[0].setting.clone());
            continue;
        }
        let _ = writeln!(text, "| {} | {} |", row[0].setting, row_cells.join(" | "));
    }
    if !same.is_empty() {
        let _ = write!(
            text,
            "\nAs modelled in every scenario: {}.\n",
            same.join(", ")
        );
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(setting: &str, scenario: Scenario, outcome: Outcome, check: &str) -> SweepRun {
        SweepRun {
            setting: setting.into(),
            scenario,
            verdict: Verdict {
                outcome,
                check: check.into(),
                detail: "…; firmware stopped it at 1.00 s: wheel_stall".into(),
                shortfall: 0.0,
            },
        }
    }

    #[test]
    fn every_parameter_is_set_at_both_ends_and_only_rows_unlike_the_model_are_shown() {
        let settings = Setting::all();
        assert_eq!(settings.len(), 1 + 2 * parameters().count());
        assert_eq!(settings[1].label(), "mass = 0.9 ×");
        let scenarios = [Scenario::W, Scenario::L];
        let runs = vec![
            run("as modelled", Scenario::W, Outcome::Pass, ""),
            run("as modelled", Scenario::L, Outcome::Pass, ""),
            run("mass = 0.9 ×", Scenario::W, Outcome::Pass, ""),
            run("mass = 0.9 ×", Scenario::L, Outcome::Pass, ""),
            run("transport_delay = 2", Scenario::W, Outcome::Aborted, "tilt"),
            run("transport_delay = 2", Scenario::L, Outcome::Missed, "roll"),
        ];
        let text = markdown(&runs, &scenarios);
        assert!(text.contains("| as modelled | pass | pass |"), "{text}");
        assert!(
            text.contains("| transport_delay = 2 | abort: wheel_stall | **missed**: roll |"),
            "{text}"
        );
        assert!(
            text.contains("As modelled in every scenario: mass = 0.9 ×."),
            "{text}"
        );
    }
}
