//! What the robot does: scripted tours of firmware motions, run through the hardware contract.

pub mod script;
pub mod tour;

pub use script::{Step, StepError};
pub use tour::{Pacing, SceneTag, TourConfig, TourError, TourEvent, TourReport, run_tour};
