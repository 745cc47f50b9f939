//! `twin run SCENARIO --replay FILE`: the scenario's controller and localisation run again on a
//! recording — `robot::replay::ReplayRobot` answering every call through the hardware contract
//! with the answer recorded in `FILE`'s tape (a `run.mcap` of `twin run` or `twin drive`) — and
//! the outputs are written as `twin drive` writes them (there is no truth in a recording).
//!
//! The same controller on the same answers makes the same calls, so the replay ends where the
//! recording ended and its estimate equals the original's to the last bit; a controller changed
//! since the recording is stopped at its first call the tape does not hold.

use super::drive::DriveRecord;
use super::run::{RunOptions, control};
use crate::config::Scenario;
use robot::control::TourError;
use robot::replay::{Exchange, ReplayError, ReplayRobot};
use std::time::Instant;

/// Why a replay failed.
#[derive(Debug, thiserror::Error)]
pub enum ReplayRunError {
    /// The controller, on the recorded answers, failed or decided differently.
    #[error("{scenario} on the recording: {source}")]
    Tour {
        /// The scenario.
        scenario: String,
        /// What happened.
        #[source]
        source: TourError<ReplayError>,
    },
    /// The controller finished with exchanges of the tape left unasked.
    #[error(
        "{scenario}: the controller finished after {used} of the recording's {recorded} exchanges — it decided differently"
    )]
    Unfinished {
        /// The scenario.
        scenario: String,
        /// Exchanges replayed.
        used: usize,
        /// Exchanges recorded.
        recorded: usize,
    },
    /// The scenes' scans cannot be made into a 3D model.
    #[error("3D reconstruction: {0}")]
    Reconstruction(#[from] robot::reconstruction::SceneError),
}

/// Runs `scenario`'s controller on `tape`.
pub fn replay_scenario(
    scenario: &Scenario,
    tape: Vec<Exchange>,
    progress: impl FnMut(usize, usize),
) -> Result<DriveRecord, ReplayRunError> {
    let started = Instant::now();
    let recorded = tape.len();
    let mut robot = ReplayRobot::new(tape);
    let tour = |source| ReplayRunError::Tour {
        scenario: scenario.name.clone(),
        source,
    };
    let controlled = control(
        &mut robot,
        scenario,
        &RunOptions::default(),
        None,
        |_| Ok(()),
        progress,
    )
    .map_err(tour)?;
    if robot.position() != recorded {
        return Err(ReplayRunError::Unfinished {
            scenario: scenario.name.clone(),
            used: robot.position(),
            recorded,
        });
    }
    // Recorded again with the outputs: a replay replays too.
    Ok(DriveRecord::assemble(
        scenario,
        controlled,
        started,
        robot.into_tape(),
    )?)
}
