//! What paces a run: [`lockstep`] (the simulator is the clock and sends SYNC; deterministic,
//! faster than real time) or [`wall`] (the wall clock at the control rate).

pub mod lockstep;
pub mod wall;
