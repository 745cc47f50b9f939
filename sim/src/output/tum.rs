//! Trajectories in the TUM RGB-D format: one `t x y z qx qy qz qw` line per pose, the format
//! trajectory tools such as evo read.

use robot::{Pose2, Stamp};
use std::io::{BufWriter, Write};
use std::path::Path;

/// Writes `poses` to `path`: time in seconds with nine decimals, position in metres with six,
/// the heading as a unit quaternion about z with nine.
pub fn write_tum(path: &Path, poses: impl Iterator<Item = (Stamp, Pose2)>) -> std::io::Result<()> {
    let mut out = BufWriter::new(robot::logs::create_file(path)?);
    out.write_all(TUM_HEADER)?;
    for (t, p) in poses {
        write_tum_line(&mut out, t, p)?;
    }
    out.flush()
}

/// The first line of a TUM file.
pub(super) const TUM_HEADER: &[u8] = b"# t x y z qx qy qz qw\n";

/// One pose's line of a TUM file.
pub(super) fn write_tum_line(out: &mut impl Write, t: Stamp, p: Pose2) -> std::io::Result<()> {
    let [qx, qy, qz, qw] = p.quaternion();
    writeln!(
        out,
        "{t} {:.6} {:.6} 0.000000 {qx:.9} {qy:.9} {qz:.9} {qw:.9}",
        p.x, p.y
    )
}

/// Reads a TUM file written by [`write_tum`] (or any tool: `t x y z qx qy qz qw`, `#` comments):
/// the planar pose of each line, its heading from the quaternion about z.
pub fn read_tum(path: &Path) -> Result<Vec<(Stamp, Pose2)>, super::ReadError> {
    use super::ReadError;
    let text = ReadError::read(path)?;
    let mut poses: Vec<(Stamp, Pose2)> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let bad = |what: &str| {
            ReadError::malformed(
                path,
                i + 1,
                format!(
                    "{what}: expected `t x y z qx qy qz qw`, eight finite numbers, t in [0, 1e9) s and increasing, positions within 100 km, a unit quaternion"
                ),
            )
        };
        let values: Vec<f64> = line
            .split_whitespace()
            .map(|v| v.parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| bad("not a number"))?;
        if values.len() != 8 {
            return Err(bad(&format!("{} fields", values.len())));
        }
        if values.iter().any(|v| !v.is_finite())
            || !(0.0..1e9).contains(&values[0])
            || values[1..4].iter().any(|v| v.abs() > 1e5)
            || values[4..].iter().any(|v| v.abs() > 1.0 + 1e-6)
        {
            return Err(bad("out of range"));
        }
        let t = Stamp((values[0] * 1e9).round() as u64);
        if poses.last().is_some_and(|(last, _)| t <= *last) {
            return Err(bad("time goes back"));
        }
        let (qz, qw) = (values[6], values[7]);
        poses.push((t, Pose2::new(values[1], values[2], 2.0 * qz.atan2(qw))));
    }
    Ok(poses)
}
