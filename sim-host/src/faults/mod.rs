//! Faults on purpose: the [`rig`] (the closed loop in lockstep with a fault layer on every
//! connection and the means to kill or restart a peer) and the [`matrix`] of fault cells it
//! runs, each judged.

mod cells;
mod judge;
pub mod matrix;
pub mod rig;
mod security;
