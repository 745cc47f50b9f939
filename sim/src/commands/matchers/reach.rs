//! What a pair's pose given as truth can judge, asked of the scans alone, with no matcher.
//!
//! A corrected log's poses are SLAM estimates. Where one is off by about the row's tolerance, a
//! matcher's success there says which side of the tolerance its answer stopped on, not whether
//! it was right. So each pair's poses are scored by the scans (the number of current points
//! within a band of the reference scan's surfaces, the trust rule's inlier count,
//! [`TrustRule::assess`]), and the best of those inside the pair's *success region* (within
//! the tolerance of the given pose) is compared with the best outside it:
//!
//! - [`Reach::Out`]: the best inside fits the margin's share of the current points fewer than
//!   the best outside: a matcher is counted right there only by an answer the scans fit worse;
//! - [`Reach::Undecided`]: poses on both sides fit within the margin of the best: the scans do
//!   not say which side of the tolerance the robot was on;
//! - [`Reach::Decided`]: every pose that fits within the margin of the best is inside.
//!
//! The search: a grid of 2 cm and 0.2° out to 16 cm and 3.2° around the given pose, hill
//! climbs (1 cm and 0.1° down to 1 mm and 0.01°) from the six best grid poses on each side,
//! kept on their side, and from the five best starts of a coarse correlative search over 40 cm
//! and 6°; a pair that looks out of reach is searched again inside, on a grid of 1 cm and 0.05°
//! with twenty climbs, before it is called so. It is a search, not a proof: the best pose
//! inside is the best found. `cargo run --release --example reach` prints it for the corrected
//! logs.

use super::{Case, off_truth};
use robot::Pose2;
use robot::localization::correlative::{Window, best_starts};
use robot::localization::{Reference, TrustRule};
use std::cmp::Reverse;

/// Where the poses that fit a pair best lie against its success region.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Reach {
    /// Every pose that fits within the margin of the best is inside the success region.
    Decided,
    /// Poses inside and outside fit within the margin of the best.
    Undecided,
    /// The best pose inside fits the margin fewer points than the best outside.
    Out,
}

/// A pose and its score: the current points within the band of the reference's surfaces.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Scored {
    /// Its score.
    pub points: usize,
    /// The current frame in the reference frame.
    pub pose: Pose2,
}

/// What the scans say of one pair.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Judged {
    /// The verdict.
    pub reach: Reach,
    /// The current scan's points.
    pub points: usize,
    /// The score of the pose given as truth.
    pub at_truth: usize,
    /// The best pose found inside the success region.
    pub inside: Scored,
    /// The best pose found outside it.
    pub outside: Scored,
}

/// How a pair is judged: the band that makes a point fit, the margin, and the success region.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Judge {
    /// A current point this near the reference's surface fits, metres.
    pub band_m: f64,
    /// The share of the current points one side must fit more to decide.
    pub margin: f64,
    /// The success region's reach in translation, metres …
    pub tolerance_m: f64,
    /// … and in heading, radians.
    pub tolerance_rad: f64,
}

impl Judge {
    /// The laser's stated accuracy (±2 cm) as the band, a margin of 5 points in 100, and the
    /// real rows' tolerance (10 cm and 2°).
    pub const LASER: Judge = Judge {
        band_m: 0.02,
        margin: 0.05,
        tolerance_m: 0.10,
        tolerance_rad: 0.034_906_585_039_886_59,
    };

    /// What the scans of `case` say of its truth.
    pub fn judge(&self, case: &Case) -> Judged {
        let reference = Reference::new(case.reference.points());
        let current = case.current.points().xy;
        let truth = case.truth;
        let rule = TrustRule {
            inlier_m: self.band_m,
            ..TrustRule::default()
        };
        let score = |pose: Pose2| Scored {
            points: rule.assess(&reference, &current, &pose).inliers,
            pose,
        };
        let inside = |p: &Pose2| {
            let (m, rad) = off_truth(case, p);
            m <= self.tolerance_m && rad <= self.tolerance_rad
        };
        let outside = |p: &Pose2| !inside(p);
        let best = |a: Scored, b: Scored| if b.points > a.points { b } else { a };

        // The coarse grid around the truth, each pose to its side.
        let (grid_in, grid_out): (Vec<_>, Vec<_>) = grid(truth, 8, 0.02, 16, 0.2f64.to_radians())
            .map(score)
            .partition(|s| inside(&s.pose));
        let climbed = |grid: Vec<Scored>, keep: &dyn Fn(&Pose2) -> bool, starts: usize| {
            best_first(grid)
                .into_iter()
                .take(starts)
                .map(|s| climb(&score, s, keep))
                .reduce(best)
        };
        // The truth is inside; the outside always has grid poses (the grid reaches past the
        // tolerance), so its best is never the truth.
        let at_truth = score(truth);
        let mut best_in = climbed(grid_in, &inside, 6).map_or(at_truth, |s| best(at_truth, s));
        let mut best_out = climbed(grid_out, &outside, 6).unwrap_or(Scored {
            points: 0,
            pose: truth,
        });
        // Starts from farther out: where most current points fall on or beside the reference's.
        let window = Window {
            half_m: 0.4,
            step_m: 0.02,
            half_rad: 6f64.to_radians(),
            step_rad: 0.25f64.to_radians(),
        };
        for start in best_starts(&reference.points.xy, &current, truth, &window, (5, 2)) {
            let found = climb(&score, score(start), &|_| true);
            if inside(&found.pose) {
                best_in = best(best_in, found);
            } else {
                best_out = best(best_out, found);
            }
        }
        // At least one point: a scan with nothing to fit (no returns) puts no side ahead.
        let slack = ((self.margin * current.len() as f64).ceil() as usize).max(1);
        if best_in.points + slack <= best_out.points {
            // Out of reach is claimed only after a closer look inside.
            let fine = grid(truth, 10, 0.01, 40, 0.05f64.to_radians())
                .filter(inside)
                .map(score)
                .collect();
            if let Some(found) = climbed(fine, &inside, 20) {
                best_in = best(best_in, found);
            }
        }
        let top = best_in.points.max(best_out.points);
        let reach = if best_in.points + slack <= top {
            Reach::Out
        } else if best_out.points + slack > top {
            Reach::Undecided
        } else {
            Reach::Decided
        };
        Judged {
            reach,
            points: current.len(),
            at_truth: at_truth.points,
            inside: best_in,
            outside: best_out,
        }
    }
}

/// Poses around `center` on a grid: translations within a disc of `reach` steps of `step_m`,
/// headings up to `turns` steps of `step_rad` each way, in the center's frame.
fn grid(
    center: Pose2,
    reach: i32,
    step_m: f64,
    turns: i32,
    step_rad: f64,
) -> impl Iterator<Item = Pose2> {
    (-reach..=reach)
        .flat_map(move |i| (-reach..=reach).map(move |j| (i, j)))
        .filter(move |(i, j)| i * i + j * j <= reach * reach)
        .flat_map(move |(i, j)| {
            (-turns..=turns).map(move |t| {
                center.compose(&Pose2::new(
                    f64::from(i) * step_m,
                    f64::from(j) * step_m,
                    f64::from(t) * step_rad,
                ))
            })
        })
}

/// Highest score first; a stable sort, so equal scores keep the grid's order and the verdict
/// depends on the points alone.
fn best_first(mut poses: Vec<Scored>) -> Vec<Scored> {
    poses.sort_by_key(|s| Reverse(s.points));
    poses
}

/// Coordinate ascent from `start`, in steps of 1 cm and 0.1° down to 1 mm and 0.01°, moving
/// only to poses `keep` accepts and only when the score rises.
fn climb(score: &dyn Fn(Pose2) -> Scored, start: Scored, keep: &dyn Fn(&Pose2) -> bool) -> Scored {
    let mut at = start;
    for (step_m, step_deg) in [(0.01, 0.1f64), (0.005, 0.05), (0.002, 0.02), (0.001, 0.01)] {
        let step_rad = step_deg.to_radians();
        let moves = [
            (step_m, 0.0, 0.0),
            (-step_m, 0.0, 0.0),
            (0.0, step_m, 0.0),
            (0.0, -step_m, 0.0),
            (0.0, 0.0, step_rad),
            (0.0, 0.0, -step_rad),
        ];
        loop {
            let before = at.points;
            for (dx, dy, dt) in moves {
                let p = Pose2::new(at.pose.x + dx, at.pose.y + dy, at.pose.theta + dt);
                if keep(&p) {
                    let s = score(p);
                    if s.points > at.points {
                        at = s;
                    }
                }
            }
            if at.points == before {
                break;
            }
        }
    }
    at
}

#[cfg(test)]
mod tests {
    use super::*;
    use robot::localization::RangeScan;

    /// A scan that returned nothing has no point to fit: neither side is ahead, so the pair is
    /// undecided, not out of reach, and nothing panics.
    #[test]
    fn a_scan_without_returns_decides_nothing() {
        let empty = RangeScan::new(-1.5, 0.0087, 32.0, vec![32.0; 361]);
        let wall = RangeScan::new(-1.5, 0.0087, 32.0, vec![2.0; 361]);
        for (reference, current) in [(&empty, &wall), (&wall, &empty), (&empty, &empty)] {
            let case = Case {
                reference: reference.clone(),
                current: current.clone(),
                truth: Pose2::new(0.1, 0.0, 0.0),
                guess: Pose2::new(0.1, 0.0, 0.0),
            };
            let judged = Judge::LASER.judge(&case);
            assert_eq!(judged.reach, Reach::Undecided, "{judged:?}");
            assert_eq!(
                judged.inside.points + judged.outside.points,
                0,
                "{judged:?}"
            );
        }
    }
}
