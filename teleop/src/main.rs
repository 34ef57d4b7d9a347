//! `teleop`: drive the robot over CAN. Scripted mode (`send`) for shells and automation; the
//! interactive terminal UI follows.

use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::{Parser, Subcommand};
use firmware_host::bus::Bus;
use firmware_host::socketcan_bus::SocketCanBus;
use teleop::keys::{action, Action, Key};
use teleop::operator::Operator;

/// Drive the hybrid wheel–leg robot over CAN with the report's keys.
///
/// Example: teleop --bus vcan0 send W --for 5
/// (holds W for 5 s with the heartbeat going; the controller stops the robot within 500 ms of
/// the last heartbeat).
#[derive(Debug, Parser)]
#[command(version, about, long_about)]
struct Cli {
    /// The SocketCAN interface (vcan0, can0).
    #[arg(long, default_value = "vcan0")]
    bus: String,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Send one key and keep the operator's heartbeat going for a while.
    Send {
        /// W S A L K X (the report's keys), T (stand), F (fold), or `space` for the E-stop.
        #[arg(value_parser = parse_key)]
        key: Action,
        /// Seconds to keep sending the command and heartbeat.
        #[arg(long = "for", default_value_t = 1.0)]
        seconds: f64,
    },
}

fn parse_key(text: &str) -> Result<Action, String> {
    let key = match text {
        "space" => ' ',
        _ if text.chars().count() == 1 => text.chars().next().unwrap_or(' '),
        _ => {
            return Err(format!(
                "`{text}`: give one key: W S A L K X T F, or `space`"
            ))
        }
    };
    match action(Key::Char(key)) {
        Some(a @ (Action::Mode(_) | Action::EStop)) => Ok(a),
        _ => Err(format!(
            "`{text}`: give one key: W S A L K X T F, or `space`"
        )),
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let Command::Send { key, seconds } = cli.command;
    if !(seconds.is_finite() && (0.0..=86_400.0).contains(&seconds)) {
        eprintln!("teleop: --for {seconds}: give 0…86400 seconds");
        return ExitCode::from(2);
    }
    let mut bus = match SocketCanBus::open(&cli.bus) {
        Ok(bus) => bus,
        Err(e) => {
            eprintln!("teleop: {e}");
            return ExitCode::FAILURE;
        }
    };
    match send(&mut bus, key, Duration::from_secs_f64(seconds)) {
        Ok(frames) => {
            println!("teleop: sent {frames} frames on {}", cli.bus);
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("teleop: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Presses `key` and keeps the command and heartbeat going for `hold`; frames sent.
fn send(bus: &mut dyn Bus, key: Action, hold: Duration) -> Result<u64, String> {
    let start = Instant::now();
    let mut operator = Operator::new();
    operator.press(0, key);
    let mut sent = 0;
    loop {
        let now_ms = u64::try_from(start.elapsed().as_millis()).unwrap_or(u64::MAX);
        for frame in operator.poll(now_ms).map_err(|e| format!("{e:?}"))? {
            bus.send(&frame).map_err(|e| e.to_string())?;
            sent += 1;
        }
        if start.elapsed() >= hold {
            return Ok(sent);
        }
        std::thread::sleep(Duration::from_millis(2));
    }
}
