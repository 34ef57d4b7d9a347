//! `cargo xtask hil`: the hardware-in-the-loop suite (`tests/`, package `hil-tests`) — the
//! firmware and the simulator as two processes on a kernel `vcan` interface.
//!
//! Where this machine can make `vcan` interfaces (root or CAP_NET_ADMIN, the `vcan` module),
//! the suite runs natively. Otherwise it boots a throwaway QEMU VM (`-accel tcg`) with a stock
//! Debian kernel from apt and an initramfs holding busybox, the kernel's `can`, `can-raw`,
//! `can-dev` and `vcan` modules (loaded in that order), `evdev` and `uinput` (a virtual gamepad), iproute2, can-utils, the project's
//! binaries and test binary with their shared libraries (libmujoco too), the models and the
//! scenarios; runs the suite inside, prints it on the console and exits with its status.
//! Everything comes from apt and is cached in `.cache/hil/`.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use crate::util::{cargo, output, root, run as sh};

/// What the suite needs from apt.
const PACKAGES: [&str; 5] = [
    "qemu-system-x86",
    "busybox-static",
    "can-utils",
    "cpio",
    "iproute2",
];
/// The kernel modules, in load order.
const MODULES: [&str; 7] = [
    "net/can/can.ko",
    "net/can/can-raw.ko",
    "drivers/net/can/dev/can-dev.ko",
    "drivers/net/can/vcan.ko",
    // A token-bucket qdisc starves a vcan's transmit queue (`ENOBUFS`), as a bus-off or an
    // overloaded controller does.
    "net/sched/sch_tbf.ko",
    // Input devices: a virtual gamepad (uinput) read as teleop reads a real one (evdev).
    "drivers/input/evdev.ko",
    "drivers/input/misc/uinput.ko",
];
/// Programs copied into the VM from the host's PATH.
const TOOLS: [&str; 5] = ["ip", "tc", "candump", "cansend", "canplayer"];
/// The test `--speed-goal` runs.
const SPEED_TEST: &str = "lockstep_over_vcan";
/// The line the VM prints last: `HIL-EXIT <status>`.
const EXIT_MARK: &str = "HIL-EXIT ";
/// Between these lines the VM prints the suite's candump log, gzip'd and base64'd.
const DUMP_BEGIN: &str = "HIL-CANDUMP-BEGIN";
const DUMP_END: &str = "HIL-CANDUMP-END";

pub fn run(args: &[String]) -> Result<(), String> {
    let force_vm = args.iter().any(|a| a == "--vm");
    // `--speed-goal`: the lockstep speed measurement alone, held to its goal (a benchmark: the
    // ratio swings with the host's load, so the suite only reports it).
    let speed_goal = args.iter().any(|a| a == "--speed-goal");
    // A test-name filter runs part of the suite (`cargo xtask hil flood`); the check of the
    // whole suite's recorded bus is then skipped.
    let filter = if speed_goal {
        Some(SPEED_TEST.to_owned())
    } else {
        args.iter().find(|a| !a.starts_with("--")).cloned()
    };
    let goal = if speed_goal { "1" } else { "0" };
    crate::setup::run()?;
    crate::apt::ensure(&PACKAGES, "the vcan suite (cargo xtask hil)")?;
    sh(cargo().args([
        "build",
        "--release",
        "-p",
        "sim-host",
        "-p",
        "firmware-host",
        "-p",
        "teleop",
    ]))?;
    let suite = build_suite()?;
    if !force_vm && native_vcan() {
        eprintln!("hil: this kernel has vcan: running natively");
        let export = root().join(".cache").join("hil").join("export");
        let _ = std::fs::remove_dir_all(&export);
        for binary in &suite {
            sh(Command::new(binary)
                .args(filter.iter())
                .args(["--test-threads", "2", "--show-output"])
                .env("HIL_BIN_DIR", crate::util::target_dir().join("release"))
                .env("HIL_EXPORT_DIR", &export)
                .env("HIL_SPEED_GOAL", goal))?;
        }
        if filter.is_some() {
            return Ok(());
        }
        return cantools_check(&export.join("candump.log"));
    }
    eprintln!("hil: no vcan here: running the suite in a QEMU VM");
    let kernel = kernel()?;
    let initrd = initramfs(&kernel, &suite, filter.as_deref().unwrap_or(""), goal)?;
    let log = root().join(".cache").join("hil").join("candump.log");
    boot(&kernel.vmlinuz, &initrd, &log)?;
    if filter.is_some() {
        return Ok(());
    }
    cantools_check(&log)
}

/// Decodes a `candump -L` log of the suite with Python `cantools` and the project's DBC: every
/// frame must decode.
fn cantools_check(log: &Path) -> Result<(), String> {
    if !log.exists() {
        return Err(format!(
            "the suite left no candump log at {} for the cantools check",
            log.display()
        ));
    }
    let script = "import sys, cantools\n\
        from cantools.logreader import Parser\n\
        db = cantools.database.load_file(sys.argv[1])\n\
        n = bad = 0\n\
        with open(sys.argv[2]) as f:\n\
        \x20   for frame in Parser(f):\n\
        \x20       n += 1\n\
        \x20       try:\n\
        \x20           db.decode_message(frame.frame_id, frame.data)\n\
        \x20       except Exception as e:\n\
        \x20           bad += 1\n\
        \x20           print('cannot decode', hex(frame.frame_id), frame.data.hex(), e)\n\
        print(f'cantools: {n} frames from candump -L, {bad} failed to decode')\n\
        sys.exit(1 if bad or n < 3000 else 0)\n";
    sh(Command::new(crate::setup::venv_python())
        .args(["-c", script])
        .arg(root().join("protocol").join("hybrid_robot.dbc"))
        .arg(log))
    .map_err(|e| format!("{e}: the recorded bus does not decode with the DBC"))
}

/// Builds the suite's test binaries in release; their paths.
fn build_suite() -> Result<Vec<PathBuf>, String> {
    let out = output(cargo().args([
        "test",
        "--release",
        "-p",
        "hil-tests",
        "--no-run",
        "--message-format=json",
    ]))
    .ok_or(
        "could not build the hil-tests suite (run `cargo test -p hil-tests --no-run` to see why)",
    )?;
    let suites: Vec<PathBuf> = out
        .lines()
        .filter(|line| line.contains("\"kind\":[\"test\"]") && line.contains("\"executable\":\""))
        .filter_map(|line| {
            let start = line.find("\"executable\":\"")? + "\"executable\":\"".len();
            let end = start + line.get(start..)?.find('"')?;
            line.get(start..end).map(PathBuf::from)
        })
        .collect();
    if suites.is_empty() {
        Err("cargo did not report the hil-tests test binaries".into())
    } else {
        Ok(suites)
    }
}

/// Whether this machine can make a vcan interface.
fn native_vcan() -> bool {
    let probe = "hilprobe0";
    let made = Command::new("ip")
        .args(["link", "add", "dev", probe, "type", "vcan"])
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if made {
        let _ = Command::new("ip")
            .args(["link", "del", "dev", probe])
            .status();
    }
    made
}

struct Kernel {
    vmlinuz: PathBuf,
    modules: PathBuf,
}

/// The Debian kernel `linux-image-amd64` depends on, unpacked in `.cache/hil/kernel`.
fn kernel() -> Result<Kernel, String> {
    let cache = root().join(".cache").join("hil");
    let dir = cache.join("kernel");
    let depends = output(Command::new("apt-cache").args(["depends", "linux-image-amd64"]))
        .ok_or("`apt-cache depends linux-image-amd64` failed: is this a Debian system with apt?")?;
    let package = depends
        .lines()
        .find_map(|l| l.trim().strip_prefix("Depends: linux-image-"))
        .map(|rest| format!("linux-image-{rest}"))
        .ok_or("no linux-image package behind linux-image-amd64")?;
    let version = package.trim_start_matches("linux-image-");
    let vmlinuz = dir.join("boot").join(format!("vmlinuz-{version}"));
    let modules = dir.join("lib").join("modules").join(version).join("kernel");
    if !vmlinuz.exists() {
        std::fs::create_dir_all(&cache).map_err(|e| format!("{}: {e}", cache.display()))?;
        eprintln!("hil: fetching {package} (~70 MB, once)");
        sh(Command::new("apt-get")
            .args(["download", "-q", &package])
            .current_dir(&cache))?;
        let deb = std::fs::read_dir(&cache)
            .map_err(|e| e.to_string())?
            .filter_map(Result::ok)
            .map(|e| e.path())
            .find(|p| {
                p.file_name()
                    .is_some_and(|n| n.to_string_lossy().starts_with(&format!("{package}_")))
            })
            .ok_or("apt-get download left no .deb")?;
        sh(Command::new("dpkg-deb").arg("-x").arg(&deb).arg(&dir))?;
        let _ = std::fs::remove_file(&deb);
    }
    Ok(Kernel { vmlinuz, modules })
}

/// Copies `file` to the same path under `root_dir`.
fn copy_to(root_dir: &Path, file: &Path) -> Result<(), String> {
    let target = root_dir.join(file.strip_prefix("/").unwrap_or(file));
    if let Some(parent) = target.parent() {
        std::fs::create_dir_all(parent).map_err(|e| format!("{}: {e}", parent.display()))?;
    }
    std::fs::copy(file, &target)
        .map(|_| ())
        .map_err(|e| format!("copy {}: {e}", file.display()))
}

/// Copies a program and every shared library `ldd` names for it.
fn copy_with_libraries(root_dir: &Path, program: &Path) -> Result<(), String> {
    copy_to(root_dir, program)?;
    let libraries = output(Command::new("ldd").arg(program)).unwrap_or_default();
    for word in libraries.split_whitespace().filter(|w| w.starts_with('/')) {
        let path = PathBuf::from(word);
        let real = std::fs::canonicalize(&path).unwrap_or(path.clone());
        copy_to(root_dir, &real)?;
        if real != path {
            copy_to(root_dir, &path).or_else(|_| copy_to(root_dir, &real))?;
            let target = root_dir.join(path.strip_prefix("/").unwrap_or(&path));
            let _ = std::fs::remove_file(&target);
            std::fs::copy(&real, &target).map_err(|e| e.to_string())?;
        }
    }
    Ok(())
}

fn which(name: &str) -> Result<PathBuf, String> {
    output(Command::new("sh").args(["-c", &format!("command -v {name}")]))
        .map(|s| PathBuf::from(s.trim()))
        .filter(|p| p.is_absolute())
        .ok_or_else(|| format!("`{name}` is not installed"))
}

fn copy_tree(from: &Path, root_dir: &Path) -> Result<(), String> {
    for entry in std::fs::read_dir(from).map_err(|e| format!("{}: {e}", from.display()))? {
        let path = entry.map_err(|e| e.to_string())?.path();
        if path.is_dir() {
            copy_tree(&path, root_dir)?;
        } else {
            copy_to(root_dir, &path)?;
        }
    }
    Ok(())
}

/// Builds `.cache/hil/initrd.gz`.
fn initramfs(
    kernel: &Kernel,
    suite: &[PathBuf],
    filter: &str,
    speed_goal: &str,
) -> Result<PathBuf, String> {
    let cache = root().join(".cache").join("hil");
    let dir = cache.join("root");
    let _ = std::fs::remove_dir_all(&dir);
    for sub in ["bin", "proc", "sys", "dev", "tmp", "lib/modules", "run"] {
        std::fs::create_dir_all(dir.join(sub)).map_err(|e| e.to_string())?;
    }
    std::fs::copy(which("busybox")?, dir.join("bin/busybox")).map_err(|e| e.to_string())?;
    for applet in [
        "sh", "mount", "insmod", "poweroff", "echo", "cat", "ls", "sleep", "mkdir", "kill", "rm",
        "env", "uname", "head", "tail", "grep", "date", "true", "renice",
    ] {
        std::os::unix::fs::symlink("busybox", dir.join("bin").join(applet))
            .map_err(|e| e.to_string())?;
    }
    for module in MODULES {
        let from = kernel.modules.join(module);
        let name = Path::new(module).file_name().ok_or("module name")?;
        std::fs::copy(&from, dir.join("lib/modules").join(name))
            .map_err(|e| format!("{}: {e}", from.display()))?;
    }
    for tool in TOOLS {
        copy_with_libraries(&dir, &which(tool)?)?;
    }
    let release = crate::util::target_dir().join("release");
    for program in ["sim-host", "firmware-host", "teleop"] {
        copy_with_libraries(&dir, &release.join(program))?;
    }
    for binary in suite {
        copy_with_libraries(&dir, binary)?;
    }
    copy_tree(&root().join("sim-host").join("models"), &dir)?;
    copy_tree(&root().join("scenarios"), &dir)?;
    let tool_dirs: Vec<String> = TOOLS
        .iter()
        .filter_map(|t| which(t).ok())
        .filter_map(|p| p.parent().map(|d| d.display().to_string()))
        .collect();
    let modules = MODULES
        .iter()
        .filter_map(|m| Path::new(m).file_name())
        .map(|n| format!("/lib/modules/{}", n.to_string_lossy()))
        .collect::<Vec<_>>()
        .join(" ");
    let init = format!(
        "#!/bin/sh\n\
         export PATH=/bin:{tools}\n\
         mount -t proc proc /proc; mount -t sysfs sys /sys; mount -t devtmpfs dev /dev\n\
         for m in {modules}; do insmod $m || echo \"hil: insmod $m failed\"; done\n\
         echo 4194304 > /proc/sys/net/core/rmem_max\n\
         echo \"hil: kernel $(uname -r), $(grep -c processor /proc/cpuinfo) CPUs\"\n\
         status=0\n\
         for suite in {suite}; do HIL_BIN_DIR={release} HIL_EXPORT_DIR=/export HIL_SPEED_GOAL={speed_goal} $suite {filter} --test-threads 2 --show-output || status=1; done\n\
         if [ -f /export/candump.log ]; then echo {begin}; gzip -c /export/candump.log | base64; echo {end}; fi\n\
         echo \"{mark}$status\"\n\
         poweroff -f\n",
        tools = tool_dirs.join(":"),
        release = release.display(),
        suite = suite
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(" "),
        mark = EXIT_MARK,
        filter = filter,
        begin = DUMP_BEGIN,
        end = DUMP_END,
    );
    let init_path = dir.join("init");
    std::fs::write(&init_path, init).map_err(|e| e.to_string())?;
    sh(Command::new("chmod").arg("+x").arg(&init_path))?;
    let initrd = cache.join("initrd.gz");
    sh(Command::new("sh").args([
        "-c",
        &format!(
            "cd '{}' && find . | cpio -o -H newc --quiet | gzip -1 > '{}'",
            dir.display(),
            initrd.display()
        ),
    ]))?;
    Ok(initrd)
}

/// Boots the VM, streams its console (but for the candump log, which goes to `log`), returns
/// the suite's status.
fn boot(vmlinuz: &Path, initrd: &Path, log: &Path) -> Result<(), String> {
    let mut child = Command::new("qemu-system-x86_64")
        // `-cpu max`: libmujoco uses AVX, which the default qemu64 model lacks (SIGILL).
        .args([
            "-accel", "tcg", "-cpu", "max", "-m", "3072", "-smp", "2", "-kernel",
        ])
        .arg(vmlinuz)
        .arg("-initrd")
        .arg(initrd)
        .args([
            "-append",
            "console=ttyS0 quiet panic=-1",
            "-nographic",
            "-no-reboot",
        ])
        .stdout(Stdio::piped())
        .stdin(Stdio::null())
        .spawn()
        .map_err(|e| {
            format!("cannot start qemu-system-x86_64: {e} (apt-get install qemu-system-x86)")
        })?;
    let stdout = child.stdout.take().ok_or("no console")?;
    let mut status = None;
    let mut dump: Option<String> = None;
    for line in BufReader::new(stdout).lines().map_while(Result::ok) {
        let trimmed = line.trim();
        if trimmed == DUMP_BEGIN {
            dump = Some(String::new());
            continue;
        }
        if trimmed == DUMP_END {
            if let Some(text) = dump.take() {
                save_dump(&text, log)?;
            }
            continue;
        }
        if let Some(text) = dump.as_mut() {
            text.push_str(trimmed);
            continue;
        }
        println!("{line}");
        if let Some(code) = trimmed.strip_prefix(EXIT_MARK) {
            status = code.trim().parse::<i32>().ok();
        }
    }
    let _ = child.wait();
    match status {
        Some(0) => Ok(()),
        Some(code) => Err(format!("the vcan suite failed in the VM (exit {code})")),
        None => {
            Err("the VM ended without reporting the suite's result (see its console above)".into())
        }
    }
}

/// Writes the VM's base64'd, gzip'd log to `log`, decoded with the system's base64 and gzip.
fn save_dump(base64_text: &str, log: &Path) -> Result<(), String> {
    let encoded = log.with_extension("gz.b64");
    std::fs::write(&encoded, base64_text).map_err(|e| format!("{}: {e}", encoded.display()))?;
    sh(Command::new("sh").args([
        "-c",
        &format!(
            "base64 -d '{}' | gzip -dc > '{}'",
            encoded.display(),
            log.display()
        ),
    ]))
}
