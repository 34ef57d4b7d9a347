//! `cargo xtask busload`: the per-cycle frame schedule and the worst-case bus load.

use protocol::busload::{bus_load, fd_frame_bits, Load, Period, ROBOT_BUS, SCHEDULE};

/// Load limit the design must meet at 1 kHz, ppm.
const LIMIT_PPM: u32 = 500_000;

pub fn run() -> Result<(), String> {
    println!(
        "CAN FD bus: {} kbit/s arbitration, {} kbit/s data, 11-bit ids, worst-case bit stuffing\n",
        ROBOT_BUS.nominal_bps / 1000,
        ROBOT_BUS.data_bps / 1000
    );
    println!(
        "{:<20} {:>5} {:>4} {:>8} {:>6} {:>9} {:>10} {:>10}",
        "message", "id", "len", "bits n/d", "µs", "phase", "rate@1kHz", "rate@250Hz"
    );
    for slot in SCHEDULE {
        let layout = slot.id.layout();
        let bits = fd_frame_bits(layout.wire_len);
        let rate = |hz: u32| match slot.period {
            Period::Sporadic => "event".to_string(),
            _ => format!("{} Hz", hz / slot.period_cycles(hz)),
        };
        println!(
            "{:<20} 0x{:03X} {:>4} {:>4}/{:<3} {:>6.1} {:>9} {:>10} {:>10}{}",
            layout.name,
            slot.id.raw(),
            layout.wire_len,
            bits.nominal,
            bits.data,
            slot.frame_ns(ROBOT_BUS) as f64 / 1000.0,
            slot.phase,
            rate(1000),
            rate(250),
            if slot.lockstep_only {
                "  (lockstep only)"
            } else {
                ""
            }
        );
    }
    println!(
        "\n{:<34} {:>9} {:>22}",
        "schedule", "average", "busiest cycle (+E-stop)"
    );
    for hz in [250, 1000] {
        for with_sync in [false, true] {
            print_load(&bus_load(hz, ROBOT_BUS, with_sync));
        }
    }
    let robot_1k = bus_load(1000, ROBOT_BUS, false);
    let lockstep_1k = bus_load(1000, ROBOT_BUS, true);
    let fits = robot_1k.average_ppm <= LIMIT_PPM && robot_1k.worst_cycle_ppm <= LIMIT_PPM;
    println!(
        "\n1 kHz control on the robot's bus: average {:.1} %, busiest cycle {:.1} % (with an E-stop) \
         — limit {:.0} %: {}",
        percent(robot_1k.average_ppm),
        percent(robot_1k.worst_cycle_ppm),
        percent(LIMIT_PPM),
        if fits { "fits" } else { "DOES NOT FIT" }
    );
    println!(
        "Lockstep simulation adds SYNC every cycle: average {:.1} %; there the bus has no deadline \
         (the simulator waits for every frame before it steps).",
        percent(lockstep_1k.average_ppm)
    );
    if !fits {
        return Err("the 1 kHz schedule exceeds 50 % of the bus".into());
    }
    Ok(())
}

fn print_load(load: &Load) {
    let label = format!(
        "{} Hz control, {}",
        load.control_hz,
        if load.with_sync {
            "lockstep (+SYNC)"
        } else {
            "robot"
        }
    );
    println!(
        "{:<34} {:>8.1}% {:>14.1}% ({:.0} µs)",
        label,
        percent(load.average_ppm),
        percent(load.worst_cycle_ppm),
        load.worst_cycle_ns as f64 / 1000.0
    );
}

fn percent(ppm: u32) -> f64 {
    f64::from(ppm) / 1e4
}
