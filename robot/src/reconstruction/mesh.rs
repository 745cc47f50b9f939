//! Meshes on a scene's grid (thesis §4.4, Fig. 4.8, App. D.2): quadrilaterals or triangles made
//! of four neighbouring readings, kept only when they plausibly lie on one surface.
//!
//! Of the four readings `v(i,j)`, `v(i+1,j)`, `v(i,j+1)`, `v(i+1,j+1)` (beam `i`, scan `j`) the
//! thesis makes the quadrilateral `v(i,j), v(i,j+1), v(i+1,j+1), v(i+1,j)` or the two triangles
//! `v(i,j), v(i,j+1), v(i+1,j+1)` and `v(i+1,j+1), v(i+1,j), v(i,j)`. A polygon is **valid** when
//! every distance from its first vertex to the others lies within thresholds: 200 mm in the prose,
//! `[DMINV, DMAXV]` = [5 mm, 200 mm] in App. D's `valida_distancia`, which [`MeshRule::Thesis`]
//! follows. Readings with no return are not vertices (the thesis kept its 32 m readings and let
//! the 200 mm rule drop them; leaving them out drops the same polygons and no others). Scenes are
//! meshed on their own: App. D also joined the last scan of one file to the first of the next,
//! across scenes, which bridges two pans with polygons nobody saw.
//!
//! **Orientation.** The prose takes a triangle's normal from "vectors from the reference vertex",
//! the code computes `(v0 − v1) × (v1 − v2)`: opposite signs, and with the head sweeping up or
//! down, or panned, neither sign faces the same way everywhere. Here every triangle is wound
//! counter-clockwise as seen from the laser that measured it, so its normal points back towards
//! the sensor — out of the surface, whatever the sweep.
//!
//! [`MeshRule::Incidence`] is the rule this project proposes instead (measured in the README): a
//! fixed 200 mm both drops real surfaces far away or seen obliquely (neighbouring readings of a
//! wall 10 m off are already 9–11 cm apart head-on) and bridges every depth jump under 20 cm up
//! close (a box in front of a wall). What gives a phantom polygon away is not its size but that
//! it runs *along* the beams: two neighbouring readings whose ranges differ by more than a surface
//! at `max_incidence` from the beams could make, plus the noise, are not on one surface.

use super::scene::Scene;

/// When a polygon of neighbouring readings is kept.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum MeshRule {
    /// App. D's rule: every distance from the polygon's first vertex to the others within
    /// `[min_m, max_m]`.
    Thesis {
        /// Shortest distance, metres (App. D: `DMINV` = 5 mm).
        min_m: f32,
        /// Longest distance, metres (thesis: 200 mm).
        max_m: f32,
    },
    /// Every edge of the triangle joins two readings whose ranges differ by at most what a
    /// surface seen at `max_incidence_deg` from its normal spans between their beams, plus
    /// `noise_m`; and no edge is longer than `max_edge_m`.
    Incidence {
        /// Steepest incidence of a surface still meshed, degrees.
        max_incidence_deg: f32,
        /// Allowance for range noise, metres (three σ of the laser's).
        noise_m: f32,
        /// Longest edge, metres (a backstop far away).
        max_edge_m: f32,
    },
}

impl MeshRule {
    /// The thesis's rule with App. D's thresholds: [5 mm, 200 mm].
    pub const THESIS: MeshRule = MeshRule::Thesis {
        min_m: 0.005,
        max_m: 0.2,
    };

    /// The proposed rule with the values measured best on the twin's lab (README): surfaces up
    /// to 80° from head-on, 3 cm of noise allowance (3 σ of the LMS), edges up to 1 m.
    pub const INCIDENCE: MeshRule = MeshRule::Incidence {
        max_incidence_deg: 80.0,
        noise_m: 0.03,
        max_edge_m: 1.0,
    };

    /// The thesis's rule with another longest distance.
    pub fn thesis_with_max(max_m: f32) -> MeshRule {
        MeshRule::Thesis {
            min_m: 0.005,
            max_m,
        }
    }
}

impl core::fmt::Display for MeshRule {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            MeshRule::Thesis { min_m, max_m } => write!(
                f,
                "thesis [{:.0}, {:.0}] mm",
                f64::from(min_m) * 1e3,
                f64::from(max_m) * 1e3
            ),
            MeshRule::Incidence {
                max_incidence_deg,
                noise_m,
                max_edge_m,
            } => write!(
                f,
                "incidence <= {max_incidence_deg:.0} deg, noise {:.0} mm, edges <= {:.1} m",
                f64::from(noise_m) * 1e3,
                max_edge_m
            ),
        }
    }
}

/// How scenes are meshed.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct MeshOptions {
    /// Which polygons are kept.
    pub rule: MeshRule,
    /// Beams left out at each end of every scan (App. D.2's `epuntos`, the `+` and space keys).
    pub trim_beams: usize,
}

impl Default for MeshOptions {
    /// The thesis's rule, no trimming.
    fn default() -> Self {
        MeshOptions {
            rule: MeshRule::THESIS,
            trim_beams: 0,
        }
    }
}

/// The valid polygons of one scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneMesh {
    /// Valid triangles as grid indices (`row * cols + col`), wound counter-clockwise seen from
    /// the laser.
    pub triangles: Vec<[u32; 3]>,
    /// Valid quadrilaterals.
    pub quads: usize,
    /// Quadrilaterals the grid offers: `(rows − 1) × (cols − 1 − 2 trim)`.
    pub quads_possible: usize,
    /// A unit normal per grid reading, facing the laser (see [`vertex_normals`]).
    pub normals: Vec<[f32; 3]>,
}

impl SceneMesh {
    /// Triangles the grid offers: two per quadrilateral.
    pub fn triangles_possible(&self) -> usize {
        2 * self.quads_possible
    }
}

/// One row of readings as three arrays of coordinates.
struct Soa {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
}

impl Soa {
    fn new(n: usize) -> Self {
        Soa {
            x: vec![0.0; n],
            y: vec![0.0; n],
            z: vec![0.0; n],
        }
    }

    fn load(&mut self, row: &[[f32; 3]]) {
        for (i, p) in row.iter().enumerate() {
            self.x[i] = p[0];
            self.y[i] = p[1];
            self.z[i] = p[2];
        }
    }

    /// `out[i]`: squared distance from reading `i` to reading `i + 1` of the same row.
    fn along(&self, out: &mut [f32]) {
        let n = self.x.len();
        for (i, out) in out.iter_mut().enumerate().take(n.saturating_sub(1)) {
            let (dx, dy, dz) = (
                self.x[i + 1] - self.x[i],
                self.y[i + 1] - self.y[i],
                self.z[i + 1] - self.z[i],
            );
            *out = dx * dx + dy * dy + dz * dz;
        }
    }

    /// `out[i]`: squared distance from reading `i` of this row to reading `i + shift` of
    /// `next`.
    fn across(&self, next: &Soa, shift: usize, out: &mut [f32]) {
        let n = self.x.len().saturating_sub(shift);
        for (i, out) in out.iter_mut().enumerate().take(n) {
            let (dx, dy, dz) = (
                next.x[i + shift] - self.x[i],
                next.y[i + shift] - self.y[i],
                next.z[i + shift] - self.z[i],
            );
            *out = dx * dx + dy * dy + dz * dz;
        }
    }
}

/// Squared distance.
#[inline]
fn dist2(a: &[f32; 3], b: &[f32; 3]) -> f32 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
}

/// Meshes `scene` by `options`.
pub fn mesh_scene(scene: &Scene, options: &MeshOptions) -> SceneMesh {
    let (rows, cols) = (scene.rows, scene.cols);
    let trim = options.trim_beams.min(cols / 2);
    let (first, last) = (trim, cols.saturating_sub(1 + trim));
    let mut out = SceneMesh {
        triangles: Vec::with_capacity(2 * rows * cols),
        quads: 0,
        quads_possible: rows.saturating_sub(1) * last.saturating_sub(first),
        normals: Vec::new(),
    };
    // Which neighbours the rule joins, for the vertex normals: 1.0 or 0.0 per grid reading for
    // its edge to the next beam of its scan, and to the same beam of the next scan.
    let mut joined_along = vec![0f32; rows * cols];
    let mut joined_up = vec![0f32; rows * cols];
    if rows < 2 || last <= first {
        out.normals = vertex_normals(scene, &joined_along, &joined_up);
        return out;
    }
    let p = &scene.points;
    match options.rule {
        MeshRule::Thesis { min_m, max_m } => {
            let (lo, hi) = (min_m * min_m, max_m * max_m);
            // NaN (no return) fails both comparisons.
            let ok = |d: f32| (d >= lo) & (d <= hi);
            // Squared distances along the rows, in columns and across the diagonals, a row
            // pair at a time, in arrays the compiler can run several lanes at a time.
            let mut rows_soa = [Soa::new(cols), Soa::new(cols)];
            rows_soa[0].load(&p[..cols]);
            let mut along = vec![0f32; cols];
            rows_soa[0].along(&mut along);
            for i in first..last {
                joined_along[i] = f32::from(u8::from(ok(along[i])));
            }
            let mut along_next = vec![0f32; cols];
            let (mut up, mut diagonal) = (vec![0f32; cols], vec![0f32; cols]);
            // One row's triangles, written without a branch and kept by advancing the count.
            let mut row_triangles = vec![[0u32; 3]; 2 * cols + 2];
            for j in 0..rows - 1 {
                let origin = scene.origins[j];
                let winding = row_winding(scene, j);
                let (low, high) = rows_soa.split_at_mut(1);
                let (a_row, b_row) = (&low[0], &mut high[0]);
                b_row.load(&p[(j + 1) * cols..(j + 2) * cols]);
                a_row.across(b_row, 0, &mut up);
                a_row.across(b_row, 1, &mut diagonal);
                b_row.along(&mut along_next);
                let row = j * cols;
                for i in first..=last {
                    joined_up[row + i] = f32::from(u8::from(ok(up[i])));
                }
                for i in first..last {
                    joined_along[row + cols + i] = f32::from(u8::from(ok(along_next[i])));
                }
                if winding.is_none() {
                    // Rows that do not tell the winding: orient each triangle by its normal.
                    for i in first..last {
                        let (k00, k10) = (j * cols + i, j * cols + i + 1);
                        let (k01, k11) = (k00 + cols, k10 + cols);
                        let a = ok(up[i]) & ok(diagonal[i]);
                        let b = ok(up[i + 1]) & ok(diagonal[i]);
                        out.quads += usize::from(a & ok(along[i]));
                        if a {
                            out.triangles.push(facing(p, origin, [k00, k01, k11]));
                        }
                        if b {
                            out.triangles.push(facing(p, origin, [k11, k10, k00]));
                        }
                    }
                } else {
                    // Without a branch per polygon: every triangle is written, and kept by
                    // advancing the end past it only when valid.
                    let rising = winding == Some(true);
                    let mut n = 0;
                    let tri = &mut row_triangles;
                    let (up, diagonal, along) = (&up[..cols], &diagonal[..cols], &along[..cols]);
                    for i in first..last {
                        let (k00, k10) = ((j * cols + i) as u32, (j * cols + i + 1) as u32);
                        let (k01, k11) = (k00 + cols as u32, k10 + cols as u32);
                        // From v(i,j): up to v(i,j+1), across to v(i+1,j+1), along to v(i+1,j);
                        // from v(i+1,j+1): down to v(i+1,j) (the next column's `up`).
                        let a = ok(up[i]) & ok(diagonal[i]);
                        let b = ok(up[i + 1]) & ok(diagonal[i]);
                        out.quads += usize::from(a & ok(along[i]));
                        tri[n] = if rising {
                            [k00, k01, k11]
                        } else {
                            [k00, k11, k01]
                        };
                        n += usize::from(a);
                        tri[n] = if rising {
                            [k11, k10, k00]
                        } else {
                            [k11, k00, k10]
                        };
                        n += usize::from(b);
                    }
                    out.triangles.extend_from_slice(&tri[..n]);
                }
                rows_soa.swap(0, 1);
                std::mem::swap(&mut along, &mut along_next);
            }
        }
        MeshRule::Incidence {
            max_incidence_deg,
            noise_m,
            max_edge_m,
        } => {
            let slope = max_incidence_deg.to_radians().tan();
            let edge2 = max_edge_m * max_edge_m;
            let ranges: Vec<f32> = (0..rows * cols)
                .map(|k| {
                    let o = &scene.origins[k / cols];
                    dist2(&p[k], o).sqrt()
                })
                .collect();
            // Two readings are on one surface if their ranges differ by no more than a surface
            // at the steepest incidence spans between their beams: r · Δ · tan θ, Δ the angle
            // between the beams (the chord over the nearer range), plus the noise.
            let ok = |a: usize, b: usize| {
                let (pa, pb) = (&p[a], &p[b]);
                let d2 = dist2(pa, pb);
                // NaN (no return) fails this comparison too.
                if d2.partial_cmp(&edge2) != Some(std::cmp::Ordering::Less) {
                    return false;
                }
                let (ra, rb) = (ranges[a], ranges[b]);
                let jump = (ra - rb).abs();
                // The chord between the beams at the nearer range: sqrt(d² − jump²) is the
                // lateral part of the edge, which a surface at incidence θ stretches by tan θ.
                let lateral = (d2 - jump * jump).max(0.0).sqrt();
                jump <= slope * lateral + noise_m
            };
            for j in 0..rows - 1 {
                let origin = scene.origins[j];
                let up = row_winding(scene, j);
                for i in first..last {
                    let (k00, k10) = (j * cols + i, j * cols + i + 1);
                    let (k01, k11) = (k00 + cols, k10 + cols);
                    let diagonal = ok(k00, k11);
                    let (left_up, right_up) = (ok(k00, k01), ok(k10, k11));
                    let (bottom, top) = (ok(k00, k10), ok(k01, k11));
                    joined_up[k00] = f32::from(u8::from(left_up));
                    joined_up[k10] = f32::from(u8::from(right_up));
                    joined_along[k00] = f32::from(u8::from(bottom));
                    joined_along[k01] = f32::from(u8::from(top));
                    let a = diagonal && left_up && top;
                    let b = diagonal && right_up && bottom;
                    if a && b {
                        out.quads += 1;
                    }
                    if a {
                        out.triangles.push(wound(p, origin, [k00, k01, k11], up));
                    }
                    if b {
                        out.triangles.push(wound(p, origin, [k11, k10, k00], up));
                    }
                }
            }
        }
    }
    out.normals = vertex_normals(scene, &joined_along, &joined_up);
    out
}

/// A unit normal for every reading of the grid, facing the laser: the cross product of its
/// differences along the scan and across the scans, each taken over the neighbours the mesh's
/// rule joins to it (both sides: the central difference; one: forward or backward), so a
/// normal never leans across a depth jump. A reading joined to no neighbour in one direction
/// faces straight back to the laser. (The thesis gives quadrilaterals per-vertex normals from
/// "that vertex and the next two": the one-sided difference.) Computed a row at a time on
/// arrays of coordinates, several readings at once.
pub fn vertex_normals(scene: &Scene, joined_along: &[f32], joined_up: &[f32]) -> Vec<[f32; 3]> {
    let (rows, cols) = (scene.rows, scene.cols);
    let p = &scene.points;
    let mut normals = vec![[0f32; 3]; rows * cols];
    if cols < 2 {
        return normals;
    }
    // Rows as coordinate arrays with no-returns at zero: a neighbour's mask is zero whenever
    // it did not return, and zero times a finite number is zero.
    let load = |soa: &mut Soa, row: &[[f32; 3]]| {
        for (i, q) in row.iter().enumerate() {
            let r = if q[0].is_nan() { [0.0; 3] } else { *q };
            soa.x[i] = r[0];
            soa.y[i] = r[1];
            soa.z[i] = r[2];
        }
    };
    let mut soa = [Soa::new(cols), Soa::new(cols), Soa::new(cols)];
    load(&mut soa[1], &p[..cols]);
    let (mut dx, mut dy) = (Soa::new(cols), Soa::new(cols));
    let zeros = vec![0f32; cols];
    // The mask of the edge to the left of each reading: the previous reading's `along`.
    let mut left = vec![0f32; cols];
    for j in 0..rows {
        let row = j * cols;
        if j + 1 < rows {
            load(&mut soa[2], &p[row + cols..row + 2 * cols]);
        } else {
            soa[2].x.fill(0.0);
            soa[2].y.fill(0.0);
            soa[2].z.fill(0.0);
        }
        let up = &joined_up[row..row + cols];
        let down = if j > 0 {
            &joined_up[row - cols..row]
        } else {
            &zeros[..]
        };
        let right = &joined_along[row..row + cols];
        left[0] = 0.0;
        left[1..].copy_from_slice(&right[..cols - 1]);
        let (prev, cur, next) = (&soa[0], &soa[1], &soa[2]);
        for (k, c, n, d, e) in [
            (&prev.x, &cur.x, &next.x, &mut dx.x, &mut dy.x),
            (&prev.y, &cur.y, &next.y, &mut dx.y, &mut dy.y),
            (&prev.z, &cur.z, &next.z, &mut dx.z, &mut dy.z),
        ] {
            // Along the scan: m_right (c[i+1] − c[i]) + m_left (c[i] − c[i−1]).
            d[0] = right[0] * (c[1] - c[0]);
            d[cols - 1] = left[cols - 1] * (c[cols - 1] - c[cols - 2]);
            for ((((d, r), l), w), (&cm, &cp)) in d[1..cols - 1]
                .iter_mut()
                .zip(&right[1..cols - 1])
                .zip(&left[1..cols - 1])
                .zip(&c[1..cols - 1])
                .zip(c[..cols - 2].iter().zip(&c[2..]))
            {
                *d = r * (cp - w) + l * (w - cm);
            }
            // Across the scans: m_up (next − c) + m_down (c − prev).
            for (((((e, u), dn), &w), &nx), &pv) in e
                .iter_mut()
                .zip(up)
                .zip(down)
                .zip(c.iter())
                .zip(n.iter())
                .zip(k.iter())
            {
                *e = u * (nx - w) + dn * (w - pv);
            }
        }
        // Across the scans the rows rise (or fall) in the laser's view, along them the beams
        // turn left: "across × along" faces the laser for rising rows.
        let winding = row_winding(scene, j.min(rows.saturating_sub(2)));
        let sign = if winding == Some(false) { -1.0 } else { 1.0 };
        let o = scene.origins[j];
        let out = &mut normals[row..row + cols];
        // Slices of one known length: no bounds check inside the loop.
        let (ax, ay, az) = (&dx.x[..cols], &dx.y[..cols], &dx.z[..cols]);
        let (bx, by, bz) = (&dy.x[..cols], &dy.y[..cols], &dy.z[..cols]);
        let (cx, cy, cz) = (&cur.x[..cols], &cur.y[..cols], &cur.z[..cols]);
        for (i, out) in out.iter_mut().enumerate() {
            let n = [
                by[i] * az[i] - bz[i] * ay[i],
                bz[i] * ax[i] - bx[i] * az[i],
                bx[i] * ay[i] - by[i] * ax[i],
            ];
            let to_laser = [o[0] - cx[i], o[1] - cy[i], o[2] - cz[i]];
            let length2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
            let back2 =
                to_laser[0] * to_laser[0] + to_laser[1] * to_laser[1] + to_laser[2] * to_laser[2];
            // Joined to nothing in one direction: face straight back to the laser.
            let (a, b) = if length2 > 0.0 {
                (sign / length2.sqrt(), 0.0)
            } else {
                (0.0, 1.0 / back2.sqrt())
            };
            *out = [0, 1, 2].map(|k| n[k] * a + to_laser[k] * b);
        }
        // Rows that do not tell (no tilt between them): face the laser by the dot product.
        if winding.is_none() {
            for (i, n) in out.iter_mut().enumerate() {
                let to_laser = [o[0] - cur.x[i], o[1] - cur.y[i], o[2] - cur.z[i]];
                if n[0] * to_laser[0] + n[1] * to_laser[1] + n[2] * to_laser[2] < 0.0 {
                    *n = [-n[0], -n[1], -n[2]];
                }
            }
        }
        soa.rotate_left(1);
    }
    normals
}

/// How the triangles between rows `j` and `j + 1` are wound to face the laser: in the laser's
/// view the beams run right to left along a row, so `v(i,j), v(i,j+1), v(i+1,j+1)` turns
/// counter-clockwise when row `j + 1` lies above row `j` (the head tilted up between them) and
/// clockwise when below. `None` when the rows do not tell (no tilt between them): each triangle
/// is then oriented by its own normal.
#[inline]
fn row_winding(scene: &Scene, j: usize) -> Option<bool> {
    let (f0, f1, up) = (
        scene.forwards.get(j)?,
        scene.forwards.get(j + 1)?,
        scene.planes.get(j)?,
    );
    let rise = (f1[0] - f0[0]) * up[0] + (f1[1] - f0[1]) * up[1] + (f1[2] - f0[2]) * up[2];
    (rise.abs() > 1e-6).then_some(rise > 0.0)
}

/// Triangle `t` (grid indices) wound as the rows say, or facing `origin` by its own normal.
#[inline]
fn wound(p: &[[f32; 3]], origin: [f32; 3], t: [usize; 3], up: Option<bool>) -> [u32; 3] {
    match up {
        Some(true) => t.map(|k| k as u32),
        Some(false) => [t[0] as u32, t[2] as u32, t[1] as u32],
        None => facing(p, origin, t),
    }
}

/// The triangle `t` wound counter-clockwise as seen from `origin` (its normal towards it).
#[inline]
fn facing(p: &[[f32; 3]], origin: [f32; 3], t: [usize; 3]) -> [u32; 3] {
    let n = normal(&p[t[0]], &p[t[1]], &p[t[2]]);
    let a = &p[t[0]];
    let towards = [origin[0] - a[0], origin[1] - a[1], origin[2] - a[2]];
    let t = t.map(|k| k as u32);
    if n[0] * towards[0] + n[1] * towards[1] + n[2] * towards[2] >= 0.0 {
        t
    } else {
        [t[0], t[2], t[1]]
    }
}

/// The (unnormalised) normal `(b − a) × (c − a)`: twice the triangle's area long.
#[inline]
pub fn normal(a: &[f32; 3], b: &[f32; 3], c: &[f32; 3]) -> [f32; 3] {
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ]
}

/// Area of the triangle `t` of `points`, square metres.
pub fn triangle_area(points: &[[f32; 3]], t: &[u32; 3]) -> f32 {
    let n = normal(
        &points[t[0] as usize],
        &points[t[1] as usize],
        &points[t[2] as usize],
    );
    0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::SceneTag;
    use crate::geometry::Pose2;

    /// A scene of `rows` × `cols` readings on the plane x = 2 seen from the origin, with `depth`
    /// added to the readings of the columns from `step_at` on (a depth jump).
    fn wall(rows: usize, cols: usize, step_at: usize, depth: f32) -> Scene {
        let mut points = Vec::new();
        for j in 0..rows {
            for i in 0..cols {
                let y = i as f32 * 0.02;
                let z = j as f32 * 0.02;
                let x = if i >= step_at { 2.0 + depth } else { 2.0 };
                points.push([x, y, z]);
            }
        }
        Scene {
            tag: SceneTag {
                scene: 0,
                station: 0,
            },
            rows,
            cols,
            points,
            origins: vec![[0.0, 0.0, 0.0]; rows],
            // The rows rise: each one's middle beam a little higher than the last.
            forwards: (0..rows).map(|j| [1.0, 0.0, 0.01 * j as f32]).collect(),
            planes: vec![[0.0, 0.0, 1.0]; rows],
            base: Pose2::IDENTITY,
            pan: 0.0,
            skipped: 0,
        }
    }

    #[test]
    fn a_flat_grid_is_all_valid_and_faces_the_laser() {
        let scene = wall(4, 5, usize::MAX, 0.0);
        let mesh = mesh_scene(&scene, &MeshOptions::default());
        assert_eq!(mesh.quads_possible, 3 * 4);
        assert_eq!(mesh.quads, 12);
        assert_eq!(mesh.triangles.len(), 24);
        for t in &mesh.triangles {
            let p = &scene.points;
            let n = normal(&p[t[0] as usize], &p[t[1] as usize], &p[t[2] as usize]);
            assert!(
                n[0] < 0.0,
                "the wall at x = 2 faces the laser at the origin"
            );
        }
        let area: f32 = mesh
            .triangles
            .iter()
            .map(|t| triangle_area(&scene.points, t))
            .sum();
        assert!((area - 0.08 * 0.06).abs() < 1e-6);
        let trimmed = mesh_scene(
            &scene,
            &MeshOptions {
                trim_beams: 1,
                ..MeshOptions::default()
            },
        );
        assert_eq!(trimmed.quads_possible, 3 * 2);
    }

    #[test]
    fn the_thesis_rule_bridges_small_jumps_and_drops_no_returns() {
        let mut scene = wall(3, 6, 3, 0.15);
        // 15 cm behind: within 200 mm, so the thesis bridges the jump…
        let thesis = mesh_scene(&scene, &MeshOptions::default());
        assert_eq!(thesis.quads, 2 * 5);
        // …where the incidence rule sees polygons running along the beams.
        let options = MeshOptions {
            rule: MeshRule::INCIDENCE,
            trim_beams: 0,
        };
        let proposed = mesh_scene(&scene, &options);
        assert_eq!(
            proposed.quads,
            2 * 4,
            "the column of quads over the jump is gone"
        );
        // A reading with no return takes every polygon it belongs to.
        scene.points[7] = [f32::NAN; 3];
        let holed = mesh_scene(&scene, &MeshOptions::default());
        assert_eq!(holed.quads, 10 - 4);
        // Readings closer than 5 mm are not a polygon for App. D.
        let dense = Scene {
            points: wall(3, 3, 9, 0.0)
                .points
                .iter()
                .map(|p| [p[0], p[1] * 0.1, p[2] * 0.1])
                .collect(),
            ..wall(3, 3, 9, 0.0)
        };
        assert_eq!(mesh_scene(&dense, &MeshOptions::default()).quads, 0);
    }
}
