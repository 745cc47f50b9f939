//! Occupancy grids from placed scans, in the ROS `map_server` convention (`map.pgm` +
//! `map.yaml`), so the maps a run or a log makes open in RViz, Nav2 and every tool that reads
//! them.
//!
//! Each beam is traced through the grid from the laser to its reading (Amanatides & Woo's
//! traversal): the cells it crosses gain evidence of being free, the cell of its end evidence of
//! being occupied; a beam that returned nothing frees the cells up to
//! [`GridConfig::free_range_m`] (none by default). Evidence is summed as log-odds and clamped, so a cell seen free a
//! hundred times is not lost to one outlier. A scan taken within 20 cm and 5° of the last one
//! inserted is left out ([`GridConfig::keyframe_m`]; mapping packages do the same, gmapping's
//! default at 1 m and 0.5 rad): it would trace nearly the same cells again (a robot at rest scans
//! the same room five times a second), and the map's cost then follows the ground covered, not
//! the time spent. The image is written with the grid's top row (largest
//! y) first, as `map_server` reads it, and `origin` is the pose of the lower-left cell's corner.

use super::scan::RangeScan;
use crate::geometry::Pose2;

/// How a grid is built.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct GridConfig {
    /// Side of a cell, metres. Default 0.05.
    pub resolution_m: f64,
    /// A beam that returned nothing frees the cells this far, metres. Default 0: indoors a
    /// beam comes back empty from glass, black paint and mirrors far more often than from open
    /// space, and freeing cells behind those would open the walls.
    pub free_range_m: f64,
    /// Readings farther than this are traced only this far, as free, metres. Default 30.
    pub max_range_m: f64,
    /// Log-odds added to a cell a beam ends in. Default 0.85 (a 70 % hit).
    pub hit: f32,
    /// Log-odds added to a cell a beam passes through. Default −0.4 (a 40 % hit).
    pub miss: f32,
    /// Log-odds are kept within ± this. Default 4.
    pub clamp: f32,
    /// Cells at least this likely occupied are written occupied. Default 0.65.
    pub occupied_thresh: f64,
    /// Cells at most this likely occupied are written free. Default 0.196.
    pub free_thresh: f64,
    /// A scan is inserted only when its laser moved this far from the last scan inserted,
    /// metres, or turned [`GridConfig::keyframe_rad`]. Default 0.2; 0 inserts every scan.
    pub keyframe_m: f64,
    /// See [`GridConfig::keyframe_m`], radians. Default 5°.
    pub keyframe_rad: f64,
}

impl Default for GridConfig {
    fn default() -> Self {
        GridConfig {
            resolution_m: 0.05,
            free_range_m: 0.0,
            max_range_m: 30.0,
            hit: 0.85,
            miss: -0.4,
            clamp: 4.0,
            occupied_thresh: 0.65,
            free_thresh: 0.196,
            keyframe_m: 0.2,
            keyframe_rad: 5f64.to_radians(),
        }
    }
}

/// A 2D occupancy grid.
#[derive(Clone, Debug, PartialEq)]
pub struct OccupancyGrid {
    config: GridConfig,
    /// World coordinates of the lower-left corner of cell (0, 0), metres.
    origin: [f64; 2],
    width: usize,
    height: usize,
    /// Log-odds, row by row from the bottom (y increasing).
    log_odds: Vec<f32>,
}

/// What a cell is, once thresholded.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Cell {
    /// Likely free.
    Free,
    /// Likely occupied.
    Occupied,
    /// Not seen enough to say.
    Unknown,
}

/// Cells a grid may hold at most (a 10 km × 10 km map at 5 cm is 4·10¹⁰: no).
const MAX_CELLS: usize = 100_000_000;

/// An occupancy grid built scan by scan, as a run goes (so a program can build its map beside
/// the work that makes the scans, and have it when they end).
///
/// Cells lie on one lattice fixed in the map frame (cell `(i, j)` covers `[i r, (i + 1) r) ×
/// [j r, (j + 1) r)`), so where a beam falls never depends on what came before; the grid's
/// storage grows as the beams reach farther.
#[derive(Clone, Debug)]
pub struct GridBuilder {
    config: GridConfig,
    /// The laser pose of the last scan inserted.
    last: Option<Pose2>,
    /// The lattice index of the storage's cell (0, 0).
    lo: [i64; 2],
    width: usize,
    height: usize,
    /// Log-odds, row by row from the bottom (y increasing).
    log_odds: Vec<f32>,
    /// The beams' ends of the scan being inserted, and whether each hit (reused).
    ends: Vec<([f64; 2], bool)>,
    inserted: usize,
    /// The grid would hold more than [`MAX_CELLS`], or a scan lay beyond 2⁴⁰ cells: nothing more
    /// is inserted.
    too_large: bool,
}

impl GridBuilder {
    /// An empty grid.
    pub fn new(config: GridConfig) -> Self {
        GridBuilder {
            config,
            last: None,
            lo: [0, 0],
            width: 0,
            height: 0,
            log_odds: Vec::new(),
            ends: Vec::new(),
            inserted: 0,
            too_large: false,
        }
    }

    /// Adds `scan` seen from the laser pose `laser` (map frame) if it adds something: a finite
    /// pose, moved from the last scan inserted by [`GridConfig::keyframe_m`] or turned by
    /// [`GridConfig::keyframe_rad`]. Returns whether it was inserted.
    pub fn push(&mut self, laser: Pose2, scan: &RangeScan) -> bool {
        let c = self.config;
        let finite = laser.x.is_finite() && laser.y.is_finite() && laser.theta.is_finite();
        let moved = self.last.is_none_or(|l| {
            l.distance(&laser) >= c.keyframe_m
                || crate::geometry::wrap_angle(l.theta - laser.theta).abs() >= c.keyframe_rad
        });
        let positive = c.resolution_m > 0.0;
        if !(finite && moved && positive) || self.too_large {
            return false;
        }
        self.last = Some(laser);
        let mut ends = std::mem::take(&mut self.ends);
        ends.clear();
        ends.extend((0..scan.ranges.len()).filter_map(|i| beam_end(&c, laser, scan, i)));
        // The cells the scan reaches, with a margin of a metre.
        let r = c.resolution_m;
        let margin = (1.0 / r).ceil() as i64;
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in ends.iter().map(|e| e.0).chain([[laser.x, laser.y]]) {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        // Lattice indices as far as 2⁴⁰ cells from the origin (55,000 km at 5 cm); a scan
        // beyond is no map anyone can hold.
        let far = (1u64 << 40) as f64;
        let (lo, hi) = (
            [0, 1].map(|k| (lo[k] / r).floor()),
            [0, 1].map(|k| (hi[k] / r).floor()),
        );
        if !(0..2).all(|k| lo[k].abs() < far && hi[k].abs() < far) {
            self.too_large = true;
        }
        let lo = [0, 1].map(|k| lo[k] as i64 - margin);
        let hi = [0, 1].map(|k| hi[k] as i64 + margin);
        let inserted = !self.too_large && self.cover(lo, hi);
        if inserted {
            for &(end, hit) in &ends {
                self.trace([laser.x, laser.y], end, hit);
            }
            self.inserted += 1;
        }
        self.ends = ends;
        inserted
    }

    /// The grid of the scans inserted, trimmed to the cells a beam reached with a margin of ten
    /// cells; `None` when none was inserted or the map would hold more than 10⁸ cells.
    pub fn finish(self) -> Option<OccupancyGrid> {
        self.grid()
    }

    /// The grid of the scans inserted so far, as [`GridBuilder::finish`] gives it (the builder
    /// goes on).
    pub fn grid(&self) -> Option<OccupancyGrid> {
        if self.inserted == 0 || self.too_large {
            return None;
        }
        let r = self.config.resolution_m;
        let storage = OccupancyGrid {
            config: self.config,
            origin: [self.lo[0] as f64 * r, self.lo[1] as f64 * r],
            width: self.width,
            height: self.height,
            log_odds: Vec::new(),
        };
        Some(storage.trimmed(&self.log_odds))
    }

    /// Grows the storage to hold the lattice cells `lo..=hi`; false when it would hold more than
    /// [`MAX_CELLS`].
    fn cover(&mut self, lo: [i64; 2], hi: [i64; 2]) -> bool {
        let size = [self.width as i64, self.height as i64];
        let inside = (0..2).all(|k| lo[k] >= self.lo[k] && hi[k] < self.lo[k] + size[k]);
        if inside && !self.log_odds.is_empty() {
            return true;
        }
        let (mut new_lo, mut new_hi) = (lo, hi);
        if !self.log_odds.is_empty() {
            for k in 0..2 {
                new_lo[k] = new_lo[k].min(self.lo[k]);
                new_hi[k] = new_hi[k].max(self.lo[k] + size[k] - 1);
            }
        }
        let needed = [0, 1].map(|k| (new_hi[k] - new_lo[k] + 1) as u64);
        if needed[0].saturating_mul(needed[1]) > MAX_CELLS as u64 {
            self.too_large = true;
            return false;
        }
        // Room to grow by a quarter more on the sides that grew, so a robot that keeps driving
        // into new ground copies its grid a few times, not at every scan (none when the slack
        // alone would pass the limit).
        let (mut grown_lo, mut grown_hi) = (new_lo, new_hi);
        for k in 0..2 {
            let slack = (needed[k] / 4) as i64;
            if self.log_odds.is_empty() || new_lo[k] < self.lo[k] {
                grown_lo[k] -= slack;
            }
            if self.log_odds.is_empty() || new_hi[k] >= self.lo[k] + size[k] {
                grown_hi[k] += slack;
            }
        }
        let grown = [0, 1].map(|k| (grown_hi[k] - grown_lo[k] + 1) as u64);
        if grown[0].saturating_mul(grown[1]) <= MAX_CELLS as u64 {
            (new_lo, new_hi) = (grown_lo, grown_hi);
        }
        let width = (new_hi[0] - new_lo[0] + 1) as usize;
        let height = (new_hi[1] - new_lo[1] + 1) as usize;
        // Written once, row by row: the old rows where they were, zeros elsewhere; every page
        // written before a cell of it is read (`crate::memory`).
        let row_shift = self.lo[1] - new_lo[1];
        let mut cells = Vec::with_capacity(width * height);
        for row in 0..height {
            let y = row as i64 - row_shift;
            if (0..self.height as i64).contains(&y) {
                // The old storage lies within the new one, so both shifts are ≥ 0.
                let (y, col) = (y as usize, (self.lo[0] - new_lo[0]) as usize);
                cells.resize(row * width + col, 0.0f32);
                cells.extend_from_slice(&self.log_odds[y * self.width..(y + 1) * self.width]);
            }
            cells.resize((row + 1) * width, 0.0f32);
        }
        self.lo = new_lo;
        self.width = width;
        self.height = height;
        self.log_odds = cells;
        true
    }

    /// Marks the cells from `a` to `b` free, and `b`'s occupied when `hit` (Amanatides & Woo:
    /// from cell border to cell border along the beam). Both ends lie inside the storage.
    fn trace(&mut self, a: [f64; 2], b: [f64; 2], hit: bool) {
        let r = self.config.resolution_m;
        let cell = |p: [f64; 2]| [(p[0] / r).floor() as i64, (p[1] / r).floor() as i64];
        let (at, last) = (cell(a), cell(b));
        let d = [b[0] - a[0], b[1] - a[1]];
        // Distance along the ray (as a share of it) to the next cell border, and between borders.
        let border = |k: usize| {
            if d[k] == 0.0 {
                return f64::INFINITY;
            }
            let next = if d[k] > 0.0 { at[k] + 1 } else { at[k] } as f64;
            (next * r - a[k]) / d[k]
        };
        let delta = |k: usize| {
            if d[k] == 0.0 {
                f64::INFINITY
            } else {
                r / d[k].abs()
            }
        };
        let (mut tx, mut ty) = (border(0), border(1));
        let (dx, dy) = (delta(0), delta(1));
        let width = self.width as i64;
        let index = |c: [i64; 2]| (c[1] - self.lo[1]) * width + (c[0] - self.lo[0]);
        let (mut i, end) = (index(at), index(last));
        let (sx, sy) = (d[0].signum() as i64, d[1].signum() as i64 * width);
        let limit = (last[0] - at[0]).unsigned_abs() + (last[1] - at[1]).unsigned_abs();
        let (miss, clamp) = (self.config.miss, self.config.clamp);
        for _ in 0..limit {
            if i == end {
                break;
            }
            if let Some(v) = self.log_odds.get_mut(i as usize) {
                *v = (*v + miss).max(-clamp);
            }
            if tx < ty {
                i += sx;
                tx += dx;
            } else {
                i += sy;
                ty += dy;
            }
        }
        let evidence = if hit {
            self.config.hit
        } else {
            self.config.miss
        };
        if let Some(v) = self.log_odds.get_mut(end as usize) {
            *v = (*v + evidence).clamp(-clamp, clamp);
        }
    }
}

/// Where beam `i` of `scan` seen from `laser` ends, and whether it ended on something; `None`
/// for a beam not traced (no return, and no free range).
fn beam_end(c: &GridConfig, laser: Pose2, scan: &RangeScan, i: usize) -> Option<([f64; 2], bool)> {
    let range = scan.ranges[i];
    let returned = scan.returned(i) && range <= c.max_range_m;
    let length = if returned {
        range
    } else if c.free_range_m > 0.0 {
        c.free_range_m.min(c.max_range_m)
    } else {
        return None;
    };
    let angle = laser.theta + scan.angle_min + scan.angle_increment * i as f64;
    let (s, co) = angle.sin_cos();
    Some(([laser.x + length * co, laser.y + length * s], returned))
}

impl OccupancyGrid {
    /// The grid of `scans`, each seen from the laser pose beside it (map frame): a
    /// [`GridBuilder`] fed them all. `None` when there is nothing to draw or the map would hold
    /// more than 10⁸ cells.
    pub fn from_scans<'a>(
        scans: impl IntoIterator<Item = (Pose2, &'a RangeScan)>,
        config: GridConfig,
    ) -> Option<Self> {
        let mut builder = GridBuilder::new(config);
        for (pose, scan) in scans {
            builder.push(pose, scan);
        }
        builder.finish()
    }

    /// Drops the rows and columns no beam reached, keeping a margin of ten cells.
    #[cfg(test)]
    fn trim(&mut self) {
        let log_odds = std::mem::take(&mut self.log_odds);
        *self = self.trimmed(&log_odds);
    }

    /// The grid of `log_odds` (this grid's size, its own cells left aside) without the rows and
    /// columns no beam reached, keeping a margin of ten cells: copied once.
    fn trimmed(&self, log_odds: &[f32]) -> OccupancyGrid {
        // The bounds of the cells seen, looking only where they could still widen: the rows
        // from each end to the first seen, then in each row between only the cells left of the
        // leftmost and right of the rightmost seen so far (the grid grows with slack, and most
        // of it is never seen).
        let seen = |v: &f32| *v != 0.0;
        let row = |y: usize| &log_odds[y * self.width..(y + 1) * self.width];
        let Some(y0) = (0..self.height).find(|&y| row(y).iter().any(seen)) else {
            return OccupancyGrid {
                log_odds: log_odds.to_vec(),
                ..self.clone()
            };
        };
        let y1 = (y0..self.height)
            .rev()
            .find(|&y| row(y).iter().any(seen))
            .unwrap_or(y0);
        let (mut x0, mut x1) = (self.width, 0);
        for y in y0..=y1 {
            let cells = row(y);
            if let Some(x) = cells[..x0].iter().position(seen) {
                x0 = x;
            }
            if let Some(x) = cells[x1..].iter().rposition(seen) {
                x1 += x;
            }
        }
        let margin = 10;
        let (x0, y0) = (x0.saturating_sub(margin), y0.saturating_sub(margin));
        let (x1, y1) = (
            (x1 + margin).min(self.width - 1),
            (y1 + margin).min(self.height - 1),
        );
        let width = x1 - x0 + 1;
        let mut cells = Vec::with_capacity(width * (y1 - y0 + 1));
        for y in y0..=y1 {
            cells.extend_from_slice(&log_odds[y * self.width + x0..=y * self.width + x1]);
        }
        let r = self.config.resolution_m;
        OccupancyGrid {
            config: self.config,
            origin: [
                self.origin[0] + x0 as f64 * r,
                self.origin[1] + y0 as f64 * r,
            ],
            width,
            height: y1 - y0 + 1,
            log_odds: cells,
        }
    }

    /// Cells across (x) and up (y).
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// World coordinates of the lower-left corner of the grid, metres.
    pub fn origin(&self) -> [f64; 2] {
        self.origin
    }

    /// Side of a cell, metres.
    pub fn resolution(&self) -> f64 {
        self.config.resolution_m
    }

    /// What the cell holding `p` (map frame, metres) is; `None` outside the grid.
    pub fn at(&self, p: [f64; 2]) -> Option<Cell> {
        let r = self.config.resolution_m;
        let x = ((p[0] - self.origin[0]) / r).floor();
        let y = ((p[1] - self.origin[1]) / r).floor();
        if x < 0.0 || y < 0.0 || x >= self.width as f64 || y >= self.height as f64 {
            return None;
        }
        Some(self.cell(y as usize * self.width + x as usize))
    }

    fn cell(&self, i: usize) -> Cell {
        self.kind(self.log_odds[i])
    }

    /// What a cell of log-odds `l` is.
    fn kind(&self, l: f32) -> Cell {
        if l == 0.0 {
            return Cell::Unknown;
        }
        let p = 1.0 - 1.0 / (1.0 + f64::from(l).exp());
        if p >= self.config.occupied_thresh {
            Cell::Occupied
        } else if p <= self.config.free_thresh {
            Cell::Free
        } else {
            Cell::Unknown
        }
    }

    /// Cells of each kind: (free, occupied, unknown).
    pub fn counts(&self) -> (usize, usize, usize) {
        (0..self.log_odds.len()).fold((0, 0, 0), |(f, o, u), i| match self.cell(i) {
            Cell::Free => (f + 1, o, u),
            Cell::Occupied => (f, o + 1, u),
            Cell::Unknown => (f, o, u + 1),
        })
    }

    /// The grid as a binary PGM (`P5`), top row first: occupied 0, free 254, unknown 205 — the
    /// values `map_server`'s trinary mode reads back as 100, 0 and −1.
    pub fn pgm(&self) -> Vec<u8> {
        let mut out = format!(
            "P5\n# robot twin occupancy grid, {} m per cell\n{} {}\n255\n",
            self.config.resolution_m, self.width, self.height
        )
        .into_bytes();
        // Log-odds are sums of a few steps, so neighbours often hold the same value: the last
        // one's kind is kept instead of taking an exponential per cell.
        let mut last = (f32::NAN, Cell::Unknown);
        for y in (0..self.height).rev() {
            let row = &self.log_odds[y * self.width..(y + 1) * self.width];
            out.extend(row.iter().map(|&l| {
                if l.to_bits() != last.0.to_bits() {
                    last = (l, self.kind(l));
                }
                match last.1 {
                    Cell::Occupied => 0u8,
                    Cell::Free => 254,
                    Cell::Unknown => 205,
                }
            }));
        }
        out
    }

    /// The `map.yaml` that goes with the image `image` (a path relative to the YAML file).
    pub fn yaml(&self, image: &str) -> String {
        format!(
            "image: {image}\nmode: trinary\nresolution: {}\norigin: [{:.6}, {:.6}, 0.0]\nnegate: 0\noccupied_thresh: {}\nfree_thresh: {}\n",
            self.config.resolution_m,
            self.origin[0],
            self.origin[1],
            self.config.occupied_thresh,
            self.config.free_thresh
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Trimming keeps every seen cell, where it was, with a margin of ten cells (less at the
    /// grid's edges): the bounds found by looking everywhere.
    #[test]
    fn trimming_keeps_the_seen_cells_where_they_were() {
        let (width, height) = (97, 61);
        let mut rng = crate::test_rng::XorShift(0x9e37_79b9_7f4a_7c15);
        let mut next = move |n: usize| (rng.next_u64() % n as u64) as usize;
        for case in 0..200 {
            let mut log_odds = vec![0.0f32; width * height];
            for _ in 0..case % 7 {
                log_odds[next(width * height)] = if next(2) == 0 { 0.5 } else { -0.25 };
            }
            if case % 5 == 0 {
                log_odds[next(width * height)] = -0.0;
            }
            let grid = OccupancyGrid {
                config: GridConfig::default(),
                origin: [1.0, -2.0],
                width,
                height,
                log_odds: log_odds.clone(),
            };
            let mut trimmed = grid.clone();
            trimmed.trim();
            let seen: Vec<(usize, usize)> = (0..width * height)
                .filter(|&i| log_odds[i] != 0.0)
                .map(|i| (i % width, i / width))
                .collect();
            if seen.is_empty() {
                assert_eq!(trimmed.size(), (width, height), "case {case}");
                continue;
            }
            let x0 = seen.iter().map(|c| c.0).min().unwrap().saturating_sub(10);
            let y0 = seen.iter().map(|c| c.1).min().unwrap().saturating_sub(10);
            let x1 = (seen.iter().map(|c| c.0).max().unwrap() + 10).min(width - 1);
            let y1 = (seen.iter().map(|c| c.1).max().unwrap() + 10).min(height - 1);
            assert_eq!(trimmed.size(), (x1 - x0 + 1, y1 - y0 + 1), "case {case}");
            let r = grid.config.resolution_m;
            assert_eq!(
                trimmed.origin(),
                [1.0 + x0 as f64 * r, -2.0 + y0 as f64 * r]
            );
            for &(x, y) in &seen {
                let i = (y - y0) * trimmed.width + (x - x0);
                assert_eq!(trimmed.log_odds[i], log_odds[y * width + x], "case {case}");
            }
        }
    }

    /// A square room 4 m wide seen from its centre by a 360° laser: its walls come out occupied,
    /// its inside free, the outside unknown.
    #[test]
    fn a_room_seen_from_inside() {
        let (pose, scan) = room_scan([10.02, -3.02], 0.3);
        let grid = OccupancyGrid::from_scans([(pose, &scan)], GridConfig::default()).unwrap();
        let world = |x: f64, y: f64| [pose.x + x, pose.y + y];
        assert_eq!(grid.at(world(0.0, 0.0)), Some(Cell::Free));
        assert_eq!(grid.at(world(1.2, -0.7)), Some(Cell::Free));
        assert_eq!(grid.at(world(2.0, 0.3)), Some(Cell::Occupied));
        assert_eq!(grid.at(world(-0.4, -2.0)), Some(Cell::Occupied));
        assert_eq!(grid.at(world(2.25, 2.25)), Some(Cell::Unknown));
        let pgm = grid.pgm();
        let (w, h) = grid.size();
        assert!(pgm.starts_with(b"P5\n"));
        assert!(pgm.len() > w * h && pgm.ends_with(&[205]));
        assert!(grid.yaml("map.pgm").contains("origin: ["));
        // Each pixel is its cell's kind (rows from the top), as `cell` tells it.
        let pixels = &pgm[pgm.len() - w * h..];
        let mut kinds = [0usize; 3];
        for y in 0..h {
            for x in 0..w {
                let (want, kind) = match grid.cell(y * w + x) {
                    Cell::Occupied => (0, 0),
                    Cell::Free => (254, 1),
                    Cell::Unknown => (205, 2),
                };
                assert_eq!(pixels[(h - 1 - y) * w + x], want, "cell {x}, {y}");
                kinds[kind] += 1;
            }
        }
        assert!(
            kinds.iter().all(|&n| n > 0),
            "all three kinds drawn: {kinds:?}"
        );
    }

    #[test]
    fn nothing_to_draw_is_no_grid() {
        assert!(OccupancyGrid::from_scans(std::iter::empty(), GridConfig::default()).is_none());
        let scan = RangeScan::new(0.0, 0.01, 30.0, vec![1.0; 3]);
        let far = Pose2::new(f64::NAN, 0.0, 0.0);
        assert!(OccupancyGrid::from_scans([(far, &scan)], GridConfig::default()).is_none());
    }

    /// A 360° scan of a square room 4 m wide around `centre`, its walls along the map's axes,
    /// from a laser turned by `theta`, and the laser pose.
    fn room_scan(centre: [f64; 2], theta: f64) -> (Pose2, RangeScan) {
        let n = 720;
        let ranges: Vec<f64> = (0..n)
            .map(|i| {
                let a = -std::f64::consts::PI + std::f64::consts::TAU * i as f64 / n as f64 + theta;
                2.0 / a.cos().abs().max(a.sin().abs())
            })
            .collect();
        let scan = RangeScan::new(
            -std::f64::consts::PI,
            std::f64::consts::TAU / n as f64,
            30.0,
            ranges,
        );
        (Pose2::new(centre[0], centre[1], theta), scan)
    }

    /// Cells lie on one lattice fixed in the map frame: a room mapped after another one far away
    /// comes out cell for cell as when mapped alone, though the grid grew to hold both.
    #[test]
    fn cells_do_not_depend_on_what_else_was_mapped() {
        let (pose, scan) = room_scan([3.3, -1.7], 0.2);
        let alone = OccupancyGrid::from_scans([(pose, &scan)], GridConfig::default()).unwrap();
        let (far_pose, far_scan) = room_scan([-41.0, 27.0], 1.0);
        let mut builder = GridBuilder::new(GridConfig::default());
        assert!(builder.push(far_pose, &far_scan));
        assert!(builder.push(pose, &scan));
        let both = builder.finish().unwrap();
        assert!(
            both.size().0 > alone.size().0 + 800,
            "the grid grew to hold both rooms"
        );
        let r = alone.resolution();
        let mut compared = 0;
        for i in -50..50 {
            for j in -50..50 {
                let p = [
                    (66.0 + f64::from(i) + 0.5) * r,
                    (-34.0 + f64::from(j) + 0.5) * r,
                ];
                assert_eq!(alone.at(p), both.at(p), "cell at {p:?}");
                compared += usize::from(alone.at(p) != Some(Cell::Unknown));
            }
        }
        assert!(compared > 3000, "{compared} cells seen");
    }

    /// A robot driving down a 60 m corridor: the grid grows as it goes and holds the whole
    /// corridor, walls occupied and floor free from end to end; a scan taken where the last
    /// one was is left out.
    #[test]
    fn the_grid_grows_as_the_robot_drives() {
        let n = 361;
        let mut builder = GridBuilder::new(GridConfig::default());
        let mut inserted = 0;
        for k in 0..=120 {
            let x = 0.5 * f64::from(k);
            // Walls at y = ±1.5 m, beyond the laser's 30 m nothing.
            let ranges: Vec<f64> = (0..n)
                .map(|i| {
                    let a = -std::f64::consts::FRAC_PI_2 + std::f64::consts::PI * i as f64 / 360.0;
                    let wall = 1.5 / a.sin().abs().max(1e-9);
                    if wall <= 29.0 { wall } else { 31.0 }
                })
                .collect();
            let scan = RangeScan::new(
                -std::f64::consts::FRAC_PI_2,
                std::f64::consts::PI / 360.0,
                30.0,
                ranges,
            );
            inserted += usize::from(builder.push(Pose2::new(x, 0.0, 0.0), &scan));
            // The same place again adds nothing.
            assert!(!builder.push(Pose2::new(x + 0.01, 0.0, 0.0), &scan));
        }
        assert_eq!(inserted, 121);
        let grid = builder.finish().unwrap();
        for x in [0.3, 15.2, 31.7, 58.1, 60.4] {
            assert_eq!(grid.at([x, 1.51]), Some(Cell::Occupied), "left wall at {x}");
            assert_eq!(
                grid.at([x, -1.49]),
                Some(Cell::Occupied),
                "right wall at {x}"
            );
            assert_eq!(grid.at([x, 0.6]), Some(Cell::Free), "floor at {x}");
        }
        assert_eq!(grid.at([30.0, 1.8]), Some(Cell::Unknown), "behind the wall");
    }

    /// A map larger than 10⁸ cells is refused, not allocated.
    #[test]
    fn an_absurd_map_is_refused() {
        let (pose, scan) = room_scan([0.0, 0.0], 0.0);
        for place in [1e6, 1e300, -1e300] {
            let (far, far_scan) = room_scan([place, 1e6], 0.0);
            let mut builder = GridBuilder::new(GridConfig::default());
            assert!(builder.push(pose, &scan));
            assert!(!builder.push(far, &far_scan), "{place}");
            assert!(builder.finish().is_none());
        }
    }
}
