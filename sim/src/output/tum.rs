//! Trajectories in the TUM RGB-D format: one `t x y z qx qy qz qw` line per pose, the format
//! trajectory tools such as evo read.

use robot::{Pose2, Stamp};
use std::io::{BufWriter, Write};
use std::path::Path;

/// Writes `poses` to `path`: time in seconds with nine decimals, position in metres with six,
/// the heading as a unit quaternion about z with nine.
pub fn write_tum(path: &Path, poses: impl Iterator<Item = (Stamp, Pose2)>) -> std::io::Result<()> {
    let mut out = BufWriter::new(std::fs::File::create(path)?);
    writeln!(out, "# t x y z qx qy qz qw")?;
    for (t, p) in poses {
        let [qx, qy, qz, qw] = p.quaternion();
        writeln!(
            out,
            "{t} {:.6} {:.6} 0.000000 {qx:.9} {qy:.9} {qz:.9} {qw:.9}",
            p.x, p.y
        )?;
    }
    out.flush()
}
