//! What `sim-host run` prints at the end, and the `summary.json` of a scenario run.

use sim_host::output::summary::{self, Summary};
use sim_host::session::SessionReport;
use teleop_core::scenario::Scenario;

use crate::run::RunArgs;

/// Prints the run's counters, the torso's end pose, the scenario's table and the files
/// written; writes `summary.json` for a scenario.
pub(crate) fn print(
    args: &RunArgs,
    scenario: Option<&Scenario>,
    report: &SessionReport,
) -> Result<(), String> {
    let s = report.stats;
    if report.interrupted {
        println!("interrupted      (Ctrl-C) — outputs cover the simulated part");
    }
    println!(
        "simulated        {:.2} s in {:.2} s wall ({:.1}x real time)",
        s.sim_s,
        s.wall_s,
        s.real_time_factor()
    );
    println!(
        "cycles           {} ({} missed, {} overruns)",
        s.cycles, s.missed_cycles, s.overruns
    );
    println!(
        "frames           {} sent, {} received",
        s.frames_sent, s.frames_received
    );
    println!(
        "rejected         {} by the drives{}",
        report.drives_rejected,
        report
            .firmware_rejected
            .map(|n| format!(", {n} by the firmware"))
            .unwrap_or_default()
    );
    println!(
        "clamped          {} commands to the drives' ratings (joint range, wheel torque)",
        report.drives_clamped
    );
    if !args.faults.tx.is_clean() || !args.faults.rx.is_clean() {
        let [tx, rx] = report.fault_stats;
        println!("faults           {}", args.faults);
        println!("  on feedback    {tx:?}");
        println!("  on commands    {rx:?}");
    }
    print_end(report);
    if let Some(s) = scenario {
        let path = args.out.join("summary.json");
        Summary::from_stats(
            &s.name,
            &args.bus,
            args.clock.name(),
            &report.stats,
            &report.segments,
        )
        .write(&path)
        .map_err(|e| e.to_string())?;
        println!("\n{}", summary::table(&report.segments));
        println!("wrote            {}", path.display());
    }
    if let Some(first) = report.frames.first() {
        println!(
            "rendered         {} frames from {}",
            report.frames.len(),
            first.display()
        );
    }
    for file in &report.files {
        println!("wrote            {}", file.display());
    }
    Ok(())
}

/// The memory the run held and where the torso ended.
fn print_end(report: &SessionReport) {
    if let Some(resident) = report.resident.describe() {
        println!("memory           resident {resident}");
    }
    if let Some(row) = report.rows.last() {
        println!(
            "torso at end     x {:.3} m, y {:.3} m, z {:.3} m, roll {:.1}°, pitch {:.1}°, yaw {:.1}°",
            row.torso_pos_m[0],
            row.torso_pos_m[1],
            row.torso_pos_m[2],
            row.torso_rpy_deg[0],
            row.torso_rpy_deg[1],
            row.torso_rpy_deg[2]
        );
    }
}
