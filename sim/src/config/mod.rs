//! Data files — worlds, robots and scenarios, written in TOML — read into validated descriptions.
//!
//! A file that cannot be used gives a [`ConfigError`] naming the file, the line, the column and
//! the field, and saying what was expected.

pub mod checks;
mod error;
pub mod map_image;
pub mod nav_study;
mod outliers;
pub mod robot_file;
pub mod scenario;
pub mod study;
pub mod values;
pub mod world;

pub use error::ConfigError;
pub use nav_study::NavStudy;
pub use outliers::Outliers;
pub use robot_file::RobotDescription;
pub use scenario::{NoiseSettings, ReconstructionSettings, Scenario};
pub use study::Study;
pub use world::{Material, Optics, Wall, WorldDescription};
