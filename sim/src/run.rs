//! The `twin run` job: a scenario's script, driven through the hardware contract by the robot
//! crate's tour, with the twin's ground truth recorded beside every scan.

use crate::config::{ConfigError, Scenario};
use crate::sim_robot::{GroundTruth, SimError, SimRobot};
use robot::control::{TourConfig, TourError, TourEvent, run_tour};
use robot::hardware::LaserScan;
use robot::{Pose2, Stamp};
use std::time::Instant;

/// One scan as recorded by a run.
#[derive(Clone, Debug, PartialEq)]
pub struct ScanRecord {
    /// The scan as the robot received it.
    pub scan: LaserScan,
    /// The robot's odometry at the scan's stamp (world frame: it starts at the start pose).
    pub odometry: Pose2,
    /// The true pose of the base at the scan's stamp.
    pub truth: Pose2,
}

/// Everything a run produced.
#[derive(Clone, Debug)]
pub struct RunRecord {
    /// The scenario's name.
    pub scenario: String,
    /// The seed used.
    pub seed: u64,
    /// Kept scans, in order.
    pub scans: Vec<ScanRecord>,
    /// Steps of the script carried out.
    pub steps: usize,
    /// Simulated time at the end.
    pub end: Stamp,
    /// Wall-clock seconds the run took.
    pub wall_seconds: f64,
    /// Length of the true path, metres.
    pub distance_m: f64,
    /// Contacts with walls.
    pub collisions: u32,
    /// The true pose at the end.
    pub final_truth: Pose2,
    /// The odometry at the end.
    pub final_odometry: Pose2,
    /// The true path, one pose per world step.
    pub true_path: Vec<(Stamp, Pose2)>,
    /// The laser's pose on the base: scan points are in this frame.
    pub laser_mount: Pose2,
    /// State of charge of the (logic, motor) batteries at the end.
    pub battery_charge: (f64, f64),
}

impl RunRecord {
    /// Simulated seconds.
    pub fn sim_seconds(&self) -> f64 {
        self.end.secs_f64()
    }

    /// Simulated seconds per wall-clock second.
    pub fn real_time_factor(&self) -> f64 {
        if self.wall_seconds > 0.0 {
            self.sim_seconds() / self.wall_seconds
        } else {
            f64::INFINITY
        }
    }

    /// Distance between the final odometry and the final true pose, metres.
    pub fn final_odometry_error_m(&self) -> f64 {
        self.final_odometry.distance(&self.final_truth)
    }

    /// Heading difference between the final odometry and the final true pose, degrees.
    pub fn final_odometry_error_deg(&self) -> f64 {
        robot::geometry::wrap_angle(self.final_odometry.theta - self.final_truth.theta)
            .to_degrees()
            .abs()
    }
}

/// Why a run failed.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scenario cannot be set up.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The tour failed on the twin.
    #[error("{scenario}: {source}")]
    Tour {
        /// The scenario's name.
        scenario: String,
        /// What went wrong.
        #[source]
        source: TourError<SimError>,
    },
}

/// How a run is made.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Replaces the scenario's seed.
    pub seed: Option<u64>,
    /// Replaces the scenario's tour pacing.
    pub tour: Option<TourConfig>,
}

/// Runs a scenario to its end. `progress(done, total)` is called before each step.
pub fn run_scenario(
    scenario: &Scenario,
    options: &RunOptions,
    mut progress: impl FnMut(usize, usize),
) -> Result<RunRecord, RunError> {
    let started = Instant::now();
    let mut scenario = scenario.clone();
    if let Some(seed) = options.seed {
        scenario.seed = seed;
    }
    let mut robot = SimRobot::from_scenario(&scenario)?;
    let mut kept = Vec::new();
    let report = {
        let mut observer = |event: TourEvent<'_>| match event {
            TourEvent::StepStarted { index, total, .. } => progress(index, total),
            TourEvent::Scan { scan, odometry } => kept.push((scan.clone(), odometry)),
        };
        run_tour(
            &mut robot,
            scenario.robot.geometry(),
            scenario.world.start,
            &scenario.steps,
            options.tour.as_ref().unwrap_or(&scenario.tour),
            &mut observer,
        )
        .map_err(|source| RunError::Tour {
            scenario: scenario.name.clone(),
            source,
        })?
    };
    progress(report.steps, report.steps);
    // Scans are delivered after they were measured: the twin has simulated past every stamp.
    let scans = kept
        .into_iter()
        .map(|(scan, odometry)| {
            let truth = robot
                .true_pose_at(scan.stamp)
                .unwrap_or_else(|| robot.true_pose());
            ScanRecord {
                scan,
                odometry,
                truth,
            }
        })
        .collect();
    let twin = robot.twin();
    Ok(RunRecord {
        scenario: scenario.name.clone(),
        seed: scenario.seed,
        scans,
        steps: report.steps,
        end: twin.now(),
        wall_seconds: started.elapsed().as_secs_f64(),
        distance_m: twin.distance_travelled(),
        collisions: twin.collisions(),
        final_truth: twin.true_pose(),
        final_odometry: report.final_odometry,
        true_path: twin.true_path().collect(),
        laser_mount: twin.laser().mount(),
        battery_charge: twin.battery_charge(),
    })
}
