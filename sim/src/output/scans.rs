//! Scans as JSON Lines, one object per scan, in the shape later tools read.

use crate::record::ScanRecord;
use robot::Pose2;
use robot::control::SceneTag;
use robot::hardware::{HeadAngles, LaserScan};
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

impl ScanLine {
    /// The scan as the robot received it (ranges back in millimetres, the head's angles).
    pub fn to_scan(&self, stamp: robot::Stamp) -> LaserScan {
        let range_max_mm = (self.range_max * 1000.0).round().clamp(1.0, 65_535.0) as u16;
        LaserScan {
            stamp,
            angle_min: self.angle_min,
            angle_increment: self.angle_increment,
            range_max_mm,
            ranges_mm: self
                .ranges
                .iter()
                .map(|&r| (r * 1000.0).round().clamp(0.0, f64::from(range_max_mm)) as u16)
                .collect(),
            head: self
                .head_pan
                .zip(self.head_tilt)
                .map(|(pan, tilt)| HeadAngles { pan, tilt }),
        }
    }
}

/// Reads a `scans.jsonl`: every line one [`ScanLine`], in time order, with finite numbers.
pub fn read_scan_lines(path: &Path) -> Result<Vec<ScanLine>, super::ReadError> {
    use super::ReadError;
    let text = ReadError::read(path)?;
    let mut lines: Vec<ScanLine> = Vec::new();
    for (i, text) in text.lines().enumerate() {
        if text.trim().is_empty() {
            continue;
        }
        let line: ScanLine = serde_json::from_str(text)
            .map_err(|e| ReadError::malformed(path, i + 1, format!("not a scan line: {e}")))?;
        let numbers = [line.t, line.angle_min, line.angle_increment, line.range_max]
            .into_iter()
            .chain(line.ranges.iter().copied())
            .chain(line.odometry)
            .chain(line.laser_mount.into_iter().flatten())
            .chain(line.laser_z)
            .chain(line.laser_tilt)
            .chain(line.head_pan)
            .chain(line.head_tilt);
        let mut numbers = numbers;
        if numbers.any(|v| !v.is_finite()) {
            return Err(ReadError::malformed(path, i + 1, "a number is not finite"));
        }
        if !(line.t >= 0.0 && line.t < 1e9 && line.range_max > 0.0 && line.range_max <= 65.0) {
            return Err(ReadError::malformed(
                path,
                i + 1,
                format!(
                    "t must be in [0, 1e9) s and range_max in (0, 65] m, found t = {} and range_max = {}",
                    line.t, line.range_max
                ),
            ));
        }
        // Finite is not enough: every field in a range a robot indoors can have.
        let tau = std::f64::consts::TAU;
        let limits: [(&str, Option<f64>, f64); 9] = [
            ("angle_min", Some(line.angle_min), tau),
            ("angle_increment", Some(line.angle_increment), 1.0),
            ("odometry[0]", Some(line.odometry[0]), 1e5),
            ("odometry[1]", Some(line.odometry[1]), 1e5),
            ("odometry[2]", Some(line.odometry[2]), 1e3),
            ("laser_z", line.laser_z, 100.0),
            ("laser_tilt", line.laser_tilt, tau),
            ("head_pan", line.head_pan, 2.0 * tau),
            ("head_tilt", line.head_tilt, tau),
        ];
        let mount = line.laser_mount.unwrap_or_default();
        let limits = limits.into_iter().chain([
            ("laser_mount[0]", Some(mount[0]), 100.0),
            ("laser_mount[1]", Some(mount[1]), 100.0),
            ("laser_mount[2]", Some(mount[2]), 2.0 * tau),
        ]);
        for (field, value, limit) in limits {
            if let Some(v) = value
                && v.abs() > limit
            {
                return Err(ReadError::malformed(
                    path,
                    i + 1,
                    format!("{field} = {v:?} is out of range: expected at most {limit} in size"),
                ));
            }
        }
        if line.ranges.len() > 10_000 || line.ranges.iter().any(|&r| r < 0.0) {
            return Err(ReadError::malformed(
                path,
                i + 1,
                "ranges must be at most 10000 readings, none negative",
            ));
        }
        if lines.last().is_some_and(|last| line.t < last.t) {
            return Err(ReadError::malformed(path, i + 1, "time goes back"));
        }
        lines.push(line);
    }
    Ok(lines)
}

/// Writes one JSON object per scan.
pub fn write_scans(path: &Path, records: &[ScanRecord], mount: &LaserMount) -> std::io::Result<()> {
    write_scan_lines(path, records.iter().map(|r| ScanLine::of(r, mount)))
}

/// Writes one JSON object per line.
pub fn write_scan_lines(path: &Path, lines: impl Iterator<Item = ScanLine>) -> std::io::Result<()> {
    let mut out = BufWriter::new(robot::logs::create_file(path)?);
    for line in lines {
        write_scan_line(&mut out, &line)?;
    }
    out.flush()
}

/// One line of `scans.jsonl`, its newline included.
fn write_scan_line(out: &mut impl Write, line: &ScanLine) -> std::io::Result<()> {
    let mut json = serde_json::Serializer::with_formatter(&mut *out, Millimetres);
    line.serialize(&mut json)?;
    out.write_all(b"\n")
}

/// [`write_scan_lines`]'s bytes for `line`, appended to `out`.
pub(super) fn push_scan_line(out: &mut Vec<u8>, line: &ScanLine) {
    // Serialising numbers and strings into memory cannot fail.
    let _ = write_scan_line(out, line);
}

/// serde_json's compact output, with a fast path for the numbers that fill a scan line — whole
/// millimetres in metres — which gives the same bytes as the general one (the shortest decimal
/// that reads back to the same number) without its work.
struct Millimetres;

impl serde_json::ser::Formatter for Millimetres {
    fn write_f64<W: ?Sized + Write>(&mut self, writer: &mut W, value: f64) -> std::io::Result<()> {
        // The nearest whole millimetre of a non-negative value (truncation after adding a half,
        // saturating), checked below to be the value exactly.
        let mm = (value * 1000.0 + 0.5) as u32;
        if value.is_sign_positive() && mm < 65_536 && f64::from(mm) / 1000.0 == value {
            // At most "65.535": whole metres, a point, then the millimetres without trailing
            // zeros (one digit at least).
            let mut text = [0u8; 8];
            let mut n = 0;
            let whole = mm / 1000;
            if whole >= 10 {
                text[n] = b'0' + (whole / 10) as u8;
                n += 1;
            }
            text[n] = b'0' + (whole % 10) as u8;
            text[n + 1] = b'.';
            n += 2;
            let digits = [mm / 100 % 10, mm / 10 % 10, mm % 10];
            let kept = digits
                .iter()
                .rposition(|&d| d != 0)
                .map_or(1, |last| last + 1);
            for &d in &digits[..kept] {
                text[n] = b'0' + d as u8;
                n += 1;
            }
            writer.write_all(&text[..n])
        } else {
            serde_json::ser::CompactFormatter.write_f64(writer, value)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn both(value: f64) -> (String, String) {
        let mut fast = Vec::new();
        let mut json = serde_json::Serializer::with_formatter(&mut fast, Millimetres);
        value.serialize(&mut json).unwrap();
        (
            String::from_utf8(fast).unwrap(),
            serde_json::to_string(&value).unwrap(),
        )
    }

    #[test]
    fn the_millimetre_path_writes_what_serde_json_writes() {
        for mm in 0..=65_535u32 {
            let (fast, general) = both(f64::from(mm) / 1000.0);
            assert_eq!(fast, general, "{mm} mm");
        }
        for value in [
            -0.0,
            -1.5,
            0.1 + 0.2,
            1e-7,
            123_456.789,
            65.5355,
            1.234_567_8,
            1e300,
        ] {
            let (fast, general) = both(value);
            assert_eq!(fast, general, "{value}");
        }
    }
}
