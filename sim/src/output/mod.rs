//! The files `twin run` writes: trajectories in TUM format (truth, odometry and — when the
//! scenario localises — the scan-matching estimate), scans as JSON Lines, a summary, a picture of
//! the map, and — when the laser was tilted — a picture of a tilted scan.
//!
//! Everything but `summary.json` (which reports wall-clock time) is a pure function of the
//! scenario and the seed: numbers are printed with fixed precision, so two runs give the same
//! bytes.

pub mod figure;
mod grid;
pub mod logmap;
mod mcap;
pub mod pair;
mod ply;
mod reconstruction;
mod render;
mod scans;
mod sonar;
mod stream;
mod summary;
mod svg;
mod tilted;
mod tum;
mod world_json;
pub use world_json::write_world_json;

use grid::grid_scan;
pub use grid::write_grid;
pub use mcap::{
    RecordedScan, Recording, estimate_msg, head_transforms, no_scan, scan_msg, scan_topics,
    static_transforms, write_mcap,
};
pub use ply::write_ply;
pub use reconstruction::{
    ReconstructionFile, THESIS_QUADS, THESIS_TRIANGLES, reconstruction_file, reconstruction_report,
    write_reconstruction,
};
pub use render::{Picture, write_model_png};
pub use scans::{ScanLine, read_scan_lines, write_scan_lines, write_scans};
pub use sonar::write_sonar;
pub use stream::ScanStream;

/// Writes what the navigating steps decided, one JSON object a line: the stamp `t` (s), the
/// `estimate` steered by and the `odometry` (x, y m, heading rad), and the `decision` — a
/// `Motion` (turn, advance, free way) or `Done` with the step's outcome.
pub fn write_decisions(
    path: &Path,
    decisions: &[crate::record::DecisionRecord],
) -> std::io::Result<()> {
    use std::io::Write;
    let mut out = std::io::BufWriter::new(robot::logs::create_file(path)?);
    for d in decisions {
        serde_json::to_writer(&mut out, d)?;
        out.write_all(b"\n")?;
    }
    out.flush()
}
pub use summary::{LocalisationSummary, Summary, estimate_errors};
pub use svg::{new_scan_dots, write_map_svg};
pub use tilted::{last_tilted, write_tilted_svg};
pub use tum::{read_tum, write_tum};

/// A run's level scans with the laser's pose in the world when each was taken: by the
/// scan-matching estimate when the run localises, else by odometry (scenes' scans, and those
/// the head's reported angles put off level, as the localiser judges, are left out).
fn level_scans(record: &RunRecord, scenario: &Scenario) -> Vec<(robot::Pose2, RangeScan)> {
    let mount = scenario.robot.mount();
    match &record.localisation {
        Some(loc) => loc
            .placed
            .iter()
            .filter_map(|p| {
                let i = record
                    .scans
                    .binary_search_by_key(&p.stamp, |s| s.scan.stamp)
                    .ok()?;
                grid_scan(&mount, &record.scans[i].scan, p.estimate)
            })
            .collect(),
        None => record
            .scans
            .iter()
            .filter(|s| s.scene.is_none())
            .filter_map(|s| grid_scan(&mount, &s.scan, s.odometry))
            .collect(),
    }
}

/// A run as the topics of `run.mcap`.
pub(crate) fn recording<'a>(record: &'a RunRecord, scenario: &Scenario) -> Recording<'a> {
    let robot = &scenario.robot;
    Recording {
        mount: robot.mount(),
        scan_time_s: scan_period_s(&robot.laser),
        scans: record
            .scans
            .iter()
            .map(|s| RecordedScan {
                scan: &s.scan,
                odometry: s.odometry,
                truth: Some(s.truth),
                after: s.after_exchanges,
            })
            .collect(),
        estimate: record
            .localisation
            .iter()
            .flat_map(|l| l.placed.iter().map(|p| (p.stamp, p.estimate)))
            .collect(),
        sonar: record.sonar.as_ref().zip(
            robot
                .sonar
                .as_ref()
                .map(|d| [d.min_range_m.get(), d.max_range_m.get()]),
        ),
        points: record.reconstruction.as_ref().map(|r| {
            let main = r.main();
            (main.placement, main.model.vertices.as_slice())
        }),
        link_events: Vec::new(),
        tape: &record.tape,
    }
}

/// Mean time between a laser's scans, seconds: its sweep or its telegram's transfer.
pub(crate) fn scan_period_s(laser: &crate::config::robot_file::LaserDescription) -> f64 {
    crate::devices::laser::LaserTiming::new(
        std::time::Duration::from_secs_f64(laser.sweep_s.get()),
        laser.telegram_bytes,
        laser.baud,
    )
    .mean_period()
    .as_secs_f64()
}

/// Why a file a run wrote cannot be read back.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file cannot be read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What failed.
        #[source]
        source: std::io::Error,
    },
    /// A line is not what the format says.
    #[error("{}:{line}: {message}", path.display())]
    Malformed {
        /// The file.
        path: PathBuf,
        /// Line number, from 1.
        line: usize,
        /// What was wrong and what was expected.
        message: String,
    },
}

impl ReadError {
    /// The whole file as text.
    pub(crate) fn read(path: &Path) -> Result<String, ReadError> {
        std::fs::read_to_string(path).map_err(|source| ReadError::Io {
            path: path.to_path_buf(),
            source,
        })
    }

    pub(crate) fn malformed(path: &Path, line: usize, message: impl Into<String>) -> ReadError {
        ReadError::Malformed {
            path: path.to_path_buf(),
            line,
            message: message.into(),
        }
    }
}

use crate::config::Scenario;
use crate::record::RunRecord;
use robot::localization::RangeScan;
use std::path::{Path, PathBuf};

/// Where each output file went.
#[derive(Clone, Debug)]
pub struct Written {
    /// The folder.
    pub dir: PathBuf,
    /// The files, in the order written.
    pub files: Vec<PathBuf>,
}

/// Writes every output of a run into `dir` (created if needed).
///
/// The files are independent, so they are written on two threads, one a core: the pictures and
/// the occupancy grid on one, the recording and the small files on this one (and the 3D model's
/// files, when the run built any, on a third). Two threads and not one a file: writing them is
/// bound by the cores, and four threads on two cores took longer than two (the README's *Whole
/// process against simulation*). Each file's bytes are what one thread would write, and the
/// list comes back in one fixed order.
pub fn write_all(record: &RunRecord, scenario: &Scenario, dir: &Path) -> std::io::Result<Written> {
    std::fs::create_dir_all(dir)?;
    let path = |name: &str| dir.join(name);
    // The twin's map of the world answers every picture's and file's questions about it.
    let map = &*record.world_map;
    let pictures = || -> std::io::Result<Vec<PathBuf>> {
        let mut files = vec![path("map.svg"), path("world.json")];
        // The scans' points drawn during the run, else drawn now.
        let drawn_now;
        let dots = match record.streamed.as_ref().and_then(|s| s.dots.as_ref()) {
            Some(dots) => dots,
            None => {
                drawn_now = svg::scan_dots(record, &scenario.world);
                &drawn_now
            }
        };
        write_map_svg(&files[0], record, &scenario.world, dots)?;
        write_world_json(&files[1], scenario, map)?;
        if let Some(scan) = last_tilted(record) {
            files.push(path("tilted-scan.svg"));
            write_tilted_svg(&files[2], scan, &scenario.world, map, &record.scenario)?;
        }
        Ok(files)
    };
    let grid = || match &record.streamed {
        Some(built) => grid::write_grid_files(dir, built.grid.grid().as_ref()),
        None => write_grid(
            dir,
            level_scans(record, scenario).iter().map(|(p, s)| (*p, s)),
        ),
    };
    let recording_file = || -> std::io::Result<Vec<PathBuf>> {
        let file = path("run.mcap");
        match record.streamed.as_ref().and_then(|s| s.run_mcap.as_ref()) {
            Some(bytes) => robot::logs::write_file(&file, bytes)?,
            None => {
                write_mcap(&file, &recording(record, scenario))?;
            }
        }
        Ok(vec![file])
    };
    let small_files = || -> std::io::Result<Vec<PathBuf>> {
        let mut files = vec![path("truth.tum"), path("odometry.tum")];
        match record.streamed.as_ref().and_then(|s| s.tum.as_ref()) {
            Some([truth, odometry]) => {
                robot::logs::write_file(&files[0], truth)?;
                robot::logs::write_file(&files[1], odometry)?;
            }
            None => {
                write_tum(
                    &files[0],
                    record.scans.iter().map(|r| (r.scan.stamp, r.truth)),
                )?;
                write_tum(
                    &files[1],
                    record.scans.iter().map(|r| (r.scan.stamp, r.odometry)),
                )?;
            }
        }
        if let Some(loc) = &record.localisation {
            files.push(path("estimate.tum"));
            write_tum(
                &path("estimate.tum"),
                loc.placed.iter().map(|p| (p.stamp, p.estimate)),
            )?;
        }
        files.push(path("scans.jsonl"));
        match &record.streamed {
            Some(built) => robot::logs::write_file(path("scans.jsonl"), &built.scan_lines)?,
            None => write_scans(&path("scans.jsonl"), &record.scans, &scenario.robot.mount())?,
        }
        files.push(path("summary.json"));
        Summary::of(record, (&scenario.world.name, &scenario.robot.name))
            .write(&path("summary.json"))?;
        if let Some(sonar) = &record.sonar {
            files.push(path("sonar.json"));
            write_sonar(&path("sonar.json"), sonar)?;
        }
        if !record.decisions.is_empty() {
            files.push(path("decisions.jsonl"));
            write_decisions(&path("decisions.jsonl"), &record.decisions)?;
        }
        Ok(files)
    };
    fn join<T>(h: std::thread::ScopedJoinHandle<'_, T>) -> T {
        h.join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
    }
    let ((pictures, grid), reconstruction, recording_file, rest) = std::thread::scope(|s| {
        let drawn = s.spawn(|| (pictures(), grid()));
        let reconstruction = record
            .reconstruction
            .as_ref()
            .map(|recon| s.spawn(|| write_reconstruction(dir, recon, &record.scenario, Some(map))));
        let recording_file = recording_file();
        let rest = small_files();
        (
            join(drawn),
            reconstruction.map_or(Ok(Vec::new()), join),
            recording_file,
            rest,
        )
    });
    let mut files = rest?;
    files.extend(pictures?);
    files.extend(recording_file?);
    files.extend(grid?);
    files.extend(reconstruction?);
    Ok(Written {
        dir: dir.to_path_buf(),
        files,
    })
}
