//! The control step and what keeps it safe: the [`controller`] runs the [`fsm`]'s mode, with
//! the [`safety`] watchdogs and clamps around it, the [`sensors`] it last heard and the
//! operator's [`teleop`] requests.

pub mod controller;
pub mod fsm;
pub mod safety;
pub mod sensors;
pub mod teleop;
