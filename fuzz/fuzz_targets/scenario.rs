//! The scenario parser (`teleop_core::scenario`, the files `sim-host run --scenario` and
//! `teleop script` read): any text gives a scenario or an error naming the file and a line,
//! never a panic. A scenario it reads is what the parser promises: a duration of 0…86 400 s,
//! at least one step, steps in time order inside it, heights and speed scales in range.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use teleop_core::scenario::{Scenario, ScenarioError};

fuzz_target!(|input: &[u8]| {
    let Ok(text) = std::str::from_utf8(input) else {
        return;
    };
    let scenario = match Scenario::parse(Path::new("fuzz.toml"), text) {
        Ok(scenario) => scenario,
        Err(error) => {
            let line = match &error {
                ScenarioError::Syntax { line, .. } | ScenarioError::Value { line, .. } => *line,
                _ => 1,
            };
            assert!(line >= 1, "{error}");
            assert!(error.to_string().starts_with("fuzz.toml:"), "{error}");
            return;
        }
    };
    let duration_s = scenario.duration_s;
    assert!(duration_s > 0.0 && duration_s <= 86_400.0, "{duration_s}");
    assert!(!scenario.steps.is_empty());
    let end_us = (duration_s * 1e6).round() as u64;
    let mut previous = None;
    for step in &scenario.steps {
        let plan = step.plan;
        assert!(plan.at_us <= end_us, "{plan:?} after {duration_s} s");
        assert!(
            previous.is_none_or(|at_us| plan.at_us >= at_us),
            "{plan:?} out of order"
        );
        assert!((-0.10..=0.12).contains(&plan.body_height_m), "{plan:?}");
        assert!((0.0..=100.0).contains(&plan.speed_scale_pct), "{plan:?}");
        previous = Some(plan.at_us);
    }
});
