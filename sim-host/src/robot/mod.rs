//! The robot: its MuJoCo [`model`] and [`physics`] (ground truth, with [`rotation`] math), and the hardware a real
//! robot puts on the bus, emulated — four [`leg_drive`]s and the [`wheel_drive`] (sharing
//! [`drive_core`], each at its [`rating`], measuring as [`sensing`] says), the [`imu`] (its chip:
//! [`imu_chip`]) and the [`rangefinder`] (their white [`noise`]), all together in [`hardware`]; the [`plant`] picks the parts.

pub mod drive_core;
pub mod hardware;
pub mod imu;
pub mod imu_chip;
pub mod leg_drive;
pub mod link;
pub mod model;
pub mod noise;
pub mod physics;
pub mod plant;
pub mod rangefinder;
pub mod rating;
pub mod rotation;
pub mod sensing;
pub mod variation;
pub mod wheel_drive;
