//! # sim — the digital twin
//!
//! A differential-drive robot with a SICK laser (on a pan-tilt, on the thesis's robot) and a
//! sonar ring in a 2.5D world, stepped deterministically and far faster than real time. The
//! folders are the layers, each using only those listed before it:
//!
//! - [`config`]: world, robot, scenario and study files (plain data), with errors that name the
//!   file, line and field;
//! - [`world`]: the 2.5D map of surfaces, its ray casts and distance queries;
//! - [`devices`]: what the twin simulates of the robot — motors, batteries, the ported firmwares
//!   and their boards, the laser and its optics, the sonar ring, the pan-tilt head;
//! - [`twin`]: the bevy_ecs world and its ordered schedule, and [`SimRobot`], the twin behind the
//!   robot crate's hardware contract (with the sim-only [`GroundTruth`]);
//! - [`record`]: what a run produced, in memory — scans with their truth, paths, the estimate;
//! - [`output`]: the files runs write and their pictures;
//! - [`commands`]: one module per thing a user runs (`twin run`, `check`, `map`, `match`,
//!   `serve`, `drive`, `montecarlo`); the `twin` binary only parses arguments and calls them.
#![warn(missing_docs)]
// `ConfigError` carries the file, line, field and excerpt; it is only returned while loading files.
#![allow(clippy::result_large_err)]

pub mod commands;
pub mod config;
pub mod devices;
pub mod output;
pub mod record;
pub mod rng;
pub mod twin;
pub mod wide;
pub mod world;

pub use twin::Twin;
pub use twin::sim_robot::{GroundTruth, SimError, SimRobot};
