//! A coarse correlative search (Olson, "Real-time correlative scan matching", 2009): the
//! current scan's points scored against a grid of the reference's over a window of poses around
//! the guess, every pose of the window tried. It finds starts a fine matcher converges from when
//! its own start, the guess, is too far: the fine matcher follows the nearest pull, this search
//! looks at the whole window.
//!
//! The reference's points are drawn into a grid of cells as wide as the window's steps; a cell
//! scores 2 when it holds a point and 1 beside one, so a point falling a step off still counts.
//! For each heading of the window the current points are turned once, and every translation of
//! the window adds up the grid under them, a row of translations at a time.

use super::matcher::transform_all;
use crate::Pose2;

/// The poses tried around a guess: translations up to `half_m` each way in steps of `step_m`
/// (also the grid's cell), headings up to `half_rad` each way in steps of `step_rad`.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Window {
    /// Largest translation tried along each axis, metres.
    pub half_m: f64,
    /// Translation step and grid cell, metres.
    pub step_m: f64,
    /// Largest turn tried each way, radians.
    pub half_rad: f64,
    /// Heading step, radians.
    pub step_rad: f64,
}

impl Window {
    /// ±60 cm in 5 cm steps and ±30° in 1° steps: three standard deviations of a guess 20 cm
    /// and 10° off.
    pub const WIDE: Window = Window {
        half_m: 0.6,
        step_m: 0.05,
        half_rad: 0.523_598_775_598_298_8,
        step_rad: 0.017_453_292_519_943_295,
    };
}

/// Grids larger than this many cells are not drawn (a reference hundreds of metres across):
/// no start is offered.
const MAX_CELLS: usize = 4_000_000;

/// Up to `count` poses of `window` around `guess` where the most of `current`'s points (in
/// its own frame) fall on or beside `reference`'s (in the reference's frame), best first: the
/// best translation of each heading, headings at least `apart` steps from a better one. Ties
/// keep the pose met first (headings from the most clockwise, translations row by row), so the
/// answer does not depend on anything but the points. Empty when either scan has no point, the
/// window is not a window (a step not positive, a half-width negative or not finite), or the
/// reference spreads too wide for a grid.
pub fn best_starts(
    reference: &[[f64; 2]],
    current: &[[f64; 2]],
    guess: Pose2,
    window: &Window,
    (count, apart): (usize, usize),
) -> Vec<Pose2> {
    let sane = window.step_m > 0.0
        && window.step_rad > 0.0
        && window.half_m >= 0.0
        && window.half_rad >= 0.0
        && window.half_m.is_finite()
        && window.half_rad.is_finite();
    if !sane || reference.is_empty() || current.is_empty() || count == 0 {
        return Vec::new();
    }
    let Some(grid) = Grid::draw(reference, window) else {
        return Vec::new();
    };
    let reach = (window.half_m / window.step_m).floor() as i64;
    let turns = (window.half_rad / window.step_rad).floor() as i64;
    let side = (2 * reach + 1) as usize;
    let mut sums = vec![0u32; side * side];
    // (score, heading index, translation index) of each heading's best translation.
    let mut bests: Vec<(u32, i64, usize)> = Vec::with_capacity((2 * turns + 1) as usize);
    let mut moved = Vec::with_capacity(current.len());
    for turn in -turns..=turns {
        let theta = guess.theta + turn as f64 * window.step_rad;
        transform_all(&Pose2::new(guess.x, guess.y, theta), current, &mut moved);
        sums.iter_mut().for_each(|v| *v = 0);
        for p in &moved {
            grid.add_window(p[0], p[1], reach, &mut sums);
        }
        let (best, &score) = sums
            .iter()
            .enumerate()
            .fold((0, &0), |b, (k, v)| if *v > *b.1 { (k, v) } else { b });
        bests.push((score, turn, best));
    }
    // Best first; equal scores in the order met.
    bests.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut kept: Vec<(i64, usize)> = Vec::new();
    for &(score, turn, at) in &bests {
        if kept.len() == count || score == 0 {
            break;
        }
        if kept
            .iter()
            .all(|&(t, _)| (t - turn).unsigned_abs() as usize > apart)
        {
            kept.push((turn, at));
        }
    }
    kept.into_iter()
        .map(|(turn, at)| {
            let (row, col) = ((at / side) as i64 - reach, (at % side) as i64 - reach);
            Pose2::new(
                guess.x + col as f64 * window.step_m,
                guess.y + row as f64 * window.step_m,
                guess.theta + turn as f64 * window.step_rad,
            )
        })
        .collect()
}

/// The reference's points drawn into cells: 2 on a point, 1 beside one.
struct Grid {
    origin: [f64; 2],
    cell: f64,
    width: i64,
    height: i64,
    scores: Vec<u8>,
}

impl Grid {
    /// The grid of `points`, with a margin of the window's reach and two cells around them;
    /// `None` when too large or a point is not finite.
    fn draw(points: &[[f64; 2]], window: &Window) -> Option<Grid> {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in points {
            if !(p[0].is_finite() && p[1].is_finite()) {
                return None;
            }
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let cell = window.step_m;
        let margin = window.half_m + 2.0 * cell;
        let origin = [lo[0] - margin, lo[1] - margin];
        let cells = |k: usize| ((hi[k] - lo[k] + 2.0 * margin) / cell).ceil() + 1.0;
        let (w, h) = (cells(0), cells(1));
        if !(w * h).is_finite() || w * h > MAX_CELLS as f64 {
            return None;
        }
        let (width, height) = (w as i64, h as i64);
        let mut scores = crate::memory::written_zeros::<u8>((width * height) as usize);
        for p in points {
            let (i, j) = (
                ((p[0] - origin[0]) / cell).floor() as i64,
                ((p[1] - origin[1]) / cell).floor() as i64,
            );
            for dj in -1..=1 {
                for di in -1..=1 {
                    let (x, y) = (i + di, j + dj);
                    if (0..width).contains(&x) && (0..height).contains(&y) {
                        let score = if di == 0 && dj == 0 { 2 } else { 1 };
                        let slot = &mut scores[(y * width + x) as usize];
                        *slot = (*slot).max(score);
                    }
                }
            }
        }
        Some(Grid {
            origin,
            cell,
            width,
            height,
            scores,
        })
    }

    /// Adds to `sums` (a square of `2 reach + 1` translations, row by row) the score under the
    /// point (`x`, `y`) moved by each translation of the window that keeps it on the grid (off
    /// the grid a point scores nothing).
    fn add_window(&self, x: f64, y: f64, reach: i64, sums: &mut [u32]) {
        let (i, j) = (
            ((x - self.origin[0]) / self.cell).floor(),
            ((y - self.origin[1]) / self.cell).floor(),
        );
        if !(i.is_finite() && j.is_finite()) {
            return;
        }
        let (i, j) = (i as i64, j as i64);
        let side = (2 * reach + 1) as usize;
        // The translations that keep the point's column on the grid: `lo..hi` of the row.
        let first = i - reach;
        let (lo, hi) = ((-first).max(0), (self.width - first).min(side as i64));
        if lo >= hi {
            return;
        }
        let (lo, hi) = (lo as usize, hi as usize);
        for (row, sum_row) in sums.chunks_exact_mut(side).enumerate() {
            let y = j - reach + row as i64;
            if !(0..self.height).contains(&y) {
                continue;
            }
            let start = (y * self.width + first + lo as i64) as usize;
            let cells = &self.scores[start..start + (hi - lo)];
            for (sum, &score) in sum_row[lo..hi].iter_mut().zip(cells) {
                *sum += u32::from(score);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The current scan: the reference's points seen from `truth`.
    fn seen_from(truth: Pose2, reference: &[[f64; 2]]) -> Vec<[f64; 2]> {
        let from = truth.inverse();
        reference
            .iter()
            .map(|&p| {
                let (x, y) = from.transform_point(p[0], p[1]);
                [x, y]
            })
            .collect()
    }

    /// An L of walls seen from the origin, and the same seen from a pose 40 cm and 20° away:
    /// from a guess at the origin the best start lies within a step of the truth.
    #[test]
    fn the_best_start_is_within_a_step_of_the_truth() {
        let mut reference = Vec::new();
        for k in 0..200 {
            let s = k as f64 * 0.05;
            reference.push([3.0, -4.0 + s]); // a wall ahead
            reference.push([-2.0 + s * 0.5, 2.5]); // a wall to the left
            reference.push([-1.0 + 0.01 * k as f64, -1.5 - 0.005 * k as f64]); // a slant
        }
        let truth = Pose2::new(0.4, -0.25, 20f64.to_radians());
        let current = seen_from(truth, &reference);
        let starts = best_starts(&reference, &current, Pose2::IDENTITY, &Window::WIDE, (3, 3));
        assert!(!starts.is_empty());
        let best = starts[0];
        assert!((best.x - truth.x).abs() <= 0.05 + 1e-9, "{best:?}");
        assert!((best.y - truth.y).abs() <= 0.05 + 1e-9, "{best:?}");
        assert!(
            (best.theta - truth.theta).abs() <= 1f64.to_radians() + 1e-9,
            "{best:?}"
        );
        // The other starts are other headings, at least three steps from the best.
        for s in &starts[1..] {
            assert!((s.theta - best.theta).abs() > 3.5f64.to_radians());
        }
    }

    /// Points the guess puts outside the reference's extent still count where a translation
    /// of the window brings them onto it: a wall and a stub seen from 35 cm down and left of
    /// the guess, every current point outside the reference's bounding box under the guess.
    #[test]
    fn points_off_the_references_extent_still_count() {
        // A wall along y, 3 m, and a stub along x, 30 cm: the reference is 30 cm wide.
        let mut reference = Vec::new();
        for k in 0..=6 {
            reference.push([k as f64 * 0.05, 0.0]);
        }
        for k in 1..=60 {
            reference.push([0.0, k as f64 * 0.05]);
        }
        let truth = Pose2::new(-0.35, -0.35, 0.0);
        let current = seen_from(truth, &reference);
        let guess = Pose2::new(-0.7, -0.7, 0.0);
        let starts = best_starts(&reference, &current, guess, &Window::WIDE, (1, 3));
        let best = starts[0];
        assert!((best.x - truth.x).abs() <= 0.05 + 1e-9, "{best:?}");
        assert!((best.y - truth.y).abs() <= 0.05 + 1e-9, "{best:?}");
        assert!(best.theta.abs() <= 1f64.to_radians() + 1e-9, "{best:?}");
    }

    /// Empty scans, a broken window and non-finite points give no start, without a panic.
    #[test]
    fn bad_input_gives_no_start() {
        let p = vec![[1.0, 0.0], [1.0, 0.5]];
        let w = Window::WIDE;
        assert!(best_starts(&[], &p, Pose2::IDENTITY, &w, (3, 3)).is_empty());
        assert!(best_starts(&p, &[], Pose2::IDENTITY, &w, (3, 3)).is_empty());
        let zero = Window { step_m: 0.0, ..w };
        assert!(best_starts(&p, &p, Pose2::IDENTITY, &zero, (3, 3)).is_empty());
        let nan = Window {
            half_rad: f64::NAN,
            ..w
        };
        assert!(best_starts(&p, &p, Pose2::IDENTITY, &nan, (3, 3)).is_empty());
        assert!(best_starts(&[[f64::NAN, 0.0]], &p, Pose2::IDENTITY, &w, (3, 3)).is_empty());
        let far = vec![[0.0, 0.0], [1e6, 1e6]];
        assert!(best_starts(&far, &p, Pose2::IDENTITY, &w, (3, 3)).is_empty());
        // A current point that is not finite is skipped.
        let starts = best_starts(
            &p,
            &[[f64::NAN, 1.0], [1.0, 0.0]],
            Pose2::IDENTITY,
            &w,
            (1, 1),
        );
        assert_eq!(starts.len(), 1);
    }
}
