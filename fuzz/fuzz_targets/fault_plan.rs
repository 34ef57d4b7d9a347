//! The fault plan parser (`host_can::fault_plan`, `--faults PLAN` of sim-host and
//! firmware-host): any text gives a plan or a typed error, never a panic. A plan it reads is in
//! range (probabilities 0…1, counts at most `MAX_CYCLES`), and what it writes of a plan that
//! breaks anything reads back to the same plan.
#![no_main]

use host_can::fault_plan::{FaultPlan, Faults, MAX_CYCLES};
use libfuzzer_sys::fuzz_target;

fn in_range(plan: &FaultPlan) -> bool {
    let probabilities = [
        plan.drop,
        plan.duplicate,
        plan.reorder,
        plan.flip,
        plan.replay,
    ];
    probabilities.iter().all(|p| (0.0..=1.0).contains(p))
        && [plan.burst_cycles, plan.delay_cycles, plan.flood_per_cycle]
            .iter()
            .all(|n| *n <= MAX_CYCLES)
}

fuzz_target!(|input: &[u8]| {
    let Ok(text) = std::str::from_utf8(input) else {
        return;
    };
    let Ok(faults) = text.parse::<Faults>() else {
        return;
    };
    assert!(
        in_range(&faults.tx) && in_range(&faults.rx),
        "{text:?}: {faults:?}"
    );
    let written = faults.to_string();
    if written == "none" {
        assert!(
            faults.tx.is_clean() && faults.rx.is_clean(),
            "{text:?}: {faults:?}"
        );
    } else {
        assert_eq!(
            written.parse::<Faults>(),
            Ok(faults),
            "{text:?} written as {written:?}"
        );
    }
});
