//! `cargo xtask bench`: the criterion benchmarks, then a table of their medians.
//!
//! Timings on shared machines are noisy: compare figures within one run (the ratio of the
//! typed step to the full CAN node, of the closed loop to raw MuJoCo), not against a fixed
//! number.

use std::fs;

use crate::util::{cargo, root, run};

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
    }
    if let [.., raw, closed] = medians[..] {
        println!(
            "\nclosed loop runs at {:.0} steps/s, {:.0} % of raw MuJoCo's {:.0} steps/s",
            1e9 / closed,
            100.0 * raw / closed,
            1e9 / raw
        );
    }
    Ok(())
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
}
