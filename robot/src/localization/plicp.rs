//! Point-to-line ICP (Censi, "An ICP variant using a point-to-line metric", ICRA 2008), with the
//! defaults of its canonical C library (CSM, `sm_options.c`): the reference the matchers are
//! measured against, here so that every table holds it beside them, in the same run.
//!
//! Each iteration pairs every current point (moved by the estimate) with its nearest reference
//! point `j1` and the nearer of `j1`'s neighbours in scan order, `j2`, and measures it to the
//! line through them. Pairs farther than [`PointToLine::max_correspondence_m`] are left out; of
//! the rest, those whose distance to the segment `j1`–`j2` is above either an order statistic
//! (the 95th percentile) or twice the 70th percentile are trimmed, and when several current
//! points share a `j1` the ones more than three times farther from it than the nearest are
//! dropped. The pose minimising the squared point-to-line distances follows (Gauss–Newton to
//! its minimum, where CSM solves it in closed form). When the mean distance at the end is above
//! a centimetre, the loop starts again from the answer moved by ±1 cm in x, in y and ±1.5° in
//! θ, and the answer with the least total distance is kept, as CSM's `restart` does. A loop ends
//! when its step is tiny or, as CSM's `icp_loop` ends ("PLICP terminates in a finite number of
//! steps"), when an iteration's pairs are the very pairs of an earlier one.

use super::kdtree::LastNearest;
use super::matcher::{Convergence, MatchResult, Reference, ScanMatcher, solve3, transform_all};
use super::quality::accumulate;
use super::scan::ScanPoints;
use crate::geometry::{Pose2, wrap_angle};
use std::collections::VecDeque;

/// Point-to-line ICP.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct PointToLine {
    /// Pairs whose points lie farther apart than this are left out, metres. Default 2 (CSM's).
    pub max_correspondence_m: f64,
    /// At most this share of the pairs is kept, the nearest to their lines. Default 0.95.
    pub max_share: f64,
    /// The order statistic of the adaptive trim and its multiple: pairs farther than
    /// `mult ×` the distance at this share are left out. Default 0.7 and 2.
    pub adaptive_order: f64,
    /// See [`adaptive_order`](Self::adaptive_order).
    pub adaptive_mult: f64,
    /// When to stop: a step under 0.1 mm and 0.1 mrad (CSM's `epsilon_xy`, `epsilon_theta`), or
    /// 100 iterations (CSM allows 1000; none of the pairs measured here needed more than 100).
    pub convergence: Convergence,
    /// Start again around the answer when its mean distance to the lines is above this, metres;
    /// `None` never does. Default 0.01.
    pub restart_above_m: Option<f64>,
    /// Gauss–Newton steps towards the minimum of each iteration's pairs. Default 10, which
    /// reaches it (CSM solves it in closed form); the next pairing moves the estimate again
    /// anyway, so one step a round settles at the same place in more, cheaper rounds.
    pub gauss_newton_steps: u32,
    /// End the loop when an iteration brings the estimate back to within `convergence` of
    /// where it was up to this many iterations before: the pairings repeat in a cycle and the
    /// estimate with them, so no later iteration would settle it. Not in CSM, which compares
    /// the pairs themselves (`stop_on_repeated_pairs`); `None` (the default) leaves it out.
    pub stop_on_cycles: Option<usize>,
    /// End the loop when an iteration's pairs, after the trims (each current point's `j1` and
    /// `j2`, or none), are the very pairs of any earlier iteration of the loop: the estimate
    /// computed from them repeats too, so the loop would only go round the cycle again. CSM's
    /// `icp_loop` ends there (it compares a hash of the pairs, `ld_corr_hash`); this compares
    /// a 64-bit hash of them. The estimate from the repeated pairs is the loop's answer, as
    /// CSM's. Default true (CSM's); false runs such a loop to `max_iterations`, as this
    /// project's reference did until 2026-12-03.
    pub stop_on_repeated_pairs: bool,
}

impl PointToLine {
    /// CSM's defaults ([`PointToLine::default`]), as a constant for other matchers' settings.
    pub const CSM: PointToLine = PointToLine {
        max_correspondence_m: 2.0,
        max_share: 0.95,
        adaptive_order: 0.7,
        adaptive_mult: 2.0,
        convergence: Convergence {
            translation_m: 1e-4,
            rotation_rad: 1e-4,
            max_iterations: 100,
        },
        restart_above_m: Some(0.01),
        gauss_newton_steps: 10,
        stop_on_cycles: None,
        stop_on_repeated_pairs: true,
    };
}

impl Default for PointToLine {
    fn default() -> Self {
        PointToLine::CSM
    }
}

/// How far the restarts move the answer: 1 cm and 1.5° (CSM's `restart_dt`, `restart_dtheta`).
const RESTART_M: f64 = 0.01;
const RESTART_RAD: f64 = 0.026_179_938_779_914_94;

/// One pair: the current point (in its own frame), the reference point it is measured from and
/// the unit normal of the reference's line there.
#[derive(Copy, Clone, Debug)]
struct Pair {
    p: [f64; 2],
    q: [f64; 2],
    n: [f64; 2],
}

/// A pair before the trims: its distance to the reference's segment, its nearest reference
/// point and the squared distance to it.
struct Candidate {
    pair: Pair,
    segment: f64,
    nearest: usize,
    d2: f64,
    /// The current point's index and `nearest`'s neighbour on the segment, which name the
    /// pair for [`PointToLine::stop_on_repeated_pairs`].
    index: usize,
    neighbour: usize,
}

/// What [`PointToLine::refine_settled`] found: the answer, the estimate after the first
/// iteration, the iterations, whether the step fell under `convergence` before the cap, and
/// the pairs of the last iteration.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(super) struct Refined {
    pub pose: Pose2,
    pub first: Pose2,
    pub iterations: u32,
    pub settled: bool,
    pub kept: usize,
    pub given_up: bool,
}

/// When a point-to-line loop gives up (a quick finish's, [`QuickFinish::give_up`]): at the end
/// of iteration `after`, when under `below_share` of the current points lie within `within_m`
/// of their reference segments (the answer would fit too few of them to be worth finishing).
///
/// [`QuickFinish::give_up`]: super::QuickFinish::give_up
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct GiveUp {
    /// The iteration that decides.
    pub after: u32,
    /// How near its segment a point must lie, metres …
    pub within_m: f64,
    /// … and the least share of the current points that must.
    pub below_share: f64,
}

/// What one run of the loop found.
struct Loop {
    pose: Pose2,
    /// The estimate after the first iteration (`pose` when there was none).
    first: Pose2,
    /// Sum of the kept pairs' distances to their segments at the last pairing, metres.
    error: f64,
    kept: usize,
    iterations: u32,
    settled: bool,
    /// Whether the loop gave up ([`GiveUp`]).
    given_up: bool,
}

impl ScanMatcher for PointToLine {
    fn name(&self) -> &'static str {
        "pl-icp"
    }

    fn align_plausible(
        &self,
        reference: &Reference,
        current: &ScanPoints,
        guess: Pose2,
    ) -> MatchResult {
        let first = self.run(reference, current, guess);
        let (mut best, mut iterations) = (first.pose, first.iterations);
        let (mut best_error, mut settled, first_kept) = (first.error, first.settled, first.kept);
        let mean = first.error / first.kept.max(1) as f64;
        if self.restart_above_m.is_some_and(|limit| mean > limit) {
            for d in [
                [RESTART_M, 0.0, 0.0],
                [-RESTART_M, 0.0, 0.0],
                [0.0, RESTART_M, 0.0],
                [0.0, -RESTART_M, 0.0],
                [0.0, 0.0, RESTART_RAD],
                [0.0, 0.0, -RESTART_RAD],
            ] {
                let start = Pose2::new(
                    first.pose.x + d[0],
                    first.pose.y + d[1],
                    first.pose.theta + d[2],
                );
                let again = self.run(reference, current, start);
                iterations += again.iterations;
                if again.kept > 0 && again.error < best_error {
                    (best, best_error, settled) = (again.pose, again.error, again.settled);
                }
            }
        }
        MatchResult {
            pose: Pose2::new(best.x, best.y, wrap_angle(best.theta)),
            iterations,
            settled,
            correspondences: first_kept,
            ..MatchResult::unmatched(guess)
        }
    }
}

impl PointToLine {
    /// The loop from `start` (no restarts), searching near each current point's last nearest
    /// reference point in `last`, which it keeps up to date: another matcher's finish, on the
    /// cache of its own searches. The answer and the iterations it took.
    pub(super) fn refine(
        &self,
        reference: &Reference,
        current: &ScanPoints,
        start: Pose2,
        last: &mut [Option<LastNearest>],
    ) -> (Pose2, u32) {
        let found = self.refine_settled(reference, current, start, None, last);
        (found.pose, found.iterations)
    }

    /// [`refine`](Self::refine), with the estimate after its first iteration (what the same
    /// loop capped at one iteration would answer), whether it settled and its last pairs;
    /// given up as `give_up` says.
    pub(super) fn refine_settled(
        &self,
        reference: &Reference,
        current: &ScanPoints,
        start: Pose2,
        give_up: Option<GiveUp>,
        last: &mut [Option<LastNearest>],
    ) -> Refined {
        let found = self.run_with(reference, current, start, give_up, last);
        let wrapped = |p: Pose2| Pose2::new(p.x, p.y, wrap_angle(p.theta));
        Refined {
            pose: wrapped(found.pose),
            first: wrapped(found.first),
            iterations: found.iterations,
            settled: found.settled,
            kept: found.kept,
            given_up: found.given_up,
        }
    }

    /// The loop from `start`: pair, trim, minimise, until the step is tiny.
    fn run(&self, reference: &Reference, current: &ScanPoints, start: Pose2) -> Loop {
        self.run_with(
            reference,
            current,
            start,
            None,
            &mut vec![None; current.len()],
        )
    }

    /// [`run`](Self::run), its nearest-point searches starting from `last`, given up as
    /// `give_up` says.
    fn run_with(
        &self,
        reference: &Reference,
        current: &ScanPoints,
        start: Pose2,
        give_up: Option<GiveUp>,
        last: &mut [Option<LastNearest>],
    ) -> Loop {
        let mut pose = start;
        // The estimates before `pose` that a cycle would come back to (`stop_on_cycles`; the
        // step's own test catches a return to `pose`).
        let kept = self.stop_on_cycles.map_or(0, |n| n.saturating_sub(1));
        let mut earlier = VecDeque::with_capacity(kept);
        let mut moved = Vec::with_capacity(current.len());
        let mut candidates: Vec<Candidate> = Vec::with_capacity(current.len());
        let mut distances = Vec::with_capacity(current.len());
        let mut nearest_to = vec![f64::INFINITY; reference.points.len()];
        let mut pairs = Vec::with_capacity(current.len());
        // Every iteration's pairs, hashed, for `stop_on_repeated_pairs`.
        let mut hashes: Vec<u64> = Vec::new();
        let gate = self.max_correspondence_m * self.max_correspondence_m;
        let mut found = Loop {
            pose,
            first: pose,
            error: 0.0,
            kept: 0,
            iterations: 0,
            settled: false,
            given_up: false,
        };
        let refs = &reference.points.xy;
        for iteration in 1..=self.convergence.max_iterations {
            found.iterations = iteration;
            transform_all(&pose, &current.xy, &mut moved);
            candidates.clear();
            for (i, m) in moved.iter().enumerate() {
                let Some((j1, d2)) = reference.tree.nearest_cached(*m, &mut last[i]) else {
                    continue;
                };
                if d2 > gate {
                    continue;
                }
                // The nearer neighbour of j1 in scan order.
                let d2_to = |j: usize| {
                    let q = refs[j];
                    (q[0] - m[0]).powi(2) + (q[1] - m[1]).powi(2)
                };
                let j2 = [j1.checked_sub(1), (j1 + 1 < refs.len()).then_some(j1 + 1)]
                    .into_iter()
                    .flatten()
                    .min_by(|&a, &b| d2_to(a).total_cmp(&d2_to(b)));
                let Some(j2) = j2 else {
                    continue;
                };
                let (a, b) = (refs[j1], refs[j2]);
                let e = [b[0] - a[0], b[1] - a[1]];
                let length = (e[0] * e[0] + e[1] * e[1]).sqrt();
                if length < 1e-9 {
                    continue;
                }
                let n = [-e[1] / length, e[0] / length];
                let pair = Pair {
                    p: current.xy[i],
                    q: a,
                    n,
                };
                candidates.push(Candidate {
                    pair,
                    segment: segment_distance(*m, a, b),
                    nearest: j1,
                    d2,
                    index: i,
                    neighbour: j2,
                });
            }
            // Several points on one reference point: only those near the nearest stay.
            for c in &candidates {
                nearest_to[c.nearest] = nearest_to[c.nearest].min(c.d2);
            }
            candidates.retain(|c| c.d2 <= 9.0 * nearest_to[c.nearest]);
            // The nearest of each reference point stays, so this resets every one set above.
            for c in &candidates {
                nearest_to[c.nearest] = f64::INFINITY;
            }
            // Then the trims: a share at most, and no farther than twice the adaptive order
            // statistic.
            distances.clear();
            distances.extend(candidates.iter().map(|c| c.segment));
            let k = distances.len();
            if k < 3 {
                break;
            }
            // Each order statistic by selection, as CSM's `hoare_selection`, not a sort.
            let mut at = |share: f64| {
                let rank = ((k as f64 * share) as usize).min(k - 1);
                *distances.select_nth_unstable_by(rank, f64::total_cmp).1
            };
            let limit = at(self.max_share).min(self.adaptive_mult * at(self.adaptive_order));
            pairs.clear();
            found.error = 0.0;
            let mut hash = PairsHash::default();
            for c in candidates.iter().filter(|c| c.segment <= limit) {
                pairs.push(c.pair);
                found.error += c.segment;
                if self.stop_on_repeated_pairs {
                    hash.add(c.index, c.nearest, c.neighbour);
                }
            }
            found.kept = pairs.len();
            let repeated = self.stop_on_repeated_pairs && {
                let seen = hashes.contains(&hash.0);
                hashes.push(hash.0);
                seen
            };
            let Some(next) = minimise(&pairs, pose, self.gauss_newton_steps) else {
                break;
            };
            let step = Pose2::new(next.x - pose.x, next.y - pose.y, next.theta - pose.theta);
            let back_to = |p: &Pose2| {
                let d = Pose2::new(next.x - p.x, next.y - p.y, next.theta - p.theta);
                self.convergence.reached(&d)
            };
            let cycled = earlier.iter().any(back_to);
            if kept > 0 {
                if earlier.len() == kept {
                    earlier.pop_front();
                }
                earlier.push_back(pose);
            }
            pose = next;
            found.pose = pose;
            if iteration == 1 {
                found.first = pose;
            }
            if self.convergence.reached(&step) {
                found.settled = true;
                break;
            }
            if cycled || repeated {
                break;
            }
            if let Some(g) = give_up.filter(|g| g.after == iteration) {
                let near = candidates
                    .iter()
                    .filter(|c| c.segment <= g.within_m)
                    .count();
                if (near as f64) < g.below_share * current.len() as f64 {
                    found.given_up = true;
                    break;
                }
            }
        }
        found
    }
}

/// The pose minimising the pairs' squared distances to their lines, by at most `steps`
/// Gauss–Newton steps from `from`; `None` when the pairs leave a direction free (a corridor).
fn minimise(pairs: &[Pair], from: Pose2, steps: u32) -> Option<Pose2> {
    let mut pose = from;
    for _ in 0..steps {
        let (s, c) = pose.theta.sin_cos();
        let (mut h, mut g) = ([[0.0f64; 3]; 3], [0.0f64; 3]);
        for pair in pairs {
            let r = [c * pair.p[0] - s * pair.p[1], s * pair.p[0] + c * pair.p[1]];
            let n = pair.n;
            let e = n[0] * (pose.x + r[0] - pair.q[0]) + n[1] * (pose.y + r[1] - pair.q[1]);
            accumulate(
                &mut h,
                &mut g,
                [n[0], n[1], -n[0] * r[1] + n[1] * r[0]],
                e,
                1.0,
            );
        }
        let d = solve3(h, g.map(|v| -v))?;
        pose = Pose2::new(pose.x + d[0], pose.y + d[1], pose.theta + d[2]);
        if d[0].hypot(d[1]) < 1e-9 && d[2].abs() < 1e-10 {
            break;
        }
    }
    Some(pose)
}

/// A 64-bit hash of an iteration's pairs, in the order of the current points: a multiply and
/// rotate per pair (the mixing of `FxHash`), which tells two sets of a few hundred pairs apart
/// as surely as CSM's 31-bit `ld_corr_hash` and costs a few nanoseconds a pair.
#[derive(Default)]
struct PairsHash(u64);

impl PairsHash {
    fn add(&mut self, index: usize, j1: usize, j2: usize) {
        for v in [index, j1, j2] {
            self.0 = (self.0.rotate_left(5) ^ v as u64).wrapping_mul(0x517c_c1b7_2722_0a95);
        }
    }
}

/// The distance from `p` to the segment `a`–`b`.
fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let e = [b[0] - a[0], b[1] - a[1]];
    let l2 = e[0] * e[0] + e[1] * e[1];
    let t = if l2 > 0.0 {
        (((p[0] - a[0]) * e[0] + (p[1] - a[1]) * e[1]) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (dx, dy) = (p[0] - a[0] - t * e[0], p[1] - a[1] - t * e[1]);
    (dx * dx + dy * dy).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points along the walls of a room, seen from `at` (an L of two walls and a pillar).
    fn room(at: Pose2) -> ScanPoints {
        let mut world = Vec::new();
        for k in 0..120 {
            world.push([4.0, -2.0 + k as f64 * 0.04]);
            world.push([-1.0 + k as f64 * 0.04, 3.0]);
        }
        for k in 0..20 {
            let a = k as f64 * 0.314;
            world.push([2.0 + 0.2 * a.cos(), -1.0 + 0.2 * a.sin()]);
        }
        let inv = at.inverse();
        let xy: Vec<[f64; 2]> = world
            .iter()
            .map(|w| {
                let (x, y) = inv.transform_point(w[0], w[1]);
                [x, y]
            })
            .collect();
        // In scan order: by bearing.
        let mut xy = xy;
        xy.sort_by(|a, b| a[1].atan2(a[0]).total_cmp(&b[1].atan2(b[0])));
        ScanPoints {
            beam: (0..xy.len()).collect(),
            xy,
        }
    }

    #[test]
    fn finds_a_small_motion() {
        let truth = Pose2::new(0.12, -0.05, 0.04);
        let reference = Reference::new(room(Pose2::IDENTITY));
        let current = room(truth);
        let result = PointToLine::default().align(&reference, &current, Pose2::IDENTITY);
        let off = truth.relative(&result.pose);
        assert!(off.x.hypot(off.y) < 1e-3, "{result:?}");
        assert!(off.theta.abs() < 1e-4, "{result:?}");
        assert!(result.converged, "{result:?}");
    }

    /// A refinement's first round is the same loop capped at one iteration, to the bit; it gives
    /// up after the round `GiveUp` names when too few points lie near their lines (a current
    /// scan of another room), and not when they do.
    #[test]
    fn a_refinement_keeps_its_first_round_and_gives_up_on_a_poor_fit() {
        let truth = Pose2::new(0.12, -0.05, 0.04);
        let reference = Reference::new(room(Pose2::IDENTITY));
        let current = room(truth);
        let icp = PointToLine {
            gauss_newton_steps: 1,
            restart_above_m: None,
            ..PointToLine::default()
        };
        let capped = PointToLine {
            convergence: Convergence {
                max_iterations: 1,
                ..icp.convergence
            },
            ..icp
        };
        let fresh = || vec![None; current.len()];
        let found = icp.refine_settled(&reference, &current, Pose2::IDENTITY, None, &mut fresh());
        let (one, rounds) = capped.refine(&reference, &current, Pose2::IDENTITY, &mut fresh());
        assert_eq!((found.first, rounds), (one, 1));
        assert!(
            found.settled && !found.given_up && found.iterations > 1,
            "{found:?}"
        );
        let off = truth.relative(&found.pose);
        assert!(off.x.hypot(off.y) < 1e-3, "{found:?}");
        let give_up = GiveUp {
            after: 2,
            within_m: 0.05,
            below_share: 0.75,
        };
        let kept = icp.refine_settled(
            &reference,
            &current,
            Pose2::IDENTITY,
            Some(give_up),
            &mut fresh(),
        );
        assert_eq!(kept, found);
        // Half the current points 30 cm beyond the walls: too few near their lines.
        let mut elsewhere = current.clone();
        for p in elsewhere.xy.iter_mut().step_by(2) {
            let r = p[0].hypot(p[1]);
            *p = [p[0] * (r + 0.3) / r, p[1] * (r + 0.3) / r];
        }
        let mut last = vec![None; elsewhere.len()];
        let poor = icp.refine_settled(
            &reference,
            &elsewhere,
            Pose2::IDENTITY,
            Some(give_up),
            &mut last,
        );
        assert!(poor.given_up && poor.iterations == 2, "{poor:?}");
    }

    /// With ranges off by up to 6 cm, the mean distance to the lines is above a centimetre: the
    /// loop starts again six times around its answer and keeps the one with the least total
    /// distance, never a worse one.
    #[test]
    fn a_poor_fit_starts_again_and_keeps_the_best() {
        let truth = Pose2::new(0.1, 0.05, -0.03);
        let reference = Reference::new(room(Pose2::IDENTITY));
        let mut current = room(truth);
        for (k, p) in current.xy.iter_mut().enumerate() {
            let range = p[0].hypot(p[1]);
            let r = range + 0.12 * ((k as f64 * 0.618_034).fract() - 0.5);
            *p = [p[0] * r / range, p[1] * r / range];
        }
        let once = PointToLine {
            restart_above_m: None,
            ..PointToLine::default()
        };
        let first = once.run(&reference, &current, Pose2::IDENTITY);
        assert!(first.error / first.kept as f64 > 0.01, "{}", first.error);
        let again = PointToLine::default();
        let result = again.align(&reference, &current, Pose2::IDENTITY);
        assert!(result.iterations > first.iterations, "{result:?}");
        let error_at = |pose: Pose2| {
            let fixed = PointToLine {
                convergence: Convergence {
                    max_iterations: 1,
                    ..again.convergence
                },
                restart_above_m: None,
                ..again
            };
            fixed.run(&reference, &current, pose).error
        };
        assert!(error_at(result.pose) <= error_at(first.pose) + 1e-9);
        let off = truth.relative(&result.pose);
        assert!(off.x.hypot(off.y) < 0.02, "{result:?}");
    }

    #[test]
    fn segment_distance_measures_to_the_ends_beyond_them() {
        assert_eq!(segment_distance([0.5, 1.0], [0.0, 0.0], [1.0, 0.0]), 1.0);
        assert_eq!(segment_distance([2.0, 0.0], [0.0, 0.0], [1.0, 0.0]), 1.0);
        assert_eq!(segment_distance([3.0, 4.0], [0.0, 0.0], [0.0, 0.0]), 5.0);
    }

    /// As CSM's loop, a loop ends when an iteration's pairs are those of an earlier one: over
    /// rooms whose ranges are off by up to 6 cm, some loops that run to the cap without the
    /// stop, going round the same pairs, end within a few iterations with it, at an answer
    /// within a few millimetres of the capped loop's; and none takes more iterations with it.
    #[test]
    fn a_loop_whose_pairs_come_back_ends_there() {
        let reference = Reference::new(room(Pose2::IDENTITY));
        let faithful = PointToLine {
            restart_above_m: None,
            ..PointToLine::CSM
        };
        let capped = PointToLine {
            stop_on_repeated_pairs: false,
            ..faithful
        };
        let cap = capped.convergence.max_iterations;
        let mut ended_early = 0;
        for trial in 0..40 {
            let truth = Pose2::new(0.1, 0.05 - 0.002 * trial as f64, -0.03);
            let mut current = room(truth);
            for (k, p) in current.xy.iter_mut().enumerate() {
                let range = p[0].hypot(p[1]);
                let phase = (k as f64 * 0.618_034 + trial as f64 * 0.377).fract();
                let r = range + 0.12 * (phase - 0.5);
                *p = [p[0] * r / range, p[1] * r / range];
            }
            let with = faithful.run(&reference, &current, Pose2::IDENTITY);
            let without = capped.run(&reference, &current, Pose2::IDENTITY);
            assert!(with.iterations <= without.iterations, "trial {trial}");
            if without.iterations == cap && !without.settled && with.iterations < cap / 4 {
                ended_early += 1;
                let off = with.pose.relative(&without.pose);
                assert!(off.x.hypot(off.y) < 0.005, "trial {trial}: {off:?}");
                assert!(off.theta.abs() < 0.002, "trial {trial}: {off:?}");
            }
        }
        assert!(ended_early > 0, "no loop went round its pairs");
    }
}
