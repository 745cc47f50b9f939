//! The files `twin run` writes: trajectories in TUM format (truth, odometry and — when the
//! scenario localises — the scan-matching estimate), scans as JSON Lines, a summary, a picture of
//! the map, and — when the laser was tilted — a picture of a tilted scan.
//!
//! Everything but `summary.json` (which reports wall-clock time) is a pure function of the
//! scenario and the seed: numbers are printed with fixed precision, so two runs give the same
//! bytes.

pub mod logmap;
mod scans;
mod sonar;
mod summary;
mod svg;
mod tilted;
mod tum;

pub use scans::{ScanLine, write_scan_lines, write_scans};
pub use sonar::write_sonar;
pub use summary::{LocalisationSummary, Summary, estimate_errors};
pub use svg::write_map_svg;
pub use tilted::{last_tilted, write_tilted_svg};
pub use tum::write_tum;

use crate::config::Scenario;
use crate::record::RunRecord;
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
pub fn write_all(record: &RunRecord, scenario: &Scenario, dir: &Path) -> std::io::Result<Written> {
    std::fs::create_dir_all(dir)?;
    let mut files = Vec::new();
    let mut file = |name: &str| {
        let path = dir.join(name);
        files.push(path.clone());
        path
    };
    write_tum(
        &file("truth.tum"),
        record.scans.iter().map(|r| (r.scan.stamp, r.truth)),
    )?;
    write_tum(
        &file("odometry.tum"),
        record.scans.iter().map(|r| (r.scan.stamp, r.odometry)),
    )?;
    if let Some(loc) = &record.localisation {
        write_tum(
            &file("estimate.tum"),
            loc.placed.iter().map(|p| (p.stamp, p.estimate)),
        )?;
    }
    write_scans(&file("scans.jsonl"), &record.scans, &scenario.robot.mount())?;
    Summary::of(record, (&scenario.world.name, &scenario.robot.name))
        .write(&file("summary.json"))?;
    if let Some(sonar) = &record.sonar {
        write_sonar(&file("sonar.json"), sonar)?;
    }
    write_map_svg(&file("map.svg"), record, &scenario.world)?;
    if let Some(scan) = last_tilted(record) {
        write_tilted_svg(
            &file("tilted-scan.svg"),
            scan,
            &scenario.world,
            &record.scenario,
        )?;
    }
    Ok(Written {
        dir: dir.to_path_buf(),
        files,
    })
}
