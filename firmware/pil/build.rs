//! Links the image with the AN386 linker script that `cargo xtask pil` generates (its path in
//! `PIL_LINK_X`), for the MCU target only. Not cortex-m-rt's `link.x`: that includes
//! `memory.x`, and the linker would find the board's, in the workspace root, first.

use std::path::PathBuf;

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=PIL_LINK_X");
    println!("cargo:rerun-if-env-changed=PIL_INPUTS");
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    let Some(script) = std::env::var_os("PIL_LINK_X").map(PathBuf::from) else {
        println!(
            "cargo:warning=firmware-pil is built by `cargo xtask pil` (it sets PIL_LINK_X and \
             PIL_INPUTS)"
        );
        std::process::exit(1);
    };
    let out = PathBuf::from(std::env::var_os("OUT_DIR").unwrap_or_default());
    if let Err(e) = std::fs::copy(&script, out.join("pil.x")) {
        println!("cargo:warning=cannot copy {}: {e}", script.display());
        std::process::exit(1);
    }
    println!("cargo:rerun-if-changed={}", script.display());
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-link-arg-bins=--nmagic");
    println!("cargo:rustc-link-arg-bins=-Tpil.x");
}
