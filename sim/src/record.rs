//! What a run produced, in memory: each kept scan with the odometry and the twin's truth beside
//! it, the true path, the sonar ring's last reading, the scan-matching estimate. The files of
//! [`crate::output`] and the checks of [`crate::commands::check`] are computed from it.

use crate::devices::laser::LaserFrame;
use robot::control::SceneTag;
use robot::hardware::{LaserScan, PanTiltStatus};
use robot::localization::{MatcherKind, Placed};
use robot::{Pose2, Stamp};

/// One scan as recorded by a run.
#[derive(Clone, Debug, PartialEq)]
pub struct ScanRecord {
    /// The scan as the robot received it.
    pub scan: LaserScan,
    /// The robot's odometry at the scan's stamp (world frame: it starts at the start pose).
    pub odometry: Pose2,
    /// The true pose of the base at the scan's stamp.
    pub truth: Pose2,
    /// The laser's true frame at the scan's stamp (on the pan-tilt: panned and tilted).
    pub frame: LaserFrame,
    /// The 3D scene the scan belongs to, if a `scene` or `survey` step took it.
    pub scene: Option<SceneTag>,
}

/// One full reading of the sonar ring, taken at rest at the end of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct SonarRecord {
    /// The report as the robot received it.
    pub echoes: robot::hardware::SonarEchoes,
    /// The true pose of the base when it was read.
    pub truth: Pose2,
    /// Each transducer's pose on the base, by transducer number.
    pub transducers: Vec<Pose2>,
    /// Full width of a transducer's cone, radians.
    pub cone: f64,
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
    /// State of charge of the (logic, motor) batteries at the end.
    pub battery_charge: (f64, f64),
    /// The sonar ring's last reading, when the scenario fires it.
    pub sonar: Option<SonarRecord>,
    /// The pan-tilt's status once it reached the scenario's position, before the script.
    pub pan_tilt: Option<PanTiltStatus>,
    /// The scan-matching estimate, when the scenario localises.
    pub localisation: Option<LocalisationRecord>,
}

/// What the localisation made of a run's scans.
#[derive(Clone, Debug)]
pub struct LocalisationRecord {
    /// The matcher used.
    pub matcher: MatcherKind,
    /// One placed scan per level scan, in order (world frame: it starts at the start pose);
    /// tilted scans are left to the 3D reconstruction.
    pub placed: Vec<Placed>,
    /// The point map, world frame.
    pub map: Vec<[f64; 2]>,
    /// Wall-clock seconds spent localising.
    pub wall_seconds: f64,
}

impl LocalisationRecord {
    /// Position and heading errors of the estimate against the truth at each scan.
    pub fn errors<'a>(&'a self, scans: &'a [ScanRecord]) -> impl Iterator<Item = (f64, f64)> + 'a {
        self.placed.iter().filter_map(|p| {
            let s = &scans[scans
                .binary_search_by_key(&p.stamp, |s| s.scan.stamp)
                .ok()?];
            Some((
                p.estimate.distance(&s.truth),
                robot::geometry::wrap_angle(p.estimate.theta - s.truth.theta).abs(),
            ))
        })
    }
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
