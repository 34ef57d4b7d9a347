//! For the MCU target only: links the image with its own linker script, `an386.x` beside this
//! file (the memory map of QEMU's mps2-an386 and the sections cortex-m-rt's start-up code
//! expects), and checks that the input file is given (`PIL_INPUTS`, which `cargo xtask pil`
//! writes). Not cortex-m-rt's `link.x`: that includes `memory.x`, and the linker would find the
//! board's, in the workspace root, first.

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=an386.x");
    println!("cargo:rerun-if-env-changed=PIL_INPUTS");
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    if std::env::var_os("PIL_INPUTS").is_none() {
        println!("cargo:warning=firmware-pil is built by `cargo xtask pil` (it sets PIL_INPUTS)");
        std::process::exit(1);
    }
    let Ok(dir) = std::env::var("CARGO_MANIFEST_DIR") else {
        println!("cargo:warning=no CARGO_MANIFEST_DIR");
        std::process::exit(1);
    };
    println!("cargo:rustc-link-search={dir}");
    println!("cargo:rustc-link-arg-bins=--nmagic");
    println!("cargo:rustc-link-arg-bins=-Tan386.x");
}
