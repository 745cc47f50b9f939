//! What the robot does: scripted tours of firmware motions, run through the hardware contract.

pub mod navigate;
pub mod script;
pub mod tour;

pub use navigate::{Decision, Method, NavConfig, NavOutcome, SonarLayout};
pub use script::{Step, StepError};
pub use tour::{
    Fix, Pacing, SceneTag, TourConfig, TourError, TourEvent, TourObserver, TourReport, run_tour,
};
