//! Exact distances from a point to the world's surfaces, through a grid over the floor plan.
//!
//! Every per-point question about the truth — is this reading a ghost, how far is this vertex
//! from the nearest wall — asks the same thing, often hundreds of thousands of times a run. The
//! plan is cut into square cells; each cell lists the surfaces whose footprint (a vertical face's
//! segment, a cap's polygon) comes within `reach` of it. A point's nearest surface among its
//! cell's list, the floor and the ceiling is the true nearest whenever it is within `reach`: a
//! surface that close in 3D is that close in the plan, so it is in the list. Farther points (a
//! ghost behind glass, an outlier, a point off the plan) search rings of cells outwards until no
//! unseen surface can be nearer: the cost follows the distance, not the number of surfaces.

use super::map::{Cap, Face, point_segment_distance, point_segment_distance2};

/// Which surface a point is nearest to.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum SurfaceId {
    /// A vertical face, by index in [`super::WorldMap::faces`].
    Face(u32),
    /// A horizontal cap (top or bottom of a box or table), by index.
    Cap(u32),
    /// The floor, z = 0.
    Floor,
    /// The ceiling.
    Ceiling,
}

/// The grid over the plan and the surfaces near each cell.
#[derive(Clone, Debug)]
pub(super) struct SurfaceIndex {
    origin: [f64; 2],
    cell: f64,
    size: [usize; 2],
    /// For cell `k`, its surfaces are `items[starts[k]..starts[k + 1]]`.
    starts: Vec<u32>,
    items: Vec<SurfaceId>,
    reach: f64,
}

/// Side of a cell and how far around it surfaces are listed, metres.
const CELL: f64 = 0.25;
const REACH: f64 = 0.25;
/// At most this many cells: a world larger than this gets larger cells.
const MAX_CELLS: f64 = 4.0e6;

impl SurfaceIndex {
    pub(super) fn new(faces: &[Face], caps: &[Cap]) -> Self {
        let mut min = [f64::INFINITY; 2];
        let mut max = [f64::NEG_INFINITY; 2];
        let corners = faces
            .iter()
            .flat_map(|f| [f.a, f.b])
            .chain(caps.iter().flat_map(|c| c.polygon.iter().copied()));
        for p in corners {
            for k in 0..2 {
                min[k] = min[k].min(p[k]);
                max[k] = max[k].max(p[k]);
            }
        }
        if !min[0].is_finite() {
            // No surface but the floor and the ceiling.
            return SurfaceIndex {
                origin: [0.0; 2],
                cell: CELL,
                size: [0, 0],
                starts: vec![0],
                items: Vec::new(),
                reach: REACH,
            };
        }
        let span = [max[0] - min[0], max[1] - min[1]];
        let cell = CELL.max((span[0] * span[1] / MAX_CELLS).sqrt());
        let size = [0, 1].map(|k| (span[k] / cell).floor() as usize + 1);
        let mut lists: Vec<Vec<SurfaceId>> = vec![Vec::new(); size[0] * size[1]];
        let cell_range = |lo: f64, hi: f64, k: usize| {
            let a = ((lo - REACH - min[k]) / cell).floor().max(0.0) as usize;
            let b = (((hi + REACH - min[k]) / cell).floor().max(0.0) as usize).min(size[k] - 1);
            a..=b
        };
        // A cell lists a surface when the surface's footprint comes within `REACH` of the
        // cell's square: the distance from the cell's centre is then within REACH plus half
        // the cell's diagonal.
        let half_diagonal = cell * std::f64::consts::FRAC_1_SQRT_2;
        let centre = |i: usize, j: usize| {
            [
                min[0] + (i as f64 + 0.5) * cell,
                min[1] + (j as f64 + 0.5) * cell,
            ]
        };
        for (n, f) in faces.iter().enumerate() {
            for i in cell_range(f.a[0].min(f.b[0]), f.a[0].max(f.b[0]), 0) {
                for j in cell_range(f.a[1].min(f.b[1]), f.a[1].max(f.b[1]), 1) {
                    if point_segment_distance(centre(i, j), f.a, f.b) <= REACH + half_diagonal {
                        lists[j * size[0] + i].push(SurfaceId::Face(n as u32));
                    }
                }
            }
        }
        for (n, c) in caps.iter().enumerate() {
            let (lo, hi) = c.polygon.iter().fold(
                ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
                |(lo, hi), p| {
                    (
                        [lo[0].min(p[0]), lo[1].min(p[1])],
                        [hi[0].max(p[0]), hi[1].max(p[1])],
                    )
                },
            );
            for i in cell_range(lo[0], hi[0], 0) {
                for j in cell_range(lo[1], hi[1], 1) {
                    if c.plan_distance(centre(i, j)) <= REACH + half_diagonal {
                        lists[j * size[0] + i].push(SurfaceId::Cap(n as u32));
                    }
                }
            }
        }
        let (starts, items) = super::packed(lists);
        SurfaceIndex {
            origin: min,
            cell,
            size,
            starts,
            items,
            reach: REACH,
        }
    }

    /// The nearest surface to `p` and its distance, exactly.
    pub(super) fn nearest(
        &self,
        p: [f64; 3],
        faces: &[Face],
        caps: &[Cap],
        ceiling: f64,
    ) -> (f64, SurfaceId) {
        // Squared distances until the end: one square root per query.
        let distance2 = |id: SurfaceId| match id {
            SurfaceId::Face(n) => faces[n as usize].distance2(p),
            SurfaceId::Cap(n) => caps[n as usize].distance2(p),
            SurfaceId::Floor => p[2] * p[2],
            SurfaceId::Ceiling => (ceiling - p[2]) * (ceiling - p[2]),
        };
        let mut best = (distance2(SurfaceId::Floor), SurfaceId::Floor);
        let up = distance2(SurfaceId::Ceiling);
        if up < best.0 {
            best = (up, SurfaceId::Ceiling);
        }
        let (d2, id) = self.search([p[0], p[1]], best, distance2);
        (d2.sqrt(), id)
    }

    /// Whether a surface lies at most `r` from `p`: `nearest(p).0 <= r`, to the last bit, with
    /// a look at `p`'s own cell only when `r` is within the cells' reach (the question a ghost
    /// test asks of every point: a ghost far from everything costs no search outwards).
    ///
    /// `hint`, a surface, is tried first, and is left holding the surface found within `r` (kept
    /// when none is). Points in a row (a scan's beams) mostly lie near the surface the last one
    /// did: one distance then answers. The answer is the same: any surface within `r` makes the
    /// nearest one within `r`.
    pub(super) fn within(
        &self,
        p: [f64; 3],
        r: f64,
        faces: &[Face],
        caps: &[Cap],
        ceiling: f64,
        hint: &mut Option<SurfaceId>,
    ) -> bool {
        // The square root of each squared distance, as `nearest` takes it of the least one
        // (the root is monotonic, so the least root is the root of the least).
        let near = |d2: f64| d2.sqrt() <= r;
        let near_surface = |id: SurfaceId| match id {
            SurfaceId::Face(n) => near(faces[n as usize].distance2(p)),
            SurfaceId::Cap(n) => near(caps[n as usize].distance2(p)),
            SurfaceId::Floor | SurfaceId::Ceiling => false,
        };
        if hint.is_some_and(near_surface) {
            return true;
        }
        if near(p[2] * p[2]) || near((ceiling - p[2]) * (ceiling - p[2])) {
            return true;
        }
        let cell_of = |x: f64, k: usize| {
            let u = (x - self.origin[k]) / self.cell;
            (u >= 0.0 && u < self.size[k] as f64).then_some(u as usize)
        };
        let (Some(i), Some(j)) = (cell_of(p[0], 0), cell_of(p[1], 1)) else {
            // Off the plan (or not a number): the full search.
            return self.nearest(p, faces, caps, ceiling).0 <= r;
        };
        if r > self.reach {
            return self.nearest(p, faces, caps, ceiling).0 <= r;
        }
        // A surface within `r` of `p` is within the reach of `p`'s cell, so the cell lists it.
        let k = j * self.size[0] + i;
        let found = self.items[self.starts[k] as usize..self.starts[k + 1] as usize]
            .iter()
            .copied()
            .find(|&id| near_surface(id));
        if found.is_some() {
            *hint = found;
        }
        found.is_some()
    }

    /// Distance in the plan from `p` to the nearest face's segment (heights and caps ignored),
    /// and that face; infinite (and the floor) for a world without faces.
    pub(super) fn nearest_face_in_plan(&self, p: [f64; 2], faces: &[Face]) -> (f64, SurfaceId) {
        let distance2 = |id: SurfaceId| match id {
            SurfaceId::Face(n) => {
                let f = &faces[n as usize];
                point_segment_distance2(p, f.a, f.b)
            }
            SurfaceId::Cap(_) | SurfaceId::Floor | SurfaceId::Ceiling => f64::INFINITY,
        };
        let (d2, id) = self.search(p, (f64::INFINITY, SurfaceId::Floor), distance2);
        (d2.sqrt(), id)
    }

    /// The surface with the least `distance2` among `best` and those listed near `p`, searching
    /// rings of cells outwards until no unseen surface can be nearer; squared distance.
    fn search(
        &self,
        p: [f64; 2],
        mut best: (f64, SurfaceId),
        distance2: impl Fn(SurfaceId) -> f64,
    ) -> (f64, SurfaceId) {
        let consider = |best: &mut (f64, SurfaceId), id: SurfaceId| {
            let d = distance2(id);
            if d < best.0 {
                *best = (d, id);
            }
        };
        // Rings of cells around the cell of `p` (or of its projection onto the grid, for a point
        // off the plan), nearest first. Once rings 0..=r are seen, an unseen surface is farther
        // than r cells plus `reach` (its nearest footprint point would otherwise be within
        // `reach` of a seen cell, which lists it): stop when the best is within that.
        if self.size[0] == 0 || self.size[1] == 0 {
            return best;
        }
        let cell_of = |x: f64, k: usize| {
            let u = (x - self.origin[k]) / self.cell;
            // NaN and points below the origin go to the first cell, points beyond to the last.
            if u >= 0.0 {
                (u as usize).min(self.size[k] - 1)
            } else {
                0
            }
        };
        let (ci, cj) = (cell_of(p[0], 0), cell_of(p[1], 1));
        let rings = self.size[0].max(self.size[1]);
        for r in 0..=rings {
            let (i0, i1) = (ci.saturating_sub(r), (ci + r).min(self.size[0] - 1));
            let (j0, j1) = (cj.saturating_sub(r), (cj + r).min(self.size[1] - 1));
            let mut visit = |i: usize, j: usize| {
                let k = j * self.size[0] + i;
                for &id in &self.items[self.starts[k] as usize..self.starts[k + 1] as usize] {
                    consider(&mut best, id);
                }
            };
            // The ring's own cells: its top and bottom rows, then its side columns between.
            for j in [cj.checked_sub(r), Some(cj + r)].into_iter().flatten() {
                if j < self.size[1] && (r > 0 || j == cj) {
                    for i in i0..=i1 {
                        visit(i, j);
                    }
                }
                if r == 0 {
                    break;
                }
            }
            if r > 0 {
                let (below, above) = ((cj + 1).saturating_sub(r).max(j0), (cj + r - 1).min(j1));
                for i in [ci.checked_sub(r), Some(ci + r)].into_iter().flatten() {
                    if i < self.size[0] {
                        for j in below..=above {
                            visit(i, j);
                        }
                    }
                }
            }
            let bound = r as f64 * self.cell + self.reach;
            if best.0 <= bound * bound {
                break;
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use crate::config::WorldDescription;
    use crate::world::WorldMap;
    use rand::RngExt;

    #[test]
    fn the_grid_finds_the_same_nearest_distance_as_every_surface() {
        let lab = WorldDescription::load(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../worlds/lab.toml"),
        )
        .unwrap();
        // And a cluttered one: 300 small boxes and tables of random heights in a 30 m hall.
        let mut rng = crate::rng::stream(11, "boxes");
        let mut text = String::from(
            "name = \"hall\"\n[start]\nx = 1.0\ny = 1.0\nheading_deg = 0.0\n[[wall]]\npoints = [[0, 0], [30, 0], [30, 12], [0, 12]]\nclosed = true\n",
        );
        for k in 0..300 {
            let (x, y) = (
                rng.random::<f64>() * 29.0 + 0.5,
                rng.random::<f64>() * 11.0 + 0.5,
            );
            let top = 0.2 + rng.random::<f64>() * 1.5;
            if k % 3 == 0 {
                text.push_str(&format!(
                    "[[table]]\ncenter = [{x}, {y}]\nsize = [0.8, 0.5]\nheight_m = {top}\n"
                ));
            } else {
                text.push_str(&format!(
                    "[[box]]\ncenter = [{x}, {y}]\nsize = [0.2, 0.1]\nheading_deg = {}\nz = [0.0, {top}]\n",
                    k * 7
                ));
            }
        }
        let hall = WorldDescription::parse(&text, "hall.toml").unwrap();
        for world in [lab, hall] {
            check_against_brute_force(&world);
        }
    }

    fn check_against_brute_force(world: &WorldDescription) {
        let map = WorldMap::new(world);
        let mut rng = crate::rng::stream(7, "test");
        let (faces, caps) = (map.faces(), map.caps());
        for _ in 0..20_000 {
            // Points on and off the plan, near surfaces and far from them.
            let p = [
                rng.random::<f64>() * 36.0 - 3.0,
                rng.random::<f64>() * 18.0 - 3.0,
                rng.random::<f64>() * 3.4 - 0.4,
            ];
            let brute = faces
                .iter()
                .map(|f| f.distance2(p))
                .chain(caps.iter().map(|c| c.distance2(p)))
                .fold((p[2] * p[2]).min((map.ceiling() - p[2]).powi(2)), f64::min)
                .sqrt();
            let (d, _) = map.nearest_surface(p);
            assert_eq!(d, brute, "at {p:?}");
            // The bounded question answers as the distance does, at and beyond the reach.
            for r in [0.0, 0.05, 0.15, 0.25, 0.6, brute] {
                assert_eq!(map.within_3d(p, r), brute <= r, "within {r} at {p:?}");
            }
            // The plan's clearance (faces only, heights ignored) through the same grid.
            let plan = faces
                .iter()
                .map(|f| super::point_segment_distance([p[0], p[1]], f.a, f.b))
                .fold(f64::INFINITY, f64::min);
            assert_eq!(map.clearance([p[0], p[1]]), plan, "clearance at {p:?}");
        }
    }

    /// Points in a row, most near the surface the last one was near (a scan's beams), with
    /// jumps to other surfaces, to the floor, off the plan and into empty space: the kinds
    /// found trying the last surface first are those found afresh for each point.
    #[test]
    fn kinds_of_points_in_a_row_are_the_kinds_of_each_point() {
        use crate::world::{PointKind, PointKinds};
        let lab = WorldDescription::load(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../worlds/lab.toml"),
        )
        .unwrap();
        let map = WorldMap::new(&lab);
        let mut rng = crate::rng::stream(11, "test");
        let mut kinds = PointKinds::new(&map);
        let faces = map.faces();
        let mut seen = [0usize; 3];
        for _ in 0..20_000 {
            let p = if rng.random::<f64>() < 0.8 {
                // On or near a face, within and beyond the ghost margin.
                let f = &faces[rng.random_range(0..faces.len())];
                let s = rng.random::<f64>();
                let off = rng.random::<f64>() * 0.4 - 0.2;
                let (dx, dy) = (f.b[0] - f.a[0], f.b[1] - f.a[1]);
                let n = dx.hypot(dy).max(1e-9);
                [
                    f.a[0] + s * dx - off * dy / n,
                    f.a[1] + s * dy + off * dx / n,
                    rng.random::<f64>() * 2.2 - 0.1,
                ]
            } else {
                [
                    rng.random::<f64>() * 36.0 - 3.0,
                    rng.random::<f64>() * 18.0 - 3.0,
                    rng.random::<f64>() * 3.4 - 0.4,
                ]
            };
            let kind = kinds.of(p);
            assert_eq!(kind, PointKind::of(&map, p), "at {p:?}");
            seen[kind as usize] += 1;
        }
        assert!(seen.iter().all(|&n| n > 500), "every kind met: {seen:?}");
    }
}
