//! `map.pgm` + `map.yaml`: the occupancy grid of a run's or a log's scans, placed by the
//! scan-matching estimate, in the ROS `map_server` convention (`robot::localization::grid`).

use robot::Pose2;
use robot::hardware::LaserScan;
use robot::localization::{
    GridBuilder, GridConfig, LEVEL_TOLERANCE_RAD, LevelLocaliser, OccupancyGrid, RangeScan,
};
use robot::mount::LaserMount;
use std::path::{Path, PathBuf};

/// Writes `map.pgm` and `map.yaml` into `dir` for `scans`, each seen from the laser pose beside
/// it (map frame); returns the files written (none when there is nothing to draw).
pub fn write_grid<'a>(
    dir: &Path,
    scans: impl IntoIterator<Item = (Pose2, &'a RangeScan)>,
) -> std::io::Result<Vec<PathBuf>> {
    write_grid_files(
        dir,
        OccupancyGrid::from_scans(scans, GridConfig::default()).as_ref(),
    )
}

/// Writes `map.pgm` and `map.yaml` of `grid` into `dir`; returns the files written (none for no
/// grid).
pub(super) fn write_grid_files(
    dir: &Path,
    grid: Option<&OccupancyGrid>,
) -> std::io::Result<Vec<PathBuf>> {
    let Some(grid) = grid else {
        return Ok(Vec::new());
    };
    let (pgm, yaml) = (dir.join("map.pgm"), dir.join("map.yaml"));
    std::fs::write(&pgm, grid.pgm())?;
    std::fs::write(&yaml, grid.yaml("map.pgm"))?;
    Ok(vec![pgm, yaml])
}

/// What a run's grid takes from one scan, its base at `base` in the map frame: the laser's
/// pose in the map and the ranges, if the scan plane was level (the robot's own rule, from the
/// head's angles, as the localiser decides).
pub(super) fn grid_scan(
    mount: &LaserMount,
    scan: &LaserScan,
    base: Pose2,
) -> Option<(Pose2, RangeScan)> {
    let laser = grid_pose(mount, scan, base)?;
    Some((laser, RangeScan::from(scan)))
}

/// The laser's pose in the map for [`grid_scan`], without the ranges.
fn grid_pose(mount: &LaserMount, scan: &LaserScan, base: Pose2) -> Option<Pose2> {
    let laser = LevelLocaliser::level_mount(mount, scan, LEVEL_TOLERANCE_RAD)?;
    Some(base.compose(&laser))
}

/// A run's occupancy grid built on a thread of its own while the run goes on, as the scans come,
/// so the map is ready when the simulation ends instead of starting then: the same grid, to the
/// last bit, as [`write_grid`] builds from the run's scans afterwards (the same scans reach the
/// same builder in the same order). Scans are handed over in batches, so the run wakes the
/// builder a few dozen times, not at every scan.
#[derive(Debug)]
pub struct GridStream {
    mount: LaserMount,
    batch: Vec<(Pose2, LaserScan)>,
    feed: std::sync::mpsc::Sender<Vec<(Pose2, LaserScan)>>,
    builder: std::thread::JoinHandle<Option<OccupancyGrid>>,
}

/// Scans handed to the builder at once.
const BATCH: usize = 32;

impl GridStream {
    /// Starts the builder for a laser on `mount`.
    pub fn start(mount: LaserMount) -> Self {
        let (feed, batches) = std::sync::mpsc::channel::<Vec<(Pose2, LaserScan)>>();
        let builder = std::thread::spawn(move || {
            let mut grid = GridBuilder::new(GridConfig::default());
            for (laser, scan) in batches.into_iter().flatten() {
                grid.push(laser, &RangeScan::from(&scan));
            }
            grid.finish()
        });
        GridStream {
            mount,
            batch: Vec::with_capacity(BATCH),
            feed,
            builder,
        }
    }

    /// Adds `scan`, its base at `base` in the map frame, if its plane was level (the rule of
    /// [`grid_scan`]).
    pub fn push(&mut self, scan: &LaserScan, base: Pose2) {
        if let Some(laser) = grid_pose(&self.mount, scan, base) {
            self.batch.push((laser, scan.clone()));
            if self.batch.len() == BATCH {
                self.hand_over();
            }
        }
    }

    /// Sends the batch to the builder. It only stops when the feed closes (or when it
    /// panicked, which [`GridStream::finish`] tells), so a send cannot fail before.
    fn hand_over(&mut self) {
        let batch = std::mem::replace(&mut self.batch, Vec::with_capacity(BATCH));
        let _ = self.feed.send(batch);
    }

    /// The grid of every scan pushed (`None`: nothing to draw), once the builder is done.
    pub fn finish(mut self) -> Option<OccupancyGrid> {
        self.hand_over();
        drop(self.feed);
        self.builder
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
    }
}
