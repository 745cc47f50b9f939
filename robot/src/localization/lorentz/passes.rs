//! A match's σ passes — search, pair, one NLM step, until a search no longer moves the estimate
//! — and the point-to-line polish and the judgement that end them.

use super::energy::Normal;
use super::{Lorentz, Thinning};
use crate::geometry::{Pose2, wrap_angle};
use crate::localization::kdtree::LastNearest;
use crate::localization::lines::LazyLines;
use crate::localization::matcher::{MatchResult, Reference, transform_all};
use crate::localization::quality::{TrustRule, polish_near};
use crate::localization::scan::ScanPoints;
use std::cell::Cell;

/// The pairs of one search by the reference point they share, for [`Lorentz::crowd_ratio`].
struct Crowding {
    /// The ratio of distances past which a pair is crowded out.
    ratio: f64,
    /// Each pair's reference point and squared distance to its target, in pair order.
    pairs: Vec<(usize, f64)>,
    /// For each reference point, the smallest squared distance of a pair on it (infinity for
    /// none); reset after each search.
    nearest: Vec<f64>,
}

impl Crowding {
    fn new(ratio: f64, reference_points: usize) -> Self {
        Crowding {
            ratio,
            pairs: Vec::new(),
            nearest: vec![f64::INFINITY; reference_points],
        }
    }

    /// Notes the next pair: the current point `p` (moved), paired with reference point `j`
    /// through `target`; its squared distance to the target back.
    fn note(&mut self, j: usize, p: [f64; 2], target: [f64; 2]) -> f64 {
        let (dx, dy) = (target[0] - p[0], target[1] - p[1]);
        let d2 = dx * dx + dy * dy;
        self.pairs.push((j, d2));
        if d2 < self.nearest[j] {
            self.nearest[j] = d2;
        }
        d2
    }

    /// Leaves out of the noted pairs those more than `ratio` times farther from their targets
    /// than the nearest pair on the same reference point and farther than it by more than
    /// `sigma`; the rest keep their order. Ready for the next search afterwards.
    fn drop_crowded(
        &mut self,
        sigma: f64,
        (sources, targets, normals): (&mut Vec<[f64; 2]>, &mut Vec<[f64; 2]>, &mut Vec<Normal>),
    ) {
        let ratio2 = self.ratio * self.ratio;
        let mut kept = 0;
        for (k, &(j, d2)) in self.pairs.iter().enumerate() {
            let nearest = self.nearest[j];
            if d2 <= ratio2 * nearest || d2.sqrt() <= nearest.sqrt() + sigma {
                sources[kept] = sources[k];
                targets[kept] = targets[k];
                normals[kept] = normals[k];
                kept += 1;
            }
        }
        for &(j, _) in &self.pairs {
            self.nearest[j] = f64::INFINITY;
        }
        self.pairs.clear();
        sources.truncate(kept);
        targets.truncate(kept);
        normals.truncate(kept);
    }
}

/// Line-assisted association: the reference's local lines ([`LazyLines`]), the margin past a
/// segment's ends a projection may reach, and when the pairs projected inside a line count
/// their distance to it alone ([`Lorentz::line_residuals_spread`], for dense scans).
///
/// [`LazyLines`]: crate::localization::lines::LazyLines
pub(super) struct Assist<'a> {
    pub(super) lines: &'a LazyLines<'a>,
    pub(super) margin: f64,
    pub(super) spread: Option<f64>,
    /// Another share for `spread`, asked of every search beside it: `alike` stays set while
    /// each search would have counted its line pairs' residuals the same way with it. Then
    /// passes run again with that share, from the same start, would make the same searches
    /// and steps and end on the same answer, to the bit ([`Lorentz::first_spread`]).
    pub(super) compare: Option<f64>,
    pub(super) alike: Cell<bool>,
}

/// Where the earlier starts of one match ended their σ passes and what each answered, for
/// [`Lorentz::merge_reach`]: a later start of the same schedule whose estimate comes that near
/// to where an earlier one ended the same pass goes on as that one did, so it takes that
/// one's answer instead of searching its way there again.
#[derive(Default)]
pub(super) struct Visits {
    /// Each finished start's pass ends: the pass, the estimate `[θ, x, y]` at its end, and the
    /// start's answer (an index into `answers`).
    ends: Vec<(usize, [f64; 3], usize)>,
    answers: Vec<MatchResult>,
}

impl Visits {
    /// The answer of the earliest start that ended pass `pass` within `reach` (metres,
    /// radians) of `phi`.
    fn met(
        &self,
        pass: usize,
        phi: [f64; 3],
        (reach_m, reach_rad): (f64, f64),
    ) -> Option<MatchResult> {
        self.ends
            .iter()
            .find(|(p, end, _)| {
                *p == pass
                    && (phi[1] - end[1]).hypot(phi[2] - end[2]) <= reach_m
                    && wrap_angle(phi[0] - end[0]).abs() <= reach_rad
            })
            .map(|&(_, _, answer)| self.answers[answer])
    }

    /// Notes a finished start: where it ended each pass, and its answer.
    fn note(&mut self, ends: &[(usize, [f64; 3])], answer: MatchResult) {
        let index = self.answers.len();
        self.answers.push(answer);
        self.ends
            .extend(ends.iter().map(|&(pass, end)| (pass, end, index)));
    }
}

/// The polish's Cauchy width: a residual this large weighs half as much as one of none, metres.
pub(super) const POLISH_WIDTH_M: f64 = 0.01;

/// The polish leaves out a residual larger than this, metres.
pub(super) const POLISH_GATE_M: f64 = 0.05;

/// The Cauchy width of the polish both ways ([`super::Lorentz::both_ways`]), metres: twice
/// the one-way polish's. Its residuals are each scan's points against the other's surfaces,
/// so both scans' noise sits in every one of them, and at 1 cm the weights cut into the
/// noise itself, not only the outliers. Widened from 1 to 2 cm (2026-12-07), over seeds 1–80
/// of `twin matchers --matchers lorentz-lines`: the twin's pairs with 20 % outliers 1.84 →
/// 1.78 mm by the pooled median, one seed's median 1.65–2.16 → 1.56–2.01 mm, 95th percentile
/// 4.88 → 4.65 mm, right on 2 more pairs of 24,000, trusted and wrong on 22, not 23; its 1°
/// pairs 2.61 → 2.53 mm, 95th percentile 6.70 → 6.40 mm, right on 2 more, trusted and wrong on
/// 16, not 18; Edmonton right on the same pairs. 2.5 and 3 cm did no better (seeds 1–20).
pub(super) const BOTH_WAYS_WIDTH_M: f64 = 0.02;

/// Whether at most `thinning.most_lonely` of the points `xy` (in beam order) lie farther than
/// `thinning.lonely_m` from both their neighbours: a scan clean enough to be thinned. The first
/// and last points, with one neighbour each, are never lonely.
pub(super) fn looks_clean(xy: &[[f64; 2]], thinning: &Thinning) -> bool {
    clean_with(lonely_points(xy, thinning), xy.len(), thinning)
}

/// Whether `lonely` points of `points` are few enough for the scan to look clean.
fn clean_with(lonely: usize, points: usize, thinning: &Thinning) -> bool {
    lonely as f64 <= thinning.most_lonely * points as f64
}

/// How many of the points `xy` (in beam order) lie farther than `thinning.lonely_m` from both
/// their neighbours; the first and last never do.
fn lonely_points(xy: &[[f64; 2]], thinning: &Thinning) -> usize {
    let far2 = thinning.lonely_m * thinning.lonely_m;
    let far = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) > far2;
    xy.windows(3)
        .filter(|w| far(w[1], w[0]) && far(w[1], w[2]))
        .count()
}

/// Whether unit normals `normals` spread enough for point-to-line residuals, as [`spreads`]
/// decides of their [`normals_eigen`].
#[cfg(test)]
fn normals_spread(normals: &[Normal], share: f64) -> bool {
    spreads(normals_eigen(normals), share)
}

/// Whether normals whose `Σ n nᵀ` has the eigenvalues `(small, large)` spread enough for
/// point-to-line residuals: the smaller at least `share` of the larger (none: no).
fn spreads((small, large): (f64, f64), share: f64) -> bool {
    large > 0.0 && small >= share * large
}

/// The smaller and the larger eigenvalue of `Σ n nᵀ` over the unit normals `normals`.
fn normals_eigen(normals: &[Normal]) -> (f64, f64) {
    let (mut xx, mut xy, mut yy) = (0.0, 0.0, 0.0);
    for n in normals.iter().flatten() {
        xx += n[0] * n[0];
        xy += n[0] * n[1];
        yy += n[1] * n[1];
    }
    let half_trace = 0.5 * (xx + yy);
    let radius = (0.25 * (xx - yy) * (xx - yy) + xy * xy).sqrt();
    (half_trace - radius, half_trace + radius)
}

impl Lorentz {
    /// The σ passes of `sigmas`, at most `steps` NLM steps a search, leaving out crowded pairs
    /// when `crowd` gives a ratio ([`Lorentz::crowd_ratio`]), the first pass stopped as
    /// [`Lorentz::first_match_convergence`] says when `first_match` (a match that takes
    /// `first_max_steps`), its first searches on every second current point as
    /// [`Lorentz::first_pass_thinning`] says (with `crowd`), and the polish from `guess`; the
    /// answer judged by the trust rule.
    /// `last` keeps each current point's last nearest reference point from one search to the
    /// next, and from one call to the next of a match (the same answers, searched less).
    /// With `visits` (and [`Lorentz::merge_reach`]), a search that brings the estimate near to
    /// where an earlier start noted there ended the same pass ends the passes with that start's
    /// answer (and this one's iterations); a start that finishes is noted there.
    pub(super) fn passes(
        &self,
        (sigmas, steps, crowd, first_match): (&[f64], u32, Option<f64>, bool),
        (reference, current): (&Reference, &ScanPoints),
        lines: Option<&Assist>,
        guess: Pose2,
        last: &mut [Option<LastNearest>],
        mut visits: Option<&mut Visits>,
    ) -> MatchResult {
        let mut phi = [guess.theta, guess.x, guess.y];
        let merge = self.merge_reach.filter(|_| visits.is_some());
        // Where this start ended each pass, for `visits`.
        let mut ends = Vec::new();
        let mut moved = Vec::with_capacity(current.len());
        let mut sources = Vec::with_capacity(current.len());
        let mut targets = Vec::with_capacity(current.len());
        // Each pair's reference line normal, where its target is a projection inside one.
        let mut normals = Vec::with_capacity(current.len());
        let mut result = MatchResult::unmatched(guess);
        // With the crowd rule: each pair's reference point and squared distance to its target.
        let mut crowding = crowd.map(|ratio| Crowding::new(ratio, reference.points.len()));
        // The estimate before the last σ pass (not the guess), when it is to be polished too.
        let mut before_last = None;
        // With `first_pass_enough` on a dense scan: the squared distance within which a pair
        // counts as close, the share of the current points that must be, and how many of the
        // last search's pairs were.
        // Whether a dense scan looks clean (`first_pass_thinning`'s test), for the thinning and
        // `clean_pass_enough`.
        let thinning_test = self.first_pass_thinning.filter(|_| crowd.is_some());
        let lonely = thinning_test.map(|thinning| lonely_points(&current.xy, &thinning));
        let clean = thinning_test
            .zip(lonely)
            .is_some_and(|(thinning, lonely)| clean_with(lonely, current.len(), &thinning));
        // With `lonely_pass_enough` on a dense scan that does not look clean: the spread its
        // line normals must reach, the polish rounds it adds, and the points not lonely.
        let lonely_enough = self
            .lonely_pass_enough
            .filter(|_| !clean)
            .zip(lonely)
            .map(|(rule, lonely)| (rule, current.len() - lonely));
        // Whether the last search's line normals spread as `lonely_enough` asks.
        let mut normals_spread = false;
        // Whether `lonely_enough` left the narrower passes out.
        let mut lonely_left_out = false;
        let enough = self
            .clean_pass_enough
            .filter(|_| clean)
            .or(self.first_pass_enough)
            .filter(|_| crowd.is_some())
            .map(|(distance, share)| (distance * distance, share));
        let mut close = 0;
        // How many current points the last search paired or left out (all but while thinned).
        let mut searched = current.len();
        // With `first_pass_surfaces` on a dense scan: the fewest points a surface that holds a
        // pair must have been fitted to.
        let surfaces = self.first_pass_surfaces.filter(|_| crowd.is_some());
        // The passes of the schedule the sparse finish follows stop sooner: the finish takes
        // the answer on.
        let finished = self.sparse_finish.is_some() && crowd.is_none() && sigmas == self.sigmas_m;
        for (pass, &sigma) in sigmas.iter().enumerate() {
            if pass == 1
                && let Some((_, share)) = enough
            {
                if close as f64 >= share * searched as f64 {
                    break;
                }
                // Counted over the points that are not lonely (no thinning on such a scan:
                // every point was searched).
                if let Some((_, not_lonely)) = lonely_enough
                    && normals_spread
                    && close as f64 >= share * not_lonely as f64
                {
                    lonely_left_out = true;
                    break;
                }
            }
            if pass > 0 && pass + 1 == sigmas.len() && self.polish_rounds > 0 {
                before_last = self
                    .before_last_margin
                    .filter(|_| crowd.is_none() && !finished)
                    .map(|margin| (phi, margin));
            }
            result.settled = false;
            // When a search of this pass has moved the estimate little enough.
            let more_passes = pass + 1 < sigmas.len();
            let stop = match (
                self.first_pass_convergence,
                self.sparse_early_convergence.filter(|_| finished),
                self.early_convergence,
            ) {
                // The crowd rule marks a dense scan's schedules but the wide one.
                (Some(first), _, _) if pass == 0 && crowd.is_some() && more_passes => self
                    .first_match_convergence
                    .filter(|_| first_match)
                    .unwrap_or(first),
                (_, Some(sparse), _) => sparse,
                (_, _, Some(early)) if more_passes => early,
                _ => self.convergence,
            };
            // The estimate before the search before the last, for `stop_on_cycles`.
            let mut two_back: Option<[f64; 3]> = None;
            // While set, each search takes every second current point (`first_pass_thinning`);
            // the searches thinned so far.
            let mut thinning = self
                .first_pass_thinning
                .filter(|_| pass == 0 && clean && more_passes)
                .map(|thinning| thinning.searches);
            let mut thinned = 0;
            for _ in 0..self.convergence.max_iterations {
                result.iterations += 1;
                let pose = Pose2::new(phi[1], phi[2], phi[0]);
                transform_all(&pose, &current.xy, &mut moved);
                sources.clear();
                targets.clear();
                normals.clear();
                close = 0;
                let every = if thinning.is_some() { 2 } else { 1 };
                searched = current.len().div_ceil(every);
                for (i, p) in moved.iter().enumerate().step_by(every) {
                    let (j, d2) = reference
                        .tree
                        .nearest_cached(*p, &mut last[i])
                        .expect("non-empty reference");
                    let mut target = reference.points.xy[j];
                    let mut normal = None;
                    if let Some(assist) = lines
                        && let Some(line) = assist.lines.get(j)
                    {
                        let (on_line, inside) = line.projection(*p, assist.margin);
                        let (dx, dy) = (on_line[0] - p[0], on_line[1] - p[1]);
                        if dx * dx + dy * dy < d2 {
                            target = on_line;
                            if inside {
                                normal = Some(line.normal());
                            }
                        }
                    }
                    if normal.is_none()
                        && pass == 0
                        && let Some(fewest) = surfaces
                        && let Some(surface) = reference.surface(j)
                        && surface.points >= fewest
                        && let Some(on_surface) = surface.projection(*p)
                    {
                        target = on_surface;
                        normal = Some(surface.normal);
                    }
                    let beyond = target == reference.points.xy[j] && reference.is_edge(j);
                    if self.drop_edge_pairs && beyond {
                        continue;
                    }
                    sources.push(current.xy[i]);
                    targets.push(target);
                    normals.push(normal);
                    if let Some(crowding) = &mut crowding {
                        let d2 = crowding.note(j, *p, target);
                        // `enough` is set only with the crowd rule (dense scans).
                        if let Some((near2, _)) = enough {
                            close += usize::from(d2 < near2);
                        }
                    }
                }
                if let Some(crowding) = &mut crowding {
                    crowding.drop_crowded(sigma, (&mut sources, &mut targets, &mut normals));
                }
                result.correspondences = targets.len();
                if targets.is_empty() {
                    break;
                }
                let before = phi;
                // The line normals' spread, once a search, for the shares asked of it.
                let spread_share = lines.and_then(|assist| assist.spread);
                let eigen = (spread_share.is_some() || lonely_enough.is_some())
                    .then(|| normals_eigen(&normals));
                let to_lines = match (lines, spread_share, eigen) {
                    (Some(assist), Some(share), Some(eigen)) => {
                        let to_lines = spreads(eigen, share);
                        if let Some(other) = assist.compare
                            && spreads(eigen, other) != to_lines
                        {
                            assist.alike.set(false);
                        }
                        to_lines
                    }
                    _ => false,
                };
                if let Some(((rule, _), eigen)) = lonely_enough.zip(eigen) {
                    normals_spread = spreads(eigen, rule.spread);
                }
                let normals = to_lines.then_some(normals.as_slice());
                phi = self.nlm((&sources, &targets), normals, phi, (sigma, steps));
                let step = Pose2::new(
                    phi[1] - before[1],
                    phi[2] - before[2],
                    wrap_angle(phi[0] - before[0]),
                );
                // A thinned search never ends the pass: the first search of all the points
                // after it may still move the estimate.
                if let Some(thin) = thinning {
                    thinned += 1;
                    if thinned >= thin.max_iterations || thin.reached(&step) {
                        thinning = None;
                    }
                    two_back = None;
                    continue;
                }
                if let Some(reach) = merge
                    && let Some(earlier) = visits.as_ref().and_then(|v| v.met(pass, phi, reach))
                {
                    return MatchResult {
                        iterations: result.iterations,
                        ..earlier
                    };
                }
                if stop.reached(&step) {
                    result.settled = true;
                    break;
                }
                let back = |o: [f64; 3]| {
                    Pose2::new(phi[1] - o[1], phi[2] - o[2], wrap_angle(phi[0] - o[0]))
                };
                if self.stop_on_cycles && two_back.is_some_and(|o| stop.reached(&back(o))) {
                    break;
                }
                two_back = Some(before);
            }
            if merge.is_some() {
                ends.push((pass, phi));
            }
        }
        result.pose = Pose2::new(phi[1], phi[2], wrap_angle(phi[0]));
        // The polish and the judgement search near where the passes did: `last` goes on.
        let mut after_rounds = None;
        if self.polish_rounds > 0 {
            // The crowd rule marks a dense scan's schedules but the wide one, as above.
            let more = self.polish_more.filter(|_| crowd.is_some());
            let extra = lonely_enough
                .filter(|_| lonely_left_out)
                .map_or(0, |(rule, _)| rule.extra_polish_rounds);
            (result.pose, after_rounds) =
                self.polish(reference, current, result.pose, (more, extra), last);
        }
        let rule = TrustRule::default();
        result.quality = rule.assess_near(reference, &current.xy, &result.pose, Some(&mut *last));
        // The polish went on past its rounds: kept unless the pose it had reached then fits
        // more of the current points.
        if let Some(earlier) = after_rounds {
            let quality = rule.assess_near(reference, &current.xy, &earlier, Some(&mut *last));
            if quality.inlier_share > result.quality.inlier_share {
                (result.pose, result.quality) = (earlier, quality);
            }
        }
        // Set only with the polish.
        if let Some((phi, margin)) = before_last {
            let earlier = Pose2::new(phi[1], phi[2], phi[0]);
            let (earlier, _) = self.polish(reference, current, earlier, (None, 0), last);
            let quality = rule.assess_near(reference, &current.xy, &earlier, Some(&mut *last));
            if quality.inlier_share > result.quality.inlier_share + margin {
                (result.pose, result.quality) = (earlier, quality);
            }
        }
        if let Some(visits) = visits.as_mut().filter(|_| merge.is_some()) {
            visits.note(&ends, result);
        }
        result
    }

    /// The point-to-line polish of `pose`, `polish_rounds` rounds and `extra` more, and, with
    /// `more`, those [`polish_near`] adds: the polished pose, and the pose after those rounds
    /// where more rounds moved it.
    fn polish(
        &self,
        reference: &Reference,
        current: &ScanPoints,
        pose: Pose2,
        (more, extra): (Option<(f64, usize)>, usize),
        last: &mut [Option<LastNearest>],
    ) -> (Pose2, Option<Pose2>) {
        let rounds = (self.polish_rounds + extra, POLISH_WIDTH_M, POLISH_GATE_M);
        let (polished, after_rounds) =
            polish_near(reference, &current.xy, pose, rounds, more, last);
        let wrapped = |p: Pose2| Pose2::new(p.x, p.y, wrap_angle(p.theta));
        (wrapped(polished), after_rounds.map(wrapped))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::localization::CROWD_RATIO;

    /// Of the pairs on one reference point, those more than three times farther than the
    /// nearest and farther than it by more than σ are left out; the others, and every pair on
    /// a point of its own, stay in their order, and the next search starts afresh.
    #[test]
    fn crowded_pairs_are_left_out() {
        let mut crowding = Crowding::new(CROWD_RATIO, 4);
        // (reference point, distance to the target along x).
        let pairs = [
            (2, 0.010),
            (2, 0.025),
            (1, 0.9),
            (2, 0.5),
            (2, 0.05),
            (3, 0.2),
        ];
        let (mut sources, mut targets, mut normals) = (Vec::new(), Vec::new(), Vec::new());
        for (k, &(j, d)) in pairs.iter().enumerate() {
            let p = [k as f64, 0.0];
            let target = [k as f64 + d, 0.0];
            sources.push(p);
            targets.push(target);
            normals.push(None);
            crowding.note(j, p, target);
        }
        crowding.drop_crowded(0.02, (&mut sources, &mut targets, &mut normals));
        // On point 2 the nearest is 0.010 away: 0.025 is within three times that and stays;
        // 0.05 and 0.5 are beyond both that and the nearest plus σ (0.03), and go. The pairs
        // on points 1 and 3 are alone there.
        let kept: Vec<usize> = sources.iter().map(|p| p[0] as usize).collect();
        assert_eq!(kept, vec![0, 1, 2, 5]);
        assert_eq!(targets.len(), 4);
        assert_eq!(normals.len(), 4);
        // With σ 5 cm, 0.05 lies within σ of the nearest (0.06) and stays; 0.5 still goes.
        for (k, &(j, d)) in pairs.iter().enumerate() {
            crowding.note(j, [k as f64, 0.0], [k as f64 + d, 0.0]);
        }
        let (mut s, mut t, mut n) = (
            (0..6).map(|k| [k as f64, 0.0]).collect::<Vec<_>>(),
            vec![[0.0; 2]; 6],
            vec![None; 6],
        );
        crowding.drop_crowded(0.05, (&mut s, &mut t, &mut n));
        let kept: Vec<usize> = s.iter().map(|p| p[0] as usize).collect();
        assert_eq!(kept, vec![0, 1, 2, 4, 5]);
        assert!(crowding.pairs.is_empty());
        assert!(crowding.nearest.iter().all(|d| d.is_infinite()));
    }

    /// A wall 3 m ahead, 361 beams: clean; with every fifth reading 10 m farther (20 % uniform
    /// outliers, most of which land far beyond the walls), not; with one beam in twelve on a
    /// chair leg 1.5 m nearer, still clean (8 % lonely, under 10 %); with one in nine (11 %),
    /// not. The end points are never lonely.
    #[test]
    fn only_scans_with_few_lonely_points_look_clean() {
        use crate::localization::FIRST_PASS_THINNING as THIN;
        let wall = |k: usize, far: &dyn Fn(usize) -> f64| {
            let a = (k as f64 * 0.5 - 90.0).to_radians();
            let r = 3.0 / a.cos().max(0.3) + far(k);
            [r * a.cos(), r * a.sin()]
        };
        let scan = |far: &dyn Fn(usize) -> f64| (0..361).map(|k| wall(k, far)).collect::<Vec<_>>();
        assert!(looks_clean(&scan(&|_| 0.0), &THIN));
        let outliers = scan(&|k| if k % 5 == 2 { 10.0 } else { 0.0 });
        assert!(!looks_clean(&outliers, &THIN));
        assert!(looks_clean(
            &scan(&|k| if k % 12 == 6 { -1.5 } else { 0.0 }),
            &THIN
        ));
        assert!(!looks_clean(
            &scan(&|k| if k % 9 == 4 { -1.5 } else { 0.0 }),
            &THIN
        ));
        // Every point far from the next: only the 359 inner ones can be lonely.
        let spread: Vec<[f64; 2]> = (0..361).map(|k| [2.0 * k as f64, 0.0]).collect();
        let share = |most_lonely| Thinning {
            most_lonely,
            ..THIN
        };
        assert!(looks_clean(&spread, &share(359.0 / 361.0)));
        assert!(!looks_clean(&spread, &share(358.0 / 361.0)));
        assert!(looks_clean(&[], &THIN));
    }

    /// Normals all one way (a corridor) or none do not spread; a corner's do, as far as the
    /// share of its walls' points allows.
    #[test]
    fn line_normals_spread_like_the_walls_they_come_from() {
        let wall = |n: usize, angle: f64| vec![Some([angle.cos(), angle.sin()]); n];
        let corridor = [wall(100, 0.3), wall(80, 0.3 + std::f64::consts::PI)].concat();
        assert!(!normals_spread(&corridor, 0.01));
        assert!(!normals_spread(&[None, None], 0.01));
        assert!(!normals_spread(&[], 0.01));
        let corner = [
            wall(100, 0.3),
            wall(60, 0.3 + std::f64::consts::FRAC_PI_2),
            vec![None; 50],
        ]
        .concat();
        assert!(normals_spread(&corner, 0.5));
        assert!(!normals_spread(&corner, 0.7));
    }
}
