//! Lets binaries and tests find `libmujoco.so` at run time without `LD_LIBRARY_PATH`: an rpath
//! to the folder `cargo xtask setup` fills (named by `MUJOCO_DYNAMIC_LINK_DIR`, which
//! `.cargo/config.toml` sets).

fn main() {
    println!("cargo::rerun-if-env-changed=MUJOCO_DYNAMIC_LINK_DIR");
    match std::env::var("MUJOCO_DYNAMIC_LINK_DIR") {
        Ok(dir) => println!("cargo::rustc-link-arg=-Wl,-rpath,{dir}"),
        Err(_) => println!(
            "cargo::warning=MUJOCO_DYNAMIC_LINK_DIR is not set: run `cargo xtask setup` from the workspace"
        ),
    }
}
