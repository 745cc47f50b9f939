//! What a run produced, in memory: each kept scan with the odometry and the twin's truth beside
//! it, the true path, the sonar ring's last reading, the scan-matching estimate, the 3D models. The files of
//! [`crate::output`] and the checks of [`crate::commands::check`] are computed from it.

use crate::devices::laser::LaserFrame;
use crate::world::score::Accuracy;
use robot::control::SceneTag;
use robot::hardware::{LaserScan, PanTiltStatus};
use robot::localization::{MatcherKind, Placed};
use robot::reconstruction::{MeshOptions, Model};
use robot::{Pose2, Stamp};
use serde::Serialize;

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
    /// Motions that ended short of their target with the motors on, stopped with `p`
    /// (`robot::control::tour::STALL`).
    pub stalled_motions: usize,
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
    /// The 3D models of the run's scenes, when its script took any.
    pub reconstruction: Option<Reconstruction>,
    /// Every call the controller made through the hardware contract, with its answer: what
    /// `twin run --replay` plays back.
    pub tape: Vec<robot::replay::Exchange>,
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

/// Where a model's scenes were placed.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Placement {
    /// By the 2D localisation of the level scans.
    Estimate,
    /// By the odometry.
    Odometry,
    /// By the twin's true pose.
    Truth,
}

impl Placement {
    /// Its name in files and reports.
    pub fn name(self) -> &'static str {
        match self {
            Placement::Estimate => "estimate",
            Placement::Odometry => "odometry",
            Placement::Truth => "truth",
        }
    }
}

/// A model and, when the world is known, its scores.
#[derive(Clone, Debug)]
pub struct PlacedModel {
    /// How its scenes were placed.
    pub placement: Placement,
    /// The points, normals and mesh.
    pub model: Model,
    /// Its accuracy against the true surfaces.
    pub accuracy: Option<Accuracy>,
}

/// One validity rule tried on the model of the sweep.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RuleTrial {
    /// The rule, readably.
    pub rule: String,
    /// Valid triangles over those the grids offer.
    pub valid_share: f64,
    /// Mesh area, square metres.
    pub mesh_area_m2: f64,
    /// The part of it farther than 5 cm from every true surface.
    pub phantom_area_m2: f64,
    /// The part of the phantom area that bridges readings lying on true surfaces (the rule's
    /// doing, not the sensor's ghosts).
    pub bridge_area_m2: f64,
    /// The part within 5 cm of a true surface.
    pub true_area_m2: f64,
}

/// The 3D reconstruction of a run.
#[derive(Clone, Debug)]
pub struct Reconstruction {
    /// How the scenes were meshed.
    pub options: MeshOptions,
    /// The models: by the estimate (if the run localised), by odometry, by the truth (twin).
    pub models: Vec<PlacedModel>,
    /// Validity rules tried on the best-placed model (truth, else estimate), with the world.
    pub sweep: Vec<RuleTrial>,
    /// Wall-clock seconds building the models (machine-dependent).
    pub build_seconds: f64,
    /// Wall-clock seconds scoring them (machine-dependent).
    pub score_seconds: f64,
}

impl Reconstruction {
    /// The model people look at: placed by the estimate if there is one, else by odometry.
    pub fn main(&self) -> &PlacedModel {
        self.models
            .iter()
            .find(|m| m.placement == Placement::Estimate)
            .unwrap_or(&self.models[0])
    }

    /// The model placed by `placement`, if built.
    pub fn placed(&self, placement: Placement) -> Option<&PlacedModel> {
        self.models.iter().find(|m| m.placement == placement)
    }
}
