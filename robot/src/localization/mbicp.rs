//! Metric-based ICP (Minguez, Montesano & Lamiraux 2005; 002 §2.2).
//!
//! The distance between a reference point `p` and a moved current point `c` is the norm of the
//! smallest rigid motion `q = (x, y, θ)` taking one onto the other, with `‖q‖² = x² + y² + L²θ²`;
//! linearised (002 eq. 2.29):
//!
//! ```text
//! d²(p, c) = |Δ|² − (Δ · (p_y, −p_x))² / (|p|² + L²),   Δ = c − p
//! ```
//!
//! so a point displaced along the circle around the sensor (a pure turn) is near. Each iteration
//! pairs every reference point with the current point (moved by the estimate `q_k`) nearest in
//! this metric, drops pairs farther than `max_distance_m`, minimises `Σ d²(p_i, q(c_i))` in closed
//! form (`q_min = −A⁻¹ b`, §2.2.2) and composes `q_{k+1} = q_min ⊕ q_k` (§2.2.4), until `q_min`
//! is below the thresholds or the iteration cap is reached.

use super::kdtree::KdTree;
use super::matcher::{Convergence, MatchResult, Reference, ScanMatcher, solve3, transform_all};
use super::scan::ScanPoints;
use crate::geometry::Pose2;

/// The MbICP matcher.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Mbicp {
    /// `L`, metres: how a turn weighs against a shift. 002 §2.2.1.2 finds 0.1–0.5 m works;
    /// default 0.5.
    pub l_m: f64,
    /// Pairs farther than this in the metric are dropped, metres. Default 0.3.
    pub max_distance_m: f64,
    /// When set, a reference point is paired with the nearest point (in the metric) on the
    /// segments joining the nearest current point to its neighbours in the scan, if they are
    /// closer together than this, metres — Minguez et al.'s interpolation, which removes the
    /// error of pairing points that sample a wall at different places. Default 0.3.
    pub interpolate_within_m: Option<f64>,
    /// Share of the pairs kept, the closest ones (Minguez et al.'s filter): the parts of one
    /// scan the other does not see would otherwise pull the least squares. Default 0.9.
    pub keep_fraction: f64,
    /// When to stop: `q_min` under 0.1 mm and 0.0001 rad, or 50 iterations.
    pub convergence: Convergence,
}

impl Default for Mbicp {
    fn default() -> Self {
        Mbicp {
            l_m: 0.5,
            max_distance_m: 0.3,
            interpolate_within_m: Some(0.3),
            keep_fraction: 0.9,
            convergence: Convergence {
                translation_m: 1e-4,
                rotation_rad: 1e-4,
                max_iterations: 50,
            },
        }
    }
}

impl Mbicp {
    /// The metric distance squared between reference point `p` and point `c` (002 eq. 2.29).
    pub fn distance2(&self, p: [f64; 2], c: [f64; 2]) -> f64 {
        let (dx, dy) = (c[0] - p[0], c[1] - p[1]);
        let k = p[0] * p[0] + p[1] * p[1] + self.l_m * self.l_m;
        let cross = dx * p[1] - dy * p[0];
        (dx * dx + dy * dy - cross * cross / k).max(0.0)
    }

    /// The point of segment `a`–`b` nearest to `p` in the metric, and its distance squared.
    fn nearest_on_segment(&self, p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> ([f64; 2], f64) {
        // d²(t) = (r + t u)ᵀ M (r + t u) with r = a − p, u = b − a, M = I − w wᵀ / k.
        let k = p[0] * p[0] + p[1] * p[1] + self.l_m * self.l_m;
        let w = [p[1], -p[0]];
        let m = |x: [f64; 2], y: [f64; 2]| {
            x[0] * y[0] + x[1] * y[1]
                - (x[0] * w[0] + x[1] * w[1]) * (y[0] * w[0] + y[1] * w[1]) / k
        };
        let (r, u) = ([a[0] - p[0], a[1] - p[1]], [b[0] - a[0], b[1] - a[1]]);
        let uu = m(u, u);
        let t = if uu > 0.0 {
            (-m(u, r) / uu).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let c = [a[0] + t * u[0], a[1] + t * u[1]];
        (c, self.distance2(p, c))
    }
}

impl ScanMatcher for Mbicp {
    fn name(&self) -> &'static str {
        "mbicp"
    }

    fn align(&self, reference: &Reference, current: &ScanPoints, guess: Pose2) -> MatchResult {
        if reference.points.is_empty() || current.is_empty() {
            return MatchResult::unmatched(guess);
        }
        // The tree holds the current points in their own frame: a reference point is brought into
        // that frame for the search, while the metric is measured in the reference frame.
        let tree = KdTree::new(&current.xy);
        let l2 = self.l_m * self.l_m;
        let gate = self.max_distance_m * self.max_distance_m;
        let mut q = guess;
        let mut moved = Vec::with_capacity(current.len());
        let mut pairs = Vec::with_capacity(reference.points.len());
        let mut hints = vec![None; reference.points.len()];
        let mut result = MatchResult::unmatched(guess);
        for iteration in 1..=self.convergence.max_iterations {
            transform_all(&q, &current.xy, &mut moved);
            let back = q.inverse();
            pairs.clear();
            for (i, &p) in reference.points.xy.iter().enumerate() {
                let k = p[0] * p[0] + p[1] * p[1] + l2;
                // d² ≥ |Δ|² L² / k, and |Δ| is at least the gap to a splitting line.
                let (qx, qy) = back.transform_point(p[0], p[1]);
                let Some((j, d2)) = tree.nearest_by([qx, qy], l2 / k, hints[i], |j, _| {
                    self.distance2(p, moved[j])
                }) else {
                    continue;
                };
                hints[i] = Some(j);
                let (mut c, mut d2) = (moved[j], d2);
                if let Some(within) = self.interpolate_within_m {
                    for n in [j.wrapping_sub(1), j + 1] {
                        let Some(&other) = moved.get(n) else { continue };
                        let (dx, dy) = (other[0] - moved[j][0], other[1] - moved[j][1]);
                        if dx * dx + dy * dy < within * within {
                            let (on, e2) = self.nearest_on_segment(p, moved[j], other);
                            if e2 < d2 {
                                (c, d2) = (on, e2);
                            }
                        }
                    }
                }
                if d2 <= gate {
                    pairs.push((d2, p, c, k));
                }
            }
            if self.keep_fraction < 1.0 && !pairs.is_empty() {
                let keep = ((pairs.len() as f64 * self.keep_fraction).ceil() as usize).max(1);
                pairs.select_nth_unstable_by(keep - 1, |x, y| x.0.total_cmp(&y.0));
                pairs.truncate(keep);
            }
            let (mut a, mut b) = ([[0.0; 3]; 3], [0.0; 3]);
            for &(_, p, c, k) in &pairs {
                accumulate(&mut a, &mut b, p, c, k);
            }
            result.iterations = iteration;
            result.correspondences = pairs.len();
            let Some(step) = (pairs.len() >= 3)
                .then(|| solve3(a, [-b[0], -b[1], -b[2]]))
                .flatten()
            else {
                result.pose = q;
                return result;
            };
            let q_min = Pose2::new(step[0], step[1], step[2]);
            q = q_min.compose(&q);
            result.pose = q;
            if self.convergence.reached(&q_min) {
                result.converged = true;
                return result;
            }
        }
        result
    }
}

/// Adds one pair to the normal equations of `Σ d²(p, q(c))` with `q(c)` linearised about the
/// identity: `δ = J q + (c − p)`, `J = [[1, 0, −c_y], [0, 1, c_x]]`, `d² = δᵀ M δ` with
/// `M = I − w wᵀ / k`, `w = (p_y, −p_x)`; so `A += Jᵀ M J`, `b += Jᵀ M (c − p)` — the sums of
/// 002 §2.2.2 (e.g. `a11 = Σ 1 − p_y²/k`, `a12 = Σ p_x p_y / k`).
fn accumulate(a: &mut [[f64; 3]; 3], b: &mut [f64; 3], p: [f64; 2], c: [f64; 2], k: f64) {
    let (w0, w1) = (p[1], -p[0]);
    let m = [
        [1.0 - w0 * w0 / k, -w0 * w1 / k],
        [-w0 * w1 / k, 1.0 - w1 * w1 / k],
    ];
    // Columns of J: e_x, e_y and (−c_y, c_x).
    let j = [[1.0, 0.0], [0.0, 1.0], [-c[1], c[0]]];
    let r = [c[0] - p[0], c[1] - p[1]];
    let mv = |v: [f64; 2]| {
        [
            m[0][0] * v[0] + m[0][1] * v[1],
            m[1][0] * v[0] + m[1][1] * v[1],
        ]
    };
    let mj = [mv(j[0]), mv(j[1]), mv(j[2])];
    let mr = mv(r);
    for row in 0..3 {
        for col in 0..3 {
            a[row][col] += j[row][0] * mj[col][0] + j[row][1] * mj[col][1];
        }
        b[row] += j[row][0] * mr[0] + j[row][1] * mr[1];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_metric_forgives_turns_and_not_shifts() {
        let m = Mbicp::default();
        let p = [4.0, 0.0];
        // A 0.1 m move along the circle (a turn) against the same move along the ray.
        let along_circle = m.distance2(p, [4.0, 0.1]);
        let along_ray = m.distance2(p, [4.1, 0.0]);
        assert!(
            along_circle < 0.1 * along_ray,
            "{along_circle} vs {along_ray}"
        );
        assert!((along_ray - 0.01).abs() < 1e-12);
        // L → ∞ gives the Euclidean distance.
        let euclid = Mbicp { l_m: 1e9, ..m };
        assert!((euclid.distance2(p, [4.0, 0.1]) - 0.01).abs() < 1e-9);
    }

    #[test]
    fn normal_equations_match_the_thesis_sums() {
        let (p, c, l) = ([1.3, -0.4], [1.1, 0.2], 0.3);
        let k = p[0] * p[0] + p[1] * p[1] + l * l;
        let (mut a, mut b) = ([[0.0; 3]; 3], [0.0; 3]);
        accumulate(&mut a, &mut b, p, c, k);
        let cp = c[0] * p[0] + c[1] * p[1];
        let cross = c[0] * p[1] - c[1] * p[0];
        let close = |x: f64, y: f64| (x - y).abs() < 1e-12;
        assert!(close(a[0][0], 1.0 - p[1] * p[1] / k));
        assert!(close(a[0][1], p[0] * p[1] / k));
        assert!(close(a[0][2], -c[1] + p[1] / k * cp));
        assert!(close(a[1][1], 1.0 - p[0] * p[0] / k));
        assert!(close(a[1][2], c[0] - p[0] / k * cp));
        assert!(close(a[2][2], c[0] * c[0] + c[1] * c[1] - cp * cp / k));
        assert!(close(b[0], c[0] - p[0] - p[1] / k * cross));
        assert!(close(b[1], c[1] - p[1] + p[0] / k * cross));
        assert!(close(b[2], (cp / k - 1.0) * cross));
    }
}
