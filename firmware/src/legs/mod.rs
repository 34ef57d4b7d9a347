//! The legs: where they attach ([`hips`]), [`kinematics`] (IK/FK of one leg), the poses ([`posture`]: the stance; the fold and
//! its [`levelling`]), the trot ([`gait`] with its [`phase`] clock, [`foot_trajectory`], the
//! watch for a swing it cannot finish ([`blocked`]) and the report's [`sine_gait`]), the
//! quasi-static [`crawl`] (its feet's loads serve the climb; its moves are not used yet), the
//! wheels-first [`climb`] of a
//! step behind, [`smoothing`] of targets,
//! joint-space [`ramp`]s, the [`transfer`] from the legs onto the wheels and [`support`] (which
//! feet carry the robot).

pub mod blocked;
pub mod climb;
pub mod crawl;
pub mod foot_trajectory;
pub mod gait;
pub mod hips;
pub mod kinematics;
pub mod levelling;
pub mod phase;
pub mod posture;
pub mod ramp;
pub mod sine_gait;
pub mod smoothing;
pub mod support;
pub mod transfer;
