//! The MuJoCo library for `sim-host`: `libmujoco.so.3.17.0` from the official PyPI wheel
//! `mujoco==3.17.0`, fetched with pip into `.cache/mujoco/`, checked against pinned SHA-256 sums,
//! and linked through `MUJOCO_DYNAMIC_LINK_DIR` (set in `.cargo/config.toml`). `sim-host`'s
//! build script adds an rpath to that folder, so binaries and tests find the library without
//! `LD_LIBRARY_PATH`.

use std::path::PathBuf;
use std::process::Command;

use crate::setup::venv_python;
use crate::util::{root, run as sh};

/// The MuJoCo release `mujoco-rs =7.0.0` binds.
const VERSION: &str = "3.17.0";
/// The wheel pip picks for the pinned interpreter and platform below; pinning both makes the
/// download (and so its checksum) the same on every machine.
const WHEEL: &str = "mujoco-3.17.0-cp311-cp311-manylinux_2_27_x86_64.manylinux_2_28_x86_64.whl";
const WHEEL_SHA256: &str = "d66928d86a2d1b601bbaa4dc11db50214d17d5301bb8afd84721313b67ff0874";
const LIBRARY: &str = "libmujoco.so.3.17.0";
const LIBRARY_SHA256: &str = "23496b023ee80fb61ab71167e94bc649f9941710fde96b18bb8204fb332523ad";

/// Where the library lives (the folder `MUJOCO_DYNAMIC_LINK_DIR` names).
pub fn lib_dir() -> PathBuf {
    root().join(".cache").join("mujoco").join("lib")
}

/// Makes sure `.cache/mujoco/lib/libmujoco.so` is the pinned library; fetches it when not.
pub fn ensure() -> Result<(), String> {
    if !cfg!(all(target_os = "linux", target_arch = "x86_64")) {
        return Err("the simulator's MuJoCo setup supports x86_64 Linux only".into());
    }
    let dir = lib_dir();
    let library = dir.join(LIBRARY);
    let link = dir.join("libmujoco.so");
    if library.is_file() && sha256(&library)? == LIBRARY_SHA256 && link.exists() {
        return Ok(());
    }
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let wheel_dir = root().join(".cache").join("mujoco").join("wheel");
    let wheel = wheel_dir.join(WHEEL);
    if !(wheel.is_file() && sha256(&wheel)? == WHEEL_SHA256) {
        eprintln!("setup: fetching MuJoCo {VERSION} (PyPI wheel, ~7 MB)");
        sh(Command::new(venv_python())
            .args([
                "-m",
                "pip",
                "download",
                "--quiet",
                "--disable-pip-version-check",
                "--no-deps",
                "--only-binary=:all:",
                "--python-version",
                "3.11",
                "--platform",
                "manylinux_2_28_x86_64",
                &format!("mujoco=={VERSION}"),
                "-d",
            ])
            .arg(&wheel_dir))
        .map_err(|e| {
            format!("{e}\nthe MuJoCo wheel comes from PyPI: check that pip can reach it")
        })?;
    }
    let got = sha256(&wheel)?;
    if got != WHEEL_SHA256 {
        return Err(format!(
            "{} has SHA-256 {got}, expected {WHEEL_SHA256}: delete it and rerun `cargo xtask setup`",
            wheel.display()
        ));
    }
    python(&format!(
        "import zipfile,sys\nwith zipfile.ZipFile(sys.argv[1]) as z:\n    \
         open(sys.argv[2],'wb').write(z.read('mujoco/{LIBRARY}'))"
    ))
    .arg(&wheel)
    .arg(&library)
    .status()
    .map_err(|e| format!("cannot run the venv's python: {e}"))?
    .success()
    .then_some(())
    .ok_or_else(|| {
        format!(
            "could not extract mujoco/{LIBRARY} from {}",
            wheel.display()
        )
    })?;
    let got = sha256(&library)?;
    if got != LIBRARY_SHA256 {
        return Err(format!(
            "{} has SHA-256 {got}, expected {LIBRARY_SHA256}",
            library.display()
        ));
    }
    let _ = std::fs::remove_file(&link);
    std::os::unix::fs::symlink(LIBRARY, &link)
        .map_err(|e| format!("cannot create {}: {e}", link.display()))?;
    eprintln!("setup: MuJoCo {VERSION} in {}", dir.display());
    Ok(())
}

fn python(script: &str) -> Command {
    let mut cmd = Command::new(venv_python());
    cmd.args(["-c", script]);
    cmd
}

fn sha256(path: &std::path::Path) -> Result<String, String> {
    let out = python(
        "import hashlib,sys\nprint(hashlib.sha256(open(sys.argv[1],'rb').read()).hexdigest())",
    )
    .arg(path)
    .output()
    .map_err(|e| format!("cannot run the venv's python: {e}"))?;
    if !out.status.success() {
        return Err(format!("cannot hash {}", path.display()));
    }
    Ok(String::from_utf8_lossy(&out.stdout).trim().to_owned())
}
