//! `summary.json`: the figures of a run.

use crate::run::RunRecord;
use serde::Serialize;
use std::path::Path;

/// The figures of a run. `wall_seconds` and `real_time_factor` depend on the machine; everything
/// else on the scenario and seed only.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// Scenario name.
    pub scenario: String,
    /// World name.
    pub world: String,
    /// Robot name.
    pub robot: String,
    /// Seed used.
    pub seed: u64,
    /// Simulated seconds.
    pub sim_seconds: f64,
    /// Wall-clock seconds.
    pub wall_seconds: f64,
    /// Simulated seconds per wall-clock second.
    pub real_time_factor: f64,
    /// Length of the true path, metres.
    pub distance_m: f64,
    /// Distance between final odometry and final truth, metres.
    pub final_odometry_error_m: f64,
    /// Heading error of the final odometry, degrees.
    pub final_odometry_error_deg: f64,
    /// Scans written.
    pub scans: usize,
    /// Script steps carried out.
    pub steps: usize,
    /// Contacts with walls.
    pub collisions: u32,
    /// State of charge of the motor batteries at the end.
    pub motor_battery_charge: f64,
}

impl Summary {
    /// The summary of a run in a world and with a robot named `(world, robot)`.
    pub fn of(record: &RunRecord, (world, robot): (&str, &str)) -> Self {
        Summary {
            scenario: record.scenario.clone(),
            world: world.to_string(),
            robot: robot.to_string(),
            seed: record.seed,
            sim_seconds: record.sim_seconds(),
            wall_seconds: record.wall_seconds,
            real_time_factor: record.real_time_factor(),
            distance_m: record.distance_m,
            final_odometry_error_m: record.final_odometry_error_m(),
            final_odometry_error_deg: record.final_odometry_error_deg(),
            scans: record.scans.len(),
            steps: record.steps,
            collisions: record.collisions,
            motor_battery_charge: record.battery_charge.1,
        }
    }

    /// Writes the summary as pretty JSON.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        let mut text = serde_json::to_string_pretty(self)?;
        text.push('\n');
        std::fs::write(path, text)
    }
}
