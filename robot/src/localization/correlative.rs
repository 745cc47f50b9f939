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
use std::ops::{AddAssign, Mul};

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

/// Grids larger than this many cells are not drawn (a reference hundreds of metres across),
/// nor windows of more translations: no start is offered.
const MAX_CELLS: usize = 4_000_000;

/// Windows of more headings each way than this are not searched (a step of a thousandth of a
/// degree over half a turn): no start is offered.
const MAX_TURNS: usize = 200_000;

/// Up to `count` poses of `window` around `guess` where the most of `current`'s points (in
/// its own frame) fall on or beside `reference`'s (in the reference's frame), best first: the
/// best translation of each heading, headings at least `apart` steps from a better one. Ties
/// keep the pose met first (headings from the most clockwise, translations row by row), so the
/// answer does not depend on anything but the points. Empty when either scan has no point, the
/// window is not a window (a step not positive, a half-width negative or not finite, more than
/// 4,000,000 translations or 200,000 headings each way), or the reference spreads too wide
/// for a grid.
///
/// Two economies, neither of which changes an answer: neighbours in the scan that fall in one
/// cell are added once with their count as weight, and the scores are added up in 16 bits (a
/// point adds at most 2) when the scan has at most 32,767 points, so that twice as many
/// translations fit in a vector register. Together they bring the search to 0.52–0.71 of its
/// time without them on the pairs of `twin matchers` (`cargo bench --bench coarse_search`,
/// against [`best_starts_plain`]).
pub fn best_starts(
    reference: &[[f64; 2]],
    current: &[[f64; 2]],
    guess: Pose2,
    window: &Window,
    (count, apart): (usize, usize),
) -> Vec<Pose2> {
    search(reference, current, guess, window, (count, apart), true)
}

/// [`best_starts`] without its economies, point by point in 32-bit sums: the reference its
/// answers are tested and its time measured against.
pub fn best_starts_plain(
    reference: &[[f64; 2]],
    current: &[[f64; 2]],
    guess: Pose2,
    window: &Window,
    (count, apart): (usize, usize),
) -> Vec<Pose2> {
    search(reference, current, guess, window, (count, apart), false)
}

/// [`best_starts`], with its economies when `economies`, else as [`best_starts_plain`].
fn search(
    reference: &[[f64; 2]],
    current: &[[f64; 2]],
    guess: Pose2,
    window: &Window,
    (count, apart): (usize, usize),
    economies: bool,
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
    let (reach, turns) = (
        (window.half_m / window.step_m).floor(),
        (window.half_rad / window.step_rad).floor(),
    );
    if (2.0 * reach + 1.0).powi(2) > MAX_CELLS as f64 || turns > MAX_TURNS as f64 {
        return Vec::new();
    }
    let (reach, turns) = (reach as i64, turns as i64);
    // Each point adds at most 2 to a translation's score: sums of 16 bits hold up to 32,767
    // points, and twice as many fit in a vector register as of 32 bits.
    let mut bests = if economies && current.len() <= usize::from(u16::MAX / 2) {
        heading_bests::<u16>(&grid, current, guess, window, (reach, turns), true)
    } else {
        heading_bests::<u32>(&grid, current, guess, window, (reach, turns), economies)
    };
    let side = (2 * reach + 1) as usize;
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

/// For each heading of the window from the most clockwise, (score, heading index,
/// translation index) of its best translation, the first met among equals; `Sum` the type
/// the scores are added up in, wide enough for twice the points; with `merge`, neighbours
/// in the scan that share a cell added once with their count as weight.
fn heading_bests<Sum>(
    grid: &Grid,
    current: &[[f64; 2]],
    guess: Pose2,
    window: &Window,
    (reach, turns): (i64, i64),
    merge: bool,
) -> Vec<(u32, i64, usize)>
where
    Sum: Copy + Ord + Default + AddAssign + Mul<Output = Sum> + From<u8> + From<u16> + Into<u32>,
{
    let side = (2 * reach + 1) as usize;
    let mut sums = vec![Sum::default(); side * side];
    let mut bests = Vec::with_capacity((2 * turns + 1) as usize);
    let mut moved = Vec::with_capacity(current.len());
    // The moved points' cells, each with the count of the points it stands for.
    let mut cells: Vec<(i64, i64, u16)> = Vec::with_capacity(current.len());
    for turn in -turns..=turns {
        let theta = guess.theta + turn as f64 * window.step_rad;
        transform_all(&Pose2::new(guess.x, guess.y, theta), current, &mut moved);
        cells.clear();
        for (i, j) in moved.iter().filter_map(|p| grid.cell_of(p[0], p[1])) {
            match cells.last_mut() {
                Some((a, b, count)) if merge && (*a, *b) == (i, j) && *count < u16::MAX => {
                    *count += 1
                }
                _ => cells.push((i, j, 1)),
            }
        }
        sums.fill(Sum::default());
        for &(i, j, count) in &cells {
            grid.add_window(i, j, Sum::from(count), reach, &mut sums);
        }
        let (best, &score) =
            sums.iter().enumerate().fold(
                (0, &Sum::default()),
                |b, (k, v)| if *v > *b.1 { (k, v) } else { b },
            );
        bests.push((score.into(), turn, best));
    }
    bests
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

    /// The cell under (`x`, `y`) as (column, row), which may lie off the grid; `None` when
    /// not finite or so far off (2^40 cells) that no window could bring it on.
    fn cell_of(&self, x: f64, y: f64) -> Option<(i64, i64)> {
        let (i, j) = (
            ((x - self.origin[0]) / self.cell).floor(),
            ((y - self.origin[1]) / self.cell).floor(),
        );
        const FAR: f64 = (1u64 << 40) as f64;
        (i.abs() < FAR && j.abs() < FAR).then_some((i as i64, j as i64))
    }

    /// Adds to `sums` (a square of `2 reach + 1` translations, row by row) `weight` times the
    /// score under the cell (`i`, `j`) moved by each translation of the window that keeps it
    /// on the grid (off the grid a point scores nothing).
    fn add_window<Sum>(&self, i: i64, j: i64, weight: Sum, reach: i64, sums: &mut [Sum])
    where
        Sum: Copy + AddAssign + Mul<Output = Sum> + From<u8>,
    {
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
                *sum += weight * Sum::from(score);
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
        // A window of absurd size: more translations or headings than can be searched.
        let fine = Window { step_m: 1e-6, ..w };
        assert!(best_starts(&p, &p, Pose2::IDENTITY, &fine, (3, 3)).is_empty());
        let turning = Window {
            step_rad: 1e-12,
            ..w
        };
        assert!(best_starts(&p, &p, Pose2::IDENTITY, &turning, (3, 3)).is_empty());
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

    /// A deterministic stream of numbers in [0, 1) for the tests (xorshift).
    struct Stream(u64);

    impl Stream {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn within(&mut self, half: f64) -> f64 {
            (2.0 * self.next() - 1.0) * half
        }
    }

    /// The search with its economies answers what the plain search answers, to the pose:
    /// rooms of walls and clutter, their walls sampled 1-6 cm apart (so that neighbours share
    /// cells, or not), seen from poses up to a metre and 40° from the guess (the best inside
    /// the window, at its edge or outside it), with outliers, points far off the grid, runs
    /// of points on one spot; windows of several sizes, one of a single translation; scores
    /// tied by symmetric rooms, and no point scoring at all.
    #[test]
    fn the_economies_change_no_answer() {
        let windows = [
            Window::WIDE,
            Window {
                half_m: 0.4,
                step_m: 0.02,
                half_rad: 6f64.to_radians(),
                step_rad: 0.25f64.to_radians(),
            },
            Window {
                half_m: 0.0,
                step_m: 0.05,
                half_rad: 2f64.to_radians(),
                step_rad: 1f64.to_radians(),
            },
        ];
        let mut stream = Stream(0x9e37_79b9_7f4a_7c15);
        let (mut compared, mut tied, mut merged) = (0, 0, 0);
        for case in 0..40 {
            let (w, h) = (4.0 + 8.0 * stream.next(), 3.0 + 5.0 * stream.next());
            let spacing = 0.01 + 0.05 * stream.next();
            let mut reference = Vec::new();
            let wall = |a: [f64; 2], b: [f64; 2], reference: &mut Vec<[f64; 2]>| {
                let n = ((b[0] - a[0]).hypot(b[1] - a[1]) / spacing).ceil() as usize;
                for k in 0..=n {
                    let t = k as f64 / n as f64;
                    reference.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
                }
            };
            let symmetric = case % 8 == 0;
            let (x, y) = (w / 2.0, h / 2.0);
            wall([-x, -y], [x, -y], &mut reference);
            wall([x, -y], [x, y], &mut reference);
            wall([x, y], [-x, y], &mut reference);
            wall([-x, y], [-x, -y], &mut reference);
            if !symmetric {
                for _ in 0..3 {
                    let (a, b) = (stream.within(w / 3.0), stream.within(h / 3.0));
                    wall([a, b], [a + 0.4, b + 0.2], &mut reference);
                }
            }
            let truth = Pose2::new(
                stream.within(1.0),
                stream.within(1.0),
                stream.within(40f64.to_radians()),
            );
            let mut current = seen_from(truth, &reference);
            for p in current.iter_mut() {
                if stream.next() < 0.1 {
                    // An outlier anywhere within 15 m, some off the grid.
                    *p = [stream.within(15.0), stream.within(15.0)];
                } else {
                    p[0] += stream.within(0.01);
                    p[1] += stream.within(0.01);
                }
            }
            if case % 5 == 3 {
                current.extend([[1e9, -1e9], [f64::INFINITY, 0.0], [0.5, 0.5], [0.5, 0.5]]);
                current.extend([[0.5, 0.5]; 40]);
            }
            if case % 13 == 5 {
                // Nothing near: no pose scores.
                current = vec![[400.0, 400.0], [401.0, 400.0]];
            }
            let guess = Pose2::new(
                stream.within(0.5),
                stream.within(0.5),
                stream.within(10f64.to_radians()),
            );
            merged += usize::from(spacing < 0.03);
            for window in &windows {
                for (count, apart) in [(1, 0), (3, 3), (12, 1)] {
                    let starts = (count, apart);
                    let fast = best_starts(&reference, &current, guess, window, starts);
                    let plain = best_starts_plain(&reference, &current, guess, window, starts);
                    assert_eq!(fast, plain, "case {case}, {window:?}, {starts:?}");
                    compared += 1;
                    tied += usize::from(symmetric && !plain.is_empty());
                }
            }
        }
        assert_eq!(compared, 40 * 3 * 3);
        assert!(tied > 0 && merged > 0, "{tied} tied, {merged} merged");
    }

    /// A scan of more points than 16-bit sums hold (40,000 on one wall: 80,000 on a pose)
    /// is added up in 32 bits, and answers as the plain search does.
    #[test]
    fn a_scan_too_large_for_short_sums_is_added_up_wide() {
        let reference: Vec<[f64; 2]> = (0..400).map(|k| [2.0, -2.0 + 0.01 * k as f64]).collect();
        let current: Vec<[f64; 2]> = (0..40_000)
            .map(|k| [1.8, -0.5 + 0.000_025 * k as f64])
            .collect();
        let window = Window {
            half_m: 0.3,
            step_m: 0.05,
            half_rad: 0.0,
            step_rad: 1f64.to_radians(),
        };
        let fast = best_starts(&reference, &current, Pose2::IDENTITY, &window, (1, 0));
        let plain = best_starts_plain(&reference, &current, Pose2::IDENTITY, &window, (1, 0));
        assert_eq!(fast, plain);
        // The wall 20 cm ahead of where the points lie: the start moves them onto it.
        assert!((fast[0].x - 0.2).abs() < 0.05 + 1e-9, "{fast:?}");
    }
}
