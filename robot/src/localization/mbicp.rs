//! Metric-based ICP (Minguez, Montesano & Lamiraux 2005; 002 §2.2).
//!
//! The distance between a point `p` of one scan and a point `c` of the other, both in `p`'s
//! sensor frame, is the norm of the smallest rigid motion `q = (x, y, θ)` taking one onto the
//! other, with `‖q‖² = x² + y² + L²θ²`; linearised (002 eq. 2.29):
//!
//! ```text
//! d²(p, c) = |Δ|² − (Δ · (p_y, −p_x))² / (|p|² + L²),   Δ = c − p
//! ```
//!
//! so a point displaced along the circle around the sensor (a pure turn) is near. Each iteration
//! pairs every current point `p` with the reference point nearest in this metric — the reference
//! moved into the current frame by the estimate, interpolated along the reference scan — drops
//! pairs farther than `max_distance_m` and points beyond what the reference saw,
//! minimises `Σ d²(p_i, c_i)` in closed form (`q_min = −A⁻¹ b`, §2.2.2) and composes the
//! correction (§2.2.4), until it is below the thresholds or the iteration cap is reached.
//!
//! 002's App. D loops the other way, over the reference points. After a 0.5 m advance down a
//! corridor half of the reference scan (the side walls just beside the robot) is out of the
//! current scan's view, and those points drag the estimate back by 0.2 m; pairing the current
//! points and dropping those beyond the ends of the reference's segments removes that bias for
//! advances and retreats alike (the L-corridor test of App. E, `tests/issue_4_localisation.rs`).

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
    /// When set, a current point is paired with the nearest point (in the metric) on the
    /// segments joining the nearest reference point to its neighbours in the scan, if they are
    /// closer together than this, metres — Minguez et al.'s interpolation, which removes the
    /// error of pairing points that sample a wall at different places. Default 0.3.
    pub interpolate_within_m: Option<f64>,
    /// Share of the pairs kept, the closest ones (Minguez et al.'s filter): the parts of one
    /// scan the other does not see would otherwise pull the least squares. Default 0.9.
    pub keep_fraction: f64,
    /// Leave out a current point that lies beyond what the reference saw: nearest to a
    /// reference point where no segment continues on one side (the scan's ends, a gap, an
    /// occlusion) rather than to a point inside a segment. After a retreat half a corridor
    /// scan is such points, and they would drag the estimate back. Default true.
    pub drop_edge_pairs: bool,
    /// Acceleration, after Besl & McKay's accelerated ICP (002's ref. \[2\]): when two successive
    /// corrections point the same way (within 10°) and shrink by `ρ`, also take the geometric
    /// remainder `ρ / (1 − ρ)` of the last one, but no longer than this, metres in
    /// `(x, y, Lθ)`. Along a wall the iteration otherwise creeps (29 iterations a twin pair
    /// instead of 15). Default 0.02.
    pub extrapolate_up_to_m: Option<f64>,
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
            drop_edge_pairs: true,
            extrapolate_up_to_m: Some(0.02),
            convergence: Convergence {
                translation_m: 1e-4,
                rotation_rad: 1e-4,
                max_iterations: 50,
            },
        }
    }
}

impl Mbicp {
    /// The metric distance squared between point `p` and point `c`, in `p`'s sensor frame (002 eq. 2.29).
    pub fn distance2(&self, p: [f64; 2], c: [f64; 2]) -> f64 {
        let (dx, dy) = (c[0] - p[0], c[1] - p[1]);
        let k = p[0] * p[0] + p[1] * p[1] + self.l_m * self.l_m;
        let cross = dx * p[1] - dy * p[0];
        (dx * dx + dy * dy - cross * cross / k).max(0.0)
    }

    /// The nearest point to `p` on the segments from `points[j]` (at metric distance² `d2`) to
    /// its neighbours in the scan, when they are close enough to sample the same surface; and
    /// whether `p` lies beyond what the scan saw: nearest to `points[j]` itself where no
    /// segment continues on one side (the scan's end, a gap, an occlusion).
    fn interpolate(
        &self,
        p: [f64; 2],
        points: &[[f64; 2]],
        j: usize,
        d2: f64,
    ) -> ([f64; 2], f64, bool) {
        // Without interpolation every neighbour continues the scan: only its ends are edges.
        let within = self.interpolate_within_m.unwrap_or(f64::INFINITY);
        let (mut best, mut segments, mut inside) = ((points[j], d2), 0, false);
        for n in [j.wrapping_sub(1), j + 1] {
            let Some(&other) = points.get(n) else {
                continue;
            };
            let (dx, dy) = (other[0] - points[j][0], other[1] - points[j][1]);
            if dx * dx + dy * dy < within * within {
                segments += 1;
                if self.interpolate_within_m.is_none() {
                    continue;
                }
                let (on, e2) = self.nearest_on_segment(p, points[j], other);
                if e2 < best.1 {
                    (best, inside) = ((on, e2), true);
                }
            }
        }
        (best.0, best.1, segments < 2 && !inside)
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

    fn align_plausible(
        &self,
        reference: &Reference,
        current: &ScanPoints,
        guess: Pose2,
    ) -> MatchResult {
        // Each current point `p`, in its own frame (the metric is centred on the sensor that
        // measured it), is paired with the reference points brought into that frame by the
        // estimate `r = q⁻¹`; the search runs in the reference's own tree, with `p` taken into the
        // reference frame, since Euclidean gaps are the same in both frames.
        let l2 = self.l_m * self.l_m;
        let gate = self.max_distance_m * self.max_distance_m;
        let mut r = guess.inverse();
        let mut moved = Vec::with_capacity(reference.points.len());
        let mut pairs = Vec::with_capacity(current.len());
        let mut hints = vec![None; current.len()];
        let mut result = MatchResult::unmatched(guess);
        let mut previous: Option<[f64; 3]> = None;
        for iteration in 1..=self.convergence.max_iterations {
            transform_all(&r, &reference.points.xy, &mut moved);
            let q = r.inverse();
            pairs.clear();
            for (i, &p) in current.xy.iter().enumerate() {
                let (qx, qy) = q.transform_point(p[0], p[1]);
                let k = p[0] * p[0] + p[1] * p[1] + l2;
                // d² ≥ |Δ|² L² / k, and |Δ| is at least the gap to a splitting line.
                let Some((j, d2)) =
                    reference
                        .tree
                        .nearest_by([qx, qy], l2 / k, hints[i], |j, _| {
                            self.distance2(p, moved[j])
                        })
                else {
                    continue;
                };
                hints[i] = Some(j);
                let (c, d2, beyond) = self.interpolate(p, &moved, j, d2);
                if d2 <= gate && !(self.drop_edge_pairs && beyond) {
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
                result.pose = r.inverse();
                return result;
            };
            let q_min = Pose2::new(step[0], step[1], step[2]);
            r = q_min.compose(&r);
            if self.convergence.reached(&q_min) {
                result.pose = r.inverse();
                result.settled = true;
                return result;
            }
            if let Some(longest) = self.extrapolate_up_to_m {
                let step = [q_min.x, q_min.y, self.l_m * q_min.theta];
                match previous.and_then(|last| geometric_remainder(last, step)) {
                    Some(factor) => {
                        let f = factor.min(MAX_EXTRAPOLATION).min(longest / norm(step));
                        r = Pose2::new(f * q_min.x, f * q_min.y, f * q_min.theta).compose(&r);
                        previous = None;
                    }
                    None => previous = Some(step),
                }
            }
            result.pose = r.inverse();
        }
        result
    }
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn norm(v: [f64; 3]) -> f64 {
    dot(v, v).sqrt()
}

/// The most a correction is ever extrapolated, times itself.
const MAX_EXTRAPOLATION: f64 = 25.0;

/// When two successive corrections (`x`, `y`, `Lθ`) point the same way, within 10°, and
/// shrink by a ratio `ρ`, the iteration is creeping geometrically along a valley: the rest of the
/// way is `ρ / (1 − ρ)` times the last correction.
fn geometric_remainder(last: [f64; 3], step: [f64; 3]) -> Option<f64> {
    let (n, n_last) = (norm(step), norm(last));
    let aligned = dot(step, last) > 10f64.to_radians().cos() * n * n_last;
    (aligned && n < n_last).then(|| {
        let rho = n / n_last;
        rho / (1.0 - rho)
    })
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
    fn extrapolates_only_shrinking_corrections_that_keep_their_direction() {
        let last = [0.010, 0.002, 0.0];
        let half = [0.005, 0.001, 0.0];
        let r = geometric_remainder(last, half).unwrap();
        assert!((r - 1.0).abs() < 1e-12, "ρ = ½ leaves as much again: {r}");
        assert_eq!(geometric_remainder(half, last), None, "growing");
        assert_eq!(
            geometric_remainder(last, [-0.005, -0.001, 0.0]),
            None,
            "reversed"
        );
        assert_eq!(
            geometric_remainder(last, [0.0, 0.005, 0.0]),
            None,
            "turned 90°"
        );
    }

    #[test]
    fn points_beyond_the_end_of_the_reference_wall_are_flagged() {
        let m = Mbicp::default();
        // A wall y = 1 seen from x = 0 to 2 in 5 cm steps.
        let wall: Vec<[f64; 2]> = (0..=40).map(|i| [0.05 * i as f64, 1.0]).collect();
        let near = |p: [f64; 2]| {
            let j = (0..wall.len())
                .min_by(|&a, &b| m.distance2(p, wall[a]).total_cmp(&m.distance2(p, wall[b])))
                .unwrap();
            m.interpolate(p, &wall, j, m.distance2(p, wall[j]))
        };
        let (on, d2, beyond) = near([1.02, 1.01]);
        assert!(!beyond && d2 < 1e-4 && (on[1] - 1.0).abs() < 1e-9);
        let (_, _, beyond) = near([-0.2, 1.0]);
        assert!(beyond, "left of the first point");
        let (_, _, beyond) = near([2.3, 1.0]);
        assert!(beyond, "right of the last point");
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
