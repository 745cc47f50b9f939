//! Scans as JSON Lines, one object per scan, in the shape later tools read.

use crate::record::ScanRecord;
use robot::Pose2;
use robot::hardware::LaserScan;
use serde::Serialize;
use std::io::{BufWriter, Write};
use std::path::Path;

/// One line of `scans.jsonl`.
///
/// Ranges are metres; a range `>= range_max` means no return. Angles are in the laser frame
/// (x forward, y left). `odometry` is the robot's `[x, y, theta]` at the scan's time,
/// `laser_mount` the laser's `[x, y, theta]` on the robot at that time (panned, on a pan-tilt),
/// `laser_z` the height of its optical centre and `laser_tilt` the tilt of its scan plane (radians,
/// positive when the forward beams rise).
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct ScanLine {
    /// Time of the scan, seconds.
    pub t: f64,
    /// Angle of the first beam, radians.
    pub angle_min: f64,
    /// Angle between beams, radians.
    pub angle_increment: f64,
    /// No-return value, metres.
    pub range_max: f64,
    /// Ranges, metres.
    pub ranges: Vec<f64>,
    /// Odometry `[x, y, theta]` at `t`.
    pub odometry: [f64; 3],
    /// The laser's pose on the base, `[x, y, theta]`.
    pub laser_mount: [f64; 3],
    /// Height of the laser's optical centre above the floor, metres.
    pub laser_z: f64,
    /// Tilt of the scan plane, radians.
    pub laser_tilt: f64,
}

impl ScanLine {
    /// The line for a recorded scan.
    pub fn of(record: &ScanRecord) -> Self {
        let mount = record.frame.mount_on(record.truth);
        Self::new(
            &record.scan,
            record.odometry,
            mount,
            record.frame.origin[2],
            record.frame.tilt,
        )
    }

    /// The line for `s`, taken at `odometry` by a laser at `mount` on the base, `z` above the
    /// floor, its scan plane tilted by `tilt`.
    pub fn new(s: &LaserScan, odometry: Pose2, mount: Pose2, z: f64, tilt: f64) -> Self {
        ScanLine {
            t: s.stamp.secs_f64(),
            angle_min: s.angle_min,
            angle_increment: s.angle_increment,
            range_max: s.range_max_m(),
            ranges: s
                .ranges_mm
                .iter()
                .map(|&mm| f64::from(mm) / 1000.0)
                .collect(),
            odometry: [odometry.x, odometry.y, odometry.theta],
            laser_mount: [mount.x, mount.y, mount.theta],
            laser_z: z,
            laser_tilt: tilt,
        }
    }
}

/// Writes one JSON object per scan.
pub fn write_scans(path: &Path, records: &[ScanRecord]) -> std::io::Result<()> {
    write_scan_lines(path, records.iter().map(ScanLine::of))
}

/// Writes one JSON object per line.
pub fn write_scan_lines(path: &Path, lines: impl Iterator<Item = ScanLine>) -> std::io::Result<()> {
    let mut out = BufWriter::new(std::fs::File::create(path)?);
    for line in lines {
        serde_json::to_writer(&mut out, &line)?;
        out.write_all(b"\n")?;
    }
    out.flush()
}
