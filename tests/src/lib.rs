//! Hardware-in-the-loop suite over SocketCAN `vcan`.
//!
//! The firmware (`firmware-host`) and the simulator (`sim-host`) run as separate processes
//! that share nothing but a kernel CAN interface. Each test makes its own `vcan` interface, so
//! tests run in parallel and never touch a real `can0`. It needs root (or CAP_NET_ADMIN) and the
//! kernel's `vcan` module: `cargo xtask hil` runs it natively where that is so, and otherwise
//! in a QEMU VM with a stock Debian kernel. Without them a test fails and says what is missing.
//!
//! Binaries come from `HIL_BIN_DIR` (default: the workspace's `target/release`).
// Functions stay short enough to read whole (clippy.toml: 80 lines); tests may run longer.
#![cfg_attr(not(test), warn(clippy::too_many_lines))]

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::{Duration, Instant};

use host_can::socketcan_bus::RECEIVE_BUFFER_BYTES;

/// The workspace root.
pub fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default()
}

/// A program of this project or of can-utils: from `HIL_BIN_DIR`, else `target/release`, else
/// the `PATH` (can-utils).
pub fn program(name: &str) -> PathBuf {
    let dir = std::env::var_os("HIL_BIN_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace().join("target").join("release"));
    let local = dir.join(name);
    if local.exists() {
        local
    } else {
        PathBuf::from(name)
    }
}

/// A `vcan` interface of this test, removed when dropped, with the state file of the
/// controller on it (see [`Vcan::state_file`]).
#[derive(Debug)]
pub struct Vcan {
    name: String,
}

static NEXT: AtomicU32 = AtomicU32::new(0);

impl Vcan {
    /// Creates `vcanhil<pid>_<n>` (CAN FD MTU, up). Panics with what to do when it cannot.
    pub fn new() -> Self {
        let name = format!(
            "vh{}_{}",
            std::process::id() % 100_000,
            NEXT.fetch_add(1, Ordering::Relaxed)
        );
        let ip = |args: &[&str]| {
            Command::new("ip")
                .args(args)
                .output()
                .map_err(|e| format!("cannot run `ip` (iproute2): {e}"))
                .and_then(|out| {
                    if out.status.success() {
                        Ok(())
                    } else {
                        Err(String::from_utf8_lossy(&out.stderr).trim().to_owned())
                    }
                })
        };
        if let Err(e) = ip(&["link", "add", "dev", &name, "type", "vcan"]) {
            panic!(
                "cannot create a vcan interface ({e}). This suite needs root (or CAP_NET_ADMIN) and \
                 the kernel's vcan module (`sudo modprobe vcan`); `cargo xtask hil` runs it in a \
                 QEMU VM where the host has neither."
            );
        }
        for args in [
            vec!["link", "set", "dev", name.as_str(), "mtu", "72"],
            vec!["link", "set", "dev", name.as_str(), "up"],
        ] {
            if let Err(e) = ip(&args) {
                panic!("cannot set up {name}: {e}");
            }
        }
        let bus = Self { name };
        // A state file left by an earlier run of the same name would start the controller in
        // its epoch, or latched.
        let _ = std::fs::remove_file(bus.state_file());
        bus
    }

    /// Puts a token-bucket qdisc on the interface's transmit queue that passes `rate` (a `tc`
    /// rate, e.g. `8kbit`): a sender faster than that finds the queue full (`ENOBUFS`), as on a
    /// bus that is off or saturated. Panics with what to do when `tc` or `sch_tbf` is missing.
    pub fn starve(&self, rate: &str) {
        let out = Command::new("tc")
            .args(["qdisc", "add", "dev", &self.name, "root", "tbf"])
            .args(["rate", rate, "burst", "1600", "latency", "20ms"])
            .output()
            .unwrap_or_else(|e| panic!("cannot run `tc` (iproute2): {e}"));
        assert!(
            out.status.success(),
            "cannot starve {} with a tbf qdisc: {} (needs the kernel's sch_tbf module)",
            self.name,
            String::from_utf8_lossy(&out.stderr).trim()
        );
    }

    /// The interface name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Where the controller on this bus keeps its session epoch and E-stop latch
    /// (`firmware-host --state-file`): a firmware restarted on the same bus opens a greater
    /// epoch, as the real controller does. Removed with the interface.
    pub fn state_file(&self) -> PathBuf {
        std::env::temp_dir().join(format!("hil-{}-firmware-host.toml", self.name))
    }
}

impl Default for Vcan {
    fn default() -> Self {
        Self::new()
    }
}

impl Drop for Vcan {
    fn drop(&mut self) {
        let _ = Command::new("ip")
            .args(["link", "del", "dev", &self.name])
            .status();
        let _ = std::fs::remove_file(self.state_file());
    }
}

/// A child process killed (SIGTERM, then SIGKILL) when dropped.
#[derive(Debug)]
pub struct Process {
    child: Child,
    name: String,
}

impl Process {
    /// Starts `program` with `args`, its output to this test's output.
    pub fn start(program_name: &str, args: &[&str]) -> Self {
        let child = Command::new(program(program_name))
            .args(args)
            .stdout(Stdio::inherit())
            .stderr(Stdio::inherit())
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {program_name}: {e} (build it: cargo build --release -p {program_name})"));
        Self {
            child,
            name: program_name.to_owned(),
        }
    }

    /// Waits for the process to exit by itself, at most `timeout`; its exit status.
    pub fn wait(mut self, timeout: Duration) -> std::process::ExitStatus {
        let started = Instant::now();
        loop {
            if let Ok(Some(status)) = self.child.try_wait() {
                return status;
            }
            if started.elapsed() > timeout {
                panic!("{} did not finish within {timeout:?}", self.name);
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// Kills the process outright (SIGKILL), as a crash would: no goodbye frames.
    pub fn kill(mut self) -> std::process::ExitStatus {
        let _ = self.child.kill();
        self.child
            .wait()
            .unwrap_or_else(|e| panic!("{}: {e}", self.name))
    }

    /// Whether the process is still running.
    pub fn running(&mut self) -> bool {
        matches!(self.child.try_wait(), Ok(None))
    }

    /// Presses Ctrl-C (SIGINT) and waits for the process to exit, at most 5 s (then kills
    /// it): its exit status, `None` if it had to be killed, and how long it took to exit.
    pub fn interrupt(mut self) -> (Option<std::process::ExitStatus>, Duration) {
        let _ = Command::new("kill")
            .args(["-INT", &self.child.id().to_string()])
            .status();
        let started = Instant::now();
        loop {
            if let Ok(Some(status)) = self.child.try_wait() {
                return (Some(status), started.elapsed());
            }
            if started.elapsed() > Duration::from_secs(5) {
                let _ = self.child.kill();
                let _ = self.child.wait();
                return (None, started.elapsed());
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    /// Asks the process to stop (SIGTERM) and waits for it.
    pub fn terminate(mut self) -> std::process::ExitStatus {
        let _ = Command::new("kill")
            .args(["-TERM", &self.child.id().to_string()])
            .status();
        let started = Instant::now();
        loop {
            if let Ok(Some(status)) = self.child.try_wait() {
                return status;
            }
            if started.elapsed() > Duration::from_secs(5) {
                let _ = self.child.kill();
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

impl Drop for Process {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// A fresh output folder for a test.
pub fn out_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hil-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// The firmware in lockstep on `bus`, keeping its state in the bus's state file.
pub fn firmware(bus: &Vcan) -> Process {
    firmware_with_state(bus, &bus.state_file())
}

/// The firmware in lockstep on `bus`, keeping its state in `state` (another bus's state file:
/// the same controller, restarted on another bus).
pub fn firmware_with_state(bus: &Vcan, state: &Path) -> Process {
    let state = state.to_string_lossy();
    Process::start(
        "firmware-host",
        &[
            "--bus",
            bus.name(),
            "--clock",
            "lockstep",
            "--idle-timeout-s",
            "20",
            "--state-file",
            &state,
        ],
    )
}

/// The firmware on its own wall clock at 250 Hz on `bus`, as on the microcontroller.
pub fn firmware_on_wall_clock(bus: &Vcan) -> Process {
    let state = bus.state_file();
    Process::start(
        "firmware-host",
        &[
            "--bus",
            bus.name(),
            "--clock",
            "wall",
            "--control-hz",
            "250",
            "--state-file",
            &state.to_string_lossy(),
        ],
    )
}

/// Starts `sim-host run` on `bus` (an interface, or `inproc`) writing to `out`, without plots
/// or progress bar, with `args` added.
///
/// Unless `args` set it, a lockstep cycle waits up to 1 s for the firmware's command instead of
/// the default 100 ms: the VM's emulated CPUs are shared by the simulator, the firmware and
/// candump, and a process there can be descheduled for longer than 100 ms. Waiting costs a
/// lockstep run nothing, while a cycle stepped without the command is a real divergence that
/// the tests count.
pub fn start_sim(bus: &str, out: &Path, args: &[&str]) -> Process {
    let out_text = out.to_string_lossy().into_owned();
    let mut all = vec![
        "run",
        "--bus",
        bus,
        "--no-plots",
        "--no-progress",
        "--out",
        &out_text,
    ];
    if !args.contains(&"--reply-timeout-ms") {
        all.extend_from_slice(&["--reply-timeout-ms", "1000"]);
    }
    all.extend_from_slice(args);
    Process::start("sim-host", &all)
}

/// Runs `sim-host run` on `bus` with `args`; returns the parsed `summary.json` if it wrote one.
pub fn simulate(bus: &Vcan, out: &Path, args: &[&str]) -> Option<serde_json::Value> {
    let status = start_sim(bus.name(), out, args).wait(Duration::from_secs(600));
    assert!(status.success(), "sim-host failed: {status}");
    std::fs::read_to_string(out.join("summary.json"))
        .ok()
        .and_then(|text| serde_json::from_str(&text).ok())
}

/// A number of segment `index` of a summary.
pub fn figure(summary: &serde_json::Value, index: usize, key: &str) -> f64 {
    summary["segments"][index][key]
        .as_f64()
        .unwrap_or_else(|| panic!("summary has no segments[{index}].{key}: {summary}"))
}

/// An acceptance scenario file.
pub fn scenario(name: &str) -> String {
    workspace()
        .join("scenarios/acceptance")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

/// Sends `frame` with can-utils' `cansend`.
pub fn cansend(bus: &Vcan, frame: &protocol::Frame) {
    let status = Command::new(program("cansend"))
        .args([bus.name(), &host_can::candump::cansend_text(frame)])
        .status()
        .unwrap_or_else(|e| panic!("cannot run cansend (can-utils): {e}"));
    assert!(status.success(), "cansend failed: {status}");
}

/// Starts `candump -L <bus>` writing to `path`.
pub fn candump(bus: &Vcan, path: &Path) -> Process {
    candump_filtered(bus, path, "")
}

/// Starts `candump -L <bus><filter>` writing to `path`; `filter` in candump's notation, e.g.
/// `,200~7FF` for everything but id 0x200. Its socket buffer is as large as the nodes' (see
/// `host_can::socketcan_bus::RECEIVE_BUFFER_BYTES`): the log is the tests' evidence, and a
/// candump descheduled on a busy VM must not drop what the nodes received.
pub fn candump_filtered(bus: &Vcan, path: &Path, filter: &str) -> Process {
    let file = std::fs::File::create(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let child = Command::new(program("candump"))
        .args(["-L", "-r", &RECEIVE_BUFFER_BYTES.to_string()])
        .arg(format!("{}{filter}", bus.name()))
        .stdout(file)
        .spawn()
        .unwrap_or_else(|e| panic!("cannot run candump (can-utils): {e}"));
    Process::from_child(child, "candump")
}

impl Process {
    /// Wraps a started child.
    pub fn from_child(child: Child, name: &str) -> Self {
        Self {
            child,
            name: name.to_owned(),
        }
    }
}

/// The frames of a `candump -L` log: `(time s, frame)`; a complete line that is not a CAN FD
/// frame of this project's form panics with the line.
pub fn read_candump(path: &Path) -> Vec<(f64, protocol::Frame)> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    host_can::candump::read_log(&text)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .into_iter()
        .map(|logged| (logged.time_s, logged.frame))
        .collect()
}

/// The rows of a `telemetry.csv` as `(time s, wheel torques N·m, mode)`.
pub fn read_telemetry(path: &Path) -> Vec<(f64, [f64; 2], String)> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("no column {name}"))
    };
    let (t, left, right, mode) = (
        col("time_s"),
        col("wheel_left_torque_nm"),
        col("wheel_right_torque_nm"),
        col("mode"),
    );
    lines
        .map(|line| {
            let cells: Vec<&str> = line.split(',').collect();
            let num = |i: usize| {
                cells
                    .get(i)
                    .and_then(|c| c.parse::<f64>().ok())
                    .unwrap_or(f64::NAN)
            };
            (
                num(t),
                [num(left), num(right)],
                cells.get(mode).copied().unwrap_or("").to_owned(),
            )
        })
        .collect()
}

/// The controller's session as its announcement in `frames` gives it (the last one), with the
/// test key: what a keyholder's tool seals its frames in. `None` before an announcement.
pub fn announced_session(frames: &[(f64, protocol::Frame)]) -> Option<protocol::Session> {
    frames.iter().rev().find_map(|(_, frame)| {
        match protocol::decode_frame(frame.id(), frame.data()).map(|d| d.message) {
            Ok(protocol::AnyMessage::Announce(announce)) => {
                Some(protocol::Session::owned(protocol::TEST_KEY, announce.epoch))
            }
            _ => None,
        }
    })
}

/// Polls the `candump` log at `path` every 20 ms until `seen` holds for its frames, at most
/// `timeout`; whether it did.
pub fn wait_for_log(
    path: &Path,
    timeout: Duration,
    seen: impl Fn(&[(f64, protocol::Frame)]) -> bool,
) -> bool {
    let found = |frames: &[(f64, protocol::Frame)]| seen(frames).then_some(());
    find_in_log(path, timeout, Duration::from_millis(20), found).is_some()
}

/// Polls the `candump` log at `path` every `every` until `find` finds something in its frames,
/// at most `timeout`; what it found. A slow poll spares the CPUs a long wait shares with the
/// processes it watches: each poll reads and decodes the whole log.
pub fn find_in_log<T>(
    path: &Path,
    timeout: Duration,
    every: Duration,
    find: impl Fn(&[(f64, protocol::Frame)]) -> Option<T>,
) -> Option<T> {
    let started = Instant::now();
    while started.elapsed() < timeout {
        std::thread::sleep(every);
        if let Some(found) = find(&read_candump(path)) {
            return Some(found);
        }
    }
    None
}

/// A test that measures timing holds this for its whole run, so that the tests of its file run
/// one at a time: in an emulated VM a second closed loop beside it would starve the simulator
/// and the firmware of CPU and skew the figure (a test binary is one process, so this orders
/// the tests of one file).
pub fn one_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());
    ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}
