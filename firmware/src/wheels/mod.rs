//! The wheels: [`balance`] (the LQR that keeps the folded robot upright on its wheels) and
//! [`wheel`] (the turn loop and the mixing into two wheel torques).

pub mod balance;
pub mod wheel;
