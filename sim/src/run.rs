//! The `twin run` job: a scenario's script, driven through the hardware contract by the robot
//! crate's tour, with the twin's ground truth recorded beside every scan.

use crate::config::scenario::SonarSettings;
use crate::config::{ConfigError, Scenario};
use crate::laser::LaserFrame;
use crate::sim_robot::{GroundTruth, SimError, SimRobot};
use robot::control::{TourConfig, TourError, TourEvent, run_tour};
use robot::hardware::{
    DriveBase, DriveWait, LaserScan, PanTilt, PanTiltPosition, PanTiltStatus, SonarCommand,
    SonarRing,
};
use robot::localization::{MapBuilder, MapConfig, MatcherKind, Placed, RangeScan};
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
    /// The laser's true frame at the scan's stamp (on the pan-tilt: panned and tilted).
    pub frame: LaserFrame,
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
    /// One placed scan per kept scan, in the same order (world frame: it starts at the start
    /// pose).
    pub placed: Vec<Placed>,
    /// The point map, world frame.
    pub map: Vec<[f64; 2]>,
    /// Wall-clock seconds spent localising.
    pub wall_seconds: f64,
}

impl LocalisationRecord {
    /// Position and heading errors of the estimate against the truth at each scan.
    pub fn errors<'a>(&'a self, scans: &'a [ScanRecord]) -> impl Iterator<Item = (f64, f64)> + 'a {
        self.placed.iter().zip(scans).map(|(p, s)| {
            (
                p.estimate.distance(&s.truth),
                robot::geometry::wrap_angle(p.estimate.theta - s.truth.theta).abs(),
            )
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
    let tour_error = |source| RunError::Tour {
        scenario: scenario.name.clone(),
        source,
    };
    let pan_tilt = match scenario.pan_tilt {
        Some(target) => Some(
            position_head(&mut robot, target)
                .map_err(|e| tour_error(hardware_error("(pan-tilt)", e)))?,
        ),
        None => None,
    };
    if let Some(sonar) = &scenario.sonar {
        start_sonar(&mut robot, sonar).map_err(|e| tour_error(hardware_error("(sonar)", e)))?;
    }
    let mut kept = Vec::new();
    let mut mapper = scenario.localisation.map(|settings| {
        let config = MapConfig {
            mount: scenario.robot.laser_mount(),
            keyframe_distance_m: settings.keyframe_distance_m,
            keyframe_angle_rad: settings.keyframe_angle_rad,
            ..MapConfig::default()
        };
        let matcher = settings.matcher.build();
        (
            settings.matcher,
            MapBuilder::in_odometry_frame(matcher, config),
        )
    });
    let mut localising = 0.0;
    let report = {
        let mut observer = |event: TourEvent<'_>| match event {
            TourEvent::StepStarted { index, total, .. } => progress(index, total),
            TourEvent::Scan { scan, odometry } => {
                if let Some((_, mapper)) = &mut mapper {
                    let clock = Instant::now();
                    mapper.push_odometry(scan.stamp, odometry);
                    mapper.push_scan(RangeScan::from(scan));
                    localising += clock.elapsed().as_secs_f64();
                }
                kept.push((scan.clone(), odometry));
            }
        };
        run_tour(
            &mut robot,
            scenario.robot.geometry(),
            scenario.world.start,
            &scenario.steps,
            options.tour.as_ref().unwrap_or(&scenario.tour),
            &mut observer,
        )
        .map_err(tour_error)?
    };
    let sonar = match &scenario.sonar {
        Some(settings) => Some(
            read_sonar_ring(&mut robot, settings)
                .map_err(|e| tour_error(hardware_error("(sonar)", e)))?,
        ),
        None => None,
    };
    progress(report.steps, report.steps);
    // Scans are delivered after they were measured: the twin has simulated past every stamp.
    let scans = kept
        .into_iter()
        .map(|(scan, odometry)| {
            let truth = robot
                .true_pose_at(scan.stamp)
                .unwrap_or_else(|| robot.true_pose());
            let frame = robot
                .laser_frame_at(scan.stamp)
                .unwrap_or_else(|| robot.twin().laser().frame_on(truth));
            ScanRecord {
                scan,
                odometry,
                truth,
                frame,
            }
        })
        .collect();
    let localisation = mapper.map(|(matcher, mut mapper)| {
        mapper.finish();
        LocalisationRecord {
            matcher,
            placed: mapper.placed().to_vec(),
            map: mapper.map_points().to_vec(),
            wall_seconds: localising,
        }
    });
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
        battery_charge: twin.battery_charge(),
        sonar,
        pan_tilt,
        localisation,
    })
}

/// Ticks between two status polls while the head moves.
const HEAD_POLL_MS: u16 = 50;
/// Longest a head move may take, in polls (a full pan turn takes about 8 s).
const HEAD_POLL_LIMIT: u32 = 1200;

/// Waits for the pan-tilt to home, moves it to `target` and waits until both motors are off.
fn position_head(robot: &mut SimRobot, target: PanTiltPosition) -> Result<PanTiltStatus, SimError> {
    robot.wait_pan_tilt_ready()?;
    let status = robot.move_pan_tilt_to(target, HEAD_POLL_MS, HEAD_POLL_LIMIT)?;
    if status.idle() {
        Ok(status)
    } else {
        Err(SimError::Timeout {
            command: format!("g{} / e{} (head still moving)", target.pan, target.tilt),
            waited: crate::twin::TICK * (u32::from(HEAD_POLL_MS) * HEAD_POLL_LIMIT),
        })
    }
}

/// `S`, `s2 Te Tr`, `s1`: the ring starts firing.
fn start_sonar(robot: &mut SimRobot, settings: &SonarSettings) -> Result<(), SimError> {
    robot.sonar(SonarCommand::Sequence(settings.sequence.clone()))?;
    robot.sonar(SonarCommand::Timing {
        echo_ms: settings.echo_ms,
        relax_ms: settings.relax_ms,
    })?;
    robot.sonar(SonarCommand::Firing(true))
}

/// Waits, at rest, one full firing cycle and reads the ring.
fn read_sonar_ring(
    robot: &mut SimRobot,
    settings: &SonarSettings,
) -> Result<SonarRecord, SimError> {
    // Each shot takes the fire tick, the echo window, the relax time and the step to the next.
    let cycle = settings.sequence.len() as u32
        * (u32::from(settings.echo_ms) + u32::from(settings.relax_ms) + 3);
    robot.wait_drive(DriveWait::sleep(cycle.min(u32::from(u16::MAX)) as u16))?;
    let echoes = robot.sonar_echoes()?;
    let model = robot
        .twin()
        .sonar()
        .expect("the scenario checked the robot has a ring");
    Ok(SonarRecord {
        truth: robot.true_pose(),
        transducers: (0..model.len())
            .filter_map(|k| model.transducer(k))
            .collect(),
        cone: model.cone(),
        echoes,
    })
}

/// A hardware error before or after the script, reported as the tour's.
fn hardware_error(step: &str, source: SimError) -> TourError<SimError> {
    TourError::Hardware {
        index: 0,
        step: step.into(),
        source,
    }
}
