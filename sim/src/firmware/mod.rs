//! Firmware of the robot's microcontrollers, ported from the thesis's C code (App. A.3), and the
//! boards that run it.

pub mod base;
pub mod board;

pub use base::{BaseFirmware, HBridge};
pub use board::BaseBoard;
