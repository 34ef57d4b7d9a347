//! Debian packages the project needs from the system (what pip and rustup cannot provide):
//! checked with `dpkg-query`, installed with `apt-get` when this user may (root, or password-less
//! sudo), otherwise an error that names the command to run.

use std::process::Command;

use crate::util::{output, run as sh};

/// Mesa's EGL and software OpenGL: headless rendering of the simulation (`renderer` feature).
pub const RENDERING: [&str; 3] = ["libegl1", "libegl-mesa0", "libgl1-mesa-dri"];

/// Makes sure `packages` are installed; `why` says what they are for, in the error.
pub fn ensure(packages: &[&str], why: &str) -> Result<(), String> {
    let missing: Vec<&str> = packages.iter().copied().filter(|p| !installed(p)).collect();
    if missing.is_empty() {
        return Ok(());
    }
    let list = missing.join(" ");
    let advice = format!("{why} needs the Debian packages: sudo apt-get install {list}");
    let prefix: Vec<&str> = if is_root() {
        Vec::new()
    } else if output(Command::new("sudo").args(["-n", "true"])).is_some() {
        vec!["sudo", "-n"]
    } else {
        return Err(advice);
    };
    eprintln!("setup: installing {list} ({why})");
    let apt = |args: &[&str]| {
        let mut cmd = Command::new(prefix.first().copied().unwrap_or("apt-get"));
        cmd.args(prefix.iter().skip(1));
        if !prefix.is_empty() {
            cmd.arg("apt-get");
        }
        cmd.args(args).env("DEBIAN_FRONTEND", "noninteractive");
        cmd
    };
    let mut install = vec!["install", "-y", "--no-install-recommends"];
    install.extend(missing.iter().copied());
    if sh(&mut apt(&install)).is_err() {
        // A fresh machine may have no package lists yet.
        sh(&mut apt(&["update"])).map_err(|e| format!("{e}\n{advice}"))?;
        sh(&mut apt(&install)).map_err(|e| format!("{e}\n{advice}"))?;
    }
    Ok(())
}

fn installed(package: &str) -> bool {
    output(Command::new("dpkg-query").args(["-W", "-f=${Status}", package]))
        .is_some_and(|status| status.contains("install ok installed"))
}

fn is_root() -> bool {
    output(Command::new("id").arg("-u")).is_some_and(|uid| uid.trim() == "0")
}
