//! Delay margin: with the CAN loop's latency of a real robot (a sample, the transfer of the
//! feedback, the command and its transfer), the robot balancing at rest on its wheels keeps its
//! wheel torque off the limit — no limit cycle.
//!
//! `cargo test -p sim-host --test latency -- --nocapture` prints the figures.

use std::path::Path;

use firmware::control::fsm::{State, WheelMotion};
use host_can::fault_plan::Faults;
use protocol::TeleopMode;
use sim_host::faults::rig::{Rig, PERIOD_US};
use sim_host::robot::model::DEFAULT_MODEL;
use sim_host::robot::plant::Plant;
use sim_host::robot::rating::Rating;
use teleop_core::scripted::PlanStep;

/// What resting on the wheels did with one loop latency.
#[derive(Debug)]
struct Figures {
    /// Added loop latency (both ways together), ms.
    latency_ms: u64,
    /// Share of cycles with a wheel torque command at 98 % of the limit or more.
    saturated: f64,
    /// Standard deviation of the left wheel's torque command, N·m.
    torque_std_nm: f64,
    /// Torso x range over the rest, m.
    drift_m: f64,
    /// Whether the controller stayed balancing at rest throughout.
    balancing: bool,
}

/// Folds, settles 8 s, then rests 10 s with `cycles` of delay in all: the plant's transport
/// delay (one cycle each way) and the rest on the commands.
fn rest_with_delay(cycles: u32) -> Figures {
    let plant = Plant {
        transport_delay_cycles: 1,
        ..Plant::default()
    };
    let mut faults = Faults::default();
    faults.rx.delay_cycles = cycles.saturating_sub(2);
    let plan = vec![PlanStep::at(0.0, TeleopMode::Fold)];
    let clean = Faults::default();
    let model = Path::new(DEFAULT_MODEL);
    let mut rig = Rig::with_plant(model, plan, &faults, &clean, plant).unwrap();
    rig.run_until(8.0).unwrap();
    let limit_nm = Rating::WHEEL.peak_torque_nm;
    let x0 = rig.sim().physics().torso().pos_m[0];
    let (mut low, mut high, mut balancing) = (x0, x0, true);
    let (mut saturated, mut n, mut sum, mut sum_sq) = (0u64, 0u64, 0.0, 0.0);
    while rig.stats().cycles * PERIOD_US < 18_000_000 {
        rig.step().unwrap();
        let record = rig.records().last().unwrap();
        balancing &= record.state == Some(State::Wheels(WheelMotion::Balance));
        let [left, right] = record.wheel_torque_nm.unwrap_or([0.0; 2]).map(f64::from);
        saturated += u64::from(left.abs().max(right.abs()) >= 0.98 * limit_nm);
        (n, sum, sum_sq) = (n + 1, sum + left, sum_sq + left * left);
        let x = rig.sim().physics().torso().pos_m[0];
        (low, high) = (low.min(x), high.max(x));
    }
    let mean = sum / n as f64;
    Figures {
        latency_ms: u64::from(cycles) * PERIOD_US / 1000,
        saturated: saturated as f64 / n as f64,
        torque_std_nm: (sum_sq / n as f64 - mean * mean).max(0.0).sqrt(),
        drift_m: high - low,
        balancing,
    }
}

#[test]
fn twelve_ms_of_loop_latency_leave_the_wheels_off_their_limit_at_rest() {
    // 3 cycles at 250 Hz: 12 ms, the acceptance. 4 cycles (16 ms) is printed, not asserted:
    // the default BMI088's filter and sample age add a millisecond or so to the loop, and at
    // 16 ms some chips' loops saturate (docs/firmware.md).
    for cycles in [3, 4] {
        let f = rest_with_delay(cycles);
        println!(
            "MEASURED {} ms of loop latency: {:.1} % of cycles saturated, wheel torque std {:.2} N·m, drift {:.4} m",
            f.latency_ms,
            100.0 * f.saturated,
            f.torque_std_nm,
            f.drift_m
        );
        if cycles == 3 {
            assert!(f.balancing, "{f:?}");
            assert!(f.saturated < 0.01, "{f:?}");
            assert!(f.drift_m < 0.05, "{f:?}");
        }
    }
}
