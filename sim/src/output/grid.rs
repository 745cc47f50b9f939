//! `map.pgm` + `map.yaml`: the occupancy grid of a run's or a log's scans, placed by the
//! scan-matching estimate, in the ROS `map_server` convention (`robot::localization::grid`).

use robot::Pose2;
use robot::hardware::LaserScan;
use robot::localization::{
    GridConfig, LEVEL_TOLERANCE_RAD, LevelLocaliser, OccupancyGrid, RangeScan,
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
    robot::logs::write_file(&pgm, grid.pgm())?;
    robot::logs::write_file(&yaml, grid.yaml("map.pgm"))?;
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
pub(super) fn grid_pose(mount: &LaserMount, scan: &LaserScan, base: Pose2) -> Option<Pose2> {
    let laser = LevelLocaliser::level_mount(mount, scan, LEVEL_TOLERANCE_RAD)?;
    Some(base.compose(&laser))
}
