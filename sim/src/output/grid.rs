//! `map.pgm` + `map.yaml`: the occupancy grid of a run's or a log's scans, placed by the
//! scan-matching estimate, in the ROS `map_server` convention (`robot::localization::grid`).

use robot::Pose2;
use robot::localization::{GridConfig, OccupancyGrid, RangeScan};
use std::path::{Path, PathBuf};

/// Writes `map.pgm` and `map.yaml` into `dir` for `scans`, each seen from the laser pose beside
/// it (map frame); returns the files written (none when there is nothing to draw).
pub fn write_grid<'a>(
    dir: &Path,
    scans: impl IntoIterator<Item = (Pose2, &'a RangeScan)> + Clone,
) -> std::io::Result<Vec<PathBuf>> {
    let Some(grid) = OccupancyGrid::from_scans(scans, GridConfig::default()) else {
        return Ok(Vec::new());
    };
    let (pgm, yaml) = (dir.join("map.pgm"), dir.join("map.yaml"));
    std::fs::write(&pgm, grid.pgm())?;
    std::fs::write(&yaml, grid.yaml("map.pgm"))?;
    Ok(vec![pgm, yaml])
}
