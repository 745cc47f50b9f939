//! # sim — the digital twin
//!
//! A differential-drive robot with a SICK laser (on a pan-tilt, on the thesis's robot) and a
//! sonar ring in a 2.5D world, stepped deterministically and far faster than real time:
//!
//! - [`config`]: world, robot and scenario files, with errors that name the file, line and field;
//! - [`twin`]: the bevy_ecs world and its ordered schedule;
//! - [`firmware`]: the base and pan-tilt microcontrollers' C firmware (thesis App. A), ported
//!   line by line, and the boards' serial timing;
//! - [`motor`], [`battery`], [`laser`], [`sonar`], [`pan_tilt`], [`world_map`]: the physical
//!   models;
//! - [`sim_robot`]: [`SimRobot`], the twin behind the robot crate's hardware contract, plus the
//!   sim-only [`GroundTruth`];
//! - [`serve`]: `twin serve`, the twin's three devices offered byte for byte on TCP ports or
//!   pseudo-terminals, for the real backend (`SerialRobot`) and legacy tools;
//! - [`drive`]: `twin drive`, a scenario's script through any backend (the real robot);
//! - [`montecarlo`]: `twin montecarlo`, the thesis's Table 5.1 study, parallel, resumable and
//!   shardable;
//! - [`checks`]: a scenario's `[[check]]` bounds, evaluated on its run;
//! - [`run`] and [`output`]: the `twin run` job and the files it writes;
//! - [`pairs`]: scan pairs with known truth, for testing and measuring the matchers;
//! - [`replay`]: localisation over recorded logs (`twin map`) and scan pairs (`twin match`).
#![warn(missing_docs)]
// `ConfigError` carries the file, line, field and excerpt; it is only returned while loading files.
#![allow(clippy::result_large_err)]

pub mod battery;
pub mod checks;
pub mod config;
pub mod drive;
pub mod firmware;
pub mod laser;
pub mod montecarlo;
pub mod motor;
pub mod pairs;
pub mod pan_tilt;
pub mod rng;
pub mod serve;
pub mod sim_robot;
pub mod twin;
pub mod world_map;
pub use sim_robot::{GroundTruth, SimError, SimRobot};
pub use twin::Twin;
pub mod output;
pub mod replay;
pub mod run;
pub mod sonar;
