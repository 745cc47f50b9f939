//! Point-to-point least-squares ICP: the baseline the thesis shows failing with outliers (§5.2).

use super::matcher::{Convergence, MatchResult, Reference, ScanMatcher, transform_all};
use super::scan::ScanPoints;
use crate::geometry::Pose2;

/// Point-to-point ICP with the closed-form least-squares step.
///
/// Each iteration pairs every current point (moved by the estimate) with its nearest reference
/// point and takes the rigid transform minimising the sum of squared distances of the pairs
/// (centroids and the cross-covariance angle, Besl & McKay), composed onto the estimate.
/// Every pair counts as much as its squared distance: one outlier 5 m off weighs as much as
/// 2,500 points 10 cm off, which is why it fails on noisy scans.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct LeastSquares {
    /// Pairs farther apart than this (metres) are left out. Default: unlimited, the thesis's
    /// plain least squares.
    pub max_distance_m: f64,
    /// When to stop. Default: a step under 0.01 mm and 0.0001°, or 100 iterations.
    pub convergence: Convergence,
}

impl Default for LeastSquares {
    fn default() -> Self {
        LeastSquares {
            max_distance_m: f64::INFINITY,
            convergence: Convergence {
                translation_m: 1e-5,
                rotation_rad: 1e-4_f64.to_radians(),
                max_iterations: 100,
            },
        }
    }
}

impl ScanMatcher for LeastSquares {
    fn name(&self) -> &'static str {
        "ls"
    }

    fn align_plausible(
        &self,
        reference: &Reference,
        current: &ScanPoints,
        guess: Pose2,
    ) -> MatchResult {
        let gate = self.max_distance_m * self.max_distance_m;
        let mut pose = guess;
        let mut moved = Vec::with_capacity(current.len());
        let mut result = MatchResult::unmatched(guess);
        // Each point's last nearest reference point (the search skipped while it cannot change).
        let mut last = vec![None; current.len()];
        for iteration in 1..=self.convergence.max_iterations {
            transform_all(&pose, &current.xy, &mut moved);
            // Sums for the closed form: centroids and cross terms of the pairs.
            let (mut n, mut sp, mut sq) = (0usize, [0.0; 2], [0.0; 2]);
            let mut pairs = Vec::with_capacity(moved.len());
            for (i, p) in moved.iter().enumerate() {
                let Some((j, d2)) = reference.tree.nearest_cached(*p, &mut last[i]) else {
                    continue;
                };
                if d2 <= gate {
                    let q = reference.points.xy[j];
                    pairs.push((*p, q));
                    n += 1;
                    sp = [sp[0] + p[0], sp[1] + p[1]];
                    sq = [sq[0] + q[0], sq[1] + q[1]];
                }
            }
            result.iterations = iteration;
            result.correspondences = n;
            if n < 2 {
                result.pose = pose;
                return result;
            }
            let inv = 1.0 / n as f64;
            let (mp, mq) = ([sp[0] * inv, sp[1] * inv], [sq[0] * inv, sq[1] * inv]);
            let (mut dot, mut cross) = (0.0, 0.0);
            for (p, q) in &pairs {
                let (px, py) = (p[0] - mp[0], p[1] - mp[1]);
                let (qx, qy) = (q[0] - mq[0], q[1] - mq[1]);
                dot += px * qx + py * qy;
                cross += px * qy - py * qx;
            }
            let theta = cross.atan2(dot);
            let (s, c) = theta.sin_cos();
            let step = Pose2::new(
                mq[0] - (c * mp[0] - s * mp[1]),
                mq[1] - (s * mp[0] + c * mp[1]),
                theta,
            );
            pose = step.compose(&pose);
            result.pose = pose;
            if self.convergence.reached(&step) {
                result.settled = true;
                return result;
            }
        }
        result
    }
}
