//! 3D models as binary PLY (little endian): vertices with their normals, and the triangles.
//!
//! In the run's world frame, metres, z up: the frame of `truth.tum` and `estimate.tum`. Readers
//! that expect y up (the thesis's OpenGL viewer, some mesh tools) rotate it themselves; the file
//! says which way is up in a comment.

use robot::reconstruction::Model;
use std::io::{BufWriter, Write};
use std::path::Path;

/// Writes `model` to `path`: `vertex` with `x y z nx ny nz` (float) and `scene` (ushort), and,
/// unless `points_only`, `face` with `vertex_indices` (uchar count, uint indices).
pub fn write_ply(path: &Path, model: &Model, points_only: bool) -> std::io::Result<()> {
    let mut out = BufWriter::new(robot::logs::create_file(path)?);
    let faces = if points_only {
        0
    } else {
        model.triangles.len()
    };
    write!(
        out,
        "ply\nformat binary_little_endian 1.0\n\
         comment robot twin 3D model: world frame, metres, z up (REP-103)\n\
         element vertex {}\n\
         property float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\n\
         property ushort scene\n",
        model.vertices.len()
    )?;
    if !points_only {
        write!(
            out,
            "element face {faces}\nproperty list uchar uint vertex_indices\n"
        )?;
    }
    out.write_all(b"end_header\n")?;
    for ((v, n), s) in model
        .vertices
        .iter()
        .zip(&model.normals)
        .zip(&model.vertex_scene)
    {
        for x in v.iter().chain(n) {
            out.write_all(&x.to_le_bytes())?;
        }
        out.write_all(&s.to_le_bytes())?;
    }
    if !points_only {
        for t in &model.triangles {
            out.write_all(&[3])?;
            for k in t {
                out.write_all(&k.to_le_bytes())?;
            }
        }
    }
    out.flush()
}
