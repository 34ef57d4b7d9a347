//! The `MEASURED` lines of a PIL run, and its budgets.

use pil_format::Recording;

use super::compare::Check;
use super::qemu::PilRun;

/// Goals: instructions per control step, peak stack bytes (8 KiB of the 128 KiB RAM until the
/// step climb's state and the drives' reported torques took the peak past it).
const INSTRUCTION_BUDGET: u64 = 20_000;
const STACK_BUDGET: u64 = 10 * 1024;

/// Prints the figures; an error if a budget is exceeded.
pub(super) fn print(recording: &Recording, pil: &PilRun, check: &Check) -> Result<(), String> {
    let per_tick = pil.instructions_per_tick();
    let mut instructions: Vec<u64> = pil
        .ticks
        .iter()
        .map(|(_, cost, _)| (cost.saturating_sub(pil.base) as f64 * per_tick).round() as u64)
        .collect();
    instructions.sort_unstable();
    let median = instructions
        .get(instructions.len() / 2)
        .copied()
        .unwrap_or(0);
    let max = instructions.last().copied().unwrap_or(0);
    let seconds = recording.ticks.len() as f64 / f64::from(recording.control_hz);
    println!(
        "MEASURED PIL outputs: {} control steps ({seconds:.1} s at {} Hz), {} frames and {} \
         values equal to the host build's; {} values one count apart, max deviation {}",
        pil.ticks.len(),
        recording.control_hz,
        check.frames,
        check.values,
        check.off_by_one,
        if check.off_by_one == 0 {
            "0 (bit-identical)".to_string()
        } else {
            check.max_at.clone()
        }
    );
    println!(
        "MEASURED PIL SysTick calibration: {} instructions in {} ticks = {per_tick:.2} \
         instructions per tick (timer read overhead {} ticks)",
        pil.cal.0, pil.cal.1, pil.base
    );
    println!(
        "MEASURED PIL instructions per control step (frames decoded + step + frames encoded, \
         Cortex-M4F, mcu profile): median {median}, max {max} (budget {INSTRUCTION_BUDGET})"
    );
    println!(
        "MEASURED PIL peak stack: {} bytes (budget {STACK_BUDGET})",
        pil.stack
    );
    if max > INSTRUCTION_BUDGET || pil.stack > STACK_BUDGET {
        return Err("the control step is over its instruction or stack budget".into());
    }
    Ok(())
}
