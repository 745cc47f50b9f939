//! The world's surfaces in 2.5D, for ray casts: the vertical faces of walls, boxes and tables
//! (each a segment extruded between a bottom and a top height), the horizontal faces of boxes and
//! tables, the floor (z = 0) and the ceiling.
//!
//! Vertical faces sit under one parry bounding-volume tree built with the PLOC strategy (a
//! tighter tree than a `Polyline`'s default, measured 1.3× faster per scan in the lab). A ray is
//! cast in the plane along its horizontal direction, nearest boxes first (`Bvh::find_best`), with
//! a slab test on the boxes and an exact ray–segment intersection in `f64` at the leaves — both
//! written here, as parry's general-purpose versions took three quarters of a scan's time. Each
//! candidate face's hit is kept only if the ray is between the face's bottom and top there. A
//! horizontal ray never needs more: the level laser and the sonar cost what a 2D cast does. A
//! tilted ray is also tested against the horizontal faces, the floor and the ceiling. Many rays
//! from one point (a laser scan) are cast in one sweep of the faces instead
//! ([`WorldMap::cast_fan`], in `fan.rs`), with the same answers.

use super::index::{SurfaceId, SurfaceIndex};
use super::walk::WalkGrid;
use crate::config::{Material, Optics, WorldDescription};
use parry2d::bounding_volume::BoundingVolume;
use parry2d::math::Vector;
use parry2d::partitioning::{Bvh, BvhBuildStrategy};
use parry2d::shape::Segment;

/// What a ray met.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Surface {
    /// A vertical face, by index.
    Face(usize),
    /// The top or bottom of a box or table, by index.
    Cap(usize),
    /// The floor.
    Floor,
    /// The ceiling.
    Ceiling,
}

/// The first surface a ray meets.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray, metres.
    pub distance: f64,
    /// Which surface.
    pub surface: Surface,
    /// What the surface is made of.
    pub material: Material,
    /// Unit normal of the surface at the hit, facing the ray's origin.
    pub normal: [f64; 3],
}

/// A vertical face: a segment extruded from `z[0]` to `z[1]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Face {
    /// First end, metres.
    pub a: [f64; 2],
    /// Second end, metres.
    pub b: [f64; 2],
    /// Bottom and top, metres.
    pub z: [f64; 2],
    /// Material.
    pub material: Material,
}

impl Face {
    /// Distance from `p` to the face in 3D, metres.
    #[inline]
    pub fn distance(&self, p: [f64; 3]) -> f64 {
        self.distance2(p).sqrt()
    }

    /// Squared distance from `p` to the face in 3D, square metres.
    #[inline]
    pub fn distance2(&self, p: [f64; 3]) -> f64 {
        let above = (self.z[0] - p[2]).max(p[2] - self.z[1]).max(0.0);
        point_segment_distance2([p[0], p[1]], self.a, self.b) + above * above
    }
}

/// A horizontal face: a polygon at height `z`.
#[derive(Clone, Debug, PartialEq)]
pub struct Cap {
    /// Corners, metres.
    pub polygon: Vec<[f64; 2]>,
    /// Height, metres.
    pub z: f64,
    /// Material.
    pub material: Material,
}

/// How far from every surface a point must be to count as a ghost, metres.
const GHOST_MARGIN: f64 = 0.15;
/// Points lower than this (metres) hit the floor.
const FLOOR_BAND: f64 = 0.03;

/// What a scan point hit, as the pictures colour it and the checks count it.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum PointKind {
    /// A wall or object.
    Surface,
    /// The floor (a tilted laser).
    Floor,
    /// No surface there: a mirror image or an outlier.
    Ghost,
}

impl PointKind {
    /// What the world point `p` is: farther than 15 cm from every surface is a ghost, lower
    /// than 3 cm is the floor.
    pub fn of(map: &WorldMap, p: [f64; 3]) -> Self {
        PointKinds::new(map).of(p)
    }
}

/// [`PointKind::of`] for points one after another, trying first the surface the last point lay
/// near: a scan's neighbouring beams mostly hit the same one, and one distance then answers.
pub struct PointKinds<'a> {
    map: &'a WorldMap,
    last: Option<SurfaceId>,
}

impl<'a> PointKinds<'a> {
    /// No point seen yet.
    pub fn new(map: &'a WorldMap) -> Self {
        PointKinds { map, last: None }
    }

    /// What the world point `p` is ([`PointKind::of`]).
    pub fn of(&mut self, p: [f64; 3]) -> PointKind {
        let m = self.map;
        if !m.index.within(
            p,
            GHOST_MARGIN,
            &m.faces,
            &m.caps,
            m.ceiling,
            &mut self.last,
        ) {
            PointKind::Ghost
        } else if p[2] < FLOOR_BAND {
            PointKind::Floor
        } else {
            PointKind::Surface
        }
    }
}

impl Cap {
    /// Distance from `q` to the polygon in the plan: zero inside, metres.
    pub fn plan_distance(&self, q: [f64; 2]) -> f64 {
        if inside(&self.polygon, q) {
            0.0
        } else {
            polygon_distance(&self.polygon, q)
        }
    }

    /// Distance from `p` to the cap in 3D, metres.
    #[inline]
    pub fn distance(&self, p: [f64; 3]) -> f64 {
        self.distance2(p).sqrt()
    }

    /// Squared distance from `p` to the cap in 3D, square metres.
    #[inline]
    pub fn distance2(&self, p: [f64; 3]) -> f64 {
        let across = self.plan_distance([p[0], p[1]]);
        let dz = p[2] - self.z;
        across * across + dz * dz
    }
}

/// No face met: what the casts of faces answer for a ray that meets none.
pub(super) const NO_FACE: (f64, u32) = (f64::INFINITY, u32::MAX);

/// Tolerance on heights when deciding whether a ray passes a face, metres.
pub(super) const Z_EPS: f64 = 1e-9;

/// Static world geometry with its materials.
#[derive(Clone)]
pub struct WorldMap {
    optics: Optics,
    tree: Bvh,
    faces: Vec<Face>,
    /// Unit normal of each face in the plane (to the left of `a`→`b`).
    normals: Vec<[f64; 2]>,
    caps: Vec<Cap>,
    ceiling: f64,
    index: SurfaceIndex,
    /// The plan's grid that single rays walk; `None` without faces, or where the tree is
    /// faster (see [`WalkGrid::new`]).
    walk: Option<WalkGrid>,
}

impl std::fmt::Debug for WorldMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("WorldMap")
            .field("faces", &self.faces.len())
            .field("caps", &self.caps.len())
            .field("ceiling", &self.ceiling)
            .field("walked", &self.walk.is_some())
            .finish_non_exhaustive()
    }
}

impl WorldMap {
    /// The surfaces of a world. Faces shorter than 0.1 mm are dropped.
    pub fn new(world: &WorldDescription) -> Self {
        let mut faces = Vec::new();
        let mut caps = Vec::new();
        for wall in &world.walls {
            for (a, b) in wall.segments() {
                if (a[0] - b[0]).hypot(a[1] - b[1]) >= 1e-4 {
                    faces.push(Face {
                        a,
                        b,
                        z: wall.z,
                        material: wall.material,
                    });
                }
            }
            if wall.closed {
                for (z, needed) in [
                    (wall.z[0], wall.z[0] > 0.0),
                    (wall.z[1], wall.z[1] < world.ceiling),
                ] {
                    if needed {
                        caps.push(Cap {
                            polygon: wall.points.clone(),
                            z,
                            material: wall.material,
                        });
                    }
                }
            }
        }
        let tree = Bvh::from_iter(
            BvhBuildStrategy::Ploc,
            faces
                .iter()
                .map(|f| {
                    Segment::new(vector(f.a), vector(f.b))
                        .local_aabb()
                        .loosened(1e-4)
                })
                .enumerate(),
        );
        let normals = faces
            .iter()
            .map(|f| {
                let length = (f.b[0] - f.a[0]).hypot(f.b[1] - f.a[1]);
                [(f.a[1] - f.b[1]) / length, (f.b[0] - f.a[0]) / length]
            })
            .collect();
        WorldMap {
            optics: world.optics,
            tree,
            index: SurfaceIndex::new(&faces, &caps),
            walk: WalkGrid::new(&faces.iter().map(|f| [f.a, f.b]).collect::<Vec<_>>()),
            faces,
            normals,
            caps,
            ceiling: world.ceiling,
        }
    }

    /// How the world's materials answer the laser.
    pub fn optics(&self) -> &Optics {
        &self.optics
    }

    /// The vertical faces.
    pub fn faces(&self) -> &[Face] {
        &self.faces
    }

    /// Whether the rays of a fan from one origin ([`WorldMap::cast_plane_fan`]) are cast by
    /// more than each going down the tree: by the sweep (at most [`super::FAN_MAX_FACES`]
    /// faces) or by walking the plan's grid. Where neither serves (many faces spread thinly
    /// over a grid of mostly empty cells), a fan casts each ray down the tree as a single ray
    /// would, and its bookkeeping only adds to that.
    pub fn casts_fans(&self) -> bool {
        self.sweeps_fans() || self.walk.is_some()
    }

    /// Whether a fan's rays are cast in one sweep of the faces: at most
    /// [`super::FAN_MAX_FACES`] of them (the rule [`WorldMap::cast_plane_fan`] and
    /// [`WorldMap::cast_fan`] follow).
    #[inline]
    pub(super) fn sweeps_fans(&self) -> bool {
        self.faces.len() <= super::FAN_MAX_FACES
    }

    /// Face `i`'s unit normal in the plan, on one side or the other: [`Hit::normal`] is this
    /// or its opposite, whichever faces the ray.
    #[inline]
    pub fn face_normal(&self, i: usize) -> [f64; 2] {
        self.normals[i]
    }

    /// Height of the ceiling, metres.
    pub fn ceiling(&self) -> f64 {
        self.ceiling
    }

    /// The vertices and index pairs of every face reaching below `height`: what a body that
    /// tall collides with.
    pub fn obstacles_below(&self, height: f64) -> (Vec<Vector>, Vec<[u32; 2]>) {
        let mut vertices = Vec::new();
        let mut indices = Vec::new();
        for f in self.faces.iter().filter(|f| f.z[0] < height) {
            let i = vertices.len() as u32;
            vertices.push(vector(f.a));
            vertices.push(vector(f.b));
            indices.push([i, i + 1]);
        }
        (vertices, indices)
    }

    /// The first surface along the ray from `origin` in the unit direction `dir`, within `max`
    /// metres, found by walking the plan's grid from the origin.
    ///
    /// Of faces met at the same distance, the one listed first wins, so this, the tree's answer
    /// ([`WorldMap::cast_down_tree`]) and [`WorldMap::cast_fan`]'s are the same to the last bit.
    pub fn cast(&self, origin: [f64; 3], dir: [f64; 3], max: f64) -> Option<Hit> {
        self.fan_hit(origin, dir, max, self.cast_faces(origin, dir, max))
    }

    /// [`WorldMap::cast`] down the world's tree of faces' boxes: the reference the walk and the
    /// sweep are tested and benchmarked against.
    pub fn cast_down_tree(&self, origin: [f64; 3], dir: [f64; 3], max: f64) -> Option<Hit> {
        self.fan_hit(origin, dir, max, self.nearest_down_tree(origin, dir, max))
    }

    /// [`WorldMap::cast_down_tree`]'s nearest vertical face and its distance (`u32::MAX` for
    /// none), from which it builds its hit.
    pub fn nearest_down_tree(&self, origin: [f64; 3], dir: [f64; 3], max: f64) -> (f64, u32) {
        self.cast_faces_from(origin, dir, max, None)
    }

    /// [`WorldMap::cast`] told the face the ray is likely to meet first (`hint`: the face a
    /// neighbouring ray met, as a scan's beams reflected by one mirror meet the same wall one
    /// after another): the same answer; the walk then stops by the hinted crossing at the
    /// latest.
    pub fn cast_near(
        &self,
        origin: [f64; 3],
        dir: [f64; 3],
        max: f64,
        hint: Option<usize>,
    ) -> Option<Hit> {
        self.fan_hit(origin, dir, max, self.nearest_near(origin, dir, max, hint))
    }

    /// [`WorldMap::cast_near`]'s nearest vertical face and its distance (`u32::MAX` for
    /// none), small enough to come back from a call in registers: a caller building the hit
    /// itself does not read it back through memory before the call's stores have landed.
    pub fn nearest_near(
        &self,
        origin: [f64; 3],
        dir: [f64; 3],
        max: f64,
        hint: Option<usize>,
    ) -> (f64, u32) {
        let start = hint
            .filter(|&i| i < self.faces.len() && !is_vertical(dir))
            .and_then(|i| Some((self.face_crossing(i, origin, dir, max)?, i as u32)));
        self.walk_faces(origin, dir, max, start)
    }

    /// The nearest vertical face along the ray within `max` metres and its distance, or
    /// `u32::MAX` for none, by walking the plan's grid (down the tree in a world without one).
    #[inline]
    pub(super) fn cast_faces(&self, origin: [f64; 3], dir: [f64; 3], max: f64) -> (f64, u32) {
        self.walk_faces(origin, dir, max, None)
    }

    /// [`WorldMap::cast_faces`] from a face the ray is known to cross, and where (`start`).
    #[inline]
    fn walk_faces(
        &self,
        origin: [f64; 3],
        dir: [f64; 3],
        max: f64,
        start: Option<(f64, u32)>,
    ) -> (f64, u32) {
        match &self.walk {
            Some(walk) if !is_vertical(dir) => {
                walk.cast(origin, dir, max, start.unwrap_or(NO_FACE), |i| {
                    self.face_crossing(i, origin, dir, max)
                })
            }
            _ => self.cast_faces_from(origin, dir, max, start),
        }
    }

    /// The nearest vertical face along the ray down the tree, from a face the ray is known to
    /// cross, and where (`start`), so only nearer boxes are searched. Ties keep the face listed
    /// first, as without it.
    fn cast_faces_from(
        &self,
        origin: [f64; 3],
        dir: [f64; 3],
        max: f64,
        start: Option<(f64, u32)>,
    ) -> (f64, u32) {
        if !is_vertical(dir) {
            // In the plan the ray runs along `dir`'s horizontal part, so a crossing's parameter
            // is the distance along the ray in 3D, with no normalising.
            let slab = Slab::new([origin[0], origin[1]], [dir[0], dir[1]]);
            // The traversal prunes with `f32` costs, a box whose entry is not below the bound;
            // the nearest face is kept here in `f64`, and each bound handed back is rounded up
            // past it, so no box that may hold it or an equally near face is pruned (a ray from
            // a face's end meets it, and maybe a face listed before it, at 0).
            let nearest = core::cell::Cell::new(start.unwrap_or(NO_FACE));
            let bound = start.map_or(max, |(t, _)| t);
            self.tree.find_best(
                round_up(bound).next_up(),
                |node, best| slab.entry(node.mins(), node.maxs(), best),
                |leaf, _| {
                    let t = self.face_crossing(leaf as usize, origin, dir, max)?;
                    let (t_best, leaf_best) = nearest.get();
                    if t < t_best || (t == t_best && leaf < leaf_best) {
                        nearest.set((t, leaf));
                    }
                    Some(round_up(nearest.get().0).next_up())
                },
            );
            nearest.get()
        } else {
            NO_FACE
        }
    }

    /// How far along the ray from `origin` in the unit direction `dir` it crosses face `i`
    /// between the face's bottom and top, within `max` metres.
    #[inline]
    pub(super) fn face_crossing(
        &self,
        i: usize,
        origin: [f64; 3],
        dir: [f64; 3],
        max: f64,
    ) -> Option<f64> {
        let face = &self.faces[i];
        let t = ray_segment([origin[0], origin[1]], [dir[0], dir[1]], face.a, face.b)?;
        let z = origin[2] + dir[2] * t;
        (t <= max && z >= face.z[0] - Z_EPS && z <= face.z[1] + Z_EPS).then_some(t)
    }

    /// The hit on face `i`, `t` metres along `dir`.
    #[inline]
    pub(crate) fn face_hit(&self, i: usize, t: f64, dir: [f64; 3]) -> Hit {
        let [nx, ny] = self.normals[i];
        let mut normal = [nx, ny, 0.0];
        if normal[0] * dir[0] + normal[1] * dir[1] > 0.0 {
            normal = [-normal[0], -normal[1], 0.0];
        }
        Hit {
            distance: t,
            surface: Surface::Face(i),
            material: self.faces[i].material,
            normal,
        }
    }

    /// Replaces `best` by the floor, the ceiling or a cap when a rising or falling ray meets
    /// one nearer.
    pub(super) fn cast_planes(
        &self,
        origin: [f64; 3],
        dir: [f64; 3],
        max: f64,
        best: &mut Option<Hit>,
    ) {
        if dir[2] == 0.0 {
            return;
        }
        let normal = [0.0, 0.0, if dir[2] < 0.0 { 1.0 } else { -1.0 }];
        let (plane, height) = if dir[2] < 0.0 {
            (Surface::Floor, 0.0)
        } else {
            (Surface::Ceiling, self.ceiling)
        };
        let nearer = |t: f64, surface: Surface, material: Material, best: &mut Option<Hit>| {
            if t > 0.0 && best.is_none_or(|b| t < b.distance) && t < max {
                *best = Some(Hit {
                    distance: t,
                    surface,
                    material,
                    normal,
                });
            }
        };
        nearer((height - origin[2]) / dir[2], plane, Material::Matte, best);
        for (i, cap) in self.caps.iter().enumerate() {
            let t = (cap.z - origin[2]) / dir[2];
            if t > 0.0 && best.is_none_or(|b| t < b.distance) {
                let p = [origin[0] + dir[0] * t, origin[1] + dir[1] * t];
                if inside(&cap.polygon, p) {
                    nearer(t, Surface::Cap(i), cap.material, best);
                }
            }
        }
    }

    /// The first surface along a horizontal ray at height `z`.
    pub fn cast_level(&self, origin: [f64; 2], z: f64, dir: [f64; 2], max: f64) -> Option<Hit> {
        self.cast([origin[0], origin[1], z], [dir[0], dir[1], 0.0], max)
    }

    /// Distance from `point` to the nearest face in the plane (heights ignored), metres; infinite
    /// for an empty world. Through the plan's grid, as every per-point question: a path of
    /// thousands of samples in a world of thousands of faces costs what the nearby faces do.
    pub fn clearance(&self, point: [f64; 2]) -> f64 {
        self.index.nearest_face_in_plan(point, &self.faces).0
    }

    /// Distance from `p` to the nearest surface in 3D — faces, caps, floor and ceiling.
    pub fn distance_3d(&self, p: [f64; 3]) -> f64 {
        self.nearest_surface(p).0
    }

    /// Whether a surface lies at most `r` metres from `p` in 3D: `distance_3d(p) <= r`, to the
    /// last bit, answered from `p`'s cell of the plan's grid when `r` is small.
    pub fn within_3d(&self, p: [f64; 3], r: f64) -> bool {
        self.index
            .within(p, r, &self.faces, &self.caps, self.ceiling, &mut None)
    }

    /// The surface nearest to `p` in 3D and its distance, through the plan's grid.
    pub fn nearest_surface(&self, p: [f64; 3]) -> (f64, SurfaceId) {
        self.index.nearest(p, &self.faces, &self.caps, self.ceiling)
    }

    /// The horizontal faces (tops and bottoms of boxes and tables).
    pub fn caps(&self) -> &[Cap] {
        &self.caps
    }
}

/// Whether `dir` is (too near) vertical to cross a vertical face.
#[inline]
pub(super) fn is_vertical(dir: [f64; 3]) -> bool {
    dir[0] * dir[0] + dir[1] * dir[1] <= 1e-24
}

/// The smallest `f32` not below `x`.
#[inline]
fn round_up(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) < x { f.next_up() } else { f }
}

/// A ray in the plane prepared for slab tests against bounding boxes.
struct Slab {
    origin: [f32; 2],
    inv_dir: [f32; 2],
}

impl Slab {
    fn new(origin: [f64; 2], dir: [f64; 2]) -> Self {
        // In f64 first: a steep ray's horizontal part may be tiny.
        let inv = |d: f64| {
            if d.abs() < 1e-30 {
                1e30f32.copysign(d as f32)
            } else {
                d.recip() as f32
            }
        };
        Slab {
            origin: [origin[0] as f32, origin[1] as f32],
            inv_dir: [inv(dir[0]), inv(dir[1])],
        }
    }

    /// Where the ray enters the box (0 when it starts inside), or `f32::MAX` when it misses it
    /// or enters it beyond `max`.
    #[inline]
    fn entry(&self, mins: Vector, maxs: Vector, max: f32) -> f32 {
        let (t1x, t2x) = (
            (mins.x - self.origin[0]) * self.inv_dir[0],
            (maxs.x - self.origin[0]) * self.inv_dir[0],
        );
        let (t1y, t2y) = (
            (mins.y - self.origin[1]) * self.inv_dir[1],
            (maxs.y - self.origin[1]) * self.inv_dir[1],
        );
        let near = t1x.min(t2x).max(t1y.min(t2y)).max(0.0);
        let far = t1x.max(t2x).min(t1y.max(t2y));
        if near <= far && near <= max {
            near
        } else {
            f32::MAX
        }
    }
}

/// Where the ray `o + t d` crosses the segment `a`–`b`, as the parameter `t`, or `None` when it
/// misses it or runs parallel to it. One division, for a crossing only.
#[inline]
pub(super) fn ray_segment(o: [f64; 2], d: [f64; 2], a: [f64; 2], b: [f64; 2]) -> Option<f64> {
    let e = [b[0] - a[0], b[1] - a[1]];
    let denom = d[0] * e[1] - d[1] * e[0];
    if denom.abs() <= 1e-15 * (d[0].abs() + d[1].abs()) {
        return None;
    }
    let w = [a[0] - o[0], a[1] - o[1]];
    let (mut nt, mut nu) = (w[0] * e[1] - w[1] * e[0], w[0] * d[1] - w[1] * d[0]);
    let den = denom.abs();
    if denom < 0.0 {
        (nt, nu) = (-nt, -nu);
    }
    // t = nt / den ≥ 0 and the crossing's place on the segment, nu / den, in [0, 1].
    (nt >= 0.0 && nu >= 0.0 && nu <= den).then(|| nt / den)
}

fn vector(p: [f64; 2]) -> Vector {
    Vector::new(p[0] as f32, p[1] as f32)
}

/// Whether `p` lies inside the polygon (crossing number).
fn inside(polygon: &[[f64; 2]], p: [f64; 2]) -> bool {
    let mut crossings = false;
    let n = polygon.len();
    for i in 0..n {
        let (a, b) = (polygon[i], polygon[(i + 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
            if p[0] < x {
                crossings = !crossings;
            }
        }
    }
    crossings
}

/// Distance from `p` to the polygon's boundary.
fn polygon_distance(polygon: &[[f64; 2]], p: [f64; 2]) -> f64 {
    let n = polygon.len();
    (0..n)
        .map(|i| point_segment_distance(p, polygon[i], polygon[(i + 1) % n]))
        .fold(f64::INFINITY, f64::min)
}

/// Distance from `p` to the segment `a`–`b`.
pub fn point_segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    point_segment_distance2(p, a, b).sqrt()
}

/// Squared distance from `p` to the segment `a`–`b`.
#[inline]
pub fn point_segment_distance2(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let ab = [b[0] - a[0], b[1] - a[1]];
    let ap = [p[0] - a[0], p[1] - a[1]];
    let len2 = ab[0] * ab[0] + ab[1] * ab[1];
    let t = if len2 > 0.0 {
        ((ap[0] * ab[0] + ap[1] * ab[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (dx, dy) = (ap[0] - t * ab[0], ap[1] - t * ab[1]);
    dx * dx + dy * dy
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> WorldMap {
        let text = r#"
name = "square"
ceiling_m = 3.0
[start]
x = 0
y = 0
[[wall]]
points = [[-2, -1], [3, -1], [3, 4], [-2, 4]]
closed = true
[[wall]]
material = "glass"
points = [[1, 0.5], [1, 1.5]]
[[box]]
center = [-1, 2]
size = [0.4, 0.4]
z = [0.0, 0.5]
[[table]]
center = [1.5, -0.5]
size = [1.0, 0.6]
"#;
        WorldMap::new(&WorldDescription::parse(text, "square.toml").unwrap())
    }

    #[test]
    fn level_rays_meet_walls_at_analytic_distances() {
        let map = square();
        let hit = map.cast_level([0.0, 0.0], 1.0, [1.0, 0.0], 32.0).unwrap();
        assert!((hit.distance - 3.0).abs() < 1e-5, "{hit:?}");
        assert_eq!(hit.normal, [-1.0, 0.0, 0.0]);
        let s = 0.5f64.sqrt();
        let hit = map.cast_level([0.0, 0.0], 1.0, [-s, -s], 32.0).unwrap();
        assert!((hit.distance - 2f64.sqrt()).abs() < 1e-5, "{hit:?}");
        let glass = map.cast_level([0.0, 1.0], 1.0, [1.0, 0.0], 32.0).unwrap();
        assert_eq!(glass.material, Material::Glass);
        assert!((glass.distance - 1.0).abs() < 1e-6);
    }

    #[test]
    fn a_low_box_is_passed_over_and_hit_below_its_top() {
        let map = square();
        // Towards the box at (-1, 2): above it at 1 m the ray meets the far wall.
        let d = [-1.0 / 5f64.sqrt(), 2.0 / 5f64.sqrt()];
        let over = map.cast_level([0.0, 0.0], 1.0, d, 32.0).unwrap();
        assert!(
            matches!(over.surface, Surface::Face(_)) && over.distance > 3.0,
            "{over:?}"
        );
        let low = map.cast_level([0.0, 0.0], 0.3, d, 32.0).unwrap();
        assert!(
            (low.distance - (5f64.sqrt() - 0.2 * 5f64.sqrt() / 2.0)).abs() < 0.05,
            "{low:?}"
        );
    }

    #[test]
    fn tilted_rays_meet_floor_ceiling_and_table_tops() {
        let map = square();
        // From 1 m up, 30° down towards +y: the floor at 1 / sin 30° = 2 m.
        let (s, c) = 30f64.to_radians().sin_cos();
        let floor = map.cast([0.0, 0.0, 1.0], [0.0, c, -s], 32.0).unwrap();
        assert_eq!(floor.surface, Surface::Floor);
        assert!((floor.distance - 2.0).abs() < 1e-12);
        assert_eq!(floor.normal, [0.0, 0.0, 1.0]);
        let up = map.cast([0.0, 0.0, 1.0], [0.0, c, s], 32.0).unwrap();
        assert_eq!(up.surface, Surface::Ceiling);
        assert!((up.distance - 4.0).abs() < 1e-12);
        // Straight down over the table at (1.5, -0.5): its top at 0.75 m.
        let top = map.cast([1.5, -0.5, 1.5], [0.0, 0.0, -1.0], 32.0).unwrap();
        assert_eq!(top.surface, Surface::Cap(top_of_table(&map)));
        assert!((top.distance - 0.75).abs() < 1e-12);
        // Level under the table, at 0.3 m, the ray passes between the legs to the wall.
        let under = map.cast_level([1.5, 1.0], 0.3, [0.0, -1.0], 32.0).unwrap();
        assert!((under.distance - 2.0).abs() < 1e-5, "{under:?}");
    }

    fn top_of_table(map: &WorldMap) -> usize {
        map.caps
            .iter()
            .position(|c| (c.z - 0.75).abs() < 1e-12)
            .unwrap()
    }

    #[test]
    fn distances_in_3d_see_floor_and_heights() {
        let map = square();
        assert!((map.distance_3d([0.0, 0.0, 0.2]) - 0.2).abs() < 1e-12);
        // Above the low box: 0.3 m over its top.
        assert!((map.distance_3d([-1.0, 2.0, 0.8]) - 0.3).abs() < 1e-12);
        assert!((map.clearance([0.0, 0.0]) - 1.0).abs() < 1e-12);
    }

    /// Absurd rays — not-a-number or infinite origins and directions, an infinite or negative
    /// range, a direction of almost nothing — end, on the walk and down the tree alike, with
    /// no panic and no NaN in what they answer.
    #[test]
    fn absurd_rays_end_without_a_nan() {
        let map = square();
        let (nan, inf) = (f64::NAN, f64::INFINITY);
        let origins = [
            [1.0, 1.0, 1.0],
            [nan, 1.0, 1.0],
            [inf, -inf, 1.0],
            [1e300, 1.0, 1.0],
        ];
        let dirs = [
            [1.0, 0.0, 0.0],
            [nan, nan, 0.0],
            [inf, 0.0, 0.0],
            [1e-250, 1.0, 0.0],
            [1e-300, -1e-300, 1.0],
        ];
        for origin in origins {
            for dir in dirs {
                for max in [32.0, inf, -1.0, 0.0] {
                    for hit in [
                        map.cast(origin, dir, max),
                        map.cast_down_tree(origin, dir, max),
                        map.cast_near(origin, dir, max, Some(0)),
                    ]
                    .into_iter()
                    .flatten()
                    {
                        assert!(!hit.distance.is_nan(), "{origin:?} {dir:?} {max}: {hit:?}");
                        assert!(hit.normal.iter().all(|v| !v.is_nan()), "{hit:?}");
                    }
                }
            }
        }
        // A sane ray still meets its wall on both paths.
        let (walked, tree) = (
            map.cast([1.0, 1.0, 1.0], [1.0, 0.0, 0.0], 32.0),
            map.cast_down_tree([1.0, 1.0, 1.0], [1.0, 0.0, 0.0], 32.0),
        );
        assert!(walked.is_some() && walked == tree, "{walked:?} {tree:?}");
    }

    #[test]
    fn a_body_collides_only_with_what_reaches_below_its_top() {
        let map = square();
        let (_, tall) = map.obstacles_below(2.0);
        let (_, short) = map.obstacles_below(0.5);
        // The table's top (4 faces at 0.72..0.75 m) blocks a tall body, not a short one.
        assert_eq!(tall.len() - short.len(), 4);
    }
}
