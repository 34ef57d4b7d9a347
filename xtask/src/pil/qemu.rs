//! Running the PIL image in QEMU (`mps2-an386`, `-icount shift=0`, semihosting) and reading
//! what it printed (the lines are described in `firmware/pil/src/main.rs`).

use std::io::Read;
use std::path::Path;
use std::process::{Command, Stdio};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::Frames;

/// QEMU gets this long.
const QEMU_TIMEOUT: Duration = Duration::from_secs(300);

/// Runs the image in QEMU (with a time limit) and returns what it printed.
pub(super) fn run(image: &Path) -> Result<String, String> {
    eprintln!(
        "$ qemu-system-arm -machine mps2-an386 … -icount shift=0 -kernel {}",
        image.display()
    );
    let started = Instant::now();
    let mut child = command(image)
        .spawn()
        .map_err(|e| format!("could not start qemu-system-arm: {e}"))?;
    let stdout = read_all(child.stdout.take().ok_or("no QEMU stdout")?);
    let stderr = read_all(child.stderr.take().ok_or("no QEMU stderr")?);
    let status = loop {
        if let Some(status) = child.try_wait().map_err(|e| e.to_string())? {
            break status;
        }
        if started.elapsed() > QEMU_TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!("QEMU did not finish within {QEMU_TIMEOUT:?}"));
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let text = stdout.join().unwrap_or_default();
    let errors = stderr.join().unwrap_or_default();
    eprintln!("pil: QEMU ran {:.1} s", started.elapsed().as_secs_f64());
    if !status.success() {
        let tail: Vec<&str> = text.lines().rev().take(5).collect();
        return Err(format!(
            "QEMU exited with {status}: {}{}",
            errors.trim(),
            tail.into_iter().rev().collect::<Vec<_>>().join("\n")
        ));
    }
    Ok(text)
}

/// The QEMU command line: the AN386 with a Cortex-M4, no display, monitor or serial port,
/// semihosting to this process's stdout, one instruction per ns of virtual time.
fn command(image: &Path) -> Command {
    let mut cmd = Command::new("qemu-system-arm");
    cmd.args([
        "-machine",
        "mps2-an386",
        "-cpu",
        "cortex-m4",
        "-nographic",
        "-monitor",
        "none",
        "-serial",
        "none",
        "-semihosting-config",
        "enable=on,target=native",
        "-icount",
        "shift=0",
        "-kernel",
    ])
    .arg(image)
    .stdin(Stdio::null())
    .stdout(Stdio::piped())
    .stderr(Stdio::piped());
    cmd
}

/// Reads `stream` to its end on a thread of its own (so that neither pipe fills up).
fn read_all(mut stream: impl Read + Send + 'static) -> JoinHandle<String> {
    std::thread::spawn(move || {
        let mut text = String::new();
        let _ = stream.read_to_string(&mut text);
        text
    })
}

/// What the image printed.
pub(super) struct PilRun {
    /// Calibration: instructions and SysTick ticks.
    pub(super) cal: (u64, u64),
    /// SysTick ticks of reading the timer twice.
    pub(super) base: u64,
    /// Per control step: tick, SysTick ticks, frames sent.
    pub(super) ticks: Vec<(u32, u64, Frames)>,
    /// Peak stack, bytes.
    pub(super) stack: u64,
}

impl PilRun {
    pub(super) fn parse(text: &str) -> Result<Self, String> {
        let mut run = PilRun {
            cal: (0, 0),
            base: 0,
            ticks: Vec::new(),
            stack: 0,
        };
        let mut ended = false;
        for line in text.lines() {
            let words: Vec<&str> = line.split_whitespace().collect();
            let num = |i: usize| -> Result<u64, String> {
                words
                    .get(i)
                    .and_then(|w| w.parse().ok())
                    .ok_or_else(|| format!("bad PIL output line `{line}`"))
            };
            match words.first().copied() {
                Some("PIL-CAL") => run.cal = (num(1)?, num(2)?),
                Some("PIL-BASE") => run.base = num(1)?,
                Some("T") => {
                    let tick = u32::try_from(num(1)?).map_err(|e| e.to_string())?;
                    run.ticks.push((tick, num(2)?, Vec::new()));
                }
                Some("F") => {
                    let id = words
                        .get(1)
                        .and_then(|w| u16::from_str_radix(w, 16).ok())
                        .ok_or_else(|| format!("bad PIL output line `{line}`"))?;
                    let data = unhex(words.get(2).copied().unwrap_or(""))
                        .ok_or_else(|| format!("bad PIL output line `{line}`"))?;
                    run.ticks
                        .last_mut()
                        .ok_or("a frame before the first tick")?
                        .2
                        .push((id, data));
                }
                Some("PIL-STACK") => run.stack = num(1)?,
                Some("PIL-END") => ended = true,
                Some("PIL-FAIL") => return Err(format!("the PIL image failed: {line}")),
                _ => {}
            }
        }
        if !ended {
            return Err("the PIL image stopped before its end mark".into());
        }
        if run.cal.1 == 0 {
            return Err("no calibration from the PIL image".into());
        }
        Ok(run)
    }

    /// Instructions per SysTick tick, from the calibration loop.
    pub(super) fn instructions_per_tick(&self) -> f64 {
        self.cal.0 as f64 / self.cal.1 as f64
    }
}

fn unhex(text: &str) -> Option<Vec<u8>> {
    if text.len() % 2 != 0 {
        return None;
    }
    (0..text.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(text.get(i..i + 2)?, 16).ok())
        .collect()
}
