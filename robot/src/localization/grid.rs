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

impl OccupancyGrid {
    /// The grid of `scans`, each seen from the laser pose beside it (map frame), with a margin of
    /// one metre; `None` when there is nothing to draw or the map would hold more than 10⁸ cells.
    pub fn from_scans<'a>(
        scans: impl IntoIterator<Item = (Pose2, &'a RangeScan)>,
        config: GridConfig,
    ) -> Option<Self> {
        // The scans that add something: a finite pose, away from the last one inserted.
        let mut last: Option<Pose2> = None;
        let scans: Vec<(Pose2, &RangeScan)> = scans
            .into_iter()
            .filter(|(pose, _)| {
                let finite = pose.x.is_finite() && pose.y.is_finite() && pose.theta.is_finite();
                let moved = last.is_none_or(|l| {
                    l.distance(pose) >= config.keyframe_m
                        || crate::geometry::wrap_angle(l.theta - pose.theta).abs()
                            >= config.keyframe_rad
                });
                if finite && moved {
                    last = Some(*pose);
                }
                finite && moved
            })
            .collect();
        // The bounds of what the beams reach.
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        let mut grow = |p: [f64; 2]| {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        };
        for &(pose, scan) in &scans {
            grow([pose.x, pose.y]);
            for i in 0..scan.ranges.len() {
                if let Some(end) = Self::beam_end(&config, pose, scan, i) {
                    grow(end.0);
                }
            }
        }
        if !(lo[0].is_finite() && config.resolution_m > 0.0) {
            return None;
        }
        let r = config.resolution_m;
        let origin = [(lo[0] / r).floor() * r - 1.0, (lo[1] / r).floor() * r - 1.0];
        let width = ((hi[0] + 1.0 - origin[0]) / r).ceil() as usize + 1;
        let height = ((hi[1] + 1.0 - origin[1]) / r).ceil() as usize + 1;
        if width.checked_mul(height).is_none_or(|n| n > MAX_CELLS) {
            return None;
        }
        let mut grid = OccupancyGrid {
            config,
            origin,
            width,
            height,
            log_odds: vec![0.0; width * height],
        };
        for (pose, scan) in scans {
            grid.insert(pose, scan);
        }
        grid.trim();
        Some(grid)
    }

    /// Where beam `i` of `scan` seen from `laser` ends, and whether it ended on something; `None`
    /// for a beam not traced (no return, and no free range).
    fn beam_end(
        c: &GridConfig,
        laser: Pose2,
        scan: &RangeScan,
        i: usize,
    ) -> Option<([f64; 2], bool)> {
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

    /// Adds one scan seen from `laser` (the laser's pose in the map frame).
    fn insert(&mut self, laser: Pose2, scan: &RangeScan) {
        for i in 0..scan.ranges.len() {
            if let Some((end, hit)) = Self::beam_end(&self.config, laser, scan, i) {
                self.trace([laser.x, laser.y], end, hit);
            }
        }
    }

    /// Marks the cells from `a` to `b` free, and `b`'s occupied when `hit`.
    fn trace(&mut self, a: [f64; 2], b: [f64; 2], hit: bool) {
        let r = self.config.resolution_m;
        let cell = |p: [f64; 2]| {
            [
                ((p[0] - self.origin[0]) / r).floor() as i64,
                ((p[1] - self.origin[1]) / r).floor() as i64,
            ]
        };
        let (mut at, last) = (cell(a), cell(b));
        let d = [b[0] - a[0], b[1] - a[1]];
        let step = [d[0].signum() as i64, d[1].signum() as i64];
        // Distance along the ray (as a share of it) to the next cell border, and between borders.
        let border = |k: usize| {
            let next = if d[k] > 0.0 { at[k] + 1 } else { at[k] } as f64;
            let edge = self.origin[k] + next * r;
            if d[k] == 0.0 {
                f64::INFINITY
            } else {
                (edge - a[k]) / d[k]
            }
        };
        let mut t_max = [border(0), border(1)];
        let t_delta = [
            if d[0] == 0.0 {
                f64::INFINITY
            } else {
                r / d[0].abs()
            },
            if d[1] == 0.0 {
                f64::INFINITY
            } else {
                r / d[1].abs()
            },
        ];
        let limit = (last[0] - at[0]).unsigned_abs() + (last[1] - at[1]).unsigned_abs();
        // The grid's bounds hold every beam with a margin, so the walk stays inside it: it
        // follows the cell's index (a column step is ±1, a row step ±width) and `add`'s checks
        // are needed only at the ends.
        let inside = |c: [i64; 2]| {
            c[0] >= 0 && c[1] >= 0 && (c[0] as usize) < self.width && (c[1] as usize) < self.height
        };
        if inside(at) && inside(last) {
            let width = self.width as i64;
            let (mut index, end) = (at[1] * width + at[0], last[1] * width + last[0]);
            let index_step = [step[0], step[1] * width];
            let (miss, clamp) = (self.config.miss, self.config.clamp);
            for _ in 0..limit {
                if index == end {
                    break;
                }
                if let Some(v) = self.log_odds.get_mut(index as usize) {
                    *v = (*v + miss).max(-clamp);
                }
                let k = usize::from(t_max[0] >= t_max[1]);
                index += index_step[k];
                t_max[k] += t_delta[k];
            }
        } else {
            for _ in 0..limit {
                if at == last {
                    break;
                }
                self.add(at, self.config.miss);
                if t_max[0] < t_max[1] {
                    at[0] += step[0];
                    t_max[0] += t_delta[0];
                } else {
                    at[1] += step[1];
                    t_max[1] += t_delta[1];
                }
            }
        }
        let end = if hit {
            self.config.hit
        } else {
            self.config.miss
        };
        self.add(last, end);
    }

    fn add(&mut self, at: [i64; 2], evidence: f32) {
        if at[0] < 0 || at[1] < 0 || at[0] as usize >= self.width || at[1] as usize >= self.height {
            return;
        }
        let i = at[1] as usize * self.width + at[0] as usize;
        let clamp = self.config.clamp;
        self.log_odds[i] = (self.log_odds[i] + evidence).clamp(-clamp, clamp);
    }

    /// Drops the rows and columns no beam reached, keeping a margin of ten cells.
    fn trim(&mut self) {
        let seen = |i: usize| self.log_odds[i] != 0.0;
        let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
        for y in 0..self.height {
            for x in 0..self.width {
                if seen(y * self.width + x) {
                    x0 = x0.min(x);
                    x1 = x1.max(x);
                    y0 = y0.min(y);
                    y1 = y1.max(y);
                }
            }
        }
        if x0 == usize::MAX {
            return;
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
            cells.extend_from_slice(&self.log_odds[y * self.width + x0..=y * self.width + x1]);
        }
        let r = self.config.resolution_m;
        self.origin = [
            self.origin[0] + x0 as f64 * r,
            self.origin[1] + y0 as f64 * r,
        ];
        self.width = width;
        self.height = y1 - y0 + 1;
        self.log_odds = cells;
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
        let p = 1.0 - 1.0 / (1.0 + f64::from(self.log_odds[i]).exp());
        if self.log_odds[i] == 0.0 {
            Cell::Unknown
        } else if p >= self.config.occupied_thresh {
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
        for y in (0..self.height).rev() {
            out.extend(
                (0..self.width).map(|x| match self.cell(y * self.width + x) {
                    Cell::Occupied => 0u8,
                    Cell::Free => 254,
                    Cell::Unknown => 205,
                }),
            );
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

    /// A square room 4 m wide seen from its centre by a 360° laser: its walls come out occupied,
    /// its inside free, the outside unknown.
    #[test]
    fn a_room_seen_from_inside() {
        let n = 720;
        let ranges: Vec<f64> = (0..n)
            .map(|i| {
                let a = -std::f64::consts::PI + std::f64::consts::TAU * i as f64 / n as f64;
                2.0 / a.cos().abs().max(a.sin().abs())
            })
            .collect();
        let scan = RangeScan::new(
            -std::f64::consts::PI,
            std::f64::consts::TAU / n as f64,
            30.0,
            ranges,
        );
        let pose = Pose2::new(10.0, -3.0, 0.3);
        // The room is square in the laser's frame: turn the points back.
        let grid = OccupancyGrid::from_scans([(pose, &scan)], GridConfig::default()).unwrap();
        let world = |x: f64, y: f64| {
            let (s, c) = pose.theta.sin_cos();
            [pose.x + c * x - s * y, pose.y + s * x + c * y]
        };
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
    }

    #[test]
    fn nothing_to_draw_is_no_grid() {
        assert!(OccupancyGrid::from_scans(std::iter::empty(), GridConfig::default()).is_none());
        let scan = RangeScan::new(0.0, 0.01, 30.0, vec![1.0; 3]);
        let far = Pose2::new(f64::NAN, 0.0, 0.0);
        assert!(OccupancyGrid::from_scans([(far, &scan)], GridConfig::default()).is_none());
    }
}
