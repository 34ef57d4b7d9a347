//! `cargo xtask bench`: the criterion benchmarks, then a table of their medians, printed and
//! written into docs/measurements.md between the `bench:begin` and `bench:end` markers; then
//! `sim-host run`, bare and with every output, beside the report's program in Python, and an
//! hour's run for its memory ([`whole_run`]), between `bench-run:begin` and `bench-run:end`.
//!
//! Timings on shared machines are noisy: compare figures within one run (the ratio of the
//! typed step to the full CAN node, of the closed loop to raw MuJoCo), not against a fixed
//! number.

use std::fs;

use crate::util::{cargo, root, run};

mod whole_run;

const BEGIN: &str = "<!-- bench:begin -->";
const END: &str = "<!-- bench:end -->";
const RUN_BEGIN: &str = "<!-- bench-run:begin -->";
const RUN_END: &str = "<!-- bench-run:end -->";
/// The page the table of medians is written into, relative to the workspace root.
const PAGE: &str = "docs/measurements.md";

/// Benchmarks reported, as `(criterion directory, what it measures)`.
const REPORTED: [(&str, &str); 5] = [
    (
        "step_trot",
        "control step, trotting (4-leg IK + gait + FSM + safety)",
    ),
    (
        "step_wheels",
        "control step, on the wheels (fold + balance + turn loop + safety)",
    ),
    (
        "node_trot",
        "CAN node tick, trotting (6 frames decoded + step + frames encoded)",
    ),
    ("mujoco_step", "one MuJoCo step of the robot model (0.004 s)"),
    (
        "closed_loop_cycle",
        "closed loop, driving on the wheels: sim frames + firmware + drives + 1 step, in-process bus",
    ),
];

pub fn run_task(args: &[String]) -> Result<(), String> {
    crate::setup::run()?;
    for (package, bench) in [("firmware", "control_step"), ("sim-host", "sim_speed")] {
        let mut cmd = cargo();
        cmd.args(["bench", "-p", package, "--bench", bench, "--"]);
        cmd.args(args);
        run(&mut cmd)?;
    }
    println!(
        "\n{:<18} {:>12} {:>14}  measures",
        "benchmark", "median", "per second"
    );
    let mut medians = Vec::new();
    let mut rows = Vec::new();
    for (name, what) in REPORTED {
        let path = root()
            .join("target/criterion")
            .join(name)
            .join("new/estimates.json");
        let text = fs::read_to_string(&path)
            .map_err(|e| format!("{}: {e} (did the benchmark run?)", path.display()))?;
        let median_ns = median_point_estimate(&text)
            .ok_or_else(|| format!("{}: no median estimate in the file", path.display()))?;
        println!(
            "{name:<18} {:>9.1} ns {:>14.0}  {what}",
            median_ns,
            1e9 / median_ns
        );
        medians.push(median_ns);
        rows.push((name, median_ns, what));
    }
    let summary = match medians[..] {
        [.., raw, closed] => {
            let line = format!(
                "closed loop runs at {:.0} steps/s, {:.0} % of raw MuJoCo's {:.0} steps/s",
                1e9 / closed,
                100.0 * raw / closed,
                1e9 / raw
            );
            println!("\n{line}");
            Some(line)
        }
        _ => None,
    };
    let table = markdown_table(&rows, summary.as_deref());
    crate::faults::write_section(&root().join(PAGE), BEGIN, END, &table, false, "bench")?;
    let (raw_steps_per_s, closed_steps_per_s) = match medians[..] {
        [.., raw, closed] => (1e9 / raw, 1e9 / closed),
        _ => return Err("no MuJoCo step median".into()),
    };
    let measured = whole_run::measure()?;
    let comparison = whole_run::markdown(&measured, raw_steps_per_s, closed_steps_per_s);
    println!("\n{comparison}");
    crate::faults::write_section(
        &root().join(PAGE),
        RUN_BEGIN,
        RUN_END,
        &comparison,
        false,
        "bench",
    )
}

/// The printed table as Markdown: one row per benchmark (`(name, median in ns, what it
/// measures)`), then the closed loop's summary line, if any.
fn markdown_table(rows: &[(&str, f64, &str)], summary: Option<&str>) -> String {
    let mut text =
        String::from("| benchmark | median | per second | measures |\n|---|---|---|---|\n");
    for (name, median_ns, what) in rows {
        text.push_str(&format!(
            "| `{name}` | {} | {} | {what} |\n",
            duration(*median_ns),
            thousands(1e9 / median_ns)
        ));
    }
    if let Some(line) = summary {
        text.push_str(&format!("\n{}.\n", capitalised(line)));
    }
    text
}

/// A duration in ns with three significant figures and a fitting unit: `389 ns`, `1.47 µs`.
fn duration(ns: f64) -> String {
    let (value, unit) = match ns {
        // Below 999.5 of a unit, so that rounding never prints `1000 ns`.
        ns if ns < 999.5 => (ns, "ns"),
        ns if ns < 999.5e3 => (ns / 1e3, "µs"),
        ns if ns < 999.5e6 => (ns / 1e6, "ms"),
        ns => (ns / 1e9, "s"),
    };
    let decimals = match value {
        v if v >= 99.95 => 0,
        v if v >= 9.995 => 1,
        _ => 2,
    };
    format!("{value:.decimals$} {unit}")
}

/// A count rounded to a whole number, with `,` between thousands: `65,300`.
fn thousands(value: f64) -> String {
    let digits = format!("{:.0}", value.max(0.0));
    let mut text = String::new();
    for (i, digit) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            text.push(',');
        }
        text.push(digit);
    }
    text
}

fn capitalised(line: &str) -> String {
    let mut chars = line.chars();
    match chars.next() {
        Some(first) => first.to_uppercase().chain(chars).collect(),
        None => String::new(),
    }
}

/// The `median.point_estimate` of a criterion `estimates.json`, in ns.
fn median_point_estimate(json: &str) -> Option<f64> {
    let median = json.find("\"median\"")?;
    let rest = json.get(median..)?;
    let key = "\"point_estimate\":";
    let start = rest.find(key)? + key.len();
    let number: String = rest
        .get(start..)?
        .chars()
        .take_while(|c| c.is_ascii_digit() || matches!(c, '.' | 'e' | 'E' | '-' | '+'))
        .collect();
    number.parse().ok()
}

#[cfg(test)]
mod tests {
    #[test]
    fn reads_the_median_not_the_mean() {
        let json = r#"{"mean":{"confidence_interval":{"lower_bound":1.0},"point_estimate":2.5},"median":{"confidence_interval":{"lower_bound":1.0,"upper_bound":9.0},"point_estimate":387.9},"slope":null}"#;
        assert_eq!(super::median_point_estimate(json), Some(387.9));
    }

    #[test]
    fn durations_and_counts_read_like_the_docs() {
        assert_eq!(super::duration(388.6), "389 ns");
        assert_eq!(super::duration(1_470.4), "1.47 µs");
        assert_eq!(super::duration(15_312.0), "15.3 µs");
        assert_eq!(super::duration(999.99), "1.00 µs");
        assert_eq!(super::thousands(65_312.4), "65,312");
        assert_eq!(super::thousands(999.0), "999");
        assert_eq!(super::thousands(2_573_000.0), "2,573,000");
    }

    #[test]
    fn the_markdown_table_has_a_row_per_benchmark() {
        let table = super::markdown_table(
            &[
                ("step_trot", 388.6, "control step"),
                ("mujoco_step", 15_312.0, "one step"),
            ],
            Some("closed loop runs at 44600 steps/s"),
        );
        assert_eq!(
            table,
            "| benchmark | median | per second | measures |\n|---|---|---|---|\n\
             | `step_trot` | 389 ns | 2,573,340 | control step |\n\
             | `mujoco_step` | 15.3 µs | 65,308 | one step |\n\
             \nClosed loop runs at 44600 steps/s.\n"
        );
    }
}
