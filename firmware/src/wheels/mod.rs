//! The wheels: [`balance`] (the LQR that keeps the folded robot upright on its wheels, designed
//! in [`lqr`]) and
//! [`wheel`] (the turn loop and the mixing into two wheel torques), [`runaway`] (which
//! stops the robot when the wheels cannot do what the balance law asks), [`lean`] (which
//! stops it when it leans on something other than its wheels), and [`traction`] (which holds
//! the wheels' rate while they are off the ground).

pub mod balance;
pub mod lean;
pub mod lqr;
pub mod runaway;
pub mod traction;
pub mod wheel;
