//! With the `sim` feature the binary links MuJoCo: an rpath to the folder `cargo xtask setup`
//! fills (named by `MUJOCO_DYNAMIC_LINK_DIR`, which `.cargo/config.toml` sets) lets it find
//! `libmujoco.so` at run time, as sim-host's own binaries do.

fn main() {
    println!("cargo::rerun-if-env-changed=MUJOCO_DYNAMIC_LINK_DIR");
    if std::env::var_os("CARGO_FEATURE_SIM").is_none() {
        return;
    }
    if let Ok(dir) = std::env::var("MUJOCO_DYNAMIC_LINK_DIR") {
        println!("cargo::rustc-link-arg=-Wl,-rpath,{dir}");
    }
}
