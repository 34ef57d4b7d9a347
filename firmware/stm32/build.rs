//! Puts the board's memory map (`memory.x` at the workspace root) on the linker path and links
//! with cortex-m-rt's `link.x`, for the MCU target only.

use std::path::PathBuf;

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    let manifest = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap_or_default());
    let memory = manifest.join("..").join("..").join("memory.x");
    let out = PathBuf::from(std::env::var_os("OUT_DIR").unwrap_or_default());
    if let Err(e) = std::fs::copy(&memory, out.join("memory.x")) {
        println!("cargo:warning=cannot copy {}: {e}", memory.display());
        std::process::exit(1);
    }
    println!("cargo:rerun-if-changed={}", memory.display());
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-link-arg-bins=--nmagic");
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
}
