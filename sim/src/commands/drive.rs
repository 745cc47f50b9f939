//! `twin drive`: a scenario's script driven through any backend of the hardware contract — the
//! real robot's `SerialRobot` above all — with the same controller and localisation as `twin run`,
//! writing the same kind of outputs. There is no ground truth out there, so the picture compares
//! the map placed by odometry with the map placed by scan matching (as `twin map` does).

use super::reconstruct::{SceneInput, reconstruct};
use crate::config::Scenario;
use crate::config::scenario::LocalisationSettings;
use crate::output::logmap::{Panel, occupied_cells, write_log_map_svg};
use crate::output::{ScanLine, write_scan_lines, write_tum};
use robot::control::{SceneTag, TourError};
use robot::hardware::{
    DriveBase, HardwareError, Laser, LaserScan, PanTilt, PanTiltStatus, SonarRing,
};
use robot::localization::{
    LEVEL_TOLERANCE_RAD, LevelLocaliser, MatchStats, MatcherKind, Placed, RangeScan,
};
use robot::{Pose2, Stamp};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Everything a drive produced.
#[derive(Clone, Debug)]
pub struct DriveRecord {
    /// The scenario's name.
    pub scenario: String,
    /// Steps carried out.
    pub steps: usize,
    /// Kept scans with the odometry at their stamp (world frame: it starts at the start pose)
    /// and the 3D scene they were taken for.
    pub scans: Vec<(LaserScan, Pose2, Option<SceneTag>)>,
    /// The odometry at the end.
    pub final_odometry: Pose2,
    /// The pan-tilt's status once at the scenario's position, if it has one.
    pub pan_tilt: Option<PanTiltStatus>,
    /// The matcher and what it placed, when localising.
    pub localisation: Option<(MatcherKind, Vec<Placed>, Vec<[f64; 2]>)>,
    /// Robot-clock stamp of the last scan.
    pub end: Stamp,
    /// Wall-clock seconds the drive took.
    pub wall_seconds: f64,
    /// The 3D models of the scenes, when the script took any (no truth out there: placed by
    /// the estimate and by odometry, not scored).
    pub reconstruction: Option<crate::record::Reconstruction>,
    /// The controller's calls through the contract and their answers (empty when not taped).
    pub tape: Vec<robot::replay::Exchange>,
    /// What the navigating steps (`goto`, `explore`) decided, in order.
    pub decisions: Vec<crate::record::DecisionRecord>,
}

/// Why a drive stopped.
#[derive(Debug, thiserror::Error)]
pub enum DriveError<E: HardwareError> {
    /// The controller failed: the head's positioning (step 0 `(pan-tilt)`), the sonar's
    /// start, or a step of the tour.
    #[error(transparent)]
    Tour(#[from] TourError<E>),
    /// The scenes' scans cannot be made into a 3D model.
    #[error("3D reconstruction: {0}")]
    Reconstruction(robot::reconstruction::SceneError),
}

/// Drives `scenario`'s script on `robot` with the same controller as `twin run`
/// ([`super::run::control`]: the pan-tilt to the scenario's position, the sonar ring fired when
/// the scenario has `[sonar]`, the tour, the localiser), localising with `matcher` (default: the
/// scenario's). `progress(done, total)` is called before each step.
pub fn drive_scenario<R>(
    robot: &mut R,
    scenario: &Scenario,
    matcher: Option<MatcherKind>,
    progress: impl FnMut(usize, usize),
) -> Result<DriveRecord, DriveError<R::Error>>
where
    R: DriveBase + Laser + PanTilt + SonarRing,
{
    let started = Instant::now();
    let mut scenario = scenario.clone();
    if let Some(matcher) = matcher {
        let settings = scenario.localisation.get_or_insert(LocalisationSettings {
            matcher,
            keyframe_distance_m: 0.0,
            keyframe_angle_rad: 0.0,
            use_untrusted: false,
        });
        settings.matcher = matcher;
    }
    let controlled = super::run::control(
        robot,
        &scenario,
        &super::run::RunOptions::default(),
        None,
        |_| Ok(()),
        progress,
    )?;
    DriveRecord::assemble(&scenario, controlled, started, Vec::new())
        .map_err(DriveError::Reconstruction)
}

impl DriveRecord {
    /// A drive's record from what its controller did: the scenes' 3D models built from the
    /// scans (placed by the estimate and by odometry; no truth to score them against).
    pub fn assemble(
        scenario: &Scenario,
        controlled: super::run::Controlled,
        started: Instant,
        tape: Vec<robot::replay::Exchange>,
    ) -> Result<Self, robot::reconstruction::SceneError> {
        let super::run::Controlled {
            kept: scans,
            localisation,
            report,
            pan_tilt,
            echoes: _,
            decisions,
        } = controlled;
        let localisation = localisation.map(|l| (l.matcher, l.placed, l.map));
        let mount = scenario.robot.mount();
        let inputs: Vec<SceneInput> = scans
            .iter()
            .filter_map(|(scan, odometry, scene)| {
                SceneInput::of(scan, *odometry, *scene, &mount, None)
            })
            .collect();
        let reconstruction = reconstruct(
            &inputs,
            localisation
                .as_ref()
                .map(|(_, placed, _)| placed.as_slice()),
            &scenario.reconstruction.mesh,
            None,
            false,
        )?;
        Ok(DriveRecord {
            scenario: scenario.name.clone(),
            steps: report.steps,
            end: scans.last().map_or(report.end, |(s, _, _)| s.stamp),
            scans,
            final_odometry: report.final_odometry,
            pan_tilt,
            localisation,
            wall_seconds: started.elapsed().as_secs_f64(),
            reconstruction,
            tape,
            decisions,
        })
    }

    /// Prints the last estimate, when the drive localised.
    pub fn say_estimate(&self) {
        if let Some((kind, placed, _)) = &self.localisation
            && let Some(last) = placed.last()
        {
            let e = last.estimate;
            say!(
                "estimate ({kind}): ({:.3} m, {:.3} m, {:.2} deg)",
                e.x,
                e.y,
                e.theta.to_degrees()
            );
        }
    }
}

/// The figures of a drive, as `summary.json` holds them.
#[derive(Clone, Debug, Serialize)]
pub struct DriveSummary {
    /// Scenario name.
    pub scenario: String,
    /// Robot name.
    pub robot: String,
    /// Script steps carried out.
    pub steps: usize,
    /// Scans written.
    pub scans: usize,
    /// Robot-clock seconds at the last scan.
    pub robot_seconds: f64,
    /// Wall-clock seconds.
    pub wall_seconds: f64,
    /// Final odometry `[x, y, theta]`.
    pub final_odometry: [f64; 3],
    /// The matcher, if the drive localised.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub matcher: Option<String>,
    /// Final estimate `[x, y, theta]`, if the drive localised.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub final_estimate: Option<[f64; 3]>,
    /// Matches made, trusted and converged.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub matches: Option<MatchStats>,
    /// 5 cm cells occupied by the map placed by odometry.
    pub odometry_cells: usize,
    /// 5 cm cells occupied by the map placed by the estimate (fewer: sharper).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub estimate_cells: Option<usize>,
    /// What happened on the links (reconnections, skipped garbage), one line each.
    pub link_events: Vec<String>,
}

/// Writes `odometry.tum`, `estimate.tum` (when localising), `scans.jsonl`, `map.svg`,
/// `run.mcap` and `summary.json` into `dir`; `link_events` go into the summary and onto the
/// recording's `/rosout`.
pub fn write_drive(
    record: &DriveRecord,
    scenario: &Scenario,
    link_events: &[robot::serial::LinkEvent],
    dir: &Path,
) -> std::io::Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir)?;
    let mut files = Vec::new();
    let mut file = |name: &str| {
        let path = dir.join(name);
        files.push(path.clone());
        path
    };
    write_tum(
        &file("odometry.tum"),
        record.scans.iter().map(|(s, p, _)| (s.stamp, *p)),
    )?;
    if let Some((_, placed, _)) = &record.localisation {
        write_tum(
            &file("estimate.tum"),
            placed.iter().map(|p| (p.stamp, p.estimate)),
        )?;
    }
    if !record.decisions.is_empty() {
        crate::output::write_decisions(&file("decisions.jsonl"), &record.decisions)?;
    }
    // The world as the scenario declares it (the real room may differ), for `twin view`.
    crate::output::write_world_json(
        &file("world.json"),
        scenario,
        &crate::world::WorldMap::new(&scenario.world),
    )?;
    let mount = scenario.robot.mount();
    write_scan_lines(
        &file("scans.jsonl"),
        record
            .scans
            .iter()
            .map(|(s, p, scene)| ScanLine::new(s, *p, &mount, *scene)),
    )?;
    // The map placed by odometry: the level scans, each from where its head put the laser.
    let mut odometry_map = Vec::new();
    for (scan, pose, _) in &record.scans {
        let Some(on_base) = LevelLocaliser::level_mount(&mount, scan, LEVEL_TOLERANCE_RAD) else {
            continue;
        };
        let laser = pose.compose(&on_base);
        odometry_map.extend(RangeScan::from(scan).points().xy.iter().map(|q| {
            let (x, y) = laser.transform_point(q[0], q[1]);
            [x, y]
        }));
    }
    let odometry_path: Vec<Pose2> = record.scans.iter().map(|(_, p, _)| *p).collect();
    let mut panels = vec![Panel {
        title: "odometry".into(),
        points: &odometry_map,
        path: &odometry_path,
    }];
    let estimate_path: Vec<Pose2> = record
        .localisation
        .as_ref()
        .map(|(_, placed, _)| placed.iter().map(|p| p.estimate).collect())
        .unwrap_or_default();
    if let Some((kind, _, map)) = &record.localisation {
        panels.push(Panel {
            title: format!("scan matching ({kind})"),
            points: map,
            path: &estimate_path,
        });
    }
    write_log_map_svg(&file("map.svg"), &panels)?;
    crate::output::write_mcap(
        &file("run.mcap"),
        &crate::output::Recording {
            mount,
            scan_time_s: crate::output::scan_period_s(&scenario.robot.laser),
            scans: record
                .scans
                .iter()
                .map(|(scan, odometry, _)| crate::output::RecordedScan {
                    scan,
                    odometry: *odometry,
                    truth: None,
                    after: None,
                })
                .collect(),
            estimate: record
                .localisation
                .iter()
                .flat_map(|(_, placed, _)| placed.iter().map(|p| (p.stamp, p.estimate)))
                .collect(),
            sonar: None,
            points: record.reconstruction.as_ref().map(|r| {
                let main = r.main();
                (main.placement, main.model.vertices.as_slice())
            }),
            link_events: link_events
                .iter()
                .map(|e| (e.stamp, e.device.to_string(), e.what.clone()))
                .collect(),
            tape: &record.tape,
        },
    )?;
    let pose = |p: &Pose2| [p.x, p.y, p.theta];
    let summary = DriveSummary {
        scenario: record.scenario.clone(),
        robot: scenario.robot.name.clone(),
        steps: record.steps,
        scans: record.scans.len(),
        robot_seconds: record.end.secs_f64(),
        wall_seconds: record.wall_seconds,
        final_odometry: pose(&record.final_odometry),
        matcher: record.localisation.as_ref().map(|(k, _, _)| k.to_string()),
        final_estimate: record
            .localisation
            .as_ref()
            .and_then(|(_, placed, _)| placed.last().map(|p| pose(&p.estimate))),
        matches: record
            .localisation
            .as_ref()
            .map(|(_, placed, _)| MatchStats::of(placed)),
        odometry_cells: occupied_cells(&odometry_map).len(),
        estimate_cells: record
            .localisation
            .as_ref()
            .map(|(_, _, map)| occupied_cells(map).len()),
        link_events: link_events.iter().map(ToString::to_string).collect(),
    };
    let mut text = serde_json::to_string_pretty(&summary)?;
    text.push('\n');
    robot::logs::write_file(file("summary.json"), text)?;
    if let Some(recon) = &record.reconstruction {
        files.extend(crate::output::write_reconstruction(
            dir,
            recon,
            &record.scenario,
            None,
        )?);
    }
    Ok(files)
}

/// `twin drive`: drive a scenario's script on the real robot (or on `twin serve`) through the
/// serial backend, with the same controller and localisation as `twin run`; write the odometry
/// and estimate trajectories, the scans, a map picture and a summary.
#[derive(Clone, Debug, clap::Args)]
pub struct DriveArgs {
    /// The scenario file: its script, robot description, pacing and matcher (its world is
    /// only used for the start pose).
    pub script: PathBuf,
    /// The base microcontroller: a serial device (/dev/ttyUSB0) or tcp:HOST:PORT.
    #[arg(long)]
    pub base: robot::serial::Endpoint,
    /// The pan-tilt microcontroller, if the scenario positions the head.
    #[arg(long = "pantilt")]
    pub pan_tilt: Option<robot::serial::Endpoint>,
    /// The laser.
    #[arg(long)]
    pub laser: robot::serial::Endpoint,
    /// The matcher: ls, lorentz, lorentz-lines, mbicp or pl-icp [default: the scenario's, if any].
    #[arg(long)]
    pub matcher: Option<MatcherKind>,
    /// Output folder [default: out/drive-SCENARIO-NAME].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// How much faster than real time the devices run (the --speed of `twin serve`; 1 on the
    /// real robot).
    #[arg(long, default_value_t = 1.0)]
    pub time_scale: f64,
    /// Print nothing but errors.
    #[arg(long, short)]
    pub quiet: bool,
}

/// How to reach the devices of `scenario`'s robot: the rates, the laser's sweep and range, and
/// the pan-tilt head's geometry from its description.
pub fn serial_config(
    scenario: &Scenario,
    base: robot::serial::Endpoint,
    pan_tilt: Option<robot::serial::Endpoint>,
    laser: Option<robot::serial::Endpoint>,
) -> robot::serial::SerialConfig {
    let robot = &scenario.robot;
    let mut config = robot::serial::SerialConfig::new(base);
    config.pan_tilt = pan_tilt;
    config.laser = laser;
    config.base_baud = robot.drive.serial_baud;
    if let Some(pt) = &robot.pan_tilt {
        config.pan_tilt_baud = pt.serial_baud;
    }
    config.laser_baud = robot.laser.baud;
    config.laser_sweep = std::time::Duration::from_secs_f64(robot.laser.sweep_s.get());
    config.laser_range_max_mm = (robot.laser.range_max_m.get() * 1000.0).round() as u16;
    if let robot::mount::LaserMount::Head(head) = robot.mount() {
        config.head = Some(head);
    }
    config
}

/// Runs `twin drive`.
pub fn main(args: DriveArgs) -> Result<(), super::CommandError> {
    use super::CommandError;
    use robot::serial::SerialRobot;
    if !(args.time_scale > 0.0 && args.time_scale <= 1000.0) {
        return Err(CommandError::option(
            "--time-scale",
            "must be above 0 and at most 1000",
            args.time_scale,
        ));
    }
    let scenario = Scenario::load(&args.script)?;
    let moves_head = scenario.pan_tilt.is_some() || scenario.steps.iter().any(|s| s.uses_head());
    if moves_head && args.pan_tilt.is_none() {
        return Err(CommandError::MissingOption {
            option: "--pantilt",
            why: format!(
                "{} moves the pan-tilt head (its [pan_tilt] table or head, sweep, scene or survey \
                 steps): give the pan-tilt microcontroller's address, e.g. --pantilt tcp:127.0.0.1:4002",
                args.script.display()
            ),
        });
    }
    let config = serial_config(&scenario, args.base, args.pan_tilt, Some(args.laser));
    let clock: std::sync::Arc<dyn robot::Clock> =
        std::sync::Arc::new(super::serve::WallClock::new(args.time_scale));
    // Every call through the contract is taped, so the drive can be replayed (`twin run --replay`).
    let mut robot =
        robot::replay::Taped::new(SerialRobot::open(config, clock).map_err(CommandError::Open)?);
    let bar = super::step_bar(args.quiet, scenario.steps.len());
    bar.set_prefix(format!("drive {}", scenario.name));
    let result = drive_scenario(&mut robot, &scenario, args.matcher, |done, _| {
        bar.set_position(done as u64)
    });
    bar.finish_and_clear();
    let events = robot.inner_mut().take_events();
    if !args.quiet {
        for e in &events {
            eprintln!("{e}");
        }
    }
    let mut record = result?;
    record.tape = robot.into_parts().1;
    let dir = args
        .out
        .unwrap_or_else(|| PathBuf::from("out").join(format!("drive-{}", scenario.name)));
    let files =
        write_drive(&record, &scenario, &events, &dir).map_err(|source| CommandError::Write {
            dir: dir.clone(),
            source,
        })?;
    if !args.quiet {
        let p = record.final_odometry;
        say!(
            "{}: {} steps, {} scans in {:.1} s; final odometry ({:.3} m, {:.3} m, {:.2} deg); {} link event(s)",
            record.scenario,
            record.steps,
            record.scans.len(),
            record.wall_seconds,
            p.x,
            p.y,
            p.theta.to_degrees(),
            events.len()
        );
        record.say_estimate();
        if let Some(recon) = &record.reconstruction {
            say!(
                "{}",
                crate::output::reconstruction_report(recon).trim_end_matches('\n')
            );
        }
        say!("wrote {}", dir.display());
        for f in &files {
            say!("  {}", f.display());
        }
    }
    Ok(())
}
