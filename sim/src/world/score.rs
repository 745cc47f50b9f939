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
use robot::reconstruction::{Model, triangle_area};
use serde::Serialize;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

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
    let (surface_area_m2, coverage) = coverage(model, map, nearest);
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
        let range = |x: f64, n: usize| {
            let lo = ((x - r) / COVERAGE_CELL - 0.5).ceil().max(0.0) as usize;
            let hi = ((x + r) / COVERAGE_CELL - 0.5).floor();
            (
                lo,
                if hi < 0.0 {
                    0
                } else {
                    (hi as usize + 1).min(n)
                },
            )
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

/// True wall, box and table area and the share of it within 5 cm of a vertex.
fn coverage(model: &Model, map: &WorldMap, nearest: &[(f64, SurfaceId)]) -> (f64, f64) {
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
    let (covered, total) = faces
        .iter()
        .chain(&caps)
        .map(Cells::counts)
        .fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    let cell_area = COVERAGE_CELL * COVERAGE_CELL;
    let share = if total > 0 {
        covered as f64 / total as f64
    } else {
        0.0
    };
    (total as f64 * cell_area, share)
}

/// A voxel's key.
type Voxel = (i32, i32, i32);

/// FNV-1a over the voxel's coordinates: the voxel maps are rebuilt for every score, and a
/// cryptographic hash would cost more than the lookups it serves.
#[derive(Default)]
struct VoxelHasher(u64);

impl Hasher for VoxelHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        let mut h = if self.0 == 0 {
            0xcbf2_9ce4_8422_2325
        } else {
            self.0
        };
        for &b in bytes {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
        self.0 = h;
    }
}

type VoxelMap = HashMap<Voxel, ([f64; 3], [f64; 3], u32), BuildHasherDefault<VoxelHasher>>;

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
    let key = |p: &[f32; 3]| -> Voxel {
        let k = |x: f32| (f64::from(x) / SEAM_REACH).floor() as i32;
        (k(p[0]), k(p[1]), k(p[2]))
    };
    // Vertices by station, in order.
    let mut by_station: Vec<Vec<usize>> = vec![Vec::new(); stations];
    for v in 0..model.vertices.len() {
        by_station[station(v)].push(v);
    }
    let mut earlier = VoxelMap::default();
    let mut errors = Vec::new();
    let mut compared = 0;
    for (s, vertices) in by_station.iter().enumerate() {
        if s > 0 {
            for &v in vertices.iter().step_by(SEAM_STRIDE) {
                compared += 1;
                let p = model.vertices[v].map(f64::from);
                let (x, y, z) = key(&model.vertices[v]);
                let mut best: Option<(f64, f64)> = None;
                for dx in -1..=1 {
                    for dy in -1..=1 {
                        for dz in -1..=1 {
                            let Some((sum, normal, count)) = earlier.get(&(x + dx, y + dy, z + dz))
                            else {
                                continue;
                            };
                            let q = sum.map(|c| c / f64::from(*count));
                            let d = [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
                            let gap = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                            if gap <= SEAM_REACH && best.is_none_or(|(g, _)| gap < g) {
                                let len = (normal[0] * normal[0]
                                    + normal[1] * normal[1]
                                    + normal[2] * normal[2])
                                    .sqrt()
                                    .max(1e-12);
                                let along =
                                    (d[0] * normal[0] + d[1] * normal[1] + d[2] * normal[2]) / len;
                                best = Some((gap, along.abs()));
                            }
                        }
                    }
                }
                if let Some((_, along)) = best {
                    errors.push(along);
                }
            }
        }
        for &v in vertices {
            let p = model.vertices[v];
            let n = model.normals[v];
            let e = earlier.entry(key(&p)).or_insert(([0.0; 3], [0.0; 3], 0));
            for k in 0..3 {
                e.0[k] += f64::from(p[k]);
                e.1[k] += f64::from(n[k]);
            }
            e.2 += 1;
        }
    }
    let found = errors.len();
    let median = (!errors.is_empty()).then(|| quantile(&mut errors, 0.5));
    (median, (compared, found))
}
