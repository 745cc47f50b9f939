//! # robot — everything that also runs on the real robot
//!
//! This crate holds the code that must behave identically on the digital twin and on the real
//! machine, so it never touches a simulator and never reads the wall clock:
//!
//! - [`hardware`]: the contract a backend fulfils — drive base, laser, sonar ring, pan-tilt and
//!   batteries — as small fallible traits, plus the shared types (`DriveStatus`, `LaserScan`, …).
//! - [`protocol`]: the bytes on the wire of the base microcontroller (thesis App. A), encoded and
//!   parsed exactly as the firmware writes them.
//! - [`mount`]: where the laser sits on the base, fixed or on the pan-tilt head (Eq. 4.1).
//! - [`odometry`]: dead reckoning from the firmware's wheel counters, and a FIFO that interpolates
//!   odometry to a scan's timestamp.
//! - [`control`]: what the robot does — scripted tours of firmware motions.
//! - [`localization`]: scan matchers (least squares, Lorentzian NLM, line-assisted, MbICP) and
//!   the map builder that chains them.
//! - [`reconstruction`]: 3D scenes from the pan-tilt laser, meshes and merged models.
//! - [`serial`]: [`SerialRobot`](serial::SerialRobot), the backend that drives the real robot (or
//!   the twin's serial face) over serial ports or TCP.
//! - [`logs`]: readers of recorded runs (CARMEN `.clf`, the `.script` and RobotLogger `.log`
//!   formats of 002 App. C).
//! - [`memory`]: storage for grids and masks read and written cell by cell, its pages written
//!   before use.
//!
//! Time is [`Stamp`] (integer nanoseconds) and is always passed in by the caller. Inside, units are
//! SI and frames follow ROS REP-103 (x forward, y left, z up, angles counter-clockwise); the
//! firmware's units (tenths of a motor turn, counts per 1.024 ms tick, millimetres) appear only in
//! the types that speak the wire format, with the unit in the name.
#![warn(missing_docs)]

pub mod control;
pub mod drive_geometry;
pub mod geometry;
pub mod hardware;
pub mod localization;
pub mod logs;
pub mod memory;
pub mod mount;
pub mod odometry;
pub mod protocol;
pub mod reconstruction;
pub mod replay;
pub mod serial;
#[cfg(test)]
mod test_rng;
pub mod time;

pub use drive_geometry::DriveGeometry;
pub use geometry::Pose2;
pub use time::{Clock, Stamp};
