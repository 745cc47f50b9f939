//! How well a 3D model matches the world it was made of — what the twin knows and the thesis
//! never had: the true surfaces.
//!
//! - **Point error**: each vertex's distance to the nearest true surface (walls, boxes, tables,
//!   floor, ceiling): median, 95th percentile, share within 2 cm and 5 cm.
//! - **Phantom area**: mesh area farther than 5 cm from every true surface — polygons that bridge
//!   a doorway or a depth jump, or join ghosts behind glass. A triangle counts by its centroid;
//!   one whose three vertices are within 5 cm of the same (convex) surface is within 5 cm of it
//!   everywhere and needs no query.
//! - **Coverage**: share of the true wall, box and table area (the floor and ceiling left out)
//!   within 5 cm of a vertex, on 5 cm cells of each surface.
//! - **Seam error**: where two stations saw the same surface, how far apart their meshes are:
//!   the median distance of a later station's vertex to the plane of the earlier stations'
//!   readings within 10 cm of it (one vertex in [`SEAM_STRIDE`]).

use super::index::SurfaceId;
use super::map::WorldMap;
use crate::config::Material;
use robot::reconstruction::{Model, triangle_area};
use serde::Serialize;

/// A vertex within this of a surface lies on it; a triangle farther is a phantom, metres.
pub const ON_SURFACE: f64 = 0.05;
/// Side of a coverage cell on a true surface, metres.
pub const COVERAGE_CELL: f64 = 0.05;
/// Seam error: readings of earlier stations are looked for within this, metres.
pub const SEAM_REACH: f64 = 0.10;
/// Seam error: one vertex in this many of a later station is compared.
pub const SEAM_STRIDE: usize = 3;

/// The accuracy figures of one model.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Accuracy {
    /// Vertices scored.
    pub vertices: usize,
    /// Median distance of a vertex to the nearest true surface, metres.
    pub median_m: f64,
    /// 95th percentile of that distance, metres.
    pub p95_m: f64,
    /// Share of vertices within 2 cm of a surface.
    pub within_2cm: f64,
    /// Share of vertices within 5 cm of a surface.
    pub within_5cm: f64,
    /// Area of the mesh, square metres.
    pub mesh_area_m2: f64,
    /// Area of the mesh farther than 5 cm from every surface, square metres.
    pub phantom_area_m2: f64,
    /// Phantom area over mesh area.
    pub phantom_share: f64,
    /// Phantom area bridging depth jumps between readings on true surfaces, square metres.
    pub bridge_area_m2: f64,
    /// Phantom area joining ghost readings (mirror images, outliers), square metres.
    pub ghost_area_m2: f64,
    /// True wall, box and table area, square metres.
    pub surface_area_m2: f64,
    /// Share of it within 5 cm of a vertex.
    pub coverage: f64,
    /// The same by material: `matte`, `black`, `glass`, `metal` (share, and true area in m²),
    /// for the materials the world has. Black surfaces lost at oblique incidence and glass seen
    /// through show here as holes.
    pub coverage_by_material: Vec<(String, f64, f64)>,
    /// Median seam error between stations, metres (`None` with one station or no overlap).
    pub seam_m: Option<f64>,
    /// Vertices of later stations compared for the seam, and how many found an earlier reading
    /// within reach.
    pub seam_pairs: (usize, usize),
}

/// Each vertex's nearest true surface and its distance: what every figure is computed from.
pub fn nearest_surfaces(model: &Model, map: &WorldMap) -> Vec<(f64, SurfaceId)> {
    model
        .vertices
        .iter()
        .map(|v| map.nearest_surface(v.map(f64::from)))
        .collect()
}

/// Scores `model` against `map`.
pub fn score(model: &Model, map: &WorldMap) -> Accuracy {
    score_with(model, map, &nearest_surfaces(model, map))
}

/// Scores `model` against `map`, its vertices' nearest surfaces being known.
pub fn score_with(model: &Model, map: &WorldMap, nearest: &[(f64, SurfaceId)]) -> Accuracy {
    let n = model.vertices.len();
    let mut distances: Vec<f64> = nearest.iter().map(|(d, _)| *d).collect();
    let within = |limit: f64| distances.iter().filter(|&&d| d <= limit).count() as f64;
    let (within_2cm, within_5cm) = (within(0.02), within(ON_SURFACE));
    let median_m = quantile(&mut distances, 0.5);
    let p95_m = quantile(&mut distances, 0.95);
    let phantom = phantom_area(model, map, nearest);
    let (mesh_area, phantom_area) = (phantom.mesh_m2, phantom.phantom_m2);
    let (surface_area_m2, coverage, coverage_by_material) = coverage(model, map, nearest);
    let (seam_m, seam_pairs) = seam(model);
    let share = |count: f64| if n > 0 { count / n as f64 } else { 0.0 };
    Accuracy {
        vertices: n,
        median_m,
        p95_m,
        within_2cm: share(within_2cm),
        within_5cm: share(within_5cm),
        mesh_area_m2: mesh_area,
        phantom_area_m2: phantom_area,
        phantom_share: if mesh_area > 0.0 {
            phantom_area / mesh_area
        } else {
            0.0
        },
        bridge_area_m2: phantom.bridge_m2,
        ghost_area_m2: phantom.ghost_m2,
        surface_area_m2,
        coverage,
        coverage_by_material,
        seam_m,
        seam_pairs,
    }
}

/// The mesh's area and its phantom part, square metres.
#[derive(Copy, Clone, Debug, Default, PartialEq, Serialize)]
pub struct PhantomArea {
    /// Area of the mesh.
    pub mesh_m2: f64,
    /// Area of the triangles whose centroid is farther than 5 cm from every true surface.
    pub phantom_m2: f64,
    /// The part of it whose three vertices lie on true surfaces: polygons that bridge a depth
    /// jump or a doorway — the validity rule's doing.
    pub bridge_m2: f64,
    /// The part with a vertex off every surface: ghosts (mirror images behind glass and metal,
    /// outliers) meshed together — the sensor's doing.
    pub ghost_m2: f64,
}

/// The mesh's area and the part of it farther than 5 cm from every true surface.
pub fn phantom_area(model: &Model, map: &WorldMap, nearest: &[(f64, SurfaceId)]) -> PhantomArea {
    let mut out = PhantomArea::default();
    for t in &model.triangles {
        let area = f64::from(triangle_area(&model.vertices, t));
        out.mesh_m2 += area;
        let [a, b, c] = t.map(|k| nearest[k as usize]);
        let worst = a.0.max(b.0).max(c.0);
        // On one convex surface, within 5 cm at the corners is within 5 cm everywhere.
        if a.1 == b.1 && b.1 == c.1 && worst <= ON_SURFACE {
            continue;
        }
        let v = t.map(|k| model.vertices[k as usize]);
        let centroid = [0, 1, 2].map(|k| f64::from(v[0][k] + v[1][k] + v[2][k]) / 3.0);
        if map.distance_3d(centroid) > ON_SURFACE {
            out.phantom_m2 += area;
            if worst <= ON_SURFACE {
                out.bridge_m2 += area;
            } else {
                out.ghost_m2 += area;
            }
        }
    }
    out
}

/// The `q` quantile of `values` (nearest rank), reordering them; 0 when empty.
fn quantile(values: &mut [f64], q: f64) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let k = ((values.len() - 1) as f64 * q).round() as usize;
    *values.select_nth_unstable_by(k, f64::total_cmp).1
}

/// 5 cm cells over one true surface, and which a vertex has come near.
struct Cells {
    /// Cells along the surface's first and second axes.
    size: [usize; 2],
    /// Whether each cell lies on the surface (a cap's cells outside its polygon do not).
    on: Vec<bool>,
    covered: Vec<bool>,
}

impl Cells {
    fn new(size: [usize; 2], on: impl Fn(usize, usize) -> bool) -> Self {
        let mut cells = vec![false; size[0] * size[1]];
        for j in 0..size[1] {
            for i in 0..size[0] {
                cells[j * size[0] + i] = on(i, j);
            }
        }
        Cells {
            size,
            covered: vec![false; cells.len()],
            on: cells,
        }
    }

    /// Marks the cells whose centres lie within `r` of `(u, v)` (surface coordinates).
    fn mark(&mut self, u: f64, v: f64, r: f64) {
        // The cells whose centres (i + ½) · cell can lie within r of x: a superset, the
        // distance test below decides. Truncation of non-negative numbers is their floor, and
        // cheaper than `f64::floor` without SSE4.1.
        let range = |x: f64, n: usize| {
            let lo = ((x - r) / COVERAGE_CELL - 0.5).max(0.0) as usize;
            let hi = ((x + r) / COVERAGE_CELL + 0.5).max(0.0) as usize;
            (lo, hi.min(n))
        };
        let (i0, i1) = range(u, self.size[0]);
        let (j0, j1) = range(v, self.size[1]);
        for j in j0..j1 {
            for i in i0..i1 {
                let (cu, cv) = (
                    (i as f64 + 0.5) * COVERAGE_CELL,
                    (j as f64 + 0.5) * COVERAGE_CELL,
                );
                if (cu - u) * (cu - u) + (cv - v) * (cv - v) <= r * r {
                    self.covered[j * self.size[0] + i] = true;
                }
            }
        }
    }

    fn counts(&self) -> (usize, usize) {
        let on = self.on.iter().filter(|&&o| o).count();
        let covered = self
            .on
            .iter()
            .zip(&self.covered)
            .filter(|(o, c)| **o && **c)
            .count();
        (covered, on)
    }
}

/// What [`coverage`] finds.
type CoverageFigures = (f64, f64, Vec<(String, f64, f64)>);

/// True wall, box and table area, the share of it within 5 cm of a vertex, and the same by
/// material.
fn coverage(model: &Model, map: &WorldMap, nearest: &[(f64, SurfaceId)]) -> CoverageFigures {
    let cells_along = |length: f64| (length / COVERAGE_CELL).ceil().max(1.0) as usize;
    let mut faces: Vec<Cells> = map
        .faces()
        .iter()
        .map(|f| {
            let length = (f.b[0] - f.a[0]).hypot(f.b[1] - f.a[1]);
            Cells::new(
                [cells_along(length), cells_along(f.z[1] - f.z[0])],
                |_, _| true,
            )
        })
        .collect();
    let bounds: Vec<([f64; 2], [f64; 2])> = map
        .caps()
        .iter()
        .map(|c| {
            c.polygon.iter().fold(
                ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
                |(lo, hi), p| {
                    (
                        [lo[0].min(p[0]), lo[1].min(p[1])],
                        [hi[0].max(p[0]), hi[1].max(p[1])],
                    )
                },
            )
        })
        .collect();
    let mut caps: Vec<Cells> = map
        .caps()
        .iter()
        .zip(&bounds)
        .map(|(c, (lo, hi))| {
            Cells::new(
                [cells_along(hi[0] - lo[0]), cells_along(hi[1] - lo[1])],
                |i, j| {
                    let q = [
                        lo[0] + (i as f64 + 0.5) * COVERAGE_CELL,
                        lo[1] + (j as f64 + 0.5) * COVERAGE_CELL,
                    ];
                    c.plan_distance(q) == 0.0
                },
            )
        })
        .collect();
    for (v, &(d, id)) in model.vertices.iter().zip(nearest) {
        if d > ON_SURFACE {
            continue;
        }
        let r = (ON_SURFACE * ON_SURFACE - d * d).sqrt();
        let p = v.map(f64::from);
        match id {
            SurfaceId::Face(k) => {
                let f = &map.faces()[k as usize];
                let e = [f.b[0] - f.a[0], f.b[1] - f.a[1]];
                let length = e[0].hypot(e[1]);
                let t = ((p[0] - f.a[0]) * e[0] + (p[1] - f.a[1]) * e[1]) / length;
                let u = t.clamp(0.0, length);
                let z = p[2].clamp(f.z[0], f.z[1]) - f.z[0];
                faces[k as usize].mark(u, z, r);
            }
            SurfaceId::Cap(k) => {
                let lo = bounds[k as usize].0;
                caps[k as usize].mark(p[0] - lo[0], p[1] - lo[1], r);
            }
            SurfaceId::Floor | SurfaceId::Ceiling => {}
        }
    }
    let materials = map
        .faces()
        .iter()
        .map(|f| f.material)
        .chain(map.caps().iter().map(|c| c.material));
    let mut by_material: Vec<(Material, usize, usize)> =
        Material::ALL.iter().map(|&m| (m, 0, 0)).collect();
    for (cells, material) in faces.iter().chain(&caps).zip(materials) {
        let (covered, total) = cells.counts();
        let entry = &mut by_material[material as usize];
        entry.1 += covered;
        entry.2 += total;
    }
    let (covered, total) = by_material
        .iter()
        .fold((0, 0), |a, b| (a.0 + b.1, a.1 + b.2));
    let cell_area = COVERAGE_CELL * COVERAGE_CELL;
    let share = |covered: usize, total: usize| {
        if total > 0 {
            covered as f64 / total as f64
        } else {
            0.0
        }
    };
    (
        total as f64 * cell_area,
        share(covered, total),
        by_material
            .into_iter()
            .filter(|(_, _, total)| *total > 0)
            .map(|(m, covered, total)| {
                (
                    m.name().to_string(),
                    share(covered, total),
                    total as f64 * cell_area,
                )
            })
            .collect(),
    )
}

/// Earlier stations' readings summed in cubes of [`SEAM_REACH`]: a dense grid over the middle
/// of the model (from the 0.5th to the 99.5th percentile of each coordinate, so that a few far
/// ghosts do not blow it up), each cube holding the sum of its points, of their normals, and
/// their count.
struct Cubes {
    origin: [f32; 3],
    size: [usize; 3],
    /// Index into `sums` per cube, `u32::MAX` when empty.
    cells: Vec<u32>,
    sums: Vec<([f64; 3], [f64; 3], u32)>,
}

impl Cubes {
    /// At most this many cubes (16 M: 64 MB of indices); a larger model is compared on the
    /// cubes nearest its middle.
    const MAX_CELLS: usize = 1 << 24;

    fn new(vertices: &[[f32; 3]]) -> Self {
        let mut lo = [0f32; 3];
        let mut hi = [0f32; 3];
        for k in 0..3 {
            let mut c: Vec<f32> = vertices.iter().map(|v| v[k]).collect();
            let n = c.len();
            if n > 0 {
                lo[k] = *c.select_nth_unstable_by(n / 200, f32::total_cmp).1;
                hi[k] = *c.select_nth_unstable_by(n - 1 - n / 200, f32::total_cmp).1;
            }
        }
        let cube = SEAM_REACH as f32;
        // One cube of margin on each side, so the neighbours of an edge cube exist.
        let mut size =
            [0, 1, 2].map(|k| (((hi[k] - lo[k]) / cube).max(0.0) as usize).saturating_add(3));
        while size.iter().product::<usize>() > Self::MAX_CELLS {
            let k = (0..3).max_by_key(|&k| size[k]).unwrap_or(0);
            let cut = size[k] / 4;
            lo[k] += cut as f32 * cube;
            size[k] -= 2 * cut;
        }
        Cubes {
            origin: [0, 1, 2].map(|k| lo[k] - cube),
            size,
            cells: vec![u32::MAX; size.iter().product()],
            sums: Vec::new(),
        }
    }

    /// The cube of `p`, if inside the grid.
    #[inline]
    fn key(&self, p: &[f32; 3]) -> Option<[usize; 3]> {
        let cube = SEAM_REACH as f32;
        let mut key = [0usize; 3];
        for k in 0..3 {
            let u = (p[k] - self.origin[k]) / cube;
            if !(u >= 0.0 && (u as usize) < self.size[k]) {
                return None;
            }
            key[k] = u as usize;
        }
        Some(key)
    }

    #[inline]
    fn index(&self, key: [usize; 3]) -> usize {
        (key[2] * self.size[1] + key[1]) * self.size[0] + key[0]
    }

    fn add(&mut self, p: &[f32; 3], n: &[f32; 3]) {
        let Some(key) = self.key(p) else {
            return;
        };
        let cell = self.index(key);
        if self.cells[cell] == u32::MAX {
            self.cells[cell] = self.sums.len() as u32;
            self.sums.push(([0.0; 3], [0.0; 3], 0));
        }
        let e = &mut self.sums[self.cells[cell] as usize];
        for k in 0..3 {
            e.0[k] += f64::from(p[k]);
            e.1[k] += f64::from(n[k]);
        }
        e.2 += 1;
    }

    /// The distance from `p` to the plane of the nearest cube's readings within reach, if any.
    fn plane_distance(&self, p: &[f32; 3]) -> Option<f64> {
        let key = self.key(p)?;
        let q = p.map(f64::from);
        let mut best: Option<(f64, f64)> = None;
        for z in key[2].saturating_sub(1)..(key[2] + 2).min(self.size[2]) {
            for y in key[1].saturating_sub(1)..(key[1] + 2).min(self.size[1]) {
                for x in key[0].saturating_sub(1)..(key[0] + 2).min(self.size[0]) {
                    let cell = self.cells[self.index([x, y, z])];
                    if cell == u32::MAX {
                        continue;
                    }
                    let (sum, normal, count) = &self.sums[cell as usize];
                    let m = sum.map(|s| s / f64::from(*count));
                    let d = [q[0] - m[0], q[1] - m[1], q[2] - m[2]];
                    let gap = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    if gap <= SEAM_REACH && best.is_none_or(|(g, _)| gap < g) {
                        let len =
                            (normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2])
                                .sqrt()
                                .max(1e-12);
                        let along = (d[0] * normal[0] + d[1] * normal[1] + d[2] * normal[2]) / len;
                        best = Some((gap, along.abs()));
                    }
                }
            }
        }
        best.map(|(_, along)| along)
    }
}

/// The median point-to-plane distance of later stations' vertices to earlier stations' readings.
fn seam(model: &Model) -> (Option<f64>, (usize, usize)) {
    let station = |v: usize| model.scenes[usize::from(model.vertex_scene[v])].tag.station;
    let stations = (0..model.vertices.len())
        .map(station)
        .max()
        .map_or(0, |s| s + 1);
    if stations < 2 {
        return (None, (0, 0));
    }
    // Vertices by station, in order.
    let mut by_station: Vec<Vec<usize>> = vec![Vec::new(); stations];
    for v in 0..model.vertices.len() {
        by_station[station(v)].push(v);
    }
    let mut earlier = Cubes::new(&model.vertices);
    let mut errors = Vec::new();
    let mut compared = 0;
    for (s, vertices) in by_station.iter().enumerate() {
        if s > 0 {
            for &v in vertices.iter().step_by(SEAM_STRIDE) {
                compared += 1;
                if let Some(along) = earlier.plane_distance(&model.vertices[v]) {
                    errors.push(along);
                }
            }
        }
        for &v in vertices {
            earlier.add(&model.vertices[v], &model.normals[v]);
        }
    }
    let found = errors.len();
    let median = (!errors.is_empty()).then(|| quantile(&mut errors, 0.5));
    (median, (compared, found))
}
