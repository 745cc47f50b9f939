//! The scans' points of `map.svg`, drawn as they come: each point placed from the laser's true
//! frame and from where odometry puts it, on a lattice of half pixels anchored at the world's
//! origin, each half pixel drawn once. The picture's frame is known only at the run's end (the
//! paths widen it), but the lattice does not move with it: a layer's path data is written in
//! lattice units (the picture places it with a transform) while the run goes on
//! (`crate::output::ScanStream`), and only the few points beyond the world are framed
//! afterwards.

use crate::config::WorldDescription;
use crate::devices::laser::LaserFrame;
use crate::world::{PointKind, PointKinds, WorldMap};
use robot::Pose2;
use robot::hardware::LaserScan;
use std::collections::HashSet;
use std::sync::Arc;

/// A point's cell on a lattice of `per_m` cells a metre counted from the world's origin (cell
/// `(i, j)` holds the points nearest `(i, j) / per_m`); `None` for a point not finite.
pub fn cell_of(x: f64, y: f64, per_m: f64) -> Option<(i64, i64)> {
    let (i, j) = ((x * per_m + 0.5).floor(), (y * per_m + 0.5).floor());
    // Not a number fails both comparisons.
    (i.abs() < 1e15 && j.abs() < 1e15).then_some((i as i64, j as i64))
}

/// The cells `k` whose centre `k / per_m` lies from `lo` to `hi` metres.
pub fn cells_within(lo: f64, hi: f64, per_m: f64) -> std::ops::RangeInclusive<i64> {
    let at = |k: i64| k as f64 / per_m;
    let (mut first, mut last) = ((lo * per_m).ceil() as i64, (hi * per_m).floor() as i64);
    // The products round: the centres themselves decide.
    while at(first - 1) >= lo {
        first -= 1;
    }
    while at(first) < lo {
        first += 1;
    }
    while at(last + 1) <= hi {
        last += 1;
    }
    while at(last) > hi {
        last -= 1;
    }
    first..=last
}

/// Which cells were drawn: a bit each inside a rectangle (where nearly every point falls), a
/// set beyond it.
#[derive(Clone, Debug)]
pub struct Drawn {
    columns: std::ops::RangeInclusive<i64>,
    rows: std::ops::RangeInclusive<i64>,
    bits: Vec<u64>,
    beyond: HashSet<(i64, i64)>,
}

/// Most cells a rectangle of bits holds (8 MiB of them); a larger rectangle keeps none, every
/// cell drawn going to the set (a world kilometres wide draws its points all the same).
pub const MAX_BITS: i64 = 1 << 26;

/// A span of cells, both ends in.
type Range = std::ops::RangeInclusive<i64>;

impl Drawn {
    /// None drawn, a bit kept for each cell of `columns` × `rows` (none when they are more
    /// than [`MAX_BITS`]).
    pub fn new(
        columns: std::ops::RangeInclusive<i64>,
        rows: std::ops::RangeInclusive<i64>,
    ) -> Self {
        let size = |r: &std::ops::RangeInclusive<i64>| (r.end() - r.start() + 1).max(0);
        let (columns, rows) = match size(&columns).checked_mul(size(&rows)) {
            Some(cells) if cells <= MAX_BITS => (columns, rows),
            // Empty: no cell lies in it.
            _ => (Range::new(1, 0), Range::new(1, 0)),
        };
        let words = usize::try_from(size(&columns) * size(&rows) / 64 + 1).unwrap_or(1);
        Drawn {
            columns,
            rows,
            bits: robot::memory::written_zeros(words),
            beyond: HashSet::new(),
        }
    }

    /// Marks `cell` drawn: `None` if it was already, else whether it lies in the rectangle.
    pub fn insert(&mut self, (i, j): (i64, i64)) -> Option<bool> {
        if !self.columns.contains(&i) || !self.rows.contains(&j) {
            return self.beyond.insert((i, j)).then_some(false);
        }
        let width = self.columns.end() - self.columns.start() + 1;
        let k = ((j - self.rows.start()) * width + (i - self.columns.start())) as usize;
        let (word, bit) = (k / 64, 1u64 << (k % 64));
        let new = self.bits[word] & bit == 0;
        self.bits[word] |= bit;
        new.then_some(true)
    }
}

/// One layer of dots: the path data of its cells in the rectangle, in lattice units (`x` the
/// column, `y` the row negated, so down the page is down the picture), a move to each from the
/// last; and its cells beyond the rectangle, left to the picture's frame.
#[derive(Clone, Debug, Default)]
pub struct DotLayer {
    /// `M i -j h0` for the first cell, `m di -dj h0` for each next.
    pub d: Vec<u8>,
    last: Option<(i64, i64)>,
    /// The cells beyond the rectangle, in the order drawn.
    pub beyond: Vec<(i64, i64)>,
}

impl DotLayer {
    /// Draws `cell`, in the rectangle or not.
    pub fn push(&mut self, cell: (i64, i64), in_rectangle: bool) {
        if !in_rectangle {
            self.beyond.push(cell);
            return;
        }
        let (i, j) = cell;
        match self.last {
            None => push_move(&mut self.d, b'M', i, -j),
            Some((li, lj)) => push_move(&mut self.d, b'm', i - li, lj - j),
        }
        self.last = Some(cell);
    }
}

/// Writes `{op}{x} {y}h0` (a dot: a move and a segment of no length), the numbers as `{}`
/// writes them.
pub fn push_move(d: &mut Vec<u8>, op: u8, x: i64, y: i64) {
    let mut digits = itoa::Buffer::new();
    d.push(op);
    d.extend_from_slice(digits.format(x).as_bytes());
    d.push(b' ');
    d.extend_from_slice(digits.format(y).as_bytes());
    d.extend_from_slice(b"h0");
}

/// Returned beams drawn before a run's points start to thin out: the next twice as many are
/// drawn every second one, the next four times as many every fourth, and so on, so a run of
/// `n` beams draws about `FIRST_DRAWN × log2(n / FIRST_DRAWN + 1)` (as the points come, without
/// knowing how many will).
pub const FIRST_DRAWN: u64 = 15_000;

/// The scans' points of a run, as drawn so far. A point placed at the true pose takes the
/// layer of what it hit ([`PointKind`]); the first point in a cell decides its layer (a half
/// pixel holds one dot). A long run's later beams are thinned ([`FIRST_DRAWN`]).
#[derive(Clone, Debug)]
pub struct ScanDots {
    map: Arc<WorldMap>,
    per_m: f64,
    /// The cells drawn from the true pose (any layer), and from odometry.
    at_truth: Drawn,
    at_odometry: Drawn,
    /// Placed at the true pose, on a surface.
    pub seen: DotLayer,
    /// Placed at the true pose, on the floor (a tilted laser's).
    pub floor: DotLayer,
    /// Placed at the true pose, far from every surface.
    pub ghosts: DotLayer,
    /// Placed at the odometry pose.
    pub drifted: DotLayer,
    /// Points that are not numbers (none from a finite range and frame), counted.
    pub unplaced: usize,
    /// Each beam's sine and cosine, for the last scan's angles.
    angles: Option<(f64, f64, usize)>,
    trig: Vec<(f64, f64)>,
    /// One returned beam in `stride` is drawn; `skip` counts down to the next; the stride
    /// doubles after `phase_left` more.
    stride: u64,
    skip: u64,
    phase_left: u64,
}

impl ScanDots {
    /// Nothing drawn yet, in `world` (its map: `map`), at `per_m` cells a metre; the
    /// rectangle of the layers' path data holds the cells within `margin` metres of the
    /// world's walls but the outermost (any frame that holds the world and that margin holds
    /// it).
    pub fn new(world: &WorldDescription, map: Arc<WorldMap>, per_m: f64, margin: f64) -> Self {
        let (min, max) = world.bounds();
        let inset = margin - 1.0 / per_m;
        let (columns, rows) = (
            cells_within(min[0] - inset, max[0] + inset, per_m),
            cells_within(min[1] - inset, max[1] + inset, per_m),
        );
        ScanDots {
            map,
            per_m,
            at_truth: Drawn::new(columns.clone(), rows.clone()),
            at_odometry: Drawn::new(columns, rows),
            seen: DotLayer::default(),
            floor: DotLayer::default(),
            ghosts: DotLayer::default(),
            drifted: DotLayer::default(),
            unplaced: 0,
            angles: None,
            trig: Vec::new(),
            stride: 1,
            skip: 1,
            phase_left: FIRST_DRAWN,
        }
    }

    /// Draws the returned beams of `scan`, taken from the laser's true `frame` with the base
    /// at `truth`, and from where `odometry` puts that frame.
    pub fn add(&mut self, scan: &LaserScan, frame: &LaserFrame, truth: Pose2, odometry: Pose2) {
        let angles = (scan.angle_min, scan.angle_increment, scan.len());
        if self.angles != Some(angles) {
            self.angles = Some(angles);
            self.trig = (0..scan.len()).map(|i| scan.angle(i).sin_cos()).collect();
        }
        let at_odometry = frame.carried(truth, odometry);
        // Each frame's axes once a scan, each beam's angle once: a point is then sums and
        // products.
        let (axes, odometry_axes) = (frame.axes(), at_odometry.axes());
        let map = Arc::clone(&self.map);
        let mut kinds = PointKinds::new(&map);
        for (i, &beam) in self.trig.iter().enumerate() {
            let Some(range) = scan.range_m(i) else {
                continue;
            };
            self.phase_left -= 1;
            if self.phase_left == 0 {
                self.stride *= 2;
                self.phase_left = FIRST_DRAWN * self.stride;
            }
            self.skip -= 1;
            if self.skip != 0 {
                continue;
            }
            self.skip = self.stride;
            let p = beam_point(frame, axes, beam, range);
            match cell_of(p[0], p[1], self.per_m) {
                Some(cell) => {
                    if let Some(inside) = self.at_truth.insert(cell) {
                        let layer = match kinds.of(p) {
                            PointKind::Surface => &mut self.seen,
                            PointKind::Floor => &mut self.floor,
                            PointKind::Ghost => &mut self.ghosts,
                        };
                        layer.push(cell, inside);
                    }
                }
                None => self.unplaced += 1,
            }
            let q = beam_point(&at_odometry, odometry_axes, beam, range);
            match cell_of(q[0], q[1], self.per_m) {
                Some(cell) => {
                    if let Some(inside) = self.at_odometry.insert(cell) {
                        self.drifted.push(cell, inside);
                    }
                }
                None => self.unplaced += 1,
            }
        }
    }
}

/// The world point `range` metres along the beam of sine and cosine `(sa, ca)` from `frame`,
/// whose axes are `(forward, left)`: sums and products.
#[inline]
fn beam_point(
    frame: &LaserFrame,
    (forward, left): ([f64; 3], [f64; 3]),
    (sa, ca): (f64, f64),
    range: f64,
) -> [f64; 3] {
    let at = |j: usize| frame.origin[j] + range * (ca * forward[j] + sa * left[j]);
    [at(0), at(1), at(2)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cell_holds_the_points_nearest_its_centre_and_is_drawn_once() {
        assert_eq!(cell_of(0.0, 0.0, 120.0), Some((0, 0)));
        assert_eq!(cell_of(1.0, -1.0, 120.0), Some((120, -120)));
        assert_eq!(cell_of(0.004, -0.004, 120.0), Some((0, 0)));
        assert_eq!(cell_of(0.0045, -0.0045, 120.0), Some((1, -1)));
        assert_eq!(cell_of(f64::NAN, 0.0, 120.0), None);
        assert_eq!(cell_of(0.0, f64::INFINITY, 120.0), None);
        let mut drawn = Drawn::new(-10..=10, -10..=10);
        for (cell, inside) in [
            ((0, 0), true),
            ((10, -10), true),
            ((-10, 10), true),
            ((11, 0), false),
            ((0, -11), false),
            ((1_000_000, 5), false),
        ] {
            assert_eq!(drawn.insert(cell), Some(inside), "{cell:?} new");
            assert_eq!(drawn.insert(cell), None, "{cell:?} drawn once");
        }
        // A rectangle kilometres wide keeps no bits: every cell is in the set, drawn once.
        let mut wide = Drawn::new(-12_000_000..=12_000_000, -12_000_000..=12_000_000);
        assert!(wide.bits.len() <= 1);
        assert_eq!(wide.insert((5, 5)), Some(false));
        assert_eq!(wide.insert((5, 5)), None);
    }

    #[test]
    fn the_cells_within_a_span_are_those_whose_centres_it_holds() {
        for (lo, hi) in [(0.0, 1.0), (-1.234, 5.678), (0.004, 0.005), (-0.6, -0.59)] {
            let r = cells_within(lo, hi, 120.0);
            for k in r.start() - 3..=r.end() + 3 {
                let x = k as f64 / 120.0;
                assert_eq!(r.contains(&k), (lo..=hi).contains(&x), "{lo}..{hi}: {k}");
            }
        }
    }

    #[test]
    fn a_layer_moves_from_dot_to_dot_and_keeps_the_cells_beyond() {
        let mut layer = DotLayer::default();
        layer.push((3, 4), true);
        layer.push((5, 1), true);
        layer.push((99, 99), false);
        layer.push((5, 2), true);
        assert_eq!(
            String::from_utf8(layer.d.clone()).unwrap(),
            "M3 -4h0m2 3h0m0 -1h0"
        );
        assert_eq!(layer.beyond, vec![(99, 99)]);
    }
}
