//! `sim-host`: the robot in MuJoCo, presented on the CAN bus as its leg drives, wheel drive and
//! IMU. The simulator lands with the sim-host issue; until then this binary says so and exits
//! with a non-zero status so no script mistakes it for a working simulator.

fn main() -> std::process::ExitCode {
    eprintln!(
        "sim-host: the MuJoCo simulator is not built yet (see the sim-host issue). \
         The CAN protocol it will speak is in the `protocol` crate: `cargo xtask busload`."
    );
    std::process::ExitCode::from(2)
}
