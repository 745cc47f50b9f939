//! Casting one ray by walking a grid over the floor plan, cell by cell from its origin.
//!
//! A reflected laser beam or a sonar ray has an origin of its own, so it cannot share a sweep
//! with its neighbours (`fan.rs`); going down the world's tree costs it about 1,600 instructions
//! in the lab, most of them boxes that hold nothing near the ray. Walking the cells the ray
//! passes through, nearest first, tries only the faces it passes by and stops in the cell where
//! its nearest crossing lies: the cost follows how far the ray goes, not how many faces the world
//! has.
//!
//! The answer is the tree's to the last bit: each face is tried with the same crossing test
//! (the map's, handed in), equally near faces go to the one listed first, and a cell lists every
//! face passing within [`PAD`] of it, far more than the rounding of the walk, so no face the ray
//! crosses before the walk stops is missed. The grid knows the faces only as segments in the
//! plan, numbered as the map numbers them.

/// How far outside a cell a face may pass and still be listed in it, metres.
const PAD: f64 = 1e-6;

/// Faces per cell of the plan's area the grid aims at; cells are kept between [`MIN_CELL`] and
/// [`MAX_CELL`] metres, and at most [`MAX_CELLS`] of them.
const FACES_PER_CELL: f64 = 0.25;
const MIN_CELL: f64 = 0.25;
const MAX_CELL: f64 = 2.0;
const MAX_CELLS: f64 = 1.0e6;

/// A grid with fewer than one cell in this many holding faces is not walked: its rays would
/// cross long stretches of empty cells (a map traced from an image, walls and wide margins),
/// where the tree skips the empty space in a few boxes.
const MIN_FILLED: usize = 8;

/// The grid over the faces' plan and the faces passing through each cell.
#[derive(Clone, Debug)]
pub(super) struct WalkGrid {
    /// The corner of cell (0, 0), metres.
    origin: [f64; 2],
    /// The opposite corner of the grid.
    far: [f64; 2],
    cell: f64,
    inv_cell: f64,
    size: [usize; 2],
    /// For cell `j · size[0] + i`, its faces are `items[starts[k]..starts[k + 1]]`, in order.
    starts: Vec<u32>,
    items: Vec<u32>,
}

impl WalkGrid {
    /// The grid of the faces whose plans are the segments `faces`, or `None` for none or for
    /// a grid mostly empty.
    pub(super) fn new(faces: &[[[f64; 2]; 2]]) -> Option<Self> {
        let mut min = [f64::INFINITY; 2];
        let mut max = [f64::NEG_INFINITY; 2];
        for &p in faces.iter().flatten() {
            for k in 0..2 {
                min[k] = min[k].min(p[k]);
                max[k] = max[k].max(p[k]);
            }
        }
        if !min[0].is_finite() {
            return None;
        }
        let span = [max[0] - min[0] + 2.0 * PAD, max[1] - min[1] + 2.0 * PAD];
        let area = span[0] * span[1];
        let cell = (area * FACES_PER_CELL / faces.len() as f64)
            .sqrt()
            .clamp(MIN_CELL, MAX_CELL)
            .max((area / MAX_CELLS).sqrt());
        let origin = [min[0] - PAD, min[1] - PAD];
        let size = [0, 1].map(|k| ((span[k] / cell).ceil() as usize).max(1));
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); size[0] * size[1]];
        for (n, &[a, b]) in faces.iter().enumerate() {
            let range = |k: usize| {
                let lo = ((a[k].min(b[k]) - PAD - origin[k]) / cell).floor().max(0.0) as usize;
                let hi = ((a[k].max(b[k]) + PAD - origin[k]) / cell).floor().max(0.0) as usize;
                lo..=hi.min(size[k] - 1)
            };
            for j in range(1) {
                for i in range(0) {
                    let lo = [
                        origin[0] + i as f64 * cell - PAD,
                        origin[1] + j as f64 * cell - PAD,
                    ];
                    let hi = [lo[0] + cell + 2.0 * PAD, lo[1] + cell + 2.0 * PAD];
                    if segment_meets_box(a, b, lo, hi) {
                        lists[j * size[0] + i].push(n as u32);
                    }
                }
            }
        }
        if lists.iter().filter(|l| !l.is_empty()).count() * MIN_FILLED < lists.len() {
            return None;
        }
        let (starts, items) = super::packed(lists);
        Some(WalkGrid {
            origin,
            far: [0, 1].map(|k| origin[k] + size[k] as f64 * cell),
            cell,
            inv_cell: cell.recip(),
            size,
            starts,
            items,
        })
    }

    /// The nearest face the ray from `origin` along `dir` (not vertical) crosses within `max`
    /// metres and its distance, starting from `best` (a crossing already known, or
    /// `(∞, u32::MAX)`), `crossing(i)` telling where the ray crosses face `i`, if it does.
    #[inline]
    pub(super) fn cast(
        &self,
        origin: [f64; 3],
        dir: [f64; 3],
        max: f64,
        mut best: (f64, u32),
        crossing: impl Fn(usize) -> Option<f64>,
    ) -> (f64, u32) {
        // A component too small to matter over the grid is taken as none (the crossings are
        // still tested with the ray as it is); one division per axis, for the walk's
        // boundaries need not be exact (see PAD).
        let o = [origin[0], origin[1]];
        let d = [dir[0], dir[1]].map(|v| if v.abs() < 1e-200 { 0.0 } else { v });
        let inv = d.map(|v| if v == 0.0 { 0.0 } else { v.recip() });
        let (lo, hi) = (self.origin, self.far);
        // Where the ray is inside the grid's box: [enter, leave]; most rays start inside.
        let mut enter = 0.0f64;
        if !(o[0] >= lo[0] && o[0] <= hi[0] && o[1] >= lo[1] && o[1] <= hi[1]) {
            let mut leave = max.min(best.0);
            for k in 0..2 {
                if d[k] == 0.0 {
                    if o[k] < lo[k] || o[k] > hi[k] {
                        return best;
                    }
                } else {
                    let (t1, t2) = ((lo[k] - o[k]) * inv[k], (hi[k] - o[k]) * inv[k]);
                    enter = enter.max(t1.min(t2));
                    leave = leave.min(t1.max(t2));
                }
            }
            if enter > leave {
                return best;
            }
        }
        // The cell where the ray enters, and for each axis the step, the distance at which
        // the ray leaves the current column (row) and the distance between two such leavings.
        let cell_of = |k: usize| {
            let x = (o[k] + d[k] * enter - lo[k]) * self.inv_cell;
            (x.max(0.0) as usize).min(self.size[k] - 1)
        };
        let mut at = [cell_of(0), cell_of(1)];
        let mut next = [f64::INFINITY; 2];
        let mut delta = [f64::INFINITY; 2];
        let step = d.map(|v| if v > 0.0 { 1 } else { usize::MAX });
        for k in 0..2 {
            if d[k] != 0.0 {
                let edge = lo[k] + (at[k] + usize::from(d[k] > 0.0)) as f64 * self.cell;
                next[k] = (edge - o[k]) * inv[k];
                delta[k] = self.cell * inv[k].abs();
            }
        }
        loop {
            let k = at[1] * self.size[0] + at[0];
            let (from, to) = (self.starts[k] as usize, self.starts[k + 1] as usize);
            for &i in &self.items[from..to] {
                if let Some(t) = crossing(i as usize)
                    && (t < best.0 || (t == best.0 && i < best.1))
                {
                    best = (t, i);
                }
            }
            // Along the axis whose boundary comes first.
            let axis = usize::from(next[1] < next[0]);
            let exit = next[axis];
            if best.0 <= exit || exit > max {
                return best;
            }
            // One step forward or back; stepping back from 0 wraps past the end.
            at[axis] = at[axis].wrapping_add(step[axis]);
            if at[axis] >= self.size[axis] {
                return best;
            }
            next[axis] += delta[axis];
        }
    }
}

/// Whether the segment `a`–`b` meets the box `lo`–`hi` (given that their bounding boxes
/// overlap): not all four corners strictly on one side of its line.
fn segment_meets_box(a: [f64; 2], b: [f64; 2], lo: [f64; 2], hi: [f64; 2]) -> bool {
    let side = |p: [f64; 2]| (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
    let s = [
        side(lo),
        side([hi[0], lo[1]]),
        side(hi),
        side([lo[0], hi[1]]),
    ];
    !(s.iter().all(|&v| v > 0.0) || s.iter().all(|&v| v < 0.0))
}
