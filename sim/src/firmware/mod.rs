//! Firmware of the robot's two microcontrollers — the base and the pan-tilt — ported from the
//! thesis's C code (App. A.3), and the boards that run it.

pub mod base;
pub mod board;
pub mod pan_tilt;

pub use base::{BaseFirmware, HBridge};
pub use board::{BaseBoard, Board, MainLoop};
pub use pan_tilt::PanTiltFirmware;
