//! Shared by the firmware's closed-loop benches: the pose they start in.

use firmware::config::Config;

/// Every leg at the nominal stance of `config`, wire order, rad: the robot standing.
pub fn standing_joints_rad(config: &Config) -> [f32; 16] {
    let stance = config
        .posture
        .stance(
            &config.geometry,
            &config.limits,
            config.posture.depth_nominal_m,
        )
        .expect("the nominal stance is reachable")
        .to_array();
    let mut joints = [0.0; 16];
    for chunk in joints.chunks_exact_mut(4) {
        chunk.copy_from_slice(&stance);
    }
    joints
}

/// A bench stepped one control tick at a time.
pub trait Ticks {
    /// One tick; its output.
    fn tick(&mut self) -> firmware::controller::Output;

    /// `ticks` ticks (at least one); the last output.
    fn run(&mut self, ticks: u32) -> firmware::controller::Output {
        let mut last = self.tick();
        for _ in 1..ticks {
            last = self.tick();
        }
        last
    }
}
