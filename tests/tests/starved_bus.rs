//! A bus whose transmit queue is starved — a token-bucket qdisc on the vcan passes far fewer
//! frames than the programs send, so their sends find the queue full (`ENOBUFS`) as on a
//! bus-off or saturated `can0` — must not trap its programs: firmware-host and teleop, each
//! blocked in a send most of the time, exit within 1 s (wall clock) of Ctrl-C.

use std::process::Command;
use std::time::Duration;

use hil_tests::{candump, firmware_on_wall_clock, out_dir, read_candump, Process, Vcan};

/// What the qdisc passes: about 460 CAN FD frames per second where the firmware alone sends
/// over a thousand. At 64 kbit (about 110 a second) a sender sometimes found the queue full for
/// the whole 100 ms send deadline and exited with its "transmit queue stays full" error before
/// the Ctrl-C this test is about.
const STARVED_RATE: &str = "256kbit";

/// Longest a program may take to exit after Ctrl-C.
const EXIT_WITHIN: Duration = Duration::from_secs(1);

/// The frames the qdisc on `bus` dropped because its queue was full (`tc -s qdisc`).
fn dropped(bus: &Vcan) -> u64 {
    let out = Command::new("tc")
        .args(["-s", "qdisc", "show", "dev", bus.name()])
        .output()
        .expect("tc runs");
    let text = String::from_utf8_lossy(&out.stdout);
    text.split_once("dropped ")
        .and_then(|(_, rest)| rest.split(|c: char| !c.is_ascii_digit()).next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no drop count in `tc -s qdisc`: {text}"))
}

#[test]
fn firmware_host_and_teleop_on_a_starved_bus_exit_within_1_s_of_ctrl_c() {
    let bus = Vcan::new();
    bus.starve(STARVED_RATE);
    let log = out_dir("starved-dump").with_extension("log");
    let dump = candump(&bus, &log);
    let mut fw = firmware_on_wall_clock(&bus);
    let mut teleop = Process::start("teleop", &["--bus", bus.name(), "send", "W", "--for", "60"]);
    std::thread::sleep(Duration::from_secs(3));
    let drops = dropped(&bus);
    let frames = read_candump(&log);
    let span_s = frames.last().map_or(0.0, |l| l.0) - frames.first().map_or(0.0, |f| f.0);
    let rate = frames.len() as f64 / span_s.max(1e-3);
    println!(
        "starved bus: {} frames passed in {span_s:.1} s ({rate:.0}/s), {drops} refused by the \
         full queue",
        frames.len()
    );
    assert!(drops > 100, "the bus was not starved: {drops} drops");
    assert!(fw.running(), "firmware-host gave up on the starved bus");
    assert!(teleop.running(), "teleop gave up on the starved bus");

    for (name, process) in [("firmware-host", fw), ("teleop", teleop)] {
        let (status, took) = process.interrupt();
        println!("{name}: Ctrl-C on the starved bus, exited in {took:?} with {status:?}");
        assert!(
            status.is_some() && took <= EXIT_WITHIN,
            "{name} took {took:?} to exit after Ctrl-C"
        );
    }
    let _ = dump.terminate();
}
