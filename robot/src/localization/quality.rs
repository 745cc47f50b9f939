//! How far a match can be trusted, judged after it by the same rule for every matcher.
//!
//! A matcher's own stopping test (the last step was tiny) says nothing about whether it stopped
//! in the right place: least squares settles in a wrong minimum as readily as in the right one.
//! So every answer is examined the same way afterwards, against the reference scan:
//!
//! - **inliers**: each current point, moved by the answer, is compared with the reference's
//!   surface near it — the line fitted to its nearest reference point's neighbours in scan
//!   order (point to line, as Censi's PL-ICP), or the point itself where the scan
//!   has no neighbour near — and is an inlier within [`TrustRule::inlier_m`]; a point whose
//!   nearest reference point has no neighbour near only because the reference's beams lie too
//!   far apart there (a sparse scan's far readings, [`unresolved`]) is not judged;
//! - **residual**: the root mean square of the inliers' distances;
//! - **covariance**: the Fisher information of the inliers' point-to-line constraints,
//!   `I = Σ J Jᵀ / s²` with `J = (n_x, n_y, n · ∂p/∂θ)` and `s` the residual (Censi, "An accurate
//!   closed-form estimate of ICP's covariance", ICRA 2007, its first term): the standard
//!   deviation it gives each of x, y and θ is large where the scene does not pin that direction
//!   down (a corridor along its length).
//!
//! - **hold**: where the inliers' surfaces all face nearly one way (a corridor), the answer is
//!   moved along the direction they leave free and must fit fewer points there
//!   ([`TrustRule::holds`]): the information above is summed from chords whose normals the
//!   laser's noise tilts, and along a corridor's walls those tilts feign a hold the scans do
//!   not give.
//!
//! [`TrustRule`] turns these into the one flag a user of a match reads,
//! [`MatchResult::converged`](super::MatchResult::converged).
//!
//! Where an answer is refused only along its free direction
//! ([`TrustRule::trusts_across`]), the scans still place it across the corridor and in
//! heading, and nothing in them places it along: a matcher with [`GuessAlongFree`] then takes
//! the guess's place along the free direction, as far as the scans allow.

use super::kdtree::LastNearest;
use super::lines::direction;
use super::matcher::{Reference, solve3};
use super::scan::turn_between;
use crate::geometry::Pose2;

/// The figures a match is judged by.
#[derive(Copy, Clone, Debug, PartialEq, serde::Serialize)]
pub struct MatchQuality {
    /// Current points within [`TrustRule::inlier_m`] of the reference's surface.
    pub inliers: usize,
    /// The inliers' share of the current scan's points that the rule can judge: all but
    /// those whose nearest reference point is a lone point where the reference's beams lie
    /// farther apart than a surface may span ([`Reference::unresolved`]; far readings of a
    /// sparse scan, 17 m out at 1° a beam).
    ///
    /// [`Reference::unresolved`]: super::Reference::unresolved
    pub inlier_share: f64,
    /// Root mean square of the inliers' distances to the reference's surface, metres.
    pub rms_m: f64,
    /// Standard deviations of the estimate's x and y (metres) and θ (radians) from the inliers'
    /// information; infinite where they leave a direction free.
    pub sigma: [f64; 3],
    /// Whether the reference scan is sparse (its beams 0.75° apart or more, as a SICK's in its
    /// 1° mode, [`SPARSE_BEAM_STEP_RAD`]): its surfaces are sampled coarsely, and
    /// [`TrustRule::min_inlier_share_sparse`] applies.
    ///
    /// [`SPARSE_BEAM_STEP_RAD`]: super::SPARSE_BEAM_STEP_RAD
    pub sparse: bool,
    /// How far one Gauss–Newton step of the inliers' point-to-line error would move the answer:
    /// metres and radians. An answer at the minimum of that error does not move; one pulled
    /// aside (least squares dragged by outliers) does.
    pub step: [f64; 2],
    /// How evenly the inliers' surfaces face: the smaller eigenvalue of the scatter of their
    /// normals over the larger, 0 where they all face one way (the walls of a corridor), 1
    /// where they face every way alike.
    pub spread: f64,
    /// The unit direction (in the reference frame) in which the inliers' surfaces hold the
    /// answer least: along a corridor.
    pub free: [f64; 2],
    /// Whether the scans hold the answer along [`free`](Self::free): false when the answer,
    /// moved [`TrustRule::hold_shift_m`] either way along it, fits nearly as many current points
    /// ([`TrustRule::holds`]). Set by [`ScanMatcher::align`] for a spread below
    /// [`TrustRule::hold_below_spread`]; true where it was not asked.
    ///
    /// [`ScanMatcher::align`]: super::ScanMatcher::align
    pub held: bool,
    /// The standard deviations of the position across [`free`](Self::free) (metres) and of θ
    /// (radians) when the position along it is known (the inverse of the information's
    /// across-and-heading block): what the scans hold of a corridor's answer, finite even where
    /// the walls leave the advance wholly free and [`sigma`](Self::sigma) is infinite.
    pub across_sigma: [f64; 2],
    /// How far one Gauss–Newton step of the inliers' point-to-line error would move the answer
    /// across [`free`](Self::free) (metres) and in θ (radians), its position along it held.
    pub across_step: [f64; 2],
}

impl MatchQuality {
    /// The quality of no match at all: nothing fits.
    pub const NONE: MatchQuality = MatchQuality {
        inliers: 0,
        inlier_share: 0.0,
        rms_m: f64::INFINITY,
        sigma: [f64::INFINITY; 3],
        sparse: false,
        step: [f64::INFINITY; 2],
        spread: 0.0,
        free: [1.0, 0.0],
        held: false,
        across_sigma: [f64::INFINITY; 2],
        across_step: [f64::INFINITY; 2],
    };
}

/// Where an answer the trust rule refuses only along its free direction is moved
/// ([`TrustRule::trusts_across`]: the scans do not hold it there, or its σ along it is too
/// large, every other test passed): along [`free`](MatchQuality::free), toward the guess's
/// place along it, in steps of `step_m`, for
/// as long as the moved answer fits at most `spare` fewer current points within `band_m` of
/// the reference's surfaces than the answer does; its heading and its place across the
/// direction stay the scans'. Such an answer stays untrusted.
///
/// Along a corridor the scans leave the advance open, so a match ends wherever its searches
/// happened to stop there: the guess (the odometry, on a robot) is the only thing that says
/// where along it the robot is, and of the places the scans fit alike the one nearest the
/// guess is the likeliest. The walk stops at the first step that loses points (a doorway's
/// edge, the corridor's end), so an answer the scans do hold, a little, keeps its place.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct GuessAlongFree {
    /// The distance from a surface within which a current point counts as fitting, metres.
    pub band_m: f64,
    /// The step of the walk toward the guess, metres; longer when the guess lies farther than
    /// `max_steps` of them, so that the walk takes `max_steps` at most.
    pub step_m: f64,
    /// The most steps the walk takes.
    pub max_steps: usize,
    /// How many fewer current points a place along the way may fit.
    pub spare: usize,
}

impl GuessAlongFree {
    /// `pose` (an answer of quality `q`) moved along `q.free` toward `guess`'s place along it,
    /// as far as the current points fit there as at `pose`, within `spare`.
    pub fn place(
        &self,
        reference: &Reference,
        current: &[[f64; 2]],
        pose: &Pose2,
        q: &MatchQuality,
        guess: &Pose2,
    ) -> Pose2 {
        let free = q.free;
        let target = free[0] * (guess.x - pose.x) + free[1] * (guess.y - pose.y);
        if !target.is_finite() || target == 0.0 {
            return *pose;
        }
        let fits = |offset: f64| fits_moved(reference, current, pose, (free, offset), self.band_m);
        let here = fits(0.0);
        let step = self.step_m.max(target.abs() / self.max_steps.max(1) as f64);
        let mut kept = 0.0;
        for k in 1..=self.max_steps.max(1) {
            let offset = (k as f64 * step).min(target.abs()).copysign(target);
            if fits(offset) + self.spare < here {
                break;
            }
            kept = offset;
            if offset.abs() >= target.abs() {
                break;
            }
        }
        Pose2::new(pose.x + kept * free[0], pose.y + kept * free[1], pose.theta)
    }
}

/// How many current points, the answer `pose` moved by `offset` metres along the unit direction
/// `along` (its heading kept), lie within `band` metres of the reference's surfaces (of those
/// the rule can judge): the count [`TrustRule::holds`] and [`GuessAlongFree`] weigh a shift by.
fn fits_moved(
    reference: &Reference,
    current: &[[f64; 2]],
    pose: &Pose2,
    (along, offset): ([f64; 2], f64),
    band: f64,
) -> usize {
    let moved = Pose2::new(
        pose.x + offset * along[0],
        pose.y + offset * along[1],
        pose.theta,
    );
    constraints(reference, current, &moved, None)
        .filter(|c| c.judged && c.residual.abs() <= band)
        .count()
}

/// When a match is trusted.
///
/// The defaults were chosen on `twin matchers --out DIR` (its `pairs.csv`: 7,200 matches of the
/// four matchers on synthetic and real pairs, seed 1): over the three robust matchers a trusted
/// answer is right 97.7 % of the time and 94 % of the right answers are trusted (the README's
/// table gives each row's precision and recall); least squares' trusted answers are right
/// 79 % of the time (64 % without the bound on the step). Tighter bounds on σ (8 mm, 0.1°)
/// bought half a point of precision for six points of recall, and distrusted good matches in
/// the lab.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct TrustRule {
    /// A current point this near the reference's surface is an inlier, metres. Default 0.05.
    pub inlier_m: f64,
    /// The least share of inliers. Default 0.5: a right match of real consecutive scans keeps
    /// 0.55–0.7 of its points on the reference's surfaces in the worst tenth of pairs.
    pub min_inlier_share: f64,
    /// The least share of inliers against a sparse reference ([`MatchQuality::sparse`]).
    /// Default 0.35: a sparse scan samples its surfaces coarsely, and a right match of the
    /// Edmonton log's consecutive 1° scans keeps 0.35 of its points on the reference's
    /// surfaces in the worst twentieth of pairs (0.38 in the worst tenth; its corrected poses
    /// 0.33). At 0.5, two thirds of its right answers were trusted; at 0.35, 95 %, as many of
    /// the trusted ones right (`twin matchers`, seeds 1–10).
    pub min_inlier_share_sparse: f64,
    /// The fewest inliers. Default 20.
    pub min_inliers: usize,
    /// The largest residual, metres. Default 0.03 (the real logs' right matches: 15–25 mm).
    pub max_rms_m: f64,
    /// The largest standard deviation of x or y, metres. Default 0.01.
    pub max_sigma_m: f64,
    /// The largest standard deviation of θ, radians. Default 0.3°.
    pub max_sigma_rad: f64,
    /// The longest Gauss–Newton [`step`](MatchQuality::step) of an answer, metres. Default 0.02.
    pub max_step_m: f64,
    /// … and radians. Default 1°.
    pub max_step_rad: f64,
    /// Below this [`spread`](MatchQuality::spread) of the inliers' surfaces an answer is also
    /// asked whether the scans hold it along its free direction ([`TrustRule::holds`]).
    /// Default 0.2: a fifth of the trusted answers of `twin matchers`, corridors and long
    /// walls (in the L-corridor of Aparicio 2011 most of them).
    pub hold_below_spread: f64,
    /// How far along its free direction [`TrustRule::holds`] moves an answer, either way,
    /// metres. Default 0.1: twice the inlier distance, so that a point on a surface across
    /// the direction leaves it.
    pub hold_shift_m: f64,
    /// How many fewer current points the moved answer must fit, each way, for the scans to
    /// hold it. Default 2. Chosen on `twin matchers --seeds 3` with the L-corridor, the
    /// corridor of black doors, the Stage lab and the lab from its map image beside the
    /// standard rows (band 2 or 5 cm, shift 6 or 10 cm, 2, 3 or 6 points, spread 0.1 to 1):
    /// the L-corridor's trusted answers went from right on 0.80 to 0.98, Edmonton's recall
    /// from 0.947 to 0.938, the large guesses' from 0.979 to 0.974, the other rows' by 0.006
    /// at most.
    pub min_hold_loss: usize,
}

impl Default for TrustRule {
    fn default() -> Self {
        TrustRule {
            inlier_m: 0.05,
            min_inlier_share: 0.5,
            min_inlier_share_sparse: 0.35,
            min_inliers: 20,
            max_rms_m: 0.03,
            max_sigma_m: 0.01,
            max_sigma_rad: 0.3f64.to_radians(),
            max_step_m: 0.02,
            max_step_rad: 1f64.to_radians(),
            hold_below_spread: 0.2,
            hold_shift_m: 0.1,
            min_hold_loss: 2,
        }
    }
}

impl TrustRule {
    /// Whether a match of this quality can be trusted.
    pub fn trusts(&self, q: &MatchQuality) -> bool {
        q.inliers >= self.min_inliers
            && q.inlier_share
                >= if q.sparse {
                    self.min_inlier_share_sparse
                } else {
                    self.min_inlier_share
                }
            && q.rms_m <= self.max_rms_m
            && q.sigma[0] <= self.max_sigma_m
            && q.sigma[1] <= self.max_sigma_m
            && q.sigma[2] <= self.max_sigma_rad
            && q.step[0] <= self.max_step_m
            && q.step[1] <= self.max_step_rad
            && q.held
    }

    /// Whether the scans hold an answer of quality `q` at `pose` along its free direction:
    /// always where its surfaces' [`spread`](MatchQuality::spread) is at least
    /// [`hold_below_spread`](Self::hold_below_spread); else when `pose` moved
    /// [`hold_shift_m`](Self::hold_shift_m) along [`free`](MatchQuality::free), either way,
    /// fits at least [`min_hold_loss`](Self::min_hold_loss) fewer current points within
    /// [`inlier_m`](Self::inlier_m) of the reference's surfaces than `pose` does (`q.inliers`,
    /// counted as [`assess`](Self::assess) counts them). Two more searches of every current
    /// point, and only for the answers that need them.
    ///
    /// A corridor seen along its walls fits as many points a few centimetres along it, and
    /// nothing in the scans says which: an answer there is not trusted, however firmly the
    /// information of the walls' noisy chords claims to hold it (σ 2–4 mm along the
    /// L-corridor's walls, whose trusted answers were 5–26 cm along them one time in five).
    pub fn holds(
        &self,
        reference: &Reference,
        current: &[[f64; 2]],
        pose: &Pose2,
        q: &MatchQuality,
    ) -> bool {
        if q.spread >= self.hold_below_spread {
            return true;
        }
        [1.0, -1.0].iter().all(|sign| {
            let shift = sign * self.hold_shift_m;
            fits_moved(reference, current, pose, (q.free, shift), self.inlier_m)
                + self.min_hold_loss
                <= q.inliers
        })
    }

    /// Whether an answer at `pose` of quality `q` is trusted as [`ScanMatcher::align`] judges
    /// it: by [`trusts`](Self::trusts), and then, asked only of an answer that passes (two more
    /// searches where its surfaces face one way), by [`holds`](Self::holds), whose finding it
    /// writes into `q`'s [`held`](MatchQuality::held).
    ///
    /// [`ScanMatcher::align`]: super::ScanMatcher::align
    pub fn confirms(
        &self,
        reference: &Reference,
        current: &[[f64; 2]],
        pose: &Pose2,
        q: &mut MatchQuality,
    ) -> bool {
        if !self.trusts(q) {
            return false;
        }
        q.held = self.holds(reference, current, pose, q);
        q.held
    }

    /// Whether a match of this quality would be trusted if enough of the scan fitted: it passes
    /// every test of [`trusts`](Self::trusts) but the share of inliers (the scans may overlap
    /// too little for it).
    pub fn trusts_but_overlap(&self, q: &MatchQuality) -> bool {
        self.trusts(&MatchQuality {
            inlier_share: 1.0,
            ..*q
        })
    }

    /// Whether a match of this quality would be trusted if the scans pinned it down more: it
    /// passes every test of [`trusts`](Self::trusts) but σ (the scans' geometry, which no
    /// start changes).
    pub fn trusts_but_sigma(&self, q: &MatchQuality) -> bool {
        self.trusts(&MatchQuality {
            sigma: [0.0; 3],
            ..*q
        })
    }

    /// Whether a match of this quality passes every test of [`trusts`](Self::trusts) but
    /// [`held`](MatchQuality::held): the scans hold it across its free direction and in
    /// heading, and leave it free along that direction (a corridor's advance).
    pub fn trusts_but_hold(&self, q: &MatchQuality) -> bool {
        !q.held && self.trusts(&MatchQuality { held: true, ..*q })
    }

    /// Whether a match of this quality can be trusted across its free direction and in heading,
    /// but not along that direction: its surfaces face nearly one way (a
    /// [`spread`](MatchQuality::spread) below [`hold_below_spread`](Self::hold_below_spread)),
    /// the match is not [trusted](Self::trusts), and the tests of [`trusts`](Self::trusts) pass
    /// with σ and the Gauss–Newton step taken across and in heading
    /// ([`across_sigma`](MatchQuality::across_sigma),
    /// [`across_step`](MatchQuality::across_step)) and the hold not asked. A corridor whose
    /// advance the scans leave open: because its answer moved along it fits as many points
    /// ([`held`](MatchQuality::held) false), or because its walls' information leaves σ along
    /// it above [`max_sigma_m`](Self::max_sigma_m) (a corridor without noise, infinite).
    pub fn trusts_across(&self, q: &MatchQuality) -> bool {
        q.spread < self.hold_below_spread
            && !self.trusts(q)
            && (self.trusts_but_hold(q)
                || self.trusts(&MatchQuality {
                    sigma: [0.0, 0.0, q.across_sigma[1]],
                    step: q.across_step,
                    held: true,
                    ..*q
                }) && q.across_sigma[0] <= self.max_sigma_m)
    }

    /// The quality of `pose` (the current frame in the reference frame) for the current scan's
    /// points `current` against `reference`.
    pub fn assess(
        &self,
        reference: &Reference,
        current: &[[f64; 2]],
        pose: &Pose2,
    ) -> MatchQuality {
        self.assess_near(reference, current, pose, None)
    }

    /// [`TrustRule::assess`] with each current point's last nearest reference point kept in
    /// `last` (one for each current point, as [`KdTree::nearest_cached`] keeps them): the
    /// same quality, searched less when the points were searched for near there before.
    ///
    /// [`KdTree::nearest_cached`]: super::KdTree::nearest_cached
    pub fn assess_near(
        &self,
        reference: &Reference,
        current: &[[f64; 2]],
        pose: &Pose2,
        last: Option<&mut [Option<LastNearest>]>,
    ) -> MatchQuality {
        // Without a floor the judgement is never given up.
        self.judge(reference, current, pose, last, None)
            .map_or(MatchQuality::NONE, |(quality, _)| quality)
    }

    /// [`TrustRule::assess_near`], and the σ of the position along the direction the inliers
    /// hold it least (the square root of the larger eigenvalue of the position's covariance,
    /// metres; infinite where they leave a direction free). `sigma`'s x and y are that
    /// covariance's diagonal: along a wall at 45° both read a fraction of this one.
    pub(super) fn assess_near_weakest(
        &self,
        reference: &Reference,
        current: &[[f64; 2]],
        pose: &Pose2,
        last: Option<&mut [Option<LastNearest>]>,
    ) -> (MatchQuality, f64) {
        self.judge(reference, current, pose, last, None)
            .unwrap_or((MatchQuality::NONE, f64::INFINITY))
    }

    /// [`TrustRule::assess_near`] for a pose that matters only if it fits more than `floor`
    /// current points: `None` as soon as the points left to judge could no longer take its
    /// inliers past `floor`, else the same quality to the last bit (the points are judged in
    /// the same order). A slide check's pose, judged only to be turned away nine times in ten
    /// with a hundred inliers fewer, is given up after a third of its points.
    pub(super) fn assess_near_above(
        &self,
        reference: &Reference,
        current: &[[f64; 2]],
        pose: &Pose2,
        last: Option<&mut [Option<LastNearest>]>,
        floor: usize,
    ) -> Option<MatchQuality> {
        self.judge(reference, current, pose, last, Some(floor))
            .map(|(quality, _)| quality)
    }

    /// The judgement of [`TrustRule::assess_near_weakest`], given up as
    /// [`TrustRule::assess_near_above`] says when `floor` is given.
    fn judge(
        &self,
        reference: &Reference,
        current: &[[f64; 2]],
        pose: &Pose2,
        last: Option<&mut [Option<LastNearest>]>,
        floor: Option<usize>,
    ) -> Option<(MatchQuality, f64)> {
        if current.is_empty() || reference.points.is_empty() {
            return floor
                .is_none()
                .then_some((MatchQuality::NONE, f64::INFINITY));
        }
        let mut information = [[0.0f64; 3]; 3];
        let mut gradient = [0.0f64; 3];
        let (mut inliers, mut judged, mut sum2) = (0usize, 0usize, 0.0f64);
        for (seen, constraint) in constraints(reference, current, pose, last).enumerate() {
            // Every point after this one an inlier would still leave `floor` unbeaten.
            if let Some(floor) = floor
                && inliers + (current.len() - seen) <= floor
            {
                return None;
            }
            if !constraint.judged {
                continue;
            }
            judged += 1;
            let distance = constraint.residual.abs();
            if distance > self.inlier_m {
                continue;
            }
            inliers += 1;
            sum2 += distance * distance;
            if let Some(jac) = constraint.jacobian {
                accumulate(
                    &mut information,
                    &mut gradient,
                    jac,
                    constraint.residual,
                    1.0,
                );
            }
        }
        let rms_m = if inliers > 0 {
            (sum2 / inliers as f64).sqrt()
        } else {
            f64::INFINITY
        };
        // The residual's scale, no smaller than a millimetre (a perfect synthetic fit would
        // otherwise claim certainty).
        let scale2 = rms_m.max(1e-3).powi(2);
        let covariance = |k: usize| {
            let mut e = [0.0; 3];
            e[k] = 1.0;
            solve3(information, e).map(|x| x.map(|v| v * scale2))
        };
        let columns = [covariance(0), covariance(1), covariance(2)];
        let column =
            |k: usize| columns[k].map_or(f64::INFINITY, |x: [f64; 3]| x[k].max(0.0).sqrt());
        // The position's covariance [[a, b], [b, c]] and its larger eigenvalue; a NaN (which
        // `max` would turn to 0) reads as free.
        let weakest = match (columns[0], columns[1]) {
            (Some([a, b, _]), Some([_, c, _])) => {
                let larger = 0.5 * (a + c) + (0.5 * (a - c)).hypot(b);
                if larger.is_nan() {
                    f64::INFINITY
                } else {
                    larger.max(0.0).sqrt()
                }
            }
            _ => f64::INFINITY,
        };
        let step = solve3(information, gradient.map(|g| -g))
            .map_or([f64::INFINITY; 2], |d| [d[0].hypot(d[1]), d[2].abs()]);
        // The scatter of the inliers' normals (the information's x–y block): its eigenvalues'
        // ratio, and square to its principal direction the direction it holds least.
        let block = [information[0][0], information[0][1], information[1][1]];
        let half_trace = 0.5 * (block[0] + block[2]);
        let radius = (0.5 * (block[0] - block[2])).hypot(block[1]);
        let spread = if half_trace + radius > 0.0 {
            ((half_trace - radius) / (half_trace + radius)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let [c, s] = direction(block);
        // Across the free direction (along [c, s]) and in heading, the advance along it held:
        // the information's block for those two, its inverse and its Gauss–Newton step.
        let (across_sigma, across_step) = {
            let uu = c * c * block[0] + 2.0 * c * s * block[1] + s * s * block[2];
            let ut = c * information[0][2] + s * information[1][2];
            let tt = information[2][2];
            let det = uu * tt - ut * ut;
            if det > 0.0 && det.is_finite() {
                let gu = c * gradient[0] + s * gradient[1];
                let gt = gradient[2];
                let du = -(tt * gu - ut * gt) / det;
                let dt = -(uu * gt - ut * gu) / det;
                (
                    [(tt / det * scale2).sqrt(), (uu / det * scale2).sqrt()],
                    [du.abs(), dt.abs()],
                )
            } else {
                ([f64::INFINITY; 2], [f64::INFINITY; 2])
            }
        };
        let quality = MatchQuality {
            inliers,
            inlier_share: inliers as f64 / judged.max(1) as f64,
            rms_m,
            sigma: [column(0), column(1), column(2)],
            sparse: reference.is_sparse(),
            step,
            spread,
            free: [-s, c],
            held: true,
            across_sigma,
            across_step,
        };
        floor
            .is_none_or(|floor| inliers > floor)
            .then_some((quality, weakest))
    }
}

/// Where the points off their surfaces would have an answer along its weakest direction
/// ([`slide_vote`]).
#[derive(Copy, Clone, Debug, PartialEq)]
pub(super) struct SlideVote {
    /// The unit direction, in the reference frame, in which the inliers' surfaces hold the
    /// answer least.
    pub direction: [f64; 2],
    /// The shift along `direction`, metres, that brings the most of the points now off their
    /// surfaces within the trust rule's distance of them: the middle of the shifts that do (0
    /// where none does).
    pub shift_m: f64,
    /// How many of the points now off their surfaces that shift brings within.
    pub recruits: usize,
}

/// The step between the shifts [`slide_vote`] weighs, metres: a twentieth of the narrowest
/// interval of shifts over which a point can be an inlier (twice the trust rule's 5 cm, for a
/// surface square to the direction).
const VOTE_STEP_M: f64 = 0.005;

/// How the points off their surfaces vote for a shift of `pose` along its weakest direction.
/// The inliers' surfaces (within `inlier_m`) give the answer's information on x and y (the sum
/// of their normals' outer products); the direction of the smaller eigenvalue is where a match
/// can slide, along a wall. The points that can say how far are those whose surface normal lies
/// within 60° of that direction and that lie beyond `inlier_m` but within `reach` (and
/// `inlier_m`) of their surface: a shift `s` moves such a point's distance from its surface by
/// `s` times the cosine, so each is an inlier for one interval of shifts. Of the shifts from
/// `min_shift` to `reach` either way (every [`VOTE_STEP_M`]), the vote is the one inside the
/// most intervals. Only the points off their surfaces vote: the inliers' own intervals hold
/// the answer where it is, and a shift of centimetres carries a point on a pillar or a box
/// onto another of the reference's points, which the linear count cannot see (the caller
/// weighs the shift by a fresh judgement). No search beyond the one at `pose` (on `last`, as
/// [`TrustRule::assess_near`] takes it); `None` where no current point lies within `reach`
/// (and `inlier_m`) of a surface.
pub(super) fn slide_vote(
    reference: &Reference,
    current: &[[f64; 2]],
    pose: &Pose2,
    last: Option<&mut [Option<LastNearest>]>,
    inlier_m: f64,
    (min_shift, reach): (f64, f64),
) -> Option<SlideVote> {
    // The information's x–y block [[a, b], [b, c]], and each point near its surface.
    let mut info = [0.0f64; 3];
    let mut near = Vec::new();
    for constraint in constraints(reference, current, pose, last) {
        let Some(jac) = constraint.jacobian else {
            continue;
        };
        let r = constraint.residual;
        if r.abs() <= inlier_m {
            if !constraint.beyond {
                info[0] += jac[0] * jac[0];
                info[1] += jac[0] * jac[1];
                info[2] += jac[1] * jac[1];
            }
        } else if r.abs() <= reach + inlier_m && !constraint.beyond {
            near.push((r, [jac[0], jac[1]]));
        }
    }
    if info == [0.0; 3] && near.is_empty() {
        return None;
    }
    // Square to the information's principal direction: where it holds the answer least.
    let [c, s] = direction(info);
    let weakest = [-s, c];
    // Each voting point's interval of shifts.
    let intervals: Vec<(f64, f64)> = near
        .into_iter()
        .filter_map(|(r, n)| {
            let k = n[0] * weakest[0] + n[1] * weakest[1];
            (k.abs() >= 0.5).then(|| {
                let (lo, hi) = ((-inlier_m - r) / k, (inlier_m - r) / k);
                (lo.min(hi), lo.max(hi))
            })
        })
        .collect();
    // Either way from `min_shift` out, the runs of shifts inside as many intervals: the run
    // inside the most, and of those the one that begins nearest the answer.
    let steps = ((reach - min_shift) / VOTE_STEP_M).floor().max(0.0) as usize;
    let (mut recruits, mut nearest, mut shift_m) = (0usize, f64::INFINITY, 0.0f64);
    for sign in [1.0, -1.0] {
        let shifts: Vec<f64> = (0..=steps)
            .map(|i| sign * (min_shift + i as f64 * VOTE_STEP_M))
            .collect();
        let counts: Vec<usize> = shifts
            .iter()
            .map(|&s| {
                intervals
                    .iter()
                    .filter(|&&(lo, hi)| lo <= s && s <= hi)
                    .count()
            })
            .collect();
        let mut from = 0;
        for run in counts.chunk_by(|x, y| x == y) {
            let (n, first, last) = (run[0], shifts[from], shifts[from + run.len() - 1]);
            if n > 0 && (n > recruits || (n == recruits && first.abs() < nearest)) {
                (recruits, nearest, shift_m) = (n, first.abs(), 0.5 * (first + last));
            }
            from += run.len();
        }
    }
    Some(SlideVote {
        direction: weakest,
        shift_m,
        recruits,
    })
}

/// The last stage of a match: Gauss–Newton on the point-to-line error of the current points
/// within `gate` metres of the reference's surfaces, each weighted by the Cauchy weight
/// `1 / (1 + (e/c)²)` (a residual of `c` metres counts half), re-associated every round, for at
/// most `rounds` rounds or until a step is below 1 µm and 0.1 µrad. It moves an answer already
/// near the right place onto the minimum of the point-to-line error — where the surfaces' chords
/// (not the scattered points) say the scans agree.
pub fn polish(
    reference: &Reference,
    current: &[[f64; 2]],
    pose: Pose2,
    rounds: usize,
    c: f64,
    gate: f64,
) -> Pose2 {
    // Each point's last nearest reference point, kept from round to round: the pose moves
    // little, and the search is skipped while no other point can have come nearer.
    let mut last = vec![None; current.len()];
    polish_near(reference, current, pose, (rounds, c, gate), None, &mut last).0
}

/// [`polish`] with each current point's last nearest reference point kept in `last` (one for
/// each current point, as [`KdTree::nearest_cached`] keeps them), from before the polish and
/// for after it: the same answer, searched less when the points were searched for near there
/// before (by the matcher whose answer is polished). With `more` = `(turn_rad, extra)`, the
/// rounds go on past `rounds`, at most `extra` more, while the last round still turned the
/// estimate by more than `turn_rad`: an answer the Cauchy weights hold back creeps a tenth
/// of a degree a round ([`POLISH_MORE`](super::POLISH_MORE)). The polished pose, and where
/// more rounds moved it, the pose after `rounds`.
///
/// [`KdTree::nearest_cached`]: super::KdTree::nearest_cached
pub fn polish_near(
    reference: &Reference,
    current: &[[f64; 2]],
    mut pose: Pose2,
    (rounds, c, gate): (usize, f64, f64),
    more: Option<(f64, usize)>,
    last: &mut [Option<LastNearest>],
) -> (Pose2, Option<Pose2>) {
    let (turn, extra) = more.unwrap_or((0.0, 0));
    let mut after_rounds = None;
    // The Cauchy weight as `c² / (c² + e²)`: one division a point where `1 / (1 + (e/c)²)`
    // took two, the same weight but for its last bit (2026-11-30: no answer of seeds 1–10 and
    // 51–60 nor of Table 5.1 moved in print; 1 % off a dense match).
    let c2 = c * c;
    for round in 0..rounds + extra {
        let mut h = [[0.0f64; 3]; 3];
        let mut g = [0.0f64; 3];
        for constraint in constraints(reference, current, &pose, Some(&mut *last)) {
            if let Some((jac, e)) = polish_term(&constraint, gate) {
                accumulate(&mut h, &mut g, jac, e, c2 / (c2 + e * e));
            }
        }
        let Some((stepped, d)) = polish_step(pose, h, g) else {
            break;
        };
        pose = stepped;
        if polish_settled(d) {
            break;
        }
        if extra > 0 && round + 1 >= rounds {
            if d[2].abs() <= turn {
                break;
            }
            after_rounds.get_or_insert(pose);
        }
    }
    (pose, after_rounds.filter(|&p| p != pose))
}

/// The point-to-line polish both ways: `rounds` Gauss–Newton rounds that hold each current
/// point, moved by the pose, to the reference's surface near it (as [`polish_near`], on
/// `last`'s cache), and each reference point, moved back into the current scan's frame, to the
/// current scan's surface near it. Both kinds of residual are Cauchy-weighted with width `c`
/// and left out past `gate`, metres, or past their line's points. Polished one way only, an
/// answer places the current points on lines through the reference's, and the reference's
/// range noise, seen only through those lines, weighs more than the current's; both ways,
/// each scan's noise counts alike.
///
/// A reference point's current neighbour is found without a search of its own: the current
/// point nearest to it among those whose nearest it is in this round's search (or its
/// neighbours' in scan order, when it is none's), walked along the current scan while a
/// neighbour in scan order lies nearer. A k-d tree over the current points gave the same
/// precision at about twice the cost (2026-12-07, the scan-matching notebook).
pub(super) fn polish_both_ways(
    reference: &Reference,
    current: &[[f64; 2]],
    mut pose: Pose2,
    (rounds, c, gate): (usize, f64, f64),
    last: &mut [Option<LastNearest>],
) -> Pose2 {
    let c2 = c * c;
    // The current scan's surface at each point a reference point comes to, fitted when one
    // first does: on the twin's pairs with 20 % outliers a third of the points, the outliers
    // among them, never are (seed 39: 72,949 fits of 104,997 points, 1.1 % of the match's
    // instructions saved).
    let mut current_surfaces: Vec<Option<Option<Surface>>> = vec![None; current.len()];
    // For each reference point, the current point nearest to it among those it is nearest to.
    let mut nearest_current: Vec<Option<(usize, f64)>> = vec![None; reference.points.len()];
    for _ in 0..rounds {
        let mut h = [[0.0f64; 3]; 3];
        let mut g = [0.0f64; 3];
        let mut add = |jac: [f64; 3], e: f64| accumulate(&mut h, &mut g, jac, e, c2 / (c2 + e * e));
        nearest_current.fill(None);
        for constraint in constraints(reference, current, &pose, Some(&mut *last)) {
            let (i, j, d2) = constraint.pair;
            if nearest_current[j].is_none_or(|(_, d)| d2 < d) {
                nearest_current[j] = Some((i, d2));
            }
            if let Some((jac, e)) = polish_term(&constraint, gate) {
                add(jac, e);
            }
        }
        let (s, co) = pose.theta.sin_cos();
        for (j, p) in reference.points.xy.iter().enumerate() {
            let Some(start) = [Some(j), j.checked_sub(1), Some(j + 1)]
                .into_iter()
                .flatten()
                .find_map(|k| nearest_current.get(k).copied().flatten())
            else {
                continue;
            };
            // q = Rᵀ (p − t): ∂q/∂x = −(c, −s), ∂q/∂y = −(s, c), ∂q/∂θ = (q_y, −q_x).
            let d = [p[0] - pose.x, p[1] - pose.y];
            let q = [co * d[0] + s * d[1], -s * d[0] + co * d[1]];
            let i = walk_to_nearest(current, q, start.0);
            let Some(surface) = current_surfaces[i].get_or_insert_with(|| surface_at(current, i))
            else {
                continue;
            };
            let (e, within) = surface.place(q);
            if within && e.abs() <= gate {
                let n = surface.normal;
                add(
                    [
                        -(n[0] * co - n[1] * s),
                        -(n[0] * s + n[1] * co),
                        n[0] * q[1] - n[1] * q[0],
                    ],
                    e,
                );
            }
        }
        let Some((stepped, d)) = polish_step(pose, h, g) else {
            break;
        };
        pose = stepped;
        if polish_settled(d) {
            break;
        }
    }
    pose
}

/// A current point's term in the polish, its residual's derivatives and the residual itself:
/// for a point on a surface's line, within `gate` of it and within the line's points.
fn polish_term(constraint: &Constraint, gate: f64) -> Option<([f64; 3], f64)> {
    let e = constraint.residual;
    constraint
        .jacobian
        .filter(|_| e.abs() <= gate && !constraint.beyond)
        .map(|jac| (jac, e))
}

/// One Gauss–Newton round of a polish: `pose` moved by the step `d` that solves `h d = −g`,
/// and that step; `None` where `h` is singular.
fn polish_step(pose: Pose2, h: [[f64; 3]; 3], g: [f64; 3]) -> Option<(Pose2, [f64; 3])> {
    let d = solve3(h, g.map(|v| -v))?;
    Some((
        Pose2::new(pose.x + d[0], pose.y + d[1], pose.theta + d[2]),
        d,
    ))
}

/// Whether a polish's step is too small for another round: under 1 µm and 0.1 µrad.
fn polish_settled(d: [f64; 3]) -> bool {
    d[0].hypot(d[1]) < 1e-6 && d[2].abs() < 1e-7
}

/// From point `i` of `points` (in scan order), the neighbour in scan order nearer to `q` while
/// there is one, up to four steps: the point nearest `q` along the scan.
fn walk_to_nearest(points: &[[f64; 2]], q: [f64; 2], mut i: usize) -> usize {
    let d2 = |k: usize| (points[k][0] - q[0]).powi(2) + (points[k][1] - q[1]).powi(2);
    for _ in 0..4 {
        let here = d2(i);
        let next = [i.checked_sub(1), (i + 1 < points.len()).then_some(i + 1)]
            .into_iter()
            .flatten()
            .map(|k| (k, d2(k)))
            .filter(|&(_, d)| d < here)
            .min_by(|a, b| a.1.total_cmp(&b.1));
        match next {
            Some((k, _)) => i = k,
            None => break,
        }
    }
    i
}

/// How far one current point, moved by the pose, lies from the reference's surface.
struct Constraint {
    /// Signed distance to the surface's line (along its normal), or the distance to the nearest
    /// reference point where the surface has no direction, metres.
    residual: f64,
    /// The residual's derivatives by x, y and θ, for a point on a line.
    jacobian: Option<[f64; 3]>,
    /// Whether the point lies past the ends of the reference points its line was fitted to
    /// (by more than [`END_MARGIN_M`]): the line's direction, extrapolated, would twist it.
    beyond: bool,
    /// Whether the trust rule can judge the point: not when its nearest reference point is
    /// [unresolved](Reference::unresolved), where the reference's beams lie too far apart for a
    /// surface and the distance to that point says nothing of the fit.
    judged: bool,
    /// The current point's index, its nearest reference point's, and the squared distance
    /// between them, metres².
    pair: (usize, usize, f64),
}

/// Each current point's [`Constraint`] at `pose`; with `last`, each point's last nearest
/// reference point is kept there (the same answers, searched less).
fn constraints<'a>(
    reference: &'a Reference,
    current: &'a [[f64; 2]],
    pose: &Pose2,
    mut last: Option<&'a mut [Option<LastNearest>]>,
) -> impl Iterator<Item = Constraint> + 'a {
    let (s, c) = pose.theta.sin_cos();
    let (x, y) = (pose.x, pose.y);
    let mut hint = None;
    current.iter().enumerate().filter_map(move |(i, p)| {
        let r = [c * p[0] - s * p[1], s * p[0] + c * p[1]];
        let q = [x + r[0], y + r[1]];
        let (j, d2) = match last.as_deref_mut().and_then(|last| last.get_mut(i)) {
            Some(kept) => reference.tree.nearest_cached_from(q, kept, hint)?,
            None => reference.tree.nearest_from(q, hint)?,
        };
        hint = Some(j);
        Some(match reference.surface(j) {
            Some(surface) => {
                let (residual, within) = surface.place(q);
                let n = surface.normal;
                Constraint {
                    residual,
                    // ∂q/∂θ = (−r_y, r_x).
                    jacobian: Some([n[0], n[1], -n[0] * r[1] + n[1] * r[0]]),
                    beyond: !within,
                    judged: true,
                    pair: (i, j, d2),
                }
            }
            None => Constraint {
                residual: d2.sqrt(),
                jacobian: None,
                beyond: false,
                judged: !reference.unresolved(j),
                pair: (i, j, d2),
            },
        })
    })
}

/// Adds a residual `e` with derivatives `jac`, weighted `w`, to the normal equations `h`, `g`.
/// Inlined: twelve multiply-adds a point in `pl-icp`'s loop, the trust rule and the polish,
/// which LLVM left a call at 413e52b (9 % of the 1° race's samples, `perf record`) and inlined
/// after an unrelated change, moving `pl-icp`'s time by a tenth.
#[inline]
pub(super) fn accumulate(h: &mut [[f64; 3]; 3], g: &mut [f64; 3], jac: [f64; 3], e: f64, w: f64) {
    for (i, row) in h.iter_mut().enumerate() {
        g[i] += w * jac[i] * e;
        for (v, &b) in row.iter_mut().zip(&jac) {
            *v += w * jac[i] * b;
        }
    }
}

/// The reference's surface at one of its points: a line, for point-to-line residuals.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(super) struct Surface {
    /// The line's unit normal.
    pub normal: [f64; 2],
    /// A point of the line.
    pub anchor: [f64; 2],
    /// How far along the line from `anchor` the points it was fitted to reach, metres: past
    /// that (and [`END_MARGIN_M`]) the polish does not hold a point to it.
    pub reach: f64,
    /// How many reference points the line was fitted to: up to `2 SPAN + 1` (all of them on
    /// the chord: a straight piece of surface), 2 for the line through a point and its nearer
    /// neighbour.
    pub points: usize,
}

impl Surface {
    /// The signed distance of `p` from the line (along its normal), and whether `p` lies within
    /// `reach` and [`END_MARGIN_M`] of `anchor` along it (past that, the line's direction,
    /// extrapolated, would twist it).
    pub(super) fn place(&self, p: [f64; 2]) -> (f64, bool) {
        let (n, a) = (self.normal, self.anchor);
        let (ax, ay) = (p[0] - a[0], p[1] - a[1]);
        let along = (n[1] * ax - n[0] * ay).abs();
        (n[0] * ax + n[1] * ay, along <= self.reach + END_MARGIN_M)
    }

    /// The orthogonal projection of `p` on the line, when it falls within `reach` and
    /// [`END_MARGIN_M`] of `anchor` ([`Surface::place`]).
    pub(super) fn projection(&self, p: [f64; 2]) -> Option<[f64; 2]> {
        let (off, within) = self.place(p);
        let n = self.normal;
        within.then(|| [p[0] - off * n[0], p[1] - off * n[1]])
    }
}

/// The most points a [`Surface`] is fitted to: all of `SPAN` either side of its point and the
/// point itself.
pub(super) const SURFACE_POINTS: usize = 2 * SPAN + 1;

/// Whether each reference point is *unresolved*: it has no surface, and its beam and the next
/// one (in the reference's scan, at its range) lie farther apart than [`MAX_GAP_M`], so no
/// neighbour could have given it one. A lone point nearer than that is an outlier or a small
/// thing (a pole) and is judged as a point; an unresolved one may lie on a wall seen between
/// beams, and a current point near that wall would be counted off it by the distance to the
/// point alone. `beam` gives each point's beam number.
pub(super) fn unresolved(
    points: &[[f64; 2]],
    beam: &[usize],
    surfaces: &[Option<Surface>],
) -> Vec<bool> {
    (0..points.len())
        .map(|j| {
            if surfaces[j].is_some() {
                return false;
            }
            // The angle a beam turns, from the neighbour in scan order (as seen from the laser).
            let k = if j + 1 < points.len() {
                j + 1
            } else {
                j.wrapping_sub(1)
            };
            let (Some(&p), Some(&q)) = (points.get(j), points.get(k)) else {
                return false;
            };
            let beams = beam[j].abs_diff(beam[k]);
            if beams == 0 {
                return false;
            }
            p[0].hypot(p[1]) * turn_between(p, q) / beams as f64 > MAX_GAP_M
        })
        .collect()
}

/// The reference's surface at each of its points ([`surface_at`]), in scan order.
pub(super) fn surfaces(points: &[[f64; 2]]) -> Vec<Option<Surface>> {
    (0..points.len()).map(|j| surface_at(points, j)).collect()
}

/// Neighbours farther apart than this per step in scan order are taken to lie on different
/// surfaces ([`surface_at`]), metres.
const MAX_GAP_M: f64 = 0.3;

/// The reference's surface at point `j`. Its direction is the chord between the farthest
/// points up to [`SPAN`] either side of `j` in scan order that lie near `j` for their gap in
/// order (an outlier between them is skipped, not taken for the surface's end), as long as `j`
/// lies on that chord (a corner within the span does not); the line passes through the mean of
/// those points lying on the chord, so the range noise of `j` alone does not place it. Else the
/// line through `j` and its nearer neighbour; `None` for a lone point.
fn surface_at(points: &[[f64; 2]], j: usize) -> Option<Surface> {
    /// How far a point may lie off the chord, metres (a corner within the span does not).
    const STRAIGHT_M: f64 = 0.02;
    let d2 = |a: [f64; 2], b: [f64; 2]| (b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2);
    let normal = |a: [f64; 2], b: [f64; 2]| {
        let d = d2(a, b).sqrt();
        (d > 1e-6).then(|| [-(b[1] - a[1]) / d, (b[0] - a[0]) / d])
    };
    let a = points[j];
    // Points within SPAN of j in scan order and near enough to j for their gap in order: an
    // outlier between them is skipped, not taken as the surface's end.
    let near = |k: usize| {
        let gap = MAX_GAP_M * k.abs_diff(j) as f64;
        d2(a, points[k]) <= gap * gap
    };
    let lo = (j.saturating_sub(SPAN)..j).find(|&k| near(k));
    let hi = (j + 1..(j + SPAN + 1).min(points.len()))
        .rev()
        .find(|&k| near(k));
    if let (Some(lo), Some(hi)) = (lo, hi)
        && let Some(n) = normal(points[lo], points[hi])
    {
        let off = |p: [f64; 2]| n[0] * (p[0] - points[lo][0]) + n[1] * (p[1] - points[lo][1]);
        if off(a).abs() <= STRAIGHT_M {
            // Through the mean of the points on the chord: the range noise of `j` alone does
            // not place the line.
            let on = || (lo..=hi).filter(|&k| near(k) && off(points[k]).abs() <= STRAIGHT_M);
            let (sum, count) = on().fold(([0.0, 0.0], 0.0), |(sum, count), k| {
                ([sum[0] + points[k][0], sum[1] + points[k][1]], count + 1.0)
            });
            let anchor = [sum[0] / count, sum[1] / count];
            let along = |p: [f64; 2]| (n[1] * (p[0] - anchor[0]) - n[0] * (p[1] - anchor[1])).abs();
            return Some(Surface {
                normal: n,
                anchor,
                reach: on().map(|k| along(points[k])).fold(0.0, f64::max),
                points: count as usize,
            });
        }
    }
    // The nearer neighbour on the same surface.
    let k = [j.checked_sub(1), (j + 1 < points.len()).then_some(j + 1)]
        .into_iter()
        .flatten()
        .filter(|&k| d2(a, points[k]) <= MAX_GAP_M * MAX_GAP_M)
        .min_by(|&k, &l| d2(a, points[k]).total_cmp(&d2(a, points[l])))?;
    normal(a, points[k]).map(|normal| Surface {
        normal,
        anchor: a,
        reach: d2(a, points[k]).sqrt(),
        points: 2,
    })
}

/// How far past the ends of its points a surface's line still holds, metres.
const END_MARGIN_M: f64 = 0.05;

/// Points either side of a reference point its surface's direction is taken from.
const SPAN: usize = 3;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::localization::ScanPoints;

    /// Points of a room's corner seen from inside: two walls at right angles.
    fn corner() -> Vec<[f64; 2]> {
        let mut points: Vec<[f64; 2]> = (0..100).map(|i| [3.0, -2.0 + 0.04 * i as f64]).collect();
        points.extend((0..100).map(|i| [3.0 - 0.04 * i as f64, 2.0]));
        points
    }

    /// A surface counts the points it was fitted to: all seven on a straight wall, fewer where
    /// the corner lies within its span; a point projects onto it only within its reach and
    /// `END_MARGIN_M` past it.
    #[test]
    fn surfaces_count_their_points_and_project_within_their_reach() {
        let points = corner();
        let wall = surface_at(&points, 50).expect("a surface on the wall");
        assert_eq!(wall.points, SURFACE_POINTS);
        let foot = wall.projection([3.3, 0.0]).expect("beside the surface");
        assert!(
            (foot[0] - 3.0).abs() < 1e-9 && foot[1].abs() < 1e-9,
            "{foot:?}"
        );
        // The wall's seven points reach 12 cm either side of the point (y = 0).
        assert!(wall.projection([3.3, 0.16]).is_some());
        assert!(wall.projection([3.3, 0.2]).is_none());
        let at_corner = surface_at(&points, 99).expect("a surface at the corner");
        assert!(at_corner.points < SURFACE_POINTS, "{at_corner:?}");
    }

    fn reference(points: &[[f64; 2]]) -> Reference {
        Reference::new(ScanPoints {
            xy: points.to_vec(),
            beam: (0..points.len()).collect(),
        })
    }

    /// A scan of 1° beams: a wall 5 m ahead (a surface at every point), an outlier 2 m out among
    /// it (lone, but its beams lie 3.5 cm apart there: judged as a point), and a wall 30 m out
    /// to one side, its beams 52 cm apart (no surface, and unresolved). A current point near
    /// that far wall, between two of its beams, is not judged: the share counts the rest.
    #[test]
    fn far_points_between_sparse_beams_are_not_judged() {
        let beam = |k: usize, r: f64| {
            let a = (-30.0 + k as f64).to_radians();
            [r * a.cos(), r * a.sin()]
        };
        let mut points: Vec<[f64; 2]> = (0..20)
            .map(|k| beam(k, 5.0 / (-30.0 + k as f64).to_radians().cos()))
            .collect();
        points[10] = beam(10, 2.0);
        points.extend((20..30).map(|k| beam(k, 30.0)));
        let prepared = reference(&points);
        assert!(!prepared.unresolved(5) && prepared.surface(5).is_some());
        assert!(
            prepared.surface(10).is_none() && !prepared.unresolved(10),
            "the outlier"
        );
        assert!((20..30).all(|j| prepared.surface(j).is_none() && prepared.unresolved(j)));
        // The current scan: the near wall's points where they are, and one point on the far
        // wall's arc half-way between two beams (25 cm from each), at the identity.
        let mut current: Vec<[f64; 2]> = (0..20).filter(|&k| k != 10).map(|k| points[k]).collect();
        let a = (-30.0f64 + 24.5).to_radians();
        current.push([30.0 * a.cos(), 30.0 * a.sin()]);
        let q = TrustRule::default().assess(&prepared, &current, &Pose2::default());
        assert_eq!(q.inliers, 19);
        assert_eq!(
            q.inlier_share, 1.0,
            "the far point is left out, not counted off"
        );
        // A sixth as far, the same beams lie 8.7 cm apart: resolved.
        let near: Vec<[f64; 2]> = points.iter().map(|p| [p[0] / 6.0, p[1] / 6.0]).collect();
        assert!(
            (20..30).all(|j| !reference(&near).unresolved(j)),
            "5 m out: resolved"
        );
    }

    /// A wall along x = 3 seen with ±1 cm of range noise and a far outlier among its points:
    /// the surface at a point 1 cm off the wall skips the outlier, keeps the wall's direction,
    /// and passes nearer the wall than the point itself (the mean of its neighbours).
    #[test]
    fn a_surface_skips_outliers_and_averages_the_noise() {
        let mut points: Vec<[f64; 2]> = (0..40)
            .map(|i| {
                let noise = if i % 2 == 0 { 0.01 } else { -0.01 };
                [3.0 + noise, -0.8 + 0.04 * i as f64]
            })
            .collect();
        points[19] = [7.5, -0.04]; // an outlier beside point 20
        let surfaces = surfaces(&points);
        let s = surfaces[20].expect("a surface");
        assert!(s.normal[0].abs() > 0.999, "{:?}", s.normal);
        let off_wall = |p: [f64; 2]| (p[0] - 3.0).abs();
        assert!(off_wall(points[20]) > 0.009);
        assert!(off_wall(s.anchor) < 0.004, "{:?}", s.anchor);
        // The points it was fitted to: 20's own and up to three either side but the outlier.
        assert!(s.reach > 0.1 && s.reach < 0.14, "{}", s.reach);
        // The outlier is a lone point: it has no surface of its own.
        assert!(surfaces[19].is_none());
    }

    /// The polish holds a point to a surface only near the points it was fitted to: points
    /// far along a wall the reference saw only a short piece of are not pulled onto that
    /// piece's direction, extrapolated.
    #[test]
    fn the_polish_does_not_extrapolate_a_short_surface() {
        // The reference saw 7 cm of a wall (x = 2), its direction 8° wrong (1 cm over 7 cm,
        // centred on the wall), and a long wall across (y = 3).
        let mut xy: Vec<[f64; 2]> = (0..8)
            .map(|i| [2.0 + 0.01 * (i as f64 - 3.5) / 7.0, 0.01 * i as f64])
            .collect();
        xy.extend((0..120).map(|i| [1.8 - 0.03 * i as f64, 3.0]));
        let reference = reference(&xy);
        // The current scan, taken from the same pose: the wall across, and 1.2 m more of the
        // first wall below what the reference saw.
        let mut current: Vec<[f64; 2]> = (0..120).map(|i| [1.8 - 0.03 * i as f64, 3.0]).collect();
        current.extend((1..=40).map(|i| [2.0, -0.03 * i as f64]));
        let pose = polish(&reference, &current, Pose2::default(), 5, 0.01, 0.05);
        // Only the points within 5 cm of the piece's ends pull: 11 mm. Held to the whole
        // extrapolated line, the answer went 34 mm aside.
        assert!(pose.x.abs() < 0.015, "{pose:?}");
        assert!(pose.y.abs() < 1e-3 && pose.theta.abs() < 1e-3, "{pose:?}");
    }

    /// A room 6 m by 5 m seen from `pose` (in the room's frame) by 361 beams 0.5° apart, each
    /// range off by up to `noise_m` (a fixed draw per beam and `salt`): the points in the
    /// laser's frame, in beam order.
    fn room_scan(pose: Pose2, noise_m: f64, salt: u64) -> Vec<[f64; 2]> {
        let ([x0, y0], [x1, y1]) = ([-2.0, -2.0], [4.0, 3.0]);
        (0..361u64)
            .map(|k| {
                let a = pose.theta + (-90.0 + 0.5 * k as f64).to_radians();
                let (dx, dy) = (a.cos(), a.sin());
                let to = |lo: f64, hi: f64, from: f64, d: f64| {
                    if d > 1e-12 {
                        (hi - from) / d
                    } else if d < -1e-12 {
                        (lo - from) / d
                    } else {
                        f64::INFINITY
                    }
                };
                let range = to(x0, x1, pose.x, dx).min(to(y0, y1, pose.y, dy));
                // A draw in [-1, 1) from the beam and the salt (SplitMix64's mixing).
                let mut z = (k + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ salt;
                z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
                z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
                let u = (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
                let r = range + noise_m * u;
                let b = (-90.0 + 0.5 * k as f64).to_radians();
                [r * b.cos(), r * b.sin()]
            })
            .collect()
    }

    /// The polish both ways: from 1 cm and 0.3° off, it lands within 0.05 mm and 0.003° of the
    /// truth between two noiseless scans of a room (where the walls meet, a point's nearest
    /// surface may be the other wall's, as one way: 0.013 mm there). Between two noisy ones,
    /// matching the first to the second and the second to the first give nearly the same
    /// answer, where polished one way the two answers differ by the scans' noise as each side
    /// sees it: over twenty draws of the noise, the two answers' RMS disagreement both ways is
    /// under a fifth of one way's, in position and in heading. (Over 199 draws, 0.19 against
    /// 2.13 mm and 0.003 against 0.036°; every run of twenty of them under 0.15 of one way's. A
    /// single draw is no claim: one way's two answers agree closely by chance now and then.)
    #[test]
    fn the_polish_both_ways_treats_both_scans_alike() {
        let (a, b) = (Pose2::new(0.0, 0.0, 0.0), Pose2::new(0.3, 0.1, 0.2));
        let truth = a.relative(&b);
        let off = truth.compose(&Pose2::new(0.01, -0.01, 0.3f64.to_radians()));
        let rounds = (5, 0.01, 0.05);
        let both = |first: &[[f64; 2]], second: &[[f64; 2]], guess: Pose2| {
            let mut last = vec![None; second.len()];
            polish_both_ways(&reference(first), second, guess, rounds, &mut last)
        };
        let clean = both(&room_scan(a, 0.0, 1), &room_scan(b, 0.0, 2), off);
        let miss = truth.relative(&clean);
        assert!(
            miss.x.hypot(miss.y) < 5e-5 && miss.theta.abs() < 5e-5,
            "{miss:?}"
        );
        let one = |first: &[[f64; 2]], second: &[[f64; 2]], guess: Pose2| {
            polish(
                &reference(first),
                second,
                guess,
                rounds.0,
                rounds.1,
                rounds.2,
            )
        };
        // Each answer composed with its swapped match: the identity if the two agree.
        let disagreement = |forth: Pose2, back: Pose2| {
            let loop_ = forth.compose(&back);
            [loop_.x.hypot(loop_.y), loop_.theta.abs()]
        };
        // Summed squares of the disagreement in position and heading, one way and both ways.
        let (mut one_way, mut both_ways) = ([0.0; 2], [0.0; 2]);
        for draw in 0..20u64 {
            let first = room_scan(a, 0.02, 2 * draw + 1);
            let second = room_scan(b, 0.02, 2 * draw + 2);
            let sums = [
                (
                    &mut one_way,
                    disagreement(
                        one(&first, &second, off),
                        one(&second, &first, off.inverse()),
                    ),
                ),
                (
                    &mut both_ways,
                    disagreement(
                        both(&first, &second, off),
                        both(&second, &first, off.inverse()),
                    ),
                ),
            ];
            for (sum, d) in sums {
                sum[0] += d[0] * d[0];
                sum[1] += d[1] * d[1];
            }
        }
        let rms = |sum: [f64; 2]| sum.map(|s| (s / 20.0).sqrt());
        let (one_way, both_ways) = (rms(one_way), rms(both_ways));
        println!("RMS disagreement one way {one_way:?}, both ways {both_ways:?}");
        for k in 0..2 {
            assert!(
                both_ways[k] < 0.2 * one_way[k],
                "{both_ways:?} against {one_way:?}"
            );
        }
    }

    #[test]
    fn a_right_answer_is_trusted_and_a_wrong_one_is_not() {
        let rule = TrustRule::default();
        let reference = reference(&corner());
        // The current scan taken 0.2 m further forward: its points are the corner's, 0.2 m nearer.
        let current: Vec<[f64; 2]> = corner().iter().map(|p| [p[0] - 0.2, p[1]]).collect();
        let right = rule.assess(&reference, &current, &Pose2::new(0.2, 0.0, 0.0));
        assert!(right.inlier_share > 0.95 && right.rms_m < 1e-9, "{right:?}");
        assert!(rule.trusts(&right), "{right:?}");
        let wrong = rule.assess(&reference, &current, &Pose2::new(0.0, 0.0, 0.0));
        assert!(!rule.trusts(&wrong), "{wrong:?}");
        let turned = rule.assess(&reference, &current, &Pose2::new(0.2, 0.0, 0.1));
        assert!(!rule.trusts(&turned), "{turned:?}");
    }

    /// A room's corner seen with 1° beams is sparse, with 0.5° beams it is not; against a
    /// sparse reference a right answer whose current scan sees 40 % of its points on the
    /// reference's surfaces (the rest on what the reference did not see) is trusted, and the
    /// same figures from a dense reference are not.
    #[test]
    fn sparse_references_ask_a_smaller_share() {
        let seen = |step_deg: f64, beams: usize| -> Vec<[f64; 2]> {
            (0..beams)
                .map(|k| {
                    let a = (-45.0 + step_deg * k as f64).to_radians();
                    // The corner x = 3, y = 2 seen from the origin.
                    let r = (3.0 / a.cos()).min(if a > 0.0 { 2.0 / a.sin() } else { f64::MAX });
                    [r * a.cos(), r * a.sin()]
                })
                .collect()
        };
        let sparse = reference(&seen(1.0, 120));
        let dense = reference(&seen(0.5, 240));
        assert!(sparse.is_sparse() && !dense.is_sparse());
        // The current scan: 40 points of the corner, where they are, and 60 on a wall 2 m
        // beyond the reference's far one (new ground).
        let mut current: Vec<[f64; 2]> = seen(1.0, 120).into_iter().step_by(3).collect();
        current.extend((0..60).map(|i| [-1.0 + 0.05 * i as f64, 4.0]));
        let rule = TrustRule::default();
        let q = rule.assess(&sparse, &current, &Pose2::default());
        assert!(q.sparse && (0.35..0.5).contains(&q.inlier_share), "{q:?}");
        assert!(rule.trusts(&q), "{q:?}");
        let as_dense = MatchQuality { sparse: false, ..q };
        assert!(!rule.trusts(&as_dense), "{as_dense:?}");
    }

    #[test]
    fn a_corridor_leaves_its_length_free() {
        let rule = TrustRule::default();
        // Two long parallel walls: nothing says where along them the robot is.
        let mut walls: Vec<[f64; 2]> = (0..200).map(|i| [-4.0 + 0.04 * i as f64, 1.0]).collect();
        walls.extend((0..200).map(|i| [4.0 - 0.04 * i as f64, -1.0]));
        let q = rule.assess(&reference(&walls), &walls, &Pose2::IDENTITY);
        assert!(q.inlier_share > 0.99, "{q:?}");
        assert!(q.sigma[0] > 1.0, "{q:?}");
        assert!(!rule.trusts(&q));
    }

    /// `n` points of a wall from `from` in steps of `step`, each moved off the wall along its
    /// normal by a laser's centimetre of noise (a fixed sequence from its index `first + i`).
    fn noisy_wall(from: [f64; 2], step: [f64; 2], n: usize, first: usize) -> Vec<[f64; 2]> {
        let noise = |k: usize| 0.02 * ((k as f64 * 0.754_877_666).fract() - 0.5);
        let len = step[0].hypot(step[1]);
        // The step turned a quarter.
        let normal = [-step[1] / len, step[0] / len];
        (0..n)
            .map(|i| {
                let (e, t) = (noise(first + i), i as f64);
                [
                    from[0] + t * step[0] + e * normal[0],
                    from[1] + t * step[1] + e * normal[1],
                ]
            })
            .collect()
    }

    /// A corridor 6 m long and 2 m wide along x, its two walls' points 1.5 cm apart with noise
    /// from index `first` ([`noisy_wall`]).
    fn corridor_walls(first: usize) -> Vec<[f64; 2]> {
        let mut walls = noisy_wall([-3.0, 1.0], [0.015, 0.0], 400, first);
        walls.extend(noisy_wall([3.0, -1.0], [-0.015, 0.0], 400, first + 400));
        walls
    }

    /// A doorway in [`corridor_walls`]' upper wall: its two jambs, 20 cm deep at x = 0 and 0.9,
    /// which face along the corridor.
    fn doorway_jambs(first: usize) -> Vec<[f64; 2]> {
        let mut jambs = noisy_wall([0.0, 1.0], [0.0, 0.015], 14, first);
        jambs.extend(noisy_wall([0.9, 1.2], [0.0, -0.015], 14, first + 14));
        jambs
    }

    /// A corridor whose walls carry a laser's centimetre of noise, points 1.5 cm apart: the
    /// chords' noisy normals sum to a σ along it under the rule's centimetre, so the
    /// information alone would trust an answer anywhere along it. Its surfaces all face one
    /// way (spread under 0.2), and moved 10 cm along, the answer fits as many points: not held,
    /// not trusted. The same corridor with a doorway's two jambs across it is held; a room's
    /// corner is not even asked.
    #[test]
    fn a_corridor_the_information_would_hold_is_not_held() {
        let rule = TrustRule::default();
        let corridor = corridor_walls(0);
        // The current scan: the same walls, its own noise.
        let current = corridor_walls(1000);
        let r = reference(&corridor);
        let q = rule.assess(&r, &current, &Pose2::IDENTITY);
        assert!(q.spread < rule.hold_below_spread, "{q:?}");
        assert!(
            q.sigma[0] < rule.max_sigma_m,
            "the noise feigns a hold: {q:?}"
        );
        assert!(q.free[0].abs() > 0.99, "free along the walls: {q:?}");
        assert!(rule.trusts(&q), "the rule without the hold: {q:?}");
        assert!(!rule.holds(&r, &current, &Pose2::IDENTITY, &q));

        // A doorway in the upper wall: its jambs, 20 cm deep, face along the corridor.
        let (mut with, mut current_with) = (corridor.clone(), current.clone());
        with.extend(doorway_jambs(2000));
        current_with.extend(doorway_jambs(3000));
        let r = reference(&with);
        let q = rule.assess(&r, &current_with, &Pose2::IDENTITY);
        assert!(q.spread < rule.hold_below_spread, "{q:?}");
        assert!(rule.holds(&r, &current_with, &Pose2::IDENTITY, &q), "{q:?}");

        // A room's corner: its surfaces spread, and nothing more is asked.
        let mut corner = noisy_wall([0.0, 2.0], [0.015, 0.0], 200, 0);
        corner.extend(noisy_wall([3.0, 2.0], [0.0, -0.015], 200, 200));
        let r = reference(&corner);
        let q = rule.assess(&r, &corner, &Pose2::IDENTITY);
        assert!(q.spread >= rule.hold_below_spread, "{q:?}");
        assert!(rule.holds(&r, &corner, &Pose2::new(5.0, 5.0, 0.0), &q));
    }

    /// An answer slid along a corridor that does not hold it is walked back toward the guess
    /// along the corridor, its heading and its place across kept; in the same corridor with a
    /// doorway's jambs (surfaces across it), the walk stops at the first step that loses
    /// points, so an answer the jambs hold keeps its place.
    #[test]
    fn an_unheld_answer_takes_the_guess_place_along_its_free_direction() {
        let rule = TrustRule::default();
        let along = GuessAlongFree {
            band_m: 0.02,
            step_m: 0.01,
            max_steps: 30,
            spare: 1,
        };
        let corridor = corridor_walls(0);
        let current = corridor_walls(1000);

        // Slid 7 cm along the corridor (and 3 mm across, 0.1° turned); the guess 1 cm off the
        // truth along it, 4 cm across.
        let slid = Pose2::new(0.07, 0.003, 0.1f64.to_radians());
        let guess = Pose2::new(0.01, 0.04, 0.0);
        let r = reference(&corridor);
        let q = rule.assess(&r, &current, &slid);
        assert!(
            rule.trusts(&q) && !rule.holds(&r, &current, &slid, &q),
            "{q:?}"
        );
        let placed = along.place(&r, &current, &slid, &q, &guess);
        // Along the corridor (x, up to the sign of `free`) the guess's place; across and in
        // heading the answer's.
        assert!((placed.x - guess.x).abs() < 1e-3, "{placed:?}");
        assert!((placed.y - slid.y).abs() < 2e-3, "{placed:?}");
        assert_eq!(placed.theta, slid.theta);

        // A doorway's jambs, 20 cm deep, across the upper wall at x = 0 and 0.9: seen in both
        // scans, they hold the answer at the truth, and a walk toward a guess 8 cm along stops
        // within the band's 2 cm.
        let (mut with, mut current_with) = (corridor.clone(), current.clone());
        with.extend(doorway_jambs(2000));
        current_with.extend(doorway_jambs(3000));
        let r = reference(&with);
        let q = rule.assess(&r, &current_with, &Pose2::IDENTITY);
        let placed = along.place(
            &r,
            &current_with,
            &Pose2::IDENTITY,
            &q,
            &Pose2::new(0.08, 0.0, 0.0),
        );
        assert!(placed.x.abs() <= 0.02, "{placed:?}");

        // A guess exactly at the answer's place along it, or a direction that is not finite,
        // leave the answer where it is.
        let q = rule.assess(&reference(&corridor), &current, &slid);
        let at = along.place(&reference(&corridor), &current, &slid, &q, &slid);
        assert_eq!(at, slid);
        let lost = MatchQuality {
            free: [f64::NAN, 0.0],
            ..q
        };
        assert_eq!(
            along.place(&reference(&corridor), &current, &slid, &lost, &guess),
            slid
        );
    }

    /// The position's weakest σ is the larger axis of its covariance, whatever the axes: a
    /// corridor 3 m long with a short end wall, turned 45°, reads the same weakest σ as
    /// unturned, where its x and y σ share it (each about 1/√2 of it); and the judgement is
    /// the same as [`TrustRule::assess`]'s to the bit.
    #[test]
    fn the_weakest_direction_is_read_whatever_the_axes() {
        let rule = TrustRule::default();
        let corridor = |turn: f64| {
            let (s, c) = turn.sin_cos();
            let mut points: Vec<[f64; 2]> =
                (0..75).map(|i| [-1.0 + 0.04 * i as f64, 1.0]).collect();
            points.extend((0..10).map(|i| [2.0, 0.9 - 0.04 * i as f64]));
            points.extend((0..75).map(|i| [2.0 - 0.04 * i as f64, -1.0]));
            // Millimetres of noise, so that the σ are not the floor's.
            for (k, p) in points.iter_mut().enumerate() {
                p[1] += 0.004 * ((k as f64 * 0.618_034).fract() - 0.5);
            }
            let turned: Vec<[f64; 2]> = points
                .iter()
                .map(|p| [c * p[0] - s * p[1], s * p[0] + c * p[1]])
                .collect();
            turned
        };
        let weakest = |points: &[[f64; 2]]| {
            let r = reference(points);
            let (q, w) = rule.assess_near_weakest(&r, points, &Pose2::IDENTITY, None);
            assert_eq!(q, rule.assess(&r, points, &Pose2::IDENTITY));
            (q, w)
        };
        let (along, w0) = weakest(&corridor(0.0));
        let (turned, w45) = weakest(&corridor(std::f64::consts::FRAC_PI_4));
        assert!(w0.is_finite() && w0 > 0.0, "{w0}");
        assert!((w45 / w0 - 1.0).abs() < 0.05, "{w0} {w45}");
        // Along the unturned corridor the weakest is x's; turned, x and y each hold ~0.7 of it.
        assert!((along.sigma[0] / w0 - 1.0).abs() < 0.05, "{along:?} {w0}");
        for k in 0..2 {
            let share = turned.sigma[k] / w45;
            assert!((0.6..0.8).contains(&share), "{turned:?} {w45}");
        }
        let none = rule.assess_near_weakest(&reference(&[]), &[], &Pose2::IDENTITY, None);
        assert_eq!(none, (MatchQuality::NONE, f64::INFINITY));
    }

    /// The polish and the judgement answer the same, to the last bit, whether each point's
    /// last nearest reference point is kept from searches near there before (the matcher's,
    /// from another pose, the other's) or not: the cache skips searches, never changes an
    /// answer. Over a noisy corner with exact ties (points 4 cm apart, queries halfway).
    #[test]
    fn searching_near_earlier_queries_changes_nothing() {
        let rule = TrustRule::default();
        let reference = reference(&corner());
        let current: Vec<[f64; 2]> = corner()
            .iter()
            .enumerate()
            .map(|(i, p)| [p[0] - 0.2 + 0.003 * ((i * 7) % 5) as f64, p[1] + 0.02])
            .collect();
        let mut last = vec![None; current.len()];
        for (k, start) in [
            Pose2::new(0.21, -0.03, 0.01),
            Pose2::new(0.2, -0.02, 0.0),
            Pose2::new(0.0, 0.0, 0.0),
            Pose2::new(0.25, 0.01, -0.02),
        ]
        .into_iter()
        .enumerate()
        {
            let cached = polish_near(
                &reference,
                &current,
                start,
                (5, 0.01, 0.05),
                None,
                &mut last,
            )
            .0;
            let fresh = polish(&reference, &current, start, 5, 0.01, 0.05);
            assert_eq!(cached, fresh, "start {k}");
            let judged = rule.assess_near(&reference, &current, &cached, Some(&mut last));
            assert_eq!(
                judged,
                rule.assess(&reference, &current, &fresh),
                "start {k}"
            );
        }
        assert!(
            last.iter().all(Option::is_some),
            "every point was searched for"
        );
    }

    /// A judgement given a floor is given up exactly when the pose fits no more than `floor`
    /// points, and is otherwise the whole judgement to the last bit, at poses that fit all,
    /// some and none of the points, and with a cache left from other poses.
    #[test]
    fn a_judgement_above_a_floor_is_the_judgement_or_nothing() {
        let rule = TrustRule::default();
        let reference = reference(&corner());
        let current: Vec<[f64; 2]> = corner()
            .iter()
            .enumerate()
            .map(|(i, p)| [p[0] + 0.003 * ((i * 7) % 5) as f64, p[1]])
            .collect();
        let mut last = vec![None; current.len()];
        let mut given_up = 0;
        for pose in [
            Pose2::IDENTITY,
            Pose2::new(0.04, 0.0, 0.0),
            Pose2::new(0.0, 0.08, 0.02),
            Pose2::new(3.0, -2.0, 1.0),
        ] {
            let whole = rule.assess(&reference, &current, &pose);
            for floor in [
                0,
                whole.inliers / 2,
                whole.inliers.saturating_sub(1),
                whole.inliers,
            ]
            .into_iter()
            .chain([whole.inliers + 1, current.len()])
            {
                let above =
                    rule.assess_near_above(&reference, &current, &pose, Some(&mut last), floor);
                if whole.inliers > floor {
                    assert_eq!(above, Some(whole), "{pose:?}, floor {floor}");
                } else {
                    assert_eq!(above, None, "{pose:?}, floor {floor}");
                    given_up += 1;
                }
            }
        }
        assert!(given_up >= 8, "{given_up}");
        assert_eq!(
            rule.assess_near_above(&reference, &[], &Pose2::IDENTITY, None, 0),
            None
        );
    }

    #[test]
    fn nothing_to_compare_is_not_trusted() {
        let rule = TrustRule::default();
        let q = rule.assess(&reference(&corner()), &[], &Pose2::IDENTITY);
        assert_eq!(q, MatchQuality::NONE);
        assert!(!rule.trusts(&q));
    }

    /// A corridor's wall 6 m long and its end wall 2 m across, seen from inside (points 1 cm
    /// apart in scan order). An answer 8 cm short along the corridor keeps the long wall's points
    /// on it, so the inliers hold it only across the corridor; the end wall's points, 8 cm off
    /// it, vote for the shift back: along the corridor, 8 cm (within the 1 cm the plateau of
    /// shifts allows for noise-free points), every one of them. At the truth they hold it and
    /// ask for nothing.
    #[test]
    fn a_slide_vote_points_back_along_the_wall() {
        let mut points: Vec<[f64; 2]> = (0..=600).map(|i| [-1.0 + 0.01 * i as f64, 1.0]).collect();
        points.extend((1..=200).map(|i| [5.0, 1.0 - 0.01 * i as f64]));
        let reference = reference(&points);
        let inlier_m = TrustRule::default().inlier_m;
        let short = Pose2::new(-0.08, 0.0, 0.0);
        let shifts = (0.025, 0.2);
        let vote = slide_vote(&reference, &points, &short, None, inlier_m, shifts).unwrap();
        assert!(vote.direction[0].abs() > 0.999, "{vote:?}");
        let back = vote.shift_m * vote.direction[0];
        assert!((back - 0.08).abs() < 0.01, "{vote:?}");
        assert!(vote.recruits >= 190, "{vote:?}");
        let truth = slide_vote(
            &reference,
            &points,
            &Pose2::IDENTITY,
            None,
            inlier_m,
            shifts,
        );
        assert_eq!(truth.map(|v| v.recruits), Some(0));
        // No point near any surface: no vote.
        let far = Pose2::new(10.0, 10.0, 0.0);
        assert_eq!(
            slide_vote(&reference, &points, &far, None, inlier_m, shifts),
            None
        );
    }

    /// Only points within their surface's reach vote: where the reference saw the end wall of a
    /// corridor only for its first 20 cm (its field of view ended there) and the current scan
    /// sees a metre of it, the points past the reference's end, held to a line extrapolated
    /// from its last beams, do not vote. And a point already on its surface does not vote
    /// against a slide: a box across the corridor, in both scans, whose face the shift back
    /// would carry out of the trust rule's distance (a box moved, or a point carried onto
    /// another surface), leaves the vote as it was; the judgement at the shift weighs it.
    #[test]
    fn only_points_off_their_surfaces_and_within_their_reach_vote() {
        let inlier_m = TrustRule::default().inlier_m;
        let shifts = (0.025, 0.2);
        let wall = (0..=600).map(|i| [-1.0 + 0.01 * i as f64, 1.0]);
        let end = |to: usize| (1..=to).map(|i| [5.0, 1.0 - 0.01 * i as f64]);
        let seen: Vec<[f64; 2]> = wall.clone().chain(end(20)).collect();
        let current: Vec<[f64; 2]> = wall.clone().chain(end(100)).collect();
        let short = Pose2::new(-0.08, 0.0, 0.0);
        let vote = slide_vote(&reference(&seen), &current, &short, None, inlier_m, shifts);
        let vote = vote.unwrap();
        assert!(
            (vote.shift_m * vote.direction[0] - 0.08).abs() < 0.01,
            "{vote:?}"
        );
        // About the reference's 20 points (those by the corner are the long wall's), and those
        // within the line's 5 cm margin past its end: not the 100 its line, extrapolated, holds.
        assert!((15..=30).contains(&vote.recruits), "{vote:?}");
        // A box's face across the corridor, 40 cm long, seen by both scans; in the current scan
        // 2 cm off it at the short pose and 6 cm off once shifted back (the box 6 cm nearer the
        // end wall than the rest): its 40 points, more than vote, would hold the answer where it
        // is if they voted to stay.
        let face = |x: f64| (0..40).map(move |i| [x, 0.2 - 0.01 * i as f64]);
        let boxed: Vec<[f64; 2]> = face(2.0).chain(seen.iter().copied()).collect();
        let moved: Vec<[f64; 2]> = face(2.06).chain(current.iter().copied()).collect();
        let with_box = slide_vote(&reference(&boxed), &moved, &short, None, inlier_m, shifts);
        let with_box = with_box.unwrap();
        assert_eq!(with_box.recruits, vote.recruits, "{with_box:?}");
        assert!(
            (with_box.shift_m * with_box.direction[0] - 0.08).abs() < 0.01,
            "{with_box:?}"
        );
    }

    /// An answer that fits too few points but fits them well and is pinned down is one the
    /// rule would trust with more overlap; one that also fits badly, or is free along a wall,
    /// or pulled aside, is not.
    #[test]
    fn only_the_overlap_can_be_set_aside() {
        let rule = TrustRule::default();
        let good = MatchQuality {
            inliers: 120,
            inlier_share: 0.8,
            rms_m: 0.015,
            sigma: [0.003, 0.004, 0.001],
            sparse: false,
            step: [0.002, 0.001],
            spread: 0.4,
            free: [1.0, 0.0],
            held: true,
            across_sigma: [0.003, 0.001],
            across_step: [0.001, 0.001],
        };
        assert!(rule.trusts(&good) && rule.trusts_but_overlap(&good));
        let little = MatchQuality {
            inlier_share: 0.4,
            ..good
        };
        assert!(!rule.trusts(&little) && rule.trusts_but_overlap(&little));
        for other in [
            MatchQuality {
                rms_m: 0.04,
                ..little
            },
            MatchQuality {
                sigma: [0.003, 0.02, 0.001],
                ..little
            },
            MatchQuality {
                step: [0.04, 0.001],
                ..little
            },
            MatchQuality {
                inliers: 10,
                ..little
            },
        ] {
            assert!(!rule.trusts_but_overlap(&other), "{other:?}");
        }
    }

    /// Only σ can be set aside by `trusts_but_sigma`: an answer loose in heading (0.304°,
    /// the rule's bound 0.3°) or across is so, one that also fits too few points, fits badly,
    /// still travels or is not held is not.
    #[test]
    fn only_sigma_can_be_set_aside() {
        let rule = TrustRule::default();
        let good = MatchQuality {
            inliers: 114,
            inlier_share: 0.88,
            rms_m: 0.0136,
            sigma: [0.002, 0.002, 0.001],
            sparse: true,
            step: [0.006, 0.016],
            spread: 0.59,
            free: [1.0, 0.0],
            held: true,
            across_sigma: [0.002, 0.001],
            across_step: [0.006, 0.016],
        };
        assert!(rule.trusts(&good) && rule.trusts_but_sigma(&good));
        for loose in [[0.002, 0.002, 0.304f64.to_radians()], [0.002, 0.02, 0.001]] {
            let loose = MatchQuality {
                sigma: loose,
                ..good
            };
            assert!(!rule.trusts(&loose) && rule.trusts_but_sigma(&loose));
            for other in [
                MatchQuality {
                    inlier_share: 0.3,
                    ..loose
                },
                MatchQuality {
                    rms_m: 0.04,
                    ..loose
                },
                MatchQuality {
                    step: [0.04, 0.001],
                    ..loose
                },
                MatchQuality {
                    held: false,
                    spread: 0.1,
                    ..loose
                },
            ] {
                assert!(!rule.trusts_but_sigma(&other), "{other:?}");
            }
        }
    }

    /// A corridor's answer held across it and in heading, free along it — because the hold
    /// test found it free there, or because the walls' information left σ along it infinite
    /// (no noise) — is trusted across only; a trusted answer is not, nor one whose surfaces
    /// spread, nor one that fits badly or is loose across.
    #[test]
    fn a_corridor_is_trusted_across_only() {
        let rule = TrustRule::default();
        let corridor = MatchQuality {
            inliers: 300,
            inlier_share: 0.95,
            rms_m: 0.004,
            sigma: [0.003, 0.001, 0.0005],
            sparse: false,
            step: [0.001, 0.0001],
            spread: 0.01,
            free: [1.0, 0.0],
            held: false,
            across_sigma: [0.001, 0.0005],
            across_step: [0.001, 0.0001],
        };
        let noiseless = MatchQuality {
            sigma: [f64::INFINITY, 0.0004, 0.0001],
            step: [f64::INFINITY; 2],
            held: true,
            rms_m: 0.0,
            ..corridor
        };
        for q in [corridor, noiseless] {
            assert!(!rule.trusts(&q) && rule.trusts_across(&q), "{q:?}");
        }
        assert!(rule.trusts_but_hold(&corridor) && !rule.trusts_but_hold(&noiseless));
        for other in [
            MatchQuality {
                held: true,
                ..corridor
            },
            MatchQuality {
                spread: 0.4,
                ..noiseless
            },
            MatchQuality {
                rms_m: 0.04,
                ..noiseless
            },
            MatchQuality {
                across_sigma: [0.02, 0.0005],
                ..noiseless
            },
            MatchQuality {
                across_step: [0.001, 0.1],
                ..noiseless
            },
            MatchQuality {
                inlier_share: 0.3,
                ..noiseless
            },
        ] {
            assert!(!rule.trusts_across(&other), "{other:?}");
        }
    }
}
