//! Scans as JSON Lines, one object per scan, in the shape later tools read.

use crate::record::ScanRecord;
use robot::Pose2;
use robot::control::SceneTag;
use robot::hardware::LaserScan;
use robot::mount::LaserMount;
use serde::Serialize;
use std::io::{BufWriter, Write};
use std::path::Path;

/// One line of `scans.jsonl`: a scan and everything needed to put its points in 3D again.
///
/// Ranges are metres; a range `>= range_max` means no return. Angles are in the laser frame
/// (x forward, y left). `odometry` is the robot's `[x, y, theta]` at the scan's time;
/// `laser_mount` the laser's `[x, y, yaw]` on the base at that time (panned, on a pan-tilt),
/// `laser_z` the height of its optical centre and `laser_tilt` the tilt of its scan plane
/// (radians, positive when the forward beams rise) — all from the robot's description and the
/// head's angles the scan carries (`head_pan`, `head_tilt`; absent for a fixed laser, and the
/// pose absent when the head's angles were unknown). `scene` and `station` number the 3D scene
/// a `scene` or `survey` step took the scan for.
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
    /// The laser's pose on the base in the plane, `[x, y, yaw]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub laser_mount: Option<[f64; 3]>,
    /// Height of the laser's optical centre above the floor, metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub laser_z: Option<f64>,
    /// Tilt of the scan plane, radians.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub laser_tilt: Option<f64>,
    /// The pan-tilt head's pan when the scan was measured, radians.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub head_pan: Option<f64>,
    /// The pan-tilt head's tilt when the scan was measured, radians.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub head_tilt: Option<f64>,
    /// The 3D scene the scan belongs to.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene: Option<usize>,
    /// The station of that scene.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub station: Option<usize>,
}

impl ScanLine {
    /// The line for a recorded scan of the twin.
    pub fn of(record: &ScanRecord, mount: &LaserMount) -> Self {
        Self::new(&record.scan, record.odometry, mount, record.scene)
    }

    /// The line for `s`, taken at `odometry` by a laser at `mount` (its head angles are the
    /// scan's), for `scene`.
    pub fn new(
        s: &LaserScan,
        odometry: Pose2,
        mount: &LaserMount,
        scene: Option<SceneTag>,
    ) -> Self {
        let laser = mount.laser_on_base(s.head);
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
            laser_mount: laser.map(|l| {
                let p = l.planar();
                [p.x, p.y, p.theta]
            }),
            laser_z: laser.map(|l| l.origin()[2]),
            laser_tilt: laser.map(|l| l.tilt()),
            head_pan: s.head.map(|h| h.pan),
            head_tilt: s.head.map(|h| h.tilt),
            scene: scene.map(|t| t.scene),
            station: scene.map(|t| t.station),
        }
    }
}

/// Writes one JSON object per scan.
pub fn write_scans(path: &Path, records: &[ScanRecord], mount: &LaserMount) -> std::io::Result<()> {
    write_scan_lines(path, records.iter().map(|r| ScanLine::of(r, mount)))
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
