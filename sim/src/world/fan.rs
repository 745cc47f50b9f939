//! Casting a fan of rays from one point: the 361 beams of a laser scan.
//!
//! The rays share their origin, so instead of one tree descent per ray the faces are swept once:
//! each face is seen from the origin under an angle, and only the rays inside that angle are
//! tried against it, with the same exact crossing test [`WorldMap::cast`] uses. A ray keeps the
//! nearest face it crosses (the first listed of equally near ones, as `cast` does), then meets
//! the floor, the ceiling and the caps the same way, so the answer is `cast`'s for every ray, to
//! the last bit. Angles are compared as *pseudo-angles* (a monotonic stand-in for the angle that
//! needs no trigonometry), padded by about a nanoradian so a ray through a face's end is always
//! tried and the crossing test decides.
//!
//! The sweep touches every face in range once per fan, where a tree descent touches a few per
//! ray: it wins while the faces are fewer than about [`FAN_MAX_FACES`], and larger worlds keep
//! the tree (`cargo bench --bench laser` measures both).

use super::map::{Face, Hit, WorldMap, Z_EPS, is_vertical};

/// Worlds with more faces than this cast each ray down the tree instead.
pub const FAN_MAX_FACES: usize = 400;

/// Padding of a face's angular interval, in pseudo-angle units (a nanoradian or two).
const PAD: f64 = 1e-9;

/// Buckets of a plane fan's index of pseudo-angles: a power of two, so a pseudo-angle's bucket
/// is exact.
const BUCKETS: usize = 1024;

/// The rays' pseudo-angles counter-clockwise from the first, increasing in [0, 4), and for a
/// fan used many times an index of them by bucket, so finding where a pseudo-angle falls costs a
/// look-up instead of a binary search.
#[derive(Clone, Debug)]
struct Turns {
    rel: Vec<f64>,
    /// `buckets[j]`: how many rays lie below `j · 4 / BUCKETS`; empty for no index.
    buckets: Vec<u32>,
}

impl Turns {
    fn indexed(rel: Vec<f64>) -> Self {
        let buckets = (0..=BUCKETS)
            .map(|j| rel.partition_point(|&r| r < (j as f64) * 4.0 / BUCKETS as f64) as u32)
            .collect();
        Turns { rel, buckets }
    }

    /// How many rays lie below `x` (or at it, with `inclusive`).
    #[inline(always)]
    fn count_below(&self, x: f64, inclusive: bool) -> usize {
        let below = |r: &f64| if inclusive { *r <= x } else { *r < x };
        if self.buckets.is_empty() {
            return self.rel.partition_point(below);
        }
        // x · BUCKETS / 4 is exact (a power of two), so is its bucket; the conversion truncates
        // and takes what is below zero to bucket 0.
        let j = ((x * (BUCKETS as f64 / 4.0)) as usize).min(BUCKETS - 1);
        let (lo, hi) = (self.buckets[j] as usize, self.buckets[j + 1] as usize);
        lo + self.rel[lo..hi].partition_point(below)
    }
}

/// The rays' pseudo-angles counter-clockwise from the first, in [0, 4), or `None` when they do
/// not turn counter-clockwise in order (or one is vertical): such fans are cast ray by ray.
fn turns(dirs: &[[f64; 3]]) -> Option<(f64, Vec<f64>)> {
    let first = dirs.first()?;
    if is_vertical(*first) {
        return None;
    }
    let p0 = pseudo_angle([first[0], first[1]]);
    let mut rel = Vec::with_capacity(dirs.len());
    let mut last = 0.0;
    for d in dirs {
        if is_vertical(*d) {
            return None;
        }
        let r = if rel.is_empty() {
            0.0
        } else {
            wrap(pseudo_angle([d[0], d[1]]) - p0)
        };
        if r < last || r > 4.0 - 4.0 * PAD {
            return None;
        }
        last = r;
        rel.push(r);
    }
    Some((p0, rel))
}

/// Rays in one plane from one point at fixed angles, as a laser sweeps them: ray `k` points along
/// `cos a_k · forward + sin a_k · left` for the plane's axes, the angles increasing. What the
/// sweep needs of the angles is computed once, not per scan.
#[derive(Clone, Debug)]
pub struct PlaneFan {
    /// Sine and cosine of each ray's angle, by column.
    sines: Vec<f64>,
    cosines: Vec<f64>,
    /// Pseudo-angle of each ray counter-clockwise from the first in the plane, indexed, or
    /// `None` when the angles do not increase within a turn.
    turns: Option<Turns>,
}

impl PlaneFan {
    /// The fan of rays at `angles` (radians, counter-clockwise from the forward axis).
    pub fn new(angles: impl IntoIterator<Item = f64>) -> Self {
        let trig: Vec<(f64, f64)> = angles.into_iter().map(f64::sin_cos).collect();
        let pseudo: Vec<f64> = trig.iter().map(|&(s, c)| pseudo_angle([c, s])).collect();
        let turns = pseudo.first().and_then(|&p0| {
            let rel: Vec<f64> = pseudo
                .iter()
                .enumerate()
                .map(|(k, &p)| if k == 0 { 0.0 } else { wrap(p - p0) })
                .collect();
            let ordered =
                rel.windows(2).all(|w| w[0] <= w[1]) && rel.last() < Some(&(4.0 - 4.0 * PAD));
            ordered.then(|| Turns::indexed(rel))
        });
        PlaneFan {
            sines: trig.iter().map(|t| t.0).collect(),
            cosines: trig.iter().map(|t| t.1).collect(),
            turns,
        }
    }

    /// Number of rays.
    pub fn len(&self) -> usize {
        self.sines.len()
    }

    /// Whether the fan has no ray.
    pub fn is_empty(&self) -> bool {
        self.sines.is_empty()
    }

    /// Ray `k`'s direction for the plane's unit axes `forward` and `left`.
    #[inline]
    pub fn direction(&self, k: usize, forward: [f64; 3], left: [f64; 3]) -> [f64; 3] {
        let (sa, ca) = (self.sines[k], self.cosines[k]);
        [0, 1, 2].map(|i| ca * forward[i] + sa * left[i])
    }

    /// Every ray's direction, first ray first.
    pub fn directions(&self, forward: [f64; 3], left: [f64; 3]) -> Vec<[f64; 3]> {
        (0..self.len())
            .map(|k| self.direction(k, forward, left))
            .collect()
    }
}

impl WorldMap {
    /// The first surface along each ray from `origin` in the unit directions `dirs`, within
    /// `max` metres, into `hits` (cleared first): exactly what [`WorldMap::cast`] answers for
    /// each ray, in one sweep of the faces when the rays turn counter-clockwise in order.
    pub fn cast_fan(
        &self,
        origin: [f64; 3],
        dirs: &[[f64; 3]],
        max: f64,
        hits: &mut Vec<Option<Hit>>,
    ) {
        hits.clear();
        let prepared = if self.sweeps_fans() {
            turns(dirs)
        } else {
            None
        };
        let Some((p0, rel)) = prepared else {
            hits.extend(dirs.iter().map(|&d| self.cast(origin, d, max)));
            return;
        };
        let rays = Rays::new(dirs);
        let turns = Turns {
            rel,
            buckets: Vec::new(),
        };
        let mut nearest = Nearest::default();
        let level = rays.z.iter().all(|&z| z == 0.0);
        self.sweep(
            origin,
            (&rays, level),
            &turns,
            |v| wrap(pseudo_angle(v) - p0),
            max,
            &mut nearest,
        );
        hits.extend(
            dirs.iter()
                .enumerate()
                .map(|(k, &dir)| self.fan_hit(origin, dir, max, nearest.get(k))),
        );
    }

    /// The hit of a ray whose nearest face the sweep found (`(distance, face)`, face `u32::MAX`
    /// for none): that face, or the floor, ceiling or a cap when nearer.
    #[inline]
    pub(crate) fn fan_hit(
        &self,
        origin: [f64; 3],
        dir: [f64; 3],
        max: f64,
        (t, i): (f64, u32),
    ) -> Option<Hit> {
        let best = (i != u32::MAX).then(|| self.face_hit(i as usize, t, dir));
        if dir[2] == 0.0 {
            return best; // a level ray meets no floor, ceiling or cap
        }
        let mut best = best;
        self.cast_planes(origin, dir, max, &mut best);
        best
    }

    /// [`WorldMap::cast_fan`] for the rays of `fan` in the plane of the unit axes `forward` and
    /// `left` (`left` horizontal, as a laser's scan plane tilts about it), into `out`: each
    /// ray's direction and what it meets ([`FanCast::hit`]).
    #[inline(always)]
    pub fn cast_plane_fan(
        &self,
        origin: [f64; 3],
        (forward, left): ([f64; 3], [f64; 3]),
        fan: &PlaneFan,
        max: f64,
        out: &mut FanCast,
    ) {
        out.origin = origin;
        out.max = max;
        out.rays.fill_plane(fan, forward, left);
        // A plan vector v lies under ray k when (v·F, |F|² v·L) points at angle a_k, F being the
        // forward axis's horizontal part: true when L is horizontal and square to F.
        let f = [forward[0], forward[1]];
        let f2 = f[0] * f[0] + f[1] * f[1];
        let square = (f[0] * left[0] + f[1] * left[1]).abs() <= 1e-12 && left[2] == 0.0;
        let (Some(turns), true, true) = (&fan.turns, square && f2 > 1e-12, self.sweeps_fans())
        else {
            out.nearest.reset(0);
            for k in 0..out.len() {
                let (t, i) = self.cast_faces(origin, out.dir(k), max);
                out.nearest.t.push(t);
                out.nearest.face.push(i);
            }
            return;
        };
        let p0 = pseudo_angle([fan.cosines[0], fan.sines[0]]);
        let in_plane = |v: [f64; 2]| {
            let q = [
                v[0] * f[0] + v[1] * f[1],
                f2 * (v[0] * left[0] + v[1] * left[1]),
            ];
            wrap(pseudo_angle(q) - p0)
        };
        // Both axes horizontal: every ray's vertical component is ±0.
        let level = forward[2] == 0.0 && left[2] == 0.0;
        self.sweep(
            origin,
            (&out.rays, level),
            turns,
            in_plane,
            max,
            &mut out.nearest,
        );
    }

    /// The sweep: each face in reach tried against the rays whose pseudo-angle `rel` (from the
    /// first ray, increasing) is within the face's, `angle_of` giving a plan vector's.
    ///
    /// Faces are taken near to far (by bands of the gap between the origin and the face's box
    /// in the plan, which no crossing of the face is nearer than), and of a face's rays only
    /// those from the first to the last that have not met a face nearer than that gap are tried:
    /// behind the first walls most faces are hidden whole. Ties go to the face listed first
    /// whatever the order, so the order changes the work, never the answer.
    ///
    /// `level` says every ray's vertical component is zero (`false` is always safe): faces
    /// the origin's height misses are then skipped, and the others tried without a height.
    #[inline(always)]
    fn sweep(
        &self,
        origin: [f64; 3],
        (rays, level): (&Rays, bool),
        turns: &Turns,
        angle_of: impl Fn([f64; 2]) -> f64,
        max: f64,
        nearest: &mut Nearest,
    ) {
        let n = turns.rel.len();
        nearest.reset(n);
        let mut order = core::mem::take(&mut nearest.order);
        order.clear();
        for (i, face) in self.faces().iter().enumerate() {
            if level && !(origin[2] >= face.z[0] - Z_EPS && origin[2] <= face.z[1] + Z_EPS) {
                continue; // a level fan passes over or under this face
            }
            let gap = |lo: f64, hi: f64, o: f64| (lo - o).max(o - hi).max(0.0);
            let gx = gap(
                face.a[0].min(face.b[0]),
                face.a[0].max(face.b[0]),
                origin[0],
            );
            let gy = gap(
                face.a[1].min(face.b[1]),
                face.a[1].max(face.b[1]),
                origin[1],
            );
            let gap2 = gx * gx + gy * gy;
            if gap2 > max * max {
                continue; // out of reach
            }
            let band = ((gap2.sqrt() * (1.0 / BAND)) as usize).min(BANDS - 1) as u32;
            order.push(InReach {
                gap2,
                face: i as u32,
                band,
            });
        }
        nearest.by_gap(&mut order);
        for &InReach { gap2, face: i, .. } in &order {
            let face = &self.faces()[i as usize];
            // A ray that met a face nearer than this one's gap (with a margin far above the
            // rounding of either) cannot meet this one first, nor as near.
            let hidden = gap2 * (1.0 - 1e-9) - 1e-18;
            let a = [face.a[0] - origin[0], face.a[1] - origin[1]];
            let b = [face.b[0] - origin[0], face.b[1] - origin[1]];
            let cross = a[0] * b[1] - a[1] * b[0];
            let scale = a[0] * a[0] + a[1] * a[1] + b[0] * b[0] + b[1] * b[1];
            // The rays the face's angle holds: one run, or two when it holds the first ray's
            // direction.
            let runs = if cross.abs() <= 1e-12 * scale {
                // The origin is on the face's line (or an end): any ray may cross it.
                [0..n, 0..0]
            } else {
                // Counter-clockwise from `lo` to `hi` is the face's side of the origin.
                let (lo, hi) = if cross > 0.0 {
                    (angle_of(a), angle_of(b))
                } else {
                    (angle_of(b), angle_of(a))
                };
                let start = wrap(lo - PAD);
                let end = start + wrap(hi - lo) + 2.0 * PAD;
                let from = turns.count_below(start, false);
                let to = turns.count_below(end, true);
                let wrapped = if end > 4.0 {
                    0..turns.count_below(end - 4.0, true).min(from)
                } else {
                    0..0
                };
                [from..to, wrapped]
            };
            for run in runs {
                if level {
                    rays.cross::<true>(face, i, origin, max, run, hidden, nearest);
                } else {
                    rays.cross::<false>(face, i, origin, max, run, hidden, nearest);
                }
            }
        }
        nearest.order = order;
    }
}

/// Each ray's nearest face and its distance (`u32::MAX` and infinity: none), by column, and the
/// faces' order for the sweep, kept from one fan to the next.
#[derive(Clone, Debug, Default)]
struct Nearest {
    t: Vec<f64>,
    face: Vec<u32>,
    /// The largest distance in each block of [`BLOCK`] rays: a face whose gap lies beyond it
    /// skips the block whole.
    block_max: Vec<f64>,
    order: Vec<InReach>,
    /// The order's buffers: faces by band of gap, and how many fall in each band.
    sorted: Vec<InReach>,
    bands: Vec<u32>,
}

/// A face within the fan's reach: its number, the square of its gap to the origin in the plan,
/// and the band of that gap.
#[derive(Copy, Clone, Debug, Default)]
struct InReach {
    gap2: f64,
    face: u32,
    band: u32,
}

/// Rays in a block of [`Nearest::block_max`].
const BLOCK: usize = 8;

/// Width of the bands of gap the faces are ordered by, metres, and their number (the last holds
/// every face farther).
const BAND: f64 = 0.5;
const BANDS: usize = 64;

impl Nearest {
    /// `order` near to far by bands of [`BAND`] metres, in one counting pass: the sweep needs
    /// the near faces first, not an exact order.
    #[inline]
    fn by_gap(&mut self, order: &mut Vec<InReach>) {
        self.bands.clear();
        self.bands.resize(BANDS + 1, 0);
        for f in order.iter() {
            self.bands[f.band as usize + 1] += 1;
        }
        for b in 1..=BANDS {
            self.bands[b] += self.bands[b - 1];
        }
        self.sorted.clear();
        self.sorted.resize(order.len(), InReach::default());
        for &f in order.iter() {
            let slot = &mut self.bands[f.band as usize];
            self.sorted[*slot as usize] = f;
            *slot += 1;
        }
        core::mem::swap(order, &mut self.sorted);
    }

    /// `n` rays that met nothing yet.
    #[inline]
    fn reset(&mut self, n: usize) {
        self.t.clear();
        self.t.resize(n, f64::INFINITY);
        self.face.clear();
        self.face.resize(n, u32::MAX);
        self.block_max.clear();
        self.block_max.resize(n.div_ceil(BLOCK), f64::INFINITY);
    }

    /// The first and the last ray of `range` still open to a face whose squared gap is
    /// `hidden` (`t · t >= hidden`: not having met a face nearer), `None` for none: the blocks
    /// whose largest distance is not open are passed over whole (`t <= m` gives
    /// `t · t <= m · m`, rounding being monotonic).
    #[inline(always)]
    fn open_span(&self, range: core::ops::Range<usize>, hidden: f64) -> Option<(usize, usize)> {
        let open = |t: &f64| t * t >= hidden;
        let mut k = range.start;
        let first = loop {
            if k >= range.end {
                return None;
            }
            let stop = ((k / BLOCK + 1) * BLOCK).min(range.end);
            if open(&self.block_max[k / BLOCK])
                && let Some(p) = self.t[k..stop].iter().position(open)
            {
                break k + p;
            }
            k = stop;
        };
        // Ray `first` is open, so this finds one before passing it.
        let mut k = range.end;
        loop {
            let begin = ((k - 1) / BLOCK * BLOCK).max(first);
            if open(&self.block_max[(k - 1) / BLOCK])
                && let Some(p) = self.t[begin..k].iter().rposition(open)
            {
                return Some((first, begin + p));
            }
            k = begin;
        }
    }

    /// Brings the blocks holding the rays of `range` up to date after their distances fell.
    #[inline(always)]
    fn refresh_blocks(&mut self, range: core::ops::Range<usize>) {
        let n = self.t.len();
        for b in range.start / BLOCK..=(range.end - 1) / BLOCK {
            let rays = &self.t[b * BLOCK..((b + 1) * BLOCK).min(n)];
            self.block_max[b] = rays.iter().fold(0.0, |m: f64, &t| m.max(t));
        }
    }

    /// Ray `k`'s nearest face: its distance and number.
    #[inline]
    fn get(&self, k: usize) -> (f64, u32) {
        (self.t[k], self.face[k])
    }
}

/// A fan cast by [`WorldMap::cast_plane_fan`], kept to be read ray by ray (and its buffers
/// reused from one scan to the next).
#[derive(Clone, Debug, Default)]
pub struct FanCast {
    origin: [f64; 3],
    max: f64,
    /// Each ray's nearest face and its distance.
    nearest: Nearest,
    /// The rays' directions by component.
    rays: Rays,
}

impl FanCast {
    /// Number of rays.
    pub fn len(&self) -> usize {
        self.rays.x.len()
    }

    /// Whether the fan has no ray.
    pub fn is_empty(&self) -> bool {
        self.rays.x.is_empty()
    }

    /// The rays' directions, first ray first.
    pub fn dirs(&self) -> Vec<[f64; 3]> {
        (0..self.len()).map(|k| self.dir(k)).collect()
    }

    /// Where the rays start.
    pub fn origin(&self) -> [f64; 3] {
        self.origin
    }

    /// Ray `k`'s direction, read from the columns the sweep keeps (a copy of a three-element
    /// row through memory can cost more than the arithmetic on it).
    #[inline]
    pub fn dir(&self, k: usize) -> [f64; 3] {
        [self.rays.x[k], self.rays.y[k], self.rays.z[k]]
    }

    /// What ray `k` meets first: exactly [`WorldMap::cast`]'s answer.
    #[inline]
    pub fn hit(&self, map: &WorldMap, k: usize) -> Option<Hit> {
        map.fan_hit(self.origin, self.dir(k), self.max, self.nearest.get(k))
    }

    /// The rays by column, for a tight loop over them: their directions' components and the
    /// nearest face each meets, its distance and number (`u32::MAX`: none). For a level ray
    /// (no vertical component) that face is what [`FanCast::hit`] answers; a rising or falling
    /// ray may meet the floor, the ceiling or a cap nearer.
    pub fn columns(&self) -> FanColumns<'_> {
        let n = self.len();
        FanColumns {
            x: &self.rays.x[..n],
            y: &self.rays.y[..n],
            z: &self.rays.z[..n],
            t: &self.nearest.t[..n],
            face: &self.nearest.face[..n],
        }
    }
}

/// A fan's rays by column ([`FanCast::columns`]), all of the fan's length.
#[derive(Copy, Clone, Debug)]
pub struct FanColumns<'a> {
    /// The directions' first component.
    pub x: &'a [f64],
    /// Their second.
    pub y: &'a [f64],
    /// Their third, vertical.
    pub z: &'a [f64],
    /// The distance to the nearest face, metres (infinity: none).
    pub t: &'a [f64],
    /// The nearest face's number, `u32::MAX` for none.
    pub face: &'a [u32],
}

/// The rays' directions by component, for a tight loop over many rays.
#[derive(Clone, Debug, Default)]
struct Rays {
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<f64>,
}

impl Rays {
    fn new(dirs: &[[f64; 3]]) -> Self {
        Rays {
            x: dirs.iter().map(|d| d[0]).collect(),
            y: dirs.iter().map(|d| d[1]).collect(),
            z: dirs.iter().map(|d| d[2]).collect(),
        }
    }

    /// The directions of `fan`'s rays for the plane's axes `forward` and `left`, in these
    /// buffers: [`PlaneFan::direction`]'s arithmetic, a column at a time.
    #[inline(always)]
    fn fill_plane(&mut self, fan: &PlaneFan, forward: [f64; 3], left: [f64; 3]) {
        for (k, column) in [&mut self.x, &mut self.y, &mut self.z]
            .into_iter()
            .enumerate()
        {
            let (f, l) = (forward[k], left[k]);
            column.clear();
            column.extend(
                fan.cosines
                    .iter()
                    .zip(&fan.sines)
                    .map(|(&ca, &sa)| ca * f + sa * l),
            );
        }
    }

    /// Tries `face` (number `i`) against the rays of `range` from the first to the last still
    /// open to it (not having met a face nearer than the square root of `hidden`), keeping in
    /// `nearest` each ray's nearest crossing, the face listed first of equally near ones: the
    /// arithmetic of [`WorldMap::face_crossing`] step for step, without branches, so it runs at
    /// the processor's pace whichever rays cross.
    ///
    /// `LEVEL`: the rays have no vertical component and the origin's height lies within the
    /// face's, so every crossing is at that height (`origin[2] + 0 · t`, `t` finite) and the
    /// height is not tested.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn cross<const LEVEL: bool>(
        &self,
        face: &Face,
        i: u32,
        origin: [f64; 3],
        max: f64,
        range: core::ops::Range<usize>,
        hidden: f64,
        nearest: &mut Nearest,
    ) {
        let Some((first, last)) = nearest.open_span(range, hidden) else {
            return;
        };
        let range = first..last + 1;
        let e = [face.b[0] - face.a[0], face.b[1] - face.a[1]];
        let w = [face.a[0] - origin[0], face.a[1] - origin[1]];
        let nt = w[0] * e[1] - w[1] * e[0];
        let (bottom, top) = (face.z[0] - Z_EPS, face.z[1] + Z_EPS);
        let (x, y, z) = (
            &self.x[range.clone()],
            &self.y[range.clone()],
            &self.z[range.clone()],
        );
        let (best_t, best_face) = (
            &mut nearest.t[range.clone()],
            &mut nearest.face[range.clone()],
        );
        let columns = x.iter().zip(y).zip(z).zip(best_t.iter_mut().zip(best_face));
        for (((&dx, &dy), &dz), (best_t, best_face)) in columns {
            let denom = dx * e[1] - dy * e[0];
            let nu = w[0] * dy - w[1] * dx;
            let flip = denom < 0.0;
            let den = denom.abs();
            let (nt, nu) = if flip { (-nt, -nu) } else { (nt, nu) };
            let t = nt / den;
            let within = LEVEL || {
                let height = origin[2] + dz * t;
                (height >= bottom) & (height <= top)
            };
            let crosses = (den > 1e-15 * (dx.abs() + dy.abs()))
                & (nt >= 0.0)
                & (nu >= 0.0)
                & (nu <= den)
                & (t <= max)
                & within;
            let nearer = (t < *best_t) | ((t == *best_t) & (i < *best_face));
            let take = crosses & nearer;
            *best_t = if take { t } else { *best_t };
            *best_face = if take { i } else { *best_face };
        }
        nearest.refresh_blocks(range);
    }
}

/// A monotonic stand-in for the angle of `v` counter-clockwise from +x, in [0, 4): 1 per
/// quarter turn, exact at the axes.
#[inline]
fn pseudo_angle(v: [f64; 2]) -> f64 {
    let p = v[1] / (v[0].abs() + v[1].abs());
    if v[0] < 0.0 {
        2.0 - p
    } else if v[1] < 0.0 {
        4.0 + p
    } else {
        p
    }
}

/// `x` brought into [0, 4) by whole turns (for `x` in [-4, 8)).
#[inline]
fn wrap(x: f64) -> f64 {
    if x < 0.0 {
        x + 4.0
    } else if x >= 4.0 {
        x - 4.0
    } else {
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pseudo_angles_turn_with_the_angle() {
        let turns: Vec<f64> = (0..720)
            .map(|k| {
                let a = f64::from(k) * std::f64::consts::PI / 360.0;
                pseudo_angle([a.cos(), a.sin()])
            })
            .collect();
        assert!(turns.windows(2).all(|w| w[0] < w[1]), "monotonic");
        assert_eq!(turns[0], 0.0);
        assert!((turns[180] - 1.0).abs() < 1e-15 && (turns[360] - 2.0).abs() < 1e-15);
        assert!(turns[719] < 4.0);
    }
}
