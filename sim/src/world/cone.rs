//! The faces a leg leaving one face can meet, listed once for many legs.
//!
//! A scan's beams share one origin, so the legs a flat mirror reflects all leave as if from one
//! point, the origin's image behind the mirror, and the legs a pane lets through go on from the
//! origin itself: each lies in the cone from that point (the apex) through the face, beyond the
//! face. The faces passing near that part of the cone are listed once, and each leg tries only
//! those instead of walking the plan's grid — the same answer to the last bit, for each face is
//! tried with the same crossing test and equally near faces still go to the one listed first.
//!
//! A leg starts a little in front of the face it leaves (the laser's nudge, 10 µm) and its
//! direction and start carry the rounding of the reflection: it runs within about 10 µm of the
//! cone. A face is left out only when a line keeps it [`MARGIN`] away from the whole cone part,
//! ten times that.

use super::Hit;
use super::map::{NO_FACE, WorldMap, is_vertical, point_segment_distance};

/// How far a face must be from the cone's part beyond the face the legs leave to be left out,
/// metres.
const MARGIN: f64 = 1e-4;

/// Listing a cone's faces tries every face of the world once; past this many faces the walk
/// of the plan's grid is cheaper for the few legs a cone serves.
const MAX_FACES: usize = 400;

impl WorldMap {
    /// The faces passing within `MARGIN` of the part of the cone from `apex` through face
    /// `m` that lies beyond face `m`, added to `out` nearest the apex first. `false` (and
    /// nothing added) when there is no such cone: the apex on the face's line, or the face a
    /// point; or when the world has too many faces for a list to pay (`MAX_FACES`).
    pub fn faces_beyond(&self, apex: [f64; 2], m: usize, out: &mut Vec<Beyond>) -> bool {
        if self.faces().len() > MAX_FACES {
            return false;
        }
        let face = &self.faces()[m];
        let sub = |p: [f64; 2], q: [f64; 2]| [p[0] - q[0], p[1] - q[1]];
        let cross = |p: [f64; 2], q: [f64; 2]| p[0] * q[1] - p[1] * q[0];
        let norm = |p: [f64; 2]| (p[0] * p[0] + p[1] * p[1]).sqrt();
        let (mut a, mut b) = (face.a, face.b);
        let (mut u, mut v) = (sub(a, apex), sub(b, apex));
        let turn = cross(u, v);
        let (lu, lv, lm) = (norm(u), norm(v), norm(sub(b, a)));
        let cone = turn.abs() > 1e-9 * lu * lv && lm > 0.0;
        if !cone {
            return false;
        }
        if turn < 0.0 {
            (a, b, u, v) = (b, a, v, u);
        }
        // The cone part is where all three are at most zero, each a distance in metres
        // (`n · (p - at)`, `n` a unit normal): left of the ray from the apex through `a`,
        // right of the one through `b`, and past the face's line from the apex.
        let ab = sub(b, a);
        let apex_side = cross(ab, sub(apex, a)).signum();
        let sides: [([f64; 2], [f64; 2]); 3] = [
            ([u[1] / lu, -u[0] / lu], apex),
            ([-v[1] / lv, v[0] / lv], apex),
            ([-apex_side * ab[1] / lm, apex_side * ab[0] / lm], a),
        ];
        let beyond = |(n, at): ([f64; 2], [f64; 2]), p: [f64; 2]| {
            n[0] * (p[0] - at[0]) + n[1] * (p[1] - at[1]) > MARGIN
        };
        let first = out.len();
        for (i, other) in self.faces().iter().enumerate() {
            let (c, d) = (other.a, other.b);
            // Outside one of the cone part's sides, by the margin, at both ends.
            let outside = sides.iter().any(|&side| beyond(side, c) && beyond(side, d));
            if outside {
                continue;
            }
            // The whole cone part on one side of the face's line, by the margin: both its
            // corners, and its two edges running away from the line, not towards it.
            let cd = sub(d, c);
            let lcd = norm(cd);
            if lcd > 0.0 {
                // Distances times the face's length, against the margin times it.
                let (side, margin) = (|p: [f64; 2]| cross(cd, sub(p, c)), MARGIN * lcd);
                let (sa, sb) = (side(a), side(b));
                let (du, dv) = (cross(cd, u), cross(cd, v));
                let left = sa > margin && sb > margin && du >= 0.0 && dv >= 0.0;
                let right = sa < -margin && sb < -margin && du <= 0.0 && dv <= 0.0;
                if left || right {
                    continue;
                }
            }
            out.push(Beyond {
                gap: point_segment_distance(apex, c, d),
                face: i as u32,
                ends: [sub(c, apex), sub(d, apex)],
            });
        }
        // A gap is a distance (zero or more), whose bits order as its values.
        out[first..].sort_unstable_by_key(|x| (x.gap.to_bits(), x.face));
        true
    }

    /// The nearest vertical face a ray from `origin` along the unit direction `dir` meets
    /// within `max` metres and its distance (`u32::MAX` for none) — the face
    /// [`WorldMap::cast`] builds its hit from, exactly — when the ray runs within 10 µm of a
    /// ray from `apex` through face `m` and `faces` are what [`WorldMap::faces_beyond`] listed
    /// for `apex` and `m`: a leg that left face `m` (reflected, `apex` the laser's image;
    /// through it, the laser) from just in front of it.
    ///
    /// A face's crossing is at least its gap to the apex less the origin's distance from the
    /// apex away (the triangle inequality), so the faces past the nearest crossing so far are
    /// not tried.
    ///
    /// Inlined into its caller, which builds the hit.
    #[inline(always)]
    pub fn nearest_among(
        &self,
        origin: [f64; 3],
        dir: [f64; 3],
        max: f64,
        apex: [f64; 2],
        faces: &[Beyond],
    ) -> (f64, u32) {
        if is_vertical(dir) {
            return self.cast_faces(origin, dir, max);
        }
        let w = [origin[0] - apex[0], origin[1] - apex[1]];
        let start = (w[0] * w[0] + w[1] * w[1]).sqrt();
        let mut best = NO_FACE;
        for &Beyond {
            gap,
            face: i,
            ends: [c, d],
        } in faces
        {
            // The rounding of the gap and the start is far below this margin.
            if gap - start > best.0 + 1e-9 * (1.0 + gap) {
                break;
            }
            // The ray's line passes within about 10 µm of the apex: both ends of the face on
            // one side of it by more than the margin, seen from the apex, and the ray misses.
            let (sc, sd) = (dir[0] * c[1] - dir[1] * c[0], dir[0] * d[1] - dir[1] * d[0]);
            if (sc > MARGIN && sd > MARGIN) || (sc < -MARGIN && sd < -MARGIN) {
                continue;
            }
            if let Some(t) = self.face_crossing(i as usize, origin, dir, max)
                && (t < best.0 || (t == best.0 && i < best.1))
            {
                best = (t, i);
            }
        }
        best
    }

    /// [`WorldMap::nearest_among`]'s hit: what [`WorldMap::cast`] answers.
    pub fn cast_among(
        &self,
        origin: [f64; 3],
        dir: [f64; 3],
        max: f64,
        apex: [f64; 2],
        faces: &[Beyond],
    ) -> Option<Hit> {
        let nearest = self.nearest_among(origin, dir, max, apex, faces);
        self.fan_hit(origin, dir, max, nearest)
    }
}

/// A face a cone can reach ([`WorldMap::faces_beyond`]) and its distance from the cone's apex,
/// metres.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Beyond {
    /// The distance from the apex to the face in the plan.
    pub gap: f64,
    /// The face's number.
    pub face: u32,
    /// Its ends, from the apex.
    ends: [[f64; 2]; 2],
}
