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

use super::scene::{Points, Scene};

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

/// What meshing one scene added to a model.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub(super) struct MeshCounts {
    /// Readings that returned: the vertices added.
    pub vertices: usize,
    /// Valid quadrilaterals.
    pub quads: usize,
    /// Quadrilaterals the grid offers: `(rows − 1) × (cols − 1 − 2 trim)`.
    pub quads_possible: usize,
    /// Valid triangles.
    pub triangles: usize,
}

/// Where a meshed scene goes: the model's arrays, appended to.
pub(super) struct MeshOut<'a> {
    /// The readings that returned, in grid order.
    pub vertices: &'a mut Vec<[f32; 3]>,
    /// Their normals, facing the laser.
    pub normals: &'a mut Vec<[f32; 3]>,
    /// Triangles as indices into `vertices`.
    pub triangles: &'a mut Vec<[u32; 3]>,
}

/// One row of readings (one scan): its coordinates in the scene, the ranges from the laser (for
/// the incidence rule) and the vertex number each reading that returned was given.
struct Row<'a> {
    x: &'a [f32],
    y: &'a [f32],
    z: &'a [f32],
    range: Vec<f32>,
    vertex: Vec<u32>,
}

impl<'a> Row<'a> {
    /// Row `j` of `scene`, not loaded.
    fn new(scene: &'a Points, cols: usize, j: usize) -> Self {
        let span = j * cols..(j + 1) * cols;
        Row {
            x: &scene.x[span.clone()],
            y: &scene.y[span.clone()],
            z: &scene.z[span],
            range: vec![0.0; cols],
            vertex: vec![0; cols],
        }
    }

    /// Loads row `j` of `points` (no return: `NaN`), seen from `origin`; the readings that
    /// returned are numbered and appended to `vertices`.
    fn load(
        &mut self,
        points: &'a Points,
        j: usize,
        origin: [f32; 3],
        ranges: bool,
        vertices: &mut Vec<[f32; 3]>,
    ) {
        let n = self.vertex.len();
        let span = j * n..(j + 1) * n;
        let (x, y, z) = (
            &points.x[span.clone()],
            &points.y[span.clone()],
            &points.z[span],
        );
        (self.x, self.y, self.z) = (x, y, z);
        let v = &mut self.vertex[..n];
        // The readings that returned are appended to `vertices` as they are numbered, a chunk
        // at a time through a buffer of fixed size: no branch per reading, no bounds checks.
        const CHUNK: usize = 256;
        let mut buffer = [[0f32; 3]; CHUNK];
        for start in (0..n).step_by(CHUNK) {
            let end = (start + CHUNK).min(n);
            let first = vertices.len();
            let mut kept = 0;
            for i in start..end {
                v[i] = (first + kept) as u32;
                // kept never passes i − start: the modulo only tells the compiler.
                buffer[kept % CHUNK] = [x[i], y[i], z[i]];
                kept += usize::from(!x[i].is_nan());
            }
            vertices.extend_from_slice(&buffer[..kept]);
        }
        if ranges {
            for (i, r) in self.range[..n].iter_mut().enumerate() {
                let d = [x[i] - origin[0], y[i] - origin[1], z[i] - origin[2]];
                *r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            }
        }
    }

    fn point(&self, i: usize) -> [f32; 3] {
        [self.x[i], self.y[i], self.z[i]]
    }
}

/// `value` where `mask` has every bit set (two readings joined), zero where it is zero: a
/// difference kept or dropped without a branch.
#[inline]
fn keep(value: f32, mask: u32) -> f32 {
    f32::from_bits(value.to_bits() & mask)
}

/// Appends to `out` the `items` whose reading returned (`x` not `NaN`), without a branch per
/// item: each is written at the end of a buffer that advances only past a kept one.
fn append_returned<T: Copy + Default>(out: &mut Vec<T>, items: &[T], x: &[f32]) {
    const CHUNK: usize = 256;
    let mut buffer = [T::default(); CHUNK];
    for (items, x) in items.chunks(CHUNK).zip(x.chunks(CHUNK)) {
        let mut n = 0;
        for (item, x) in items.iter().zip(x) {
            // n never passes the item's index in the chunk: the modulo only tells the compiler.
            buffer[n % CHUNK] = *item;
            n += usize::from(!x.is_nan());
        }
        out.extend_from_slice(&buffer[..n]);
    }
}

/// A rule's edge test, prepared once per scene.
#[derive(Copy, Clone)]
enum EdgeTest {
    /// Squared length within `[lo, hi]`.
    Length { lo: f32, hi: f32 },
    /// Shorter than `sqrt(edge2)`, and a range jump within `slope × lateral + noise`.
    Incidence { slope: f32, noise: f32, edge2: f32 },
}

impl EdgeTest {
    fn new(rule: MeshRule) -> Self {
        match rule {
            MeshRule::Thesis { min_m, max_m } => EdgeTest::Length {
                lo: min_m * min_m,
                hi: max_m * max_m,
            },
            MeshRule::Incidence {
                max_incidence_deg,
                noise_m,
                max_edge_m,
            } => EdgeTest::Incidence {
                slope: max_incidence_deg.to_radians().tan(),
                noise: noise_m,
                edge2: max_edge_m * max_edge_m,
            },
        }
    }

    /// `out[i]`: every bit set when reading `i` of `a` and reading `i + shift` of `b` may share
    /// a polygon, zero when not, for `i` in `span` (zero elsewhere). A reading with no return
    /// (`NaN`) fails every test.
    fn run(self, a: &Row, b: &Row, shift: usize, span: core::ops::Range<usize>, out: &mut [u32]) {
        out.fill(0);
        let (s, e) = (span.start, span.end);
        if s >= e {
            return;
        }
        let (ax, ay, az) = (&a.x[s..e], &a.y[s..e], &a.z[s..e]);
        let (bx, by, bz) = (
            &b.x[s + shift..e + shift],
            &b.y[s + shift..e + shift],
            &b.z[s + shift..e + shift],
        );
        let out = &mut out[s..e];
        let n = out.len();
        // Slices of one known length: no bounds check inside the loops.
        let (ax, ay, az, bx, by, bz) = (&ax[..n], &ay[..n], &az[..n], &bx[..n], &by[..n], &bz[..n]);
        match self {
            EdgeTest::Length { lo, hi } => {
                for i in 0..n {
                    let (dx, dy, dz) = (bx[i] - ax[i], by[i] - ay[i], bz[i] - az[i]);
                    let d2 = dx * dx + dy * dy + dz * dz;
                    // NaN fails both comparisons.
                    out[i] = 0u32.wrapping_sub(u32::from((d2 >= lo) & (d2 <= hi)));
                }
            }
            EdgeTest::Incidence {
                slope,
                noise,
                edge2,
            } => {
                // Two readings are on one surface if their ranges differ by no more than a
                // surface at the steepest incidence spans between their beams: the lateral
                // part of the edge, sqrt(d² − jump²), stretched by tan θ, plus the noise.
                let (ra, rb) = (&a.range[s..e][..n], &b.range[s + shift..e + shift][..n]);
                for i in 0..n {
                    let (dx, dy, dz) = (bx[i] - ax[i], by[i] - ay[i], bz[i] - az[i]);
                    let d2 = dx * dx + dy * dy + dz * dz;
                    let jump = (ra[i] - rb[i]).abs();
                    let lateral = (d2 - jump * jump).max(0.0).sqrt();
                    // NaN fails the first comparison.
                    let ok = (d2 < edge2) & (jump <= slope * lateral + noise);
                    out[i] = 0u32.wrapping_sub(u32::from(ok));
                }
            }
        }
    }
}

/// The edge masks of a row pair, as [`EdgeTest::run`] writes them. Of `v(i,j)`, `v(i+1,j)`,
/// `v(i,j+1)`, `v(i+1,j+1)`: `up[i]` joins `v(i,j)`–`v(i,j+1)`, `diagonal[i]` joins
/// `v(i,j)`–`v(i+1,j+1)`, `below[i]` and `above[i]` join beam `i` to beam `i + 1` in rows `j`
/// and `j + 1`.
struct PairEdges<'a> {
    up: &'a [u32],
    diagonal: &'a [u32],
    below: &'a [u32],
    above: &'a [u32],
}

impl PairEdges<'_> {
    /// Whether the two triangles of quadrilateral `i` are valid, and the quadrilateral. The
    /// thesis's rule tests the distances from each polygon's first vertex: from `v(i,j)` up,
    /// across and (the quadrilateral) along; from `v(i+1,j+1)` down (the next column's `up`)
    /// and across. The incidence rule tests every edge of each triangle.
    #[inline]
    fn valid<const INCIDENCE: bool>(&self, i: usize) -> (u32, u32, u32) {
        let (up, diagonal) = (self.up[i], self.diagonal[i]);
        if INCIDENCE {
            let first = diagonal & up & self.above[i];
            let second = diagonal & self.up[i + 1] & self.below[i];
            (first, second, first & second)
        } else {
            let first = up & diagonal;
            (first, self.up[i + 1] & diagonal, first & self.below[i])
        }
    }
}

/// Meshes `scene` by `options` and appends its vertices, normals and triangles to `out`.
///
/// A row pair at a time: the readings of the next scan are loaded into arrays, the rule tests
/// the edges along that scan, up to it and across the diagonals (several lanes at a time), the
/// pair's triangles are written without a branch per polygon, and the normals of the row whose
/// neighbours are now all known are computed. Nothing the size of the grid is allocated.
pub(super) fn mesh_into(scene: &Scene, options: &MeshOptions, out: MeshOut<'_>) -> MeshCounts {
    let rows = scene.rows.min(scene.origins.len());
    let cols = scene
        .cols
        .min(scene.points.len().checked_div(rows).unwrap_or(0));
    let trim = options.trim_beams.min(cols / 2);
    let (first, last) = (trim, cols.saturating_sub(1 + trim));
    let vertices_before = out.vertices.len();
    let triangles_before = out.triangles.len();
    let mut counts = MeshCounts {
        quads_possible: rows.saturating_sub(1) * last.saturating_sub(first),
        ..MeshCounts::default()
    };
    if cols == 0 {
        return counts;
    }
    let test = EdgeTest::new(options.rule);
    let incidence = matches!(test, EdgeTest::Incidence { .. });
    let points = &scene.points;
    // Rows j − 1, j and j + 1; the edge masks along rows j and j + 1, up from rows j − 1 and j,
    // and across the diagonals from row j.
    let mut row = [0, 0, 0].map(|j| Row::new(points, cols, j));
    let mut along = [vec![0u32; cols], vec![0u32; cols]];
    let mut up = [vec![0u32; cols], vec![0u32; cols]];
    let mut diagonal = vec![0u32; cols];
    let mut normals = Normals::new(cols);
    row[1].load(points, 0, scene.origins[0], incidence, out.vertices);
    test.run(&row[1], &row[1], 1, first..last, &mut along[0]);
    for j in 0..rows {
        if j + 1 < rows {
            let (low, high) = row.split_at_mut(2);
            let (a, b) = (&low[1], &mut high[0]);
            b.load(points, j + 1, scene.origins[j + 1], incidence, out.vertices);
            test.run(b, b, 1, first..last, &mut along[1]);
            test.run(a, b, 0, first..last + 1, &mut up[1]);
            test.run(a, b, 1, first..last, &mut diagonal);
            let edges = PairEdges {
                up: &up[1],
                diagonal: &diagonal,
                below: &along[0],
                above: &along[1],
            };
            let (span, tri, o) = (first..last, &mut *out.triangles, scene.origins[j]);
            counts.quads += match (row_winding(scene, j), incidence) {
                (Some(true), false) => pair::<false, true>(a, b, &edges, span, tri),
                (Some(false), false) => pair::<false, false>(a, b, &edges, span, tri),
                (Some(true), true) => pair::<true, true>(a, b, &edges, span, tri),
                (Some(false), true) => pair::<true, false>(a, b, &edges, span, tri),
                (None, false) => pair_facing::<false>(a, b, &edges, span, o, tri),
                (None, true) => pair_facing::<true>(a, b, &edges, span, o, tri),
            };
        } else {
            up[1].fill(0);
        }
        // Row j's neighbours are all known: its normals. The last row takes the winding of
        // the pair below it.
        let winding = row_winding(scene, j.min(rows.saturating_sub(2)));
        normals.row(
            [&row[0], &row[1], &row[2]],
            [&up[0], &up[1], &along[0]],
            scene.origins[j],
            winding,
        );
        append_returned(out.normals, &normals.out, row[1].x);
        row.rotate_left(1);
        along.swap(0, 1);
        up.swap(0, 1);
    }
    counts.vertices = out.vertices.len() - vertices_before;
    counts.triangles = out.triangles.len() - triangles_before;
    counts
}

/// The triangles of rows `a` (scan `j`) and `b` (scan `j + 1`) over the quadrilaterals in
/// `span`, wound counter-clockwise seen from the laser (`RISING`: row `b` above row `a` in its
/// view), appended to `out` without a branch per polygon; returns the valid quadrilaterals.
#[inline]
fn pair<const INCIDENCE: bool, const RISING: bool>(
    a: &Row,
    b: &Row,
    edges: &PairEdges<'_>,
    span: core::ops::Range<usize>,
    out: &mut Vec<[u32; 3]>,
) -> usize {
    // A chunk of columns at a time into a buffer of fixed size: no bounds checks inside.
    const CHUNK: usize = 128;
    let mut buffer = [[0u32; 3]; 2 * CHUNK];
    let mut quads = 0;
    for start in span.clone().step_by(CHUNK) {
        let end = (start + CHUNK).min(span.end);
        let (av, bv) = (&a.vertex[start..=end], &b.vertex[start..=end]);
        let chunk = PairEdges {
            up: &edges.up[start..=end],
            diagonal: &edges.diagonal[start..end],
            below: &edges.below[start..end],
            above: &edges.above[start..end],
        };
        let mut n = 0;
        for i in 0..end - start {
            let (v00, v10, v01, v11) = (av[i], av[i + 1], bv[i], bv[i + 1]);
            let (first, second, quad) = chunk.valid::<INCIDENCE>(i);
            quads += (quad & 1) as usize;
            // Every triangle is written, and kept by advancing the end past it only when
            // valid; n stays below 2 i + 2, the modulo only tells the compiler.
            buffer[n % (2 * CHUNK)] = if RISING {
                [v00, v01, v11]
            } else {
                [v00, v11, v01]
            };
            n += (first & 1) as usize;
            buffer[n % (2 * CHUNK)] = if RISING {
                [v11, v10, v00]
            } else {
                [v11, v00, v10]
            };
            n += (second & 1) as usize;
        }
        out.extend_from_slice(&buffer[..n]);
    }
    quads
}

/// As [`pair`] for rows that do not tell the winding (no tilt between them): each triangle is
/// oriented by its own normal to face the laser at `origin`.
fn pair_facing<const INCIDENCE: bool>(
    a: &Row,
    b: &Row,
    edges: &PairEdges<'_>,
    span: core::ops::Range<usize>,
    origin: [f32; 3],
    out: &mut Vec<[u32; 3]>,
) -> usize {
    let mut quads = 0;
    for i in span {
        let (first, second, quad) = edges.valid::<INCIDENCE>(i);
        quads += (quad & 1) as usize;
        let (p00, p10, p01, p11) = (a.point(i), a.point(i + 1), b.point(i), b.point(i + 1));
        let (v00, v10) = (a.vertex[i], a.vertex[i + 1]);
        let (v01, v11) = (b.vertex[i], b.vertex[i + 1]);
        if first != 0 {
            out.push(facing(origin, [p00, p01, p11], [v00, v01, v11]));
        }
        if second != 0 {
            out.push(facing(origin, [p11, p10, p00], [v11, v10, v00]));
        }
    }
    quads
}

/// Vertex normals a row at a time, with scratch arrays kept between rows.
struct Normals {
    /// Differences along the scan, per coordinate.
    along: [Vec<f32>; 3],
    /// Differences across the scans, per coordinate.
    across: [Vec<f32>; 3],
    /// The mask of the edge to the left of each reading.
    left: Vec<u32>,
    /// The row's normals.
    out: Vec<[f32; 3]>,
}

impl Normals {
    fn new(cols: usize) -> Self {
        Normals {
            along: [vec![0.0; cols], vec![0.0; cols], vec![0.0; cols]],
            across: [vec![0.0; cols], vec![0.0; cols], vec![0.0; cols]],
            left: vec![0; cols],
            out: vec![[0.0; 3]; cols],
        }
    }

    /// A unit normal for every reading of row `cur`, facing the laser at `origin`: the cross
    /// product of its differences along the scan and across the scans, each taken over the
    /// neighbours the mesh's rule joins to it (both sides: the central difference; one: forward
    /// or backward), so a normal never leans across a depth jump. A reading joined to no
    /// neighbour in one direction faces straight back to the laser. (The thesis gives
    /// quadrilaterals per-vertex normals from "that vertex and the next two": the one-sided
    /// difference.) `down` and `up`: the masks of the edges from the row below and to the row
    /// above; `right`: along the row. `winding`: whether the rows rise in the laser's view
    /// (`None`: they do not tell, and each normal is turned to the laser by its dot product).
    fn row(
        &mut self,
        [prev, cur, next]: [&Row<'_>; 3],
        [down, up, right]: [&[u32]; 3],
        origin: [f32; 3],
        winding: Option<bool>,
    ) {
        let cols = self.out.len();
        self.left[0] = 0;
        self.left[1..].copy_from_slice(&right[..cols - 1]);
        let left = &self.left[..];
        let coordinates = [
            (cur.x, next.x, prev.x),
            (cur.y, next.y, prev.y),
            (cur.z, next.z, prev.z),
        ];
        for (k, (c, n, pv)) in coordinates.into_iter().enumerate() {
            let d = &mut self.along[k][..cols];
            // Along the scan: (c[i+1] − c[i]) where joined right, plus (c[i] − c[i−1]) where
            // joined left; a difference not joined is zero, even to a reading with no return.
            if cols >= 2 {
                d[0] = keep(c[1] - c[0], right[0]);
                d[cols - 1] = keep(c[cols - 1] - c[cols - 2], left[cols - 1]);
                for ((((d, &r), &l), &w), (&cm, &cp)) in d[1..cols - 1]
                    .iter_mut()
                    .zip(&right[1..cols - 1])
                    .zip(&left[1..cols - 1])
                    .zip(&c[1..cols - 1])
                    .zip(c[..cols - 2].iter().zip(&c[2..cols]))
                {
                    *d = keep(cp - w, r) + keep(w - cm, l);
                }
            } else {
                d.fill(0.0);
            }
            // Across the scans: (next − c) where joined up, plus (c − prev) where joined down.
            for (((((e, &u), &dn), &w), &nx), &pr) in self.across[k][..cols]
                .iter_mut()
                .zip(&up[..cols])
                .zip(&down[..cols])
                .zip(&c[..cols])
                .zip(&n[..cols])
                .zip(&pv[..cols])
            {
                *e = keep(nx - w, u) + keep(w - pr, dn);
            }
        }
        // Across the scans the rows rise (or fall) in the laser's view, along them the beams
        // turn left: "across × along" faces the laser for rising rows.
        let sign = if winding == Some(false) { -1.0 } else { 1.0 };
        let [ax, ay, az] = &self.along;
        let [bx, by, bz] = &self.across;
        let (ax, ay, az) = (&ax[..cols], &ay[..cols], &az[..cols]);
        let (bx, by, bz) = (&bx[..cols], &by[..cols], &bz[..cols]);
        let (cx, cy, cz) = (&cur.x[..cols], &cur.y[..cols], &cur.z[..cols]);
        for (i, out) in self.out.iter_mut().enumerate() {
            let n = [
                by[i] * az[i] - bz[i] * ay[i],
                bz[i] * ax[i] - bx[i] * az[i],
                bx[i] * ay[i] - by[i] * ax[i],
            ];
            let to_laser = [origin[0] - cx[i], origin[1] - cy[i], origin[2] - cz[i]];
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
        if winding.is_none() {
            for (i, n) in self.out.iter_mut().enumerate() {
                let to_laser = [origin[0] - cx[i], origin[1] - cy[i], origin[2] - cz[i]];
                if n[0] * to_laser[0] + n[1] * to_laser[1] + n[2] * to_laser[2] < 0.0 {
                    *n = [-n[0], -n[1], -n[2]];
                }
            }
        }
    }
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

/// The triangle of points `p` and vertex numbers `v`, wound counter-clockwise as seen from
/// `origin` (its normal towards it).
#[inline]
fn facing(origin: [f32; 3], p: [[f32; 3]; 3], v: [u32; 3]) -> [u32; 3] {
    let n = normal(&p[0], &p[1], &p[2]);
    let a = &p[0];
    let towards = [origin[0] - a[0], origin[1] - a[1], origin[2] - a[2]];
    if n[0] * towards[0] + n[1] * towards[1] + n[2] * towards[2] >= 0.0 {
        v
    } else {
        [v[0], v[2], v[1]]
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
    use crate::reconstruction::Model;

    fn mesh(scene: &Scene, options: &MeshOptions) -> Model {
        Model::build(std::slice::from_ref(scene), options)
    }

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
            points: points.into_iter().collect(),
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
        let model = mesh(&scene, &MeshOptions::default());
        assert_eq!(model.scenes[0].quads, (12, 3 * 4));
        assert_eq!(model.triangles.len(), 24);
        for t in &model.triangles {
            let p = &model.vertices;
            let n = normal(&p[t[0] as usize], &p[t[1] as usize], &p[t[2] as usize]);
            assert!(
                n[0] < 0.0,
                "the wall at x = 2 faces the laser at the origin"
            );
        }
        let area: f32 = model
            .triangles
            .iter()
            .map(|t| triangle_area(&model.vertices, t))
            .sum();
        assert!((area - 0.08 * 0.06).abs() < 1e-6);
        let trimmed = mesh(
            &scene,
            &MeshOptions {
                trim_beams: 1,
                ..MeshOptions::default()
            },
        );
        assert_eq!(trimmed.scenes[0].quads, (3 * 2, 3 * 2));
    }

    #[test]
    fn the_thesis_rule_bridges_small_jumps_and_drops_no_returns() {
        let mut scene = wall(3, 6, 3, 0.15);
        // 15 cm behind: within 200 mm, so the thesis bridges the jump…
        let thesis = mesh(&scene, &MeshOptions::default());
        assert_eq!(thesis.scenes[0].quads.0, 2 * 5);
        // …where the incidence rule sees polygons running along the beams.
        let options = MeshOptions {
            rule: MeshRule::INCIDENCE,
            trim_beams: 0,
        };
        let proposed = mesh(&scene, &options);
        assert_eq!(
            proposed.scenes[0].quads.0,
            2 * 4,
            "the column of quads over the jump is gone"
        );
        // A reading with no return takes every polygon it belongs to.
        scene.points.set(7, [f32::NAN; 3]);
        let holed = mesh(&scene, &MeshOptions::default());
        assert_eq!(holed.scenes[0].quads.0, 10 - 4);
        assert_eq!(holed.vertices.len(), 3 * 6 - 1);
        // Readings closer than 5 mm are not a polygon for App. D.
        let dense = Scene {
            points: wall(3, 3, 9, 0.0)
                .points
                .iter()
                .map(|p| [p[0], p[1] * 0.1, p[2] * 0.1])
                .collect(),
            ..wall(3, 3, 9, 0.0)
        };
        assert_eq!(mesh(&dense, &MeshOptions::default()).scenes[0].quads.0, 0);
    }

    /// The rules written plainly, polygon by polygon on the grid, with the vertices numbered
    /// afterwards: the streamed mesh must give the same triangles, in the same order.
    fn plain(scene: &Scene, options: &MeshOptions) -> (Vec<[u32; 3]>, usize) {
        let (rows, cols) = (scene.rows, scene.cols);
        let p: Vec<[f32; 3]> = scene.points.iter().collect();
        let mut number = vec![u32::MAX; p.len()];
        let mut next = 0;
        for (k, q) in p.iter().enumerate() {
            if !q[0].is_nan() {
                number[k] = next;
                next += 1;
            }
        }
        let range = |k: usize| {
            let o = scene.origins[k / cols];
            let d = [p[k][0] - o[0], p[k][1] - o[1], p[k][2] - o[2]];
            (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
        };
        let ok = |a: usize, b: usize| {
            let d = [p[b][0] - p[a][0], p[b][1] - p[a][1], p[b][2] - p[a][2]];
            let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            match options.rule {
                MeshRule::Thesis { min_m, max_m } => d2 >= min_m * min_m && d2 <= max_m * max_m,
                MeshRule::Incidence {
                    max_incidence_deg,
                    noise_m,
                    max_edge_m,
                } => {
                    let jump = (range(a) - range(b)).abs();
                    let lateral = (d2 - jump * jump).max(0.0).sqrt();
                    d2 < max_edge_m * max_edge_m
                        && jump <= max_incidence_deg.to_radians().tan() * lateral + noise_m
                }
            }
        };
        let trim = options.trim_beams;
        let (mut triangles, mut quads) = (Vec::new(), 0);
        for j in 0..rows - 1 {
            for i in trim..cols - 1 - trim {
                let (k00, k10) = (j * cols + i, j * cols + i + 1);
                let (k01, k11) = (k00 + cols, k10 + cols);
                let (a, b, quad) = match options.rule {
                    MeshRule::Thesis { .. } => {
                        let a = ok(k00, k01) && ok(k00, k11);
                        (a, ok(k11, k10) && ok(k11, k00), a && ok(k00, k10))
                    }
                    MeshRule::Incidence { .. } => {
                        let a = ok(k00, k11) && ok(k00, k01) && ok(k01, k11);
                        let b = ok(k00, k11) && ok(k10, k11) && ok(k00, k10);
                        (a, b, a && b)
                    }
                };
                quads += usize::from(quad);
                let rising = row_winding(scene, j).unwrap();
                let wind = |t: [usize; 3]| {
                    let t = t.map(|k| number[k]);
                    if rising { t } else { [t[0], t[2], t[1]] }
                };
                if a {
                    triangles.push(wind([k00, k01, k11]));
                }
                if b {
                    triangles.push(wind([k11, k10, k00]));
                }
            }
        }
        (triangles, quads)
    }

    #[test]
    fn the_streamed_mesh_is_the_rules_applied_polygon_by_polygon() {
        // A rough, holed surface whose depth jumps now and then, seen rising and falling.
        let mut rng = crate::test_rng::XorShift(0x2545_f491_4f6c_dd1d);
        let mut noise = move || (rng.next_u64() >> 40) as f32 / (1u64 << 24) as f32;
        for falling in [false, true] {
            let mut scene = wall(23, 41, usize::MAX, 0.0);
            for k in 0..scene.points.len() {
                let u = noise();
                scene.points.x[k] += 0.3 * noise() + if u > 0.9 { 0.5 } else { 0.0 };
                if u < 0.05 {
                    scene.points.set(k, [f32::NAN; 3]);
                }
            }
            if falling {
                scene.forwards.reverse();
            }
            for rule in [
                MeshRule::THESIS,
                MeshRule::thesis_with_max(0.35),
                MeshRule::INCIDENCE,
            ] {
                for trim_beams in [0, 3] {
                    let options = MeshOptions { rule, trim_beams };
                    let model = mesh(&scene, &options);
                    let (triangles, quads) = plain(&scene, &options);
                    assert!(!triangles.is_empty() && quads < model.scenes[0].quads.1);
                    assert_eq!(model.triangles, triangles, "{rule}, trim {trim_beams}");
                    assert_eq!(model.scenes[0].quads.0, quads, "{rule}, trim {trim_beams}");
                    assert_eq!(model.vertices.len(), model.normals.len());
                    for n in &model.normals {
                        let length = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                        assert!((length - 1.0).abs() < 1e-4, "{n:?}");
                    }
                }
            }
        }
    }
}
