//! The Lorentzian scan matcher of the thesis (§3.4, App. F): the robust error
//! `E = Σ ρσ(e_x,i) + ρσ(e_y,i)`, `ρσ(e) = log(1 + ½ (e/σ)²)`, minimised over `Φ = (θ, tx, ty)` by
//! Newton–Levenberg–Marquardt, three times with σ = 2, 5 and 0.5 (§5.2); optionally with
//! line-assisted association (§3.4.3).
//!
//! The constants' docs quote what each step measured when it was chosen. Edmonton's figures
//! dated before 2026-11-28's beam-step fix of the CARMEN reader were measured with its 180
//! readings spread over 180° instead of 1° apart ([`SPARSE_FINISH`] gives both).

use super::correlative;
use super::kdtree::LastNearest;
use super::lines::{Line, LineParams, lines_of};
use super::matcher::{Convergence, MatchResult, Reference, ScanMatcher, solve3, transform_all};
use super::plicp::PointToLine;
use super::quality::{TrustRule, polish_near, slide_vote};
use super::scan::{SPARSE_BEAM_STEP_RAD, ScanPoints, beam_step_below};
use crate::geometry::{Pose2, wrap_angle};

/// The thesis's σ schedule, in the unit [`Lorentz::SIGMA_UNIT_M`].
pub const THESIS_SIGMAS: [f64; 3] = [2.0, 5.0, 0.5];

/// The Lorentzian matcher.
///
/// Each σ pass alternates a correspondence search (every current point, moved by the estimate,
/// paired with its nearest reference point — or a point on the reference's local line) with an
/// NLM minimisation over those pairs, until a search no longer moves the estimate. The NLM is
/// §3.4.2's: analytic gradient and Hessian (App. F), solve `(A + λI) δΦ = −B`, accept the step
/// and divide λ by 10 when `E` falls, else multiply λ by 10 and retry; stop when `E` no longer
/// falls noticeably or λ grows past `lambda_max`.
#[derive(Clone, Debug, PartialEq)]
pub struct Lorentz {
    /// σ of each pass, metres. Default: the thesis's 2 → 5 → 0.5 in centimetres (0.02, 0.05,
    /// 0.005 m); `cargo run --release --example sigma_sweep` shows why centimetres.
    /// [`Lorentz::with_lines`] has [`SPARSE_SIGMAS`]: a point-to-line round in place of the
    /// first pass ([`Lorentz::sparse_start`]), the finish in place of the last.
    pub sigmas_m: Vec<f64>,
    /// λ at the start of each minimisation. Default 0.001.
    pub lambda0: f64,
    /// Above this λ no better step exists. Default 1e12.
    pub lambda_max: f64,
    /// A minimisation stops when an accepted step lowers `E` by less than this per pair.
    /// Default 1e-9.
    pub energy_tolerance: f64,
    /// Accepted NLM steps allowed per minimisation. Default 30.
    pub max_steps: u32,
    /// Accepted NLM steps allowed per minimisation in the first match from the guess (and a
    /// loose answer's second match, [`Lorentz::first_spread`]), instead of `max_steps`; the
    /// wide schedule, the restarts and the coarse search's starts keep `max_steps`. Not in the
    /// thesis; `None` (the default) leaves `max_steps` everywhere, and
    /// [`Lorentz::with_lines`] has [`FIRST_STEPS`].
    pub first_max_steps: Option<u32>,
    /// When a σ pass stops: a search that moves the estimate by under 0.01 mm and 0.0001°, or
    /// 30 searches.
    pub convergence: Convergence,
    /// When a σ pass before the last stops, if not as `convergence` (which the last pass
    /// keeps). Not in the thesis; `None` (the default) stops every pass alike, and
    /// [`Lorentz::with_lines`] has [`EARLY_CONVERGENCE`].
    pub early_convergence: Option<Convergence>,
    /// Line-assisted association, when set.
    pub lines: Option<LineParams>,
    /// Leave out a current point whose nearest reference point is an
    /// [edge](Reference::is_edge) of the reference scan, unless it is projected onto a line: it
    /// lies where the reference did not look. Not in the thesis; without it a 0.5 m retreat down
    /// the L-corridor comes out 0.1–0.4 m short. Default true.
    pub drop_edge_pairs: bool,
    /// For dense scans (as `dense_sigmas_m`), in every schedule but the wide one: of the pairs
    /// that share a nearest reference point, those more than this many times farther from their
    /// targets than the nearest of them, and farther than it by more than the pass's σ, are
    /// left out of the search. Not in the thesis; `None` (the default) keeps them, and
    /// [`Lorentz::with_lines`] has [`CROWD_RATIO`].
    pub crowd_ratio: Option<f64>,
    /// A last point-to-line stage ([`polish`](super::polish)) after the σ passes: at most this
    /// many Gauss–Newton rounds on the current points within 5 cm of the reference's surfaces,
    /// Cauchy-weighted at 1 cm. Not in the thesis; 0 (the default) leaves it out, and
    /// [`Lorentz::with_lines`] has 5: the median error of synthetic pairs fell from 2.0 to
    /// 1.9 mm without outliers and from 2.8 to 2.5 mm with 20 % (`twin matchers`), and to 1.7
    /// and 1.9 mm once the reference's surfaces were fitted to their points' mean, skipping
    /// outliers.
    pub polish_rounds: usize,
    /// For dense scans (as `dense_sigmas_m`), after every schedule but the wide one: the
    /// polish goes on past `polish_rounds` while its last round still turned the estimate by
    /// more than the first figure (radians), at most the second figure more rounds, and its
    /// answer is kept unless the pose after `polish_rounds` fits more of the current points.
    /// Not in the thesis; `None` (the default) stops at `polish_rounds`, and
    /// [`Lorentz::with_lines`] has [`POLISH_MORE`].
    pub polish_more: Option<(f64, usize)>,
    /// With the polish: the answer from before the last σ pass is polished too, and kept when the
    /// share of current points within 5 cm of the reference's surfaces is more than this above the
    /// last pass's. Not in the thesis; `None` (the default) leaves it out, and
    /// [`Lorentz::with_lines`] has 0.01. The last pass, at σ 5 mm, is what makes the synthetic
    /// pairs precise; on Edmonton's sparse 1° scans it sometimes settles a few centimetres aside,
    /// and over 2,400 pairs (`twin matchers`, seeds 1–6, 11, 12) keeping the earlier answer there
    /// raised Edmonton's right answers from 0.934 to 0.945 (better on every seed), lost no
    /// synthetic pair and left the Table 5.1 study as it was. Only where the crowd rule does not
    /// run (the wide schedule; [`Lorentz::crowd_ratio`]): on dense scans with the rule, over seeds
    /// 1–20 it changed no right answer and no Table 5.1 trial (about ten answers a seed by
    /// millimetres) for 5–8 % of the time. Nor before the sparse finish
    /// ([`Lorentz::sparse_finish`]): since the last pass of a sparse scan stopped at 3 mm (before
    /// [`SPARSE_SIGMAS`] left that pass out) it no longer settled aside, the finish places the
    /// answer, and the second polish and its judgement were a tenth of a 1° match's time for no
    /// steady gain (over seeds 1–10 and held-out 21–30 of `twin matchers`, Edmonton −1 and ±0 right
    /// answers, the twin's 1° rows +1 and −2 of 6,000 each).
    pub before_last_margin: Option<f64>,
    /// A second σ schedule, metres, tried from the guess when the first answer is not trusted
    /// ([`TrustRule`]), or is trusted but fits loosely (under `wide_below` of the current
    /// points inliers) after going more than 10 cm or 3° from the guess: the trusted answer
    /// with the larger inlier share is kept. A trusted wide answer that fits fewer points than
    /// an untrusted first one may have slid to a look-alike place, so the restarts still run
    /// and it is kept only if none fits better. Not in the thesis; empty (the default) leaves
    /// it out, and [`Lorentz::with_lines`] has [`WIDE_SIGMAS`].
    pub wide_sigmas_m: Vec<f64>,
    /// The inlier share under which a trusted answer also tries `wide_sigmas_m`. Default 0.7.
    pub wide_below: f64,
    /// Where to start again, relative to the guess, when the answer is still not trusted
    /// ([`TrustRule`]) after `wide_sigmas_m`: the trusted answer with the most inliers is
    /// kept. Not in the thesis; empty (the default) leaves it out, and
    /// [`Lorentz::with_lines`] has `RESTARTS`.
    pub restarts: Vec<Pose2>,
    /// When the restarts (so only with some) gave no trusted answer either, the best starts of
    /// a coarse correlative search over this window around the guess
    /// ([`correlative::best_starts`]), and how many: of their trusted answers that fit clearly
    /// more points than the first answer (`COARSE_MARGIN`), the one with the most inliers is
    /// kept. Not in the thesis; `None` (the default) leaves it out, and
    /// [`Lorentz::with_lines`] has [`COARSE`].
    pub coarse: Option<(correlative::Window, usize)>,
    /// With `coarse`: a trusted answer that lies farther than this from the guess, metres, is
    /// checked against the match from the coarse search's best start, which replaces it when
    /// trusted and fitting `COARSE_MARGIN` more of the current points: a match that slid a
    /// corridor's length along may have found a look-alike place. Not in the thesis; `None`
    /// (the default) leaves it out, and [`Lorentz::with_lines`] has [`FAR_SLIDE_M`].
    pub far_slide_m: Option<f64>,
    /// The σ schedule, metres, for scans whose beams lie closer than `dense_below_rad`
    /// (measured on the current scan, [`beam_step`](super::beam_step)) instead of `sigmas_m`.
    /// Not in the thesis; empty (the default) leaves it out, and [`Lorentz::with_lines`] has
    /// [`DENSE_SIGMAS`].
    pub dense_sigmas_m: Vec<f64>,
    /// The angle between neighbouring beams under which a scan counts as dense, radians.
    /// [`Lorentz::with_lines`]: 0.75°, between the 0.5° of the LMS at 361 beams and the 1° of
    /// 180-beam scans.
    pub dense_below_rad: f64,
    /// Point-to-line residuals inside the Lorentzian, for dense scans (as `dense_sigmas_m`)
    /// with line-assisted association: in a search whose pairs projected inside a reference
    /// line have normals spread enough — the smaller eigenvalue of their `Σ n nᵀ` at least this
    /// share of the larger — such a pair's error is its distance to the line alone,
    /// `ρσ(n · e)`, so a point may slide along its wall instead of being held to its
    /// projection; the other pairs, and every pair of a search whose lines mostly run one way
    /// (a corridor, which would leave the estimate free along it), keep the product form, and
    /// so do the restarts and the coarse search's starts (away from the guess, a pair free to
    /// slide can settle in a look-alike place the trust rule accepts). With `first_spread` the
    /// first match from the guess asks less of the spread. Not in the thesis; `None` (the
    /// default) leaves it out, and [`Lorentz::with_lines`] has [`LINE_RESIDUALS_SPREAD`].
    pub line_residuals_spread: Option<f64>,
    /// For sparse scans (not dense, as `dense_sigmas_m`): as `line_residuals_spread`, the share
    /// of the larger eigenvalue of the line normals' `Σ n nᵀ` the smaller must reach for a
    /// search to count its line pairs' distances to their lines alone; restarts and the coarse
    /// search's starts keep the product form there too. Not in the thesis; `None` (the
    /// default) keeps the product form on sparse scans, and [`Lorentz::with_lines`] has
    /// [`SPARSE_LINE_RESIDUALS_SPREAD`].
    pub sparse_line_residuals_spread: Option<f64>,
    /// With `line_residuals_spread`: the share of the larger eigenvalue the smaller must reach
    /// in the first match from the guess, instead of `line_residuals_spread`'s. An answer of
    /// that match that fits loosely (under `wide_below` of the current points inliers: the
    /// scans overlap little, or one wall alone holds them) is matched again from the guess
    /// with `line_residuals_spread`, and that answer is kept when it is trusted and fits no
    /// fewer than [`FIRST_SPREAD_MARGIN`] of the current points less. Not in the thesis; `None`
    /// (the default) asks `line_residuals_spread` of every search, and
    /// [`Lorentz::with_lines`] has [`FIRST_SPREAD`].
    pub first_spread: Option<f64>,
    /// For dense scans (as `dense_sigmas_m`), in every schedule but the wide one: when, in the
    /// last search of the first σ pass, at least this share (`.1`) of the current points were
    /// paired within this distance (`.0`, metres) of their targets, the narrower passes are
    /// left out and the polish finishes the answer. Not in the thesis; `None` (the default)
    /// runs every pass, and [`Lorentz::with_lines`] has [`FIRST_PASS_ENOUGH`].
    pub first_pass_enough: Option<(f64, f64)>,
    /// End a σ pass when a search brings the estimate back to within `convergence` (or
    /// `early_convergence`) of where it was two searches before: the searches alternate
    /// between two sets of pairs, and the estimate between two poses, so no later search would
    /// settle it (it would run to the cap of searches and stop on one of the two). Not in the
    /// thesis; false (the default) runs such a pass to its cap, and [`Lorentz::with_lines`]
    /// stops it.
    pub stop_on_cycles: bool,
    /// For dense scans (as `dense_sigmas_m`), in the first σ pass of every schedule but the
    /// wide one: a pair that no reference line holds (none grew at its nearest reference point,
    /// or the current point projects past its ends) is held instead to the reference's surface
    /// at that point, the line the trust rule measures against, when the surface was fitted to
    /// at least this many points (a straight piece of it) and the projection falls within its
    /// reach: its target is the projection, and where the search counts distances to lines
    /// ([`Lorentz::line_residuals_spread`]) it counts its distance to that line alone. Not in
    /// the thesis; `None` (the default) leaves such pairs to their nearest points, and
    /// [`Lorentz::with_lines`] has [`FIRST_PASS_SURFACE_POINTS`].
    pub first_pass_surfaces: Option<usize>,
    /// For dense scans (as `dense_sigmas_m`), in every schedule but the wide one: when the
    /// first σ pass stops, instead of `early_convergence`, when narrower passes follow it. Not
    /// in the thesis; `None` (the default) stops it as the other passes before the last, and
    /// [`Lorentz::with_lines`] has [`FIRST_PASS_CONVERGENCE`].
    pub first_pass_convergence: Option<Convergence>,
    /// For sparse scans, in the schedule the sparse finish follows (`sparse_finish`): when
    /// every σ pass stops, the last included, instead of `early_convergence` and
    /// `convergence`; the finish takes the answer on. Not in the thesis; `None` (the default)
    /// stops them as the other schedules' passes, and [`Lorentz::with_lines`] has
    /// [`SPARSE_EARLY_CONVERGENCE`].
    pub sparse_early_convergence: Option<Convergence>,
    /// For sparse scans (not dense, as `dense_sigmas_m`): when the match has its answer, this
    /// point-to-line ICP ([`PointToLine`]) runs from it on the match's nearest-point cache, and
    /// its answer replaces the match's when the trust rule trusts it and it fits no fewer of the
    /// current points. Not in the thesis; `None` (the default) keeps the match's answer, and
    /// [`Lorentz::with_lines`] has [`SPARSE_FINISH`].
    pub sparse_finish: Option<PointToLine>,
    /// For sparse scans (not dense, as `dense_sigmas_m`): before the σ passes, these rounds
    /// of point-to-line ICP run from the guess on the match's nearest-point cache, and the
    /// match goes on from their answer when it lies within their reach of the guess
    /// ([`StartRounds`]): the σ passes start there, and the wide schedule, the restarts and
    /// the coarse search, when they run, centre on it as they would on the guess. Not in the
    /// thesis; `None` (the default) starts at the guess, and [`Lorentz::with_lines`] has
    /// [`SPARSE_START`].
    pub sparse_start: Option<StartRounds>,
    /// For dense scans (as `dense_sigmas_m`): a trusted answer is checked along the direction
    /// its inliers hold it least ([`SlideCheck`]). Not in the thesis; `None` (the default)
    /// leaves it out, and [`Lorentz::with_lines`] has [`SLIDE_CHECK`].
    pub slide_check: Option<SlideCheck>,
    /// For sparse scans (not dense, as `dense_sigmas_m`): as `slide_check`, on the answer
    /// `sparse_finish` has finished; the second match takes a sparse match's schedule,
    /// `sparse_line_residuals_spread` and no crowd rule, and is finished too before the two are
    /// weighed. Not in the thesis; `None` (the default) leaves it out, and
    /// [`Lorentz::with_lines`] has [`SLIDE_CHECK`] here as well.
    pub sparse_slide_check: Option<SlideCheck>,
}

/// How a sparse match starts ([`Lorentz::sparse_start`]): `icp`'s rounds from the guess, and
/// the σ passes from their answer when it moved no farther than `reach_m` and `reach_rad` from
/// the guess, else from the guess (a round that carries the estimate farther paired most
/// points with the wrong reference points).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct StartRounds {
    /// The point-to-line ICP that runs, its `convergence.max_iterations` the rounds.
    pub icp: PointToLine,
    /// The farthest its answer may lie from the guess, metres …
    pub reach_m: f64,
    /// … and radians.
    pub reach_rad: f64,
}

/// The start of a sparse match in [`Lorentz::with_lines`] ([`Lorentz::sparse_start`]): one
/// round of point-to-line ICP (the finish's settings, [`SPARSE_FINISH`]) from the guess, kept
/// within 30 cm and 0.1 rad (5.7°) of it; the σ passes then start at 5 cm
/// ([`SPARSE_SIGMAS`]). The thesis's first pass, at σ 2 cm, had made most of a 1° match's
/// correspondence searches: from a guess centimetres off, most residuals lie where the
/// Lorentzian's slope is small, and its estimate crept towards the answer a little each search
/// (the nearest-point searches of those first steps, which the last answer's cache cannot
/// answer, were a third of a match's time). One point-to-line round jumps most of the way for
/// one search, trimmed as point-to-line ICP trims (outliers stay out of it). Measured
/// (`twin matchers --matchers lorentz-lines --seeds 10`, right answers of 3,000 a row, against
/// the build before on the same seeds; 2026-11-30): on the tuning seeds 1–10 and 51–60 the 1°
/// rows +3 −2, Edmonton +12 −11, the large guesses +2 −2; held out, 21–30 and 41–50, the 1°
/// rows +4 −1, Edmonton +4 −5, the large guesses +5 −2; every dense row the same answers to
/// the bit. Searches a pair (seeds 1–10) 16.6 → 11.8 on the 1° pairs without outliers, 21.5 →
/// 14.1 with 20 %, 51.6 → 32.2 on Edmonton. Raced against `pl-icp` (`cargo bench --bench
/// matcher_race`, in turn with the build before): the 1° pairs without outliers 1.72 → 1.43
/// of its time, with 20 % 0.57 → 0.47, Edmonton 0.60 → 0.41, the large guesses 1.00 → 0.93.
/// Tried in a first form (the 5 cm pass then stopped at the last pass's tight test, 1.46):
/// two rounds were no faster (1.46–1.48) and the 2 cm pass kept after the round slower
/// (1.51–1.54), both about as right; without the reach, 7 of the large guesses' answers of
/// 6,000 were lost (the notebook, *2026-11-30*).
pub const SPARSE_START: StartRounds = StartRounds {
    icp: PointToLine {
        convergence: Convergence {
            max_iterations: 1,
            ..SPARSE_FINISH.convergence
        },
        ..SPARSE_FINISH
    },
    reach_m: 0.3,
    reach_rad: 0.1,
};

/// When [`Lorentz::slide_check`] matches again, and what it keeps: where the points that lie
/// off their surfaces but across the direction a trusted answer's inliers hold it least (along
/// a wall) say that a shift of `min_shift_m` to `reach_m` along it would bring at least
/// `min_gain` of them within the trust rule's distance of their surfaces, and the trust rule
/// finds more of the current points inliers there than at the answer, the σ passes run again
/// from the answer so shifted; their answer replaces the first when trusted, fitting more than
/// `margin` more of the current points and lying at least `min_shift_m` from it (nearer, it is
/// the same answer settled a few millimetres aside, not a slide undone).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct SlideCheck {
    /// The fewest points the shift must bring in.
    pub min_gain: usize,
    /// The shortest shift worth a match, and the least the second answer must lie from the
    /// first, metres.
    pub min_shift_m: f64,
    /// The farthest shift looked at, metres.
    pub reach_m: f64,
    /// How much larger a share of the current points the second answer must fit.
    pub margin: f64,
}

/// The slide check of [`Lorentz::with_lines`]: two points, 2.5 cm to 20 cm, a margin of one
/// percent of the current points. The twin's pairs with 20 % outliers that `lorentz-lines`
/// got wrong were mostly answers 5–15 cm along a wall from the truth, trusted, where the few
/// points on the surfaces across it (a doorway's side, a box's end) lay centimetres off theirs
/// and the truth fitted up to 5 % more of the current points; each of those points says, by
/// how far it lies off its surface, how far the answer should move (`slide_vote`). First
/// chosen (seeds 1–10 and 51–60 of `twin matchers --matchers lorentz-lines`, held out on 21–30
/// and 41–50) with every point near its surface voting, the inliers' votes to stay counted
/// against the others': a point on a pillar or a box, carried by the shift onto another of the
/// reference's points, then voted against a slide the truth undid (pair 280 of seed 52). Now
/// only the points off their surfaces vote, those beyond their surface's end not at all (a
/// line extrapolated from the reference's last beam drew slides 6 cm off the truth that fitted
/// more there: pair 10 of seed 57 without outliers), the judgement at the voted shift decides
/// whether to match again, and the margin is one percent (half of one kept a slide 10 cm off
/// the truth fitting 0.57 % more than the truth did: pair 187 of seed 56). Against the first
/// form on the same seeds: right answers +1 on the 20 % row of 51–60 and of held-out 21–30, +1
/// on the large guesses of 51–60, none lost, 5 % fewer searches on the dense pairs. A
/// second answer that fitted more but lay millimetres from the first moved two Table 5.1
/// trials from 1.0 and 4.2 mm to 7.4 and 8.8 mm off: it must lie `min_shift_m` away. Five
/// points had been asked while the vote counted the inliers against the shift; now that the
/// judgement there and the margin weigh the shift, two are enough (one gave the same answers
/// on the tuning seeds): Belgioioso's pair 125, 14 cm along its corridor from every guess that
/// left it there, comes back to 3 cm (+7 and +3 right answers on seeds 1–10 and 51–60, +5 and
/// +4 held out on 21–30 and 41–50), and one synthetic pair each without and with outliers held
/// out (13 cm and 7 cm off before); none lost. On seeds 61–80, first run after the choice:
/// Belgioioso +9, two more synthetic pairs with 20 % outliers, none lost.
///
/// Sparse scans (the twin's 1° scans, Edmonton's) run the same check
/// ([`Lorentz::sparse_slide_check`]) on their finished answer, the second match finished too:
/// over seeds 1–10 and 51–60 +15 right answers on the 1° rows, two lost (pair 132 of seed 9
/// and pair 137 of seed 57, 13–15 mm off before, now 6–18 cm along a wall where the answer
/// fits 0.5–5 % more of the current points than the truth does); Edmonton's the same. A
/// margin of two percent kept 10 of the gains and lost one; checking the answer before the
/// finish lost a third (the finish would have brought the first answer level). Held out,
/// seeds 21–30 and 41–50: +8, none lost; seeds 61–80, run after the choice: +22 on the 1°
/// rows, +1 on the large guesses (a third of their pairs are Edmonton's), none lost.
pub const SLIDE_CHECK: SlideCheck = SlideCheck {
    min_gain: 2,
    min_shift_m: 0.025,
    reach_m: 0.2,
    margin: 0.01,
};

/// The schedule of [`Lorentz::with_lines`] for dense scans (beams under 0.75° apart): σ 5 cm,
/// then 2 and 0.5 cm, narrowing throughout. The thesis's 2 → 5 → 0.5 cm widens in its middle
/// pass, and at 5 cm the points of a dense scan that see what the reference did not (new
/// ground, the far side of a pillar) pull the estimate aside: started at the truth,
/// `lorentz-lines` left it for a place 57–95 mm away on pairs where point-to-line ICP stayed
/// within 2 mm. Over 3,600 pairs a row (`twin matchers`, seeds 1–12) it raised the right
/// answers from 0.9983 to 0.9989 (synthetic, 0 %), 0.9961 to 0.9972 (20 %) and 0.9969 to
/// 0.9992 (Belgioioso), and lost one pair each on Freiburg 101 and the large guesses, with 6 %
/// fewer correspondence searches. On sparse scans (Edmonton's 1° beams) the widening middle
/// pass pulls in guesses the narrowing schedule leaves out: every narrowing schedule tried lost
/// 15–40 of Edmonton's 2,400 pairs, so those keep the thesis's.
pub const DENSE_SIGMAS: [f64; 3] = [0.05, 0.02, 0.005];

/// How spread the line normals of a search must be for [`Lorentz::with_lines`] to count its
/// line pairs' distance to their lines alone ([`Lorentz::line_residuals_spread`]): the smaller
/// eigenvalue of `Σ n nᵀ` at least half the larger. The product form holds a point to its
/// projection, so the estimate crawls along walls by what the projections move in one search;
/// measured over seeds 1–12 of `twin matchers` (3,600 pairs a row), the median correspondence
/// searches a pair fell from 57 to 35 (synthetic, 0 %), 54 to 40 (20 %), 63 to 30
/// (Belgioioso), 66 to 60 (Freiburg 101) and 87 to 73 (large guesses), with the same right
/// answers on every row. At a quarter the searches fell further (to 25, 32, 24, 44 and 60)
/// but Belgioioso lost a pair. Since [`FIRST_SPREAD`], the first match from the guess asks a
/// tenth; sparse scans ask [`SPARSE_LINE_RESIDUALS_SPREAD`].
pub const LINE_RESIDUALS_SPREAD: f64 = 0.5;

/// How spread the line normals of a search of a sparse scan (Edmonton's 1° beams, the twin's
/// SICK in its 1° mode) must be for [`Lorentz::with_lines`] to count its line pairs' distance
/// to their lines alone ([`Lorentz::sparse_line_residuals_spread`]): a tenth. In the product
/// form the first σ pass (2 cm) of a 1° scan crawled along the walls, a search at a time, each
/// moving the estimate a little over half as far as the one before, and took half of a match's
/// searches. Over seeds 1–20 of `twin matchers` (`lorentz-lines` alone, 6,000 pairs a row),
/// against the product form: right answers 5,995 → 5,995 (synthetic 1°, 0 %), 5,970 → 5,968
/// (1°, 20 %; +2 −4, the lost answers 1.0–3.7° off, fitting as many of the current points as
/// the answers before or more), Edmonton 5,801 → 5,816 (+22 −7), the large guesses 5,909 →
/// 5,909 (+2 −2); the dense rows the same answers to the bit. Correspondence searches a pair,
/// mean: 40.0 → 22.4 (1°, 0 %), 36.7 → 26.5 (1°, 20 %), 66.2 → 61.3 (Edmonton). A tenth took
/// fewer searches still (20.4 without outliers) but was right less often (Edmonton 5,807, 1°
/// with outliers 5,967); 0.3 (seeds 1–10) as often as a fifth, for 24.5 searches against 22.4;
/// a half, the dense scans' share, took more time than a tenth (`cargo bench --bench
/// matcher_race`). Held out, seeds 21–30: the same right answers on every row (Edmonton 2,898,
/// +8 −8; the 1° rows 2,993 and 2,990), searches 39.4 → 22.1 (1°, 0 %) and 65.7 → 60.9
/// (Edmonton). So a fifth was chosen then; since the finish took the place of the 5 mm pass
/// ([`SPARSE_SIGMAS`]), a tenth is right as often: over seeds 1–10 and held-out 21–30, against
/// a fifth, Edmonton 2,911 → 2,911 and 2,910 → 2,911, the 1° pairs with outliers 2,981 →
/// 2,981 and 2,991 → 2,990, the 1° pairs without and the large guesses the same, for 8 % fewer
/// searches (18.2 → 16.6 and 18.5 → 17.0 a pair on the 1° pairs without outliers, 54.0 → 51.1
/// and 53.3 → 50.7 on Edmonton); a twentieth lost a pair on Edmonton and one with outliers
/// over seeds 1–10 for 16.0 searches.
pub const SPARSE_LINE_RESIDUALS_SPREAD: f64 = 0.1;

/// How spread the line normals of a search of the first match from the guess must be for
/// [`Lorentz::with_lines`] to count its line pairs' distance to their lines alone
/// ([`Lorentz::first_spread`]): a tenth, not [`LINE_RESIDUALS_SPREAD`]'s half. Under the half,
/// the product form holds each point to its projection, and the estimate crawls along the walls
/// by what the projections move in one search, up to the cap of searches; a room seen with
/// most of its walls one way (down a long room, along one side) is not a corridor, and there
/// point-to-line residuals bring the scans together in fewer searches. Under a tenth the lines
/// all run one way, and the product form still holds.
///
/// Where the scans share little more than one wall, the line pairs can slide along it to
/// where a few other points put them: Belgioioso's pair 125 slid 14 cm on 8 seeds of 12 with
/// this share and no second match. So a loose answer is matched again with the half, whose
/// product form along such a wall stays nearer the guess, and that answer wins unless the first
/// fits clearly more points ([`FIRST_SPREAD_MARGIN`]). Over seeds 1–20 of `twin matchers`
/// (6,000 pairs a row, Freiburg 101 5,820), against the half throughout: right answers
/// 5996 → 5996 (synthetic, 0 %), 5981 → 5985 (20 %), 5996 → 5998 (Belgioioso), 5714 → 5714
/// (Freiburg 101) and 5572 → 5577 (large guesses), Edmonton's sparse scans unchanged;
/// correspondence searches a pair, mean over seeds 1–12, 40 → 27 (synthetic, 0 %), 54 → 46
/// (Belgioioso), 63 → 48 (Freiburg 101), about the same on the other rows. Asking nothing of
/// the spread (a share of 0) took fewer searches still on Freiburg 101 (27), but let pure
/// corridors slide: 002's L-corridor 7 cm, a synthetic pair started at the truth 13 cm.
pub const FIRST_SPREAD: f64 = 0.1;

/// The NLM steps [`Lorentz::with_lines`] takes on each search's pairs in its first match from
/// the guess ([`Lorentz::first_max_steps`]): one. The thesis minimises each search's pairs to
/// the end (up to 30 accepted steps) before it searches again; but the pairs change at the next
/// search, and a full minimisation on pairs found from a pose some centimetres off carries the
/// estimate as far as they lead, wrong ones included. One damped Newton step a search (λ from
/// 0.001, raised tenfold until the error falls) ends where a search no longer moves the
/// estimate in about as many searches, each a fraction of the cost. Over seeds 1–20 of `twin
/// matchers` (6,000 pairs a row, Freiburg 101 5,820), against 30: right answers 5996 → 5995
/// (synthetic, 0 %), 5985 → 5982 (20 %), 5998 → 5999 (Belgioioso), 5714 → 5717 (Freiburg 101),
/// 5645 → 5677 (Edmonton) and 5577 → 5595 (large guesses). The fallbacks keep 30: with one
/// step there too, a restart 15 cm from the guess slid 55 cm down the lab in a closed-loop
/// `goto-lab` run (seed 2027, trial 73) and the map builder trusted it. With the steps in every
/// match, two a search did no better than 30 on Edmonton, four little better.
pub const FIRST_STEPS: u32 = 1;

/// When [`Lorentz::with_lines`] leaves out the narrower σ passes of a dense scan
/// ([`Lorentz::first_pass_enough`]): 65 % of the current points paired within 2 cm of their
/// targets in the last search of the first pass (σ 5 cm); 70 % until 2026-11-30 (below). The
/// narrowing passes are there to take the pull of the points that do not belong (outliers,
/// what only one scan saw) off the estimate; where most points already lie within 2 cm, few
/// are left to pull, and the point-to-line polish that follows places the answer as precisely.
/// At 70 % (the figures that follow, until the last paragraph's), measured after the first
/// pass of seed 1's first matches: a median of 88 % within 2 cm without outliers (5 % of pairs
/// under 74 %), 55 % with 20 % outliers (10 % over 67 %). Over seeds 1–20 of `twin matchers`
/// (6,000 pairs a row, Freiburg 101 5,820), with [`Lorentz::stop_on_cycles`]: right answers
/// 5999 → 5998 (synthetic, 0 %; a pair sliding along a wall, 39 → 56 mm off, where the truth
/// fits barely more points), 5983 → 5983 (20 %), 5989 → 5989 (Belgioioso), 5716 → 5716
/// (Freiburg 101), 5817 → 5817 (Edmonton) and 5891 → 5890 (large guesses); median
/// correspondence searches a pair 22 → 12, 35 → 31, 26 → 18, 25 → 20, 56 → 55 and 61 → 55.
/// Leaving the narrower passes out everywhere took as few searches but, with 20 % outliers,
/// turned the Table 5.1 study's mean heading error up by a fortieth (0.0297 → 0.0305°) and its
/// largest from 0.42 to 0.55°; leaving out only the middle pass (5 → 0.5 cm) lost 5 pairs of
/// 6,000 with 20 % outliers and 5 of the large guesses.
///
/// 65 % since 2026-11-30: Belgioioso's real scans, where a median pair fits 81 % of its
/// points, seldom reached 70 % and ran all three passes (a median of 15 searches a pair,
/// 1.02–1.08 of `pl-icp`'s time). At 65 %, over `twin matchers --matchers lorentz-lines` on
/// seeds 1–10 and 51–60 (chosen there, from 60 and 65 %) and held out on 21–30, 41–50 and
/// 61–80, every row is right on the same pairs but one more with 20 % outliers (seeds 61–70);
/// Belgioioso's median searches 15 → 10, its time 1.03–1.05 of `pl-icp`'s (`cargo bench
/// --bench matcher_race`, three races in turn with 70 %); the twin's median errors within
/// 0.01 mm, the real logs' the same or lower. Table 5.1: the 20 % row's worst e_t 13.03 →
/// 12.58 mm, every other printed figure the same. At 60 % Belgioioso came level (0.998) but
/// the 20 % row's sd of e_θ rose from 0.02946 to 0.02962°, printed 0.029 → 0.030.
pub const FIRST_PASS_ENOUGH: (f64, f64) = (0.02, 0.65);

/// The fewest points a reference surface must have been fitted to for [`Lorentz::with_lines`]
/// to hold a pair no line holds to it in the first σ pass of a dense scan
/// ([`Lorentz::first_pass_surfaces`]): seven, three either side of the point and the point
/// itself, all on the chord, so a straight piece of surface. Counted in that pass (seed 1,
/// the synthetic pairs without outliers), 37 % of the pairs had no line to be held to: grown
/// lines need five points within 2 cm RMS and end where the points do, so a corner, a short
/// face or a point past a line's end paired with the nearest point alone and pulled the
/// estimate toward it, point to point, search after search. Over seeds 1–20 of `twin matchers`
/// (6,000 pairs a row, Freiburg 101 5,820), with [`FIRST_PASS_ENOUGH`] and
/// [`Lorentz::stop_on_cycles`] before and after: right answers 5998 → 5998 (synthetic, 0 %),
/// 5983 → 5982 (20 %), 5989 → 5990 (Belgioioso), 5716 → 5716 (Freiburg 101), 5817 → 5817
/// (Edmonton, not dense: the same answers) and 5890 → 5892 (large guesses); median
/// correspondence searches a pair 12 → 7, 31 → 30, 18 → 16, 20 → 19, 55 → 55 and 55 → 48; the
/// synthetic median error 1.63 → 1.62 mm. Five points (any straight piece of the chord) took
/// fewer searches still with 20 % outliers (31 → 24), but turned the Table 5.1 study's worst
/// heading error at 20 % from 0.42 to 0.52° (trial 14132, the far outliers' torque); in every
/// pass, not only the first, the study's mean e_t at 20 % rose by 0.009 mm and that worst
/// heading error to 0.63°; every surface, however short, in every pass, lost 3 of
/// Belgioioso's pairs in 1,200 and raised that worst heading error to 0.56°.
pub const FIRST_PASS_SURFACE_POINTS: usize = super::quality::SURFACE_POINTS;

/// How long [`Lorentz::with_lines`]' polish goes on past its five rounds on a dense scan
/// ([`Lorentz::polish_more`]): while its last round still turned the estimate by more than
/// 0.02°, at most 25 rounds more. Each round weighs a point by `1 / (1 + (e / 1 cm)²)` and
/// leaves out those more than 5 cm from a surface, so where the σ passes end a degree or two
/// off in heading, the farther points, which would say so, count for little, and the answer
/// creeps toward the minimum a tenth of a degree a round: printed round by round on six
/// failing synthetic pairs with 20 % outliers, 30 rounds brought five of them within 0.4°
/// (from 1.05–1.83° after five). The longer answer is kept unless the one after five rounds
/// fits more of the current points (the trust rule's share): on Belgioioso one scan pair went
/// on to a place 0.4° farther from the log's pose fitting 2 % fewer points. Over seeds 1–20
/// of `twin matchers` (6,000 pairs a row): right answers with 20 % outliers 5982 → 5988 (7
/// gained; 1 lost, whose polish minimum lies 1.1° off where five rounds had stopped short of
/// it), every other row the same pairs; Edmonton's 1° scans are not dense (the same answers
/// to the bit). The heading errors summed over the 20 % row fell by 8 %; on Belgioioso 456
/// answers moved, most by hundredths of a degree, the larger moves away from the log's
/// heading to places that fit more points than the log's pose. The Table 5.1 study: with
/// 20 % outliers the worst heading error 0.416 → 0.315° (trial 14132, the far outliers'
/// torque), the mean 0.0297 → 0.0296° and the sd of e_t 1.1857 → 1.1853 mm; at 2 % 23 trials
/// of 10,000 moved, the mean e_t by 0.0001 mm. Without the guard: 5987 right (0.01° the same,
/// 0.05° 5986, 0.08° 5986) and Belgioioso's summed heading error up 3 %.
pub const POLISH_MORE: (f64, usize) = (0.02_f64.to_radians(), 25);

/// How many fewer of the current points (as a share) the answer matched again with
/// [`LINE_RESIDUALS_SPREAD`] may fit than a loose first answer and still be kept
/// ([`Lorentz::first_spread`]): when the scans cannot tell the two apart, the product form's,
/// which stays nearer the guess along what the scans leave free. 0 and 0.02 gave the same
/// answers over seeds 1–12 but for one pair.
pub const FIRST_SPREAD_MARGIN: f64 = 0.01;

/// How many times farther from its target than the nearest pair on the same reference point
/// a pair of a dense scan may lie and still count ([`Lorentz::crowd_ratio`]): three, as the
/// reference matcher's rule for doubles ([`PointToLine`](super::PointToLine)), here with the
/// pass's σ as a floor so that neighbouring points of one wall a few millimetres apart all
/// stay.
///
/// Current points that see what the reference did not — past the end of the reference's
/// view, round a corner it hid — have their nearest reference points at the edge of what it
/// saw, tens of them on one point, 0.2–1.3 m away. Each pulls little at σ 5 cm, but together
/// they pull like as many inliers a centimetre off: in the Table 5.1 study's trial 13357 (20 %
/// outliers, a 25° turn left, the guess 1.2 mm from the truth) 45 current points of a wall the
/// reference never saw lay on its last point of that wall, and the first pass walked 6 cm
/// from the truth; the answer, 27.6 mm off, was trusted. Left out, the study's worst
/// translation errors of `lorentz-lines` fell from 33.8 to 16.0 mm at 2 % outliers and from
/// 27.6 to 13.0 mm at 20 % (`pl-icp`: 16.8 mm), every other figure of its rows the same or
/// better. Over seeds 1–20 of `twin matchers` (6,000 pairs a row, Freiburg 101 5,820), with
/// [`EARLY_CONVERGENCE`]: right answers 5995 → 5999 (synthetic, 0 %), 5982 → 5983 (20 %),
/// 5717 → 5716 (Freiburg 101), 5677 → 5681 (Edmonton), 5595 → 5597 (large guesses), and
/// Belgioioso 5999 → 5989: there the scans of pair 125 share one corner's walls, and the
/// log's pose fits fewer of the current points (39 % within 5 cm) than either answer (53 %);
/// the two stay equally good to the scans, and the one kept is now 14 cm from the log's pose,
/// not 4 cm (the same pair on 9 seeds; pair 115 on 2 more, now 2.7° off, fitting 75 % of the
/// points where the log's pose fits 68 %). Since [`SLIDE_CHECK`] asks two points across the
/// wall, not five, pair 125 comes back to 3 cm from the log's pose, fitting 55 %.
///
/// Sparse scans (the thesis's schedule) keep every pair: on Edmonton's 1° beams several
/// current points share a reference point at long range, and the rule lost 63 of its 6,000
/// pairs. Nor does the wide schedule ([`WIDE_SIGMAS`]) use it, which starts where the scans
/// may still be decimetres apart and the nearest pair on a reference point is no better a
/// guide than the others: with the rule there too the large guesses lost 7 pairs of 6,000.
pub const CROWD_RATIO: f64 = 3.0;

/// The finish of [`Lorentz::with_lines`] on sparse scans ([`Lorentz::sparse_finish`]):
/// point-to-line ICP with CSM's defaults ([`PointToLine::default`]) but no restarts, one
/// Gauss–Newton step a round, and a stop when the pairings come round in a cycle of up to seven
/// iterations. On 1° beams the Lorentzian's pairs are a point and its nearest
/// reference point or a line fitted to a few far-apart points, and its answers depend on the
/// guess: on Edmonton's pairs (`twin matchers`, seeds 1–20, each from its own guess) they lay
/// more than 1 cm from the median of the 20 answers on 105 of 300 pairs and more than 3 cm on
/// 44, where point-to-line ICP's, paired with the segment between two neighbouring reference
/// points, did so on 40 and 11. Finished so, 66 and 20, and the right answers rose from 5,817
/// to 5,872 of 6,000 (pl-icp: 5,833), none lost; from large guesses 5,892 to 5,901. With CSM's
/// restarts too: 5,844 and 5,906, at 2.2 times `pl-icp`'s time. Without the cycle stop a
/// quarter of Edmonton's finishes ran to the cap of 100 iterations, coming back again and
/// again to where they had been. Stopped there, the same pairs are right on every row (over
/// seeds 1–20 the answers moved on 872 of the 12,000 pairs of Edmonton and the large guesses,
/// by more than 5 mm on 91, none across the line of success) for a fifth of the finish's
/// iterations, and `lorentz-lines` went from 0.95 to 0.71 of `pl-icp`'s time on Edmonton
/// (`cargo bench --bench matcher_race`; 0.62 without the finish); with a cycle of two only,
/// as [`Lorentz::stop_on_cycles`], 448 of 6,000 still ran to the cap. The dense scans' rows do
/// not run it. Measured again with Edmonton's readings 1° apart, as CARMEN reads them: over
/// seeds 1–20 Edmonton's right answers 5,736 without the finish, 5,753 with it; the large
/// guesses 5,867 and 5,882; answers more than 1 / 3 cm from their median 97 / 37 and 80 / 18
/// (`pl-icp` 33 / 10). Kept then only when it fits no fewer of the current points: kept when it
/// fitted up to 2 in 100 fewer (as on the stretched scans), 5,734 and 5,883.
pub const SPARSE_FINISH: PointToLine = PointToLine {
    restart_above_m: None,
    gauss_newton_steps: 1,
    stop_on_cycles: Some(7),
    ..PointToLine::CSM
};

/// When the σ passes before the last stop in [`Lorentz::with_lines`]
/// ([`Lorentz::early_convergence`]): a search that moves the estimate by under 0.1 mm and
/// 0.001°, ten times the last pass's test; the next pass moves the estimate on anyway. Alone,
/// over seeds 1–20 of `twin matchers`: Edmonton's right answers 5677 → 5681 and the large
/// guesses' 5595 → 5598, the other rows within a pair; the median correspondence searches a
/// pair on Edmonton 71 → 64. Alone it also moved one Table 5.1 trial's heading error up
/// (14132, 20 % outliers: 0.505 → 0.518°); with [`CROWD_RATIO`] every figure of the study is
/// the same or better.
pub const EARLY_CONVERGENCE: Convergence = Convergence {
    translation_m: 1e-4,
    rotation_rad: 1e-3 * std::f64::consts::PI / 180.0,
    max_iterations: 30,
};

/// When the first σ pass of a dense scan stops in [`Lorentz::with_lines`]
/// ([`Lorentz::first_pass_convergence`]): a search that moves the estimate by under 0.3 mm and
/// 0.003°, three times [`EARLY_CONVERGENCE`]. The polish, or the narrower passes, take the
/// answer on from there; a third of a millimetre is under a hundredth of the pass's σ (5 cm).
/// Over seeds 1–20 of `twin matchers` every row was right on as many pairs, and a pair's
/// searches fell by 1–10 % on average on the dense rows (8.9 → 8.0 on the synthetic pairs
/// without outliers). Five times lost a pair with 20 % outliers, ten times seven pairs without
/// and with outliers.
pub const FIRST_PASS_CONVERGENCE: Convergence = Convergence {
    translation_m: 3e-4,
    rotation_rad: 3e-3 * std::f64::consts::PI / 180.0,
    max_iterations: 30,
};

/// When the σ passes of a sparse scan's schedule ([`SPARSE_SIGMAS`]) stop in
/// [`Lorentz::with_lines`] ([`Lorentz::sparse_early_convergence`]), the sparse finish
/// following the last: a search that moves the estimate by under 0.3 mm and 0.003°, as a
/// dense scan's first pass ([`FIRST_PASS_CONVERGENCE`]), three times [`EARLY_CONVERGENCE`]; the
/// finish places the answer, so no pass need crawl to a tenth of a millimetre. For the passes
/// before the last, over seeds 1–10 and held-out 21–30 of `twin matchers` (`lorentz-lines`
/// alone, with the second polish already left out of sparse scans,
/// [`Lorentz::before_last_margin`], and the thesis's σ 5 mm pass still last): no right answer
/// lost on any row and seven gained (the large guesses +5, the twin's 1° pairs with outliers
/// +2), searches a pair 22.4 → 20.0 on the 1° pairs without outliers and 61.3 → 58.2 on
/// Edmonton; the first pass alone so: nothing gained or lost, 22.4 → 21.3 searches; the first
/// at 1 mm and 0.01°: 19.9 searches, but Edmonton and the 1° pairs with outliers each one pair
/// fewer. The σ 5 mm pass stopped at 3 mm and 0.03° then (it had crawled along Edmonton's
/// walls); the last pass is now the 5 cm one, and stopped there it left nine answers of
/// 6,000 on the 1° rows 6–13 cm along their walls, trusted (seeds 1–10): it stops as the
/// others.
pub const SPARSE_EARLY_CONVERGENCE: Convergence = FIRST_PASS_CONVERGENCE;

/// The σ schedule of [`Lorentz::with_lines`] for sparse scans (beams 0.75° apart or more, a
/// SICK's 1° mode; [`Lorentz::sigmas_m`]): the thesis's 2 → 5 cm without its last pass at
/// 5 mm ([`THESIS_SIGMAS`]), metres. The point-to-line finish that follows ([`SPARSE_FINISH`])
/// places the answer where the narrow pass did: stopped at 3 mm, that pass had come to a
/// sixth of a 1° match's correspondence searches. Over seeds 1–10 and held-out 21–30 of
/// `twin matchers` (`lorentz-lines` alone, every pass stopped at
/// [`SPARSE_EARLY_CONVERGENCE`]): Edmonton's right answers 2,906 → 2,911 and 2,898 → 2,910
/// (+28 −11 over both), the large guesses 2,961 → 2,967 and 2,956 → 2,957, the twin's 1° pairs
/// 2,998 → 2,998 and 2,994 → 2,993 without outliers, 2,980 → 2,981 and 2,990 → 2,991 with
/// 20 %; the dense rows the same answers to the bit; searches a pair 20.0 → 18.2 on the 1°
/// pairs without outliers, 58.2 → 54.0 on Edmonton. Since 2026-11-30 the 2 cm pass is gone
/// too: a round of point-to-line ICP from the guess starts the match ([`SPARSE_START`]), and
/// the 5 cm pass takes it on; restarts, the coarse search's starts and the slide check's second
/// match run the 5 cm pass alone.
pub const SPARSE_SIGMAS: [f64; 1] = [0.05];

/// The second schedule of [`Lorentz::with_lines`]: σ 20 cm first, then 5 and 0.5 cm. At
/// σ 2 cm a point farther than a few centimetres from its pair barely pulls, so from a guess
/// 20 cm and 10° off the first pass can settle on whatever few pairs happen to be near (a
/// corridor's doors one door along); at 20 cm every pair pulls and the scans are brought
/// together first. It is not the first schedule because with 20 % outliers the wide pass is
/// pulled aside too and 3 % of synthetic pairs end in another minimum (`twin matchers`).
pub const WIDE_SIGMAS: [f64; 3] = [0.2, 0.05, 0.005];

/// How far from the guess a loosely fitting answer must have gone for the second schedule to
/// be tried: 10 cm or 3°. Nearer, the first pass started close enough for its narrow σ.
const WIDE_AFTER: (f64, f64) = (0.1, 0.052_359_877_559_829_89);

/// The restarts of [`Lorentz::with_lines`]: the guess turned by ±8° and ±16°, and moved 15 cm
/// forward, back, left and right. From guesses σ 20 cm / 10° off the corrected real logs they
/// raised the share of right answers from 0.85 to 0.91 (`twin matchers`) before the wide
/// schedule ([`WIDE_SIGMAS`]) ran ahead of them; adding ±24° and 30 cm moves gained 0.003 more,
/// so they were left out.
pub const RESTARTS: [Pose2; 8] = [
    Pose2 {
        x: 0.0,
        y: 0.0,
        theta: 0.139_626_340_159_546_36,
    },
    Pose2 {
        x: 0.0,
        y: 0.0,
        theta: -0.139_626_340_159_546_36,
    },
    Pose2 {
        x: 0.0,
        y: 0.0,
        theta: 0.279_252_680_319_092_7,
    },
    Pose2 {
        x: 0.0,
        y: 0.0,
        theta: -0.279_252_680_319_092_7,
    },
    Pose2 {
        x: 0.15,
        y: 0.0,
        theta: 0.0,
    },
    Pose2 {
        x: -0.15,
        y: 0.0,
        theta: 0.0,
    },
    Pose2 {
        x: 0.0,
        y: 0.15,
        theta: 0.0,
    },
    Pose2 {
        x: 0.0,
        y: -0.15,
        theta: 0.0,
    },
];

/// The coarse search of [`Lorentz::with_lines`]: ±60 cm and ±30° around the guess
/// ([`correlative::Window::WIDE`]), its three best headings at least 3° apart. From guesses
/// σ 20 cm / 10° off the corrected real logs it raised the right answers from 0.9267 to 0.9303
/// over seeds 1–12 (3,600 pairs) and from 0.9175 to 0.9225 over seeds 13–16, every other row
/// of `twin matchers` unchanged.
pub const COARSE: (correlative::Window, usize) = (correlative::Window::WIDE, 3);

/// How far from the guess a trusted answer of [`Lorentz::with_lines`] may lie before the coarse
/// search's best start is matched too ([`Lorentz::far_slide_m`]): 50 cm. From guesses
/// σ 20 cm / 10° off the corrected real logs, `lorentz-lines` trusted 19 answers 0.4–3 m off
/// (or more than 5°) over seeds 1–20 of `twin matchers` (6,000 pairs), all on Freiburg 101's
/// corridor (its pairs 8–10, 20, 21, 44, 45), each fitting 0.50–0.67 of the current points
/// where the log's pose fits 0.62–0.84. Checked so: 4 such answers, the right answers
/// 5,882 → 5,896 (held out, seeds 21–30: 2,939 → 2,946), every other row unchanged to the
/// bit, the Table 5.1 study too. At 35 cm or 25 cm: 15 or 17 more right answers, at 1.1 or
/// 1.2 times the row's time (`pl-icp`'s time then: 1.05 times at 35 cm); with the three best
/// starts, one more or two.
pub const FAR_SLIDE_M: f64 = 0.5;

/// How much larger a share of the current points a coarse start's trusted answer must fit than
/// the untrusted first answer to replace it. The coarse search looks up to 60 cm and 30° away,
/// where a corridor offers look-alike places: on Edmonton's sparse scans, without a margin,
/// it replaced 8 untrusted right answers in 3,600 by trusted wrong ones that fitted at most
/// 6 points in 100 more.
const COARSE_MARGIN: f64 = 0.08;

impl Lorentz {
    /// The unit in which the thesis's σ values work for this laser: centimetres.
    pub const SIGMA_UNIT_M: f64 = 0.01;

    /// The thesis's schedule with σ counted in `unit_m` metres.
    pub fn with_sigma_unit(unit_m: f64) -> Self {
        Lorentz {
            sigmas_m: THESIS_SIGMAS.iter().map(|s| s * unit_m).collect(),
            ..Lorentz::default()
        }
    }

    /// The default matcher with line-assisted association.
    pub fn with_lines() -> Self {
        Lorentz {
            lines: Some(LineParams::default()),
            polish_rounds: 5,
            polish_more: Some(POLISH_MORE),
            before_last_margin: Some(0.01),
            wide_sigmas_m: WIDE_SIGMAS.to_vec(),
            restarts: RESTARTS.to_vec(),
            coarse: Some(COARSE),
            far_slide_m: Some(FAR_SLIDE_M),
            dense_sigmas_m: DENSE_SIGMAS.to_vec(),
            dense_below_rad: SPARSE_BEAM_STEP_RAD,
            line_residuals_spread: Some(LINE_RESIDUALS_SPREAD),
            sparse_line_residuals_spread: Some(SPARSE_LINE_RESIDUALS_SPREAD),
            first_spread: Some(FIRST_SPREAD),
            first_max_steps: Some(FIRST_STEPS),
            first_pass_enough: Some(FIRST_PASS_ENOUGH),
            stop_on_cycles: true,
            first_pass_surfaces: Some(FIRST_PASS_SURFACE_POINTS),
            early_convergence: Some(EARLY_CONVERGENCE),
            first_pass_convergence: Some(FIRST_PASS_CONVERGENCE),
            sparse_early_convergence: Some(SPARSE_EARLY_CONVERGENCE),
            sigmas_m: SPARSE_SIGMAS.to_vec(),
            crowd_ratio: Some(CROWD_RATIO),
            sparse_finish: Some(SPARSE_FINISH),
            sparse_start: Some(SPARSE_START),
            slide_check: Some(SLIDE_CHECK),
            sparse_slide_check: Some(SLIDE_CHECK),
            ..Lorentz::default()
        }
    }

    /// The Lorentzian error of pairs `(source moved by phi, target)` at scale σ.
    fn energy(src: &[[f64; 2]], dst: &[[f64; 2]], phi: [f64; 3], two_s2: f64) -> f64 {
        let (s, c) = phi[0].sin_cos();
        let inv = 1.0 / two_s2;
        let factor = |(p, q): (&[f64; 2], &[f64; 2])| {
            let (_, e) = moved(p, q, (s, c), phi);
            factor(e, &None, inv)
        };
        // The logarithm of a product of eight factors instead of eight logarithms: the same sum
        // but for rounding, at an eighth of the cost. A product that overflows (residuals of
        // kilometres at a σ of millimetres) is summed term by term.
        src.chunks(8)
            .zip(dst.chunks(8))
            .map(|(p, q)| {
                let product: f64 = p.iter().zip(q).map(factor).product();
                if product.is_finite() {
                    product.ln()
                } else {
                    p.iter().zip(q).map(|pq| factor(pq).ln()).sum()
                }
            })
            .sum()
    }

    /// Gradient `B` and Hessian `A` of the error (App. F, F.12–F.13, with the common factor kept).
    fn derivatives(
        src: &[[f64; 2]],
        dst: &[[f64; 2]],
        phi: [f64; 3],
        two_s2: f64,
    ) -> ([f64; 3], [[f64; 3]; 3]) {
        let (s, c) = phi[0].sin_cos();
        let (mut g, mut h) = ([0.0; 3], [[0.0; 3]; 3]);
        for (p, q) in src.iter().zip(dst) {
            // Rotated point; x' = rx + tx, ∂x'/∂θ = −ry, ∂²x'/∂θ² = −rx; ∂y'/∂θ = rx, ∂²y'/∂θ² = −ry.
            let (r, e) = moved(p, q, (s, c), phi);
            add_product_pair((&mut g, &mut h), r, e, two_s2);
        }
        h[1][0] = h[0][1];
        h[2][0] = h[0][2];
        (g, h)
    }

    /// The error of [`Lorentz::energy`] with point-to-line residuals: a pair with a normal
    /// `n` (its target a projection inside a reference line) counts `ρσ(n · e)` alone.
    fn energy_to_lines(pairs: Pairs<'_>, normals: &[Normal], phi: [f64; 3], two_s2: f64) -> f64 {
        let (src, dst) = pairs;
        let (s, c) = phi[0].sin_cos();
        let inv = 1.0 / two_s2;
        let factor = |p: &[f64; 2], q: &[f64; 2], n: &Normal| {
            let (_, e) = moved(p, q, (s, c), phi);
            factor(e, n, inv)
        };
        // Eight factors a logarithm, as in `energy`.
        src.chunks(8)
            .zip(dst.chunks(8))
            .zip(normals.chunks(8))
            .map(|((p, q), n)| {
                let each = || p.iter().zip(q).zip(n).map(|((p, q), n)| factor(p, q, n));
                let product: f64 = each().product();
                if product.is_finite() {
                    product.ln()
                } else {
                    each().map(f64::ln).sum()
                }
            })
            .sum()
    }

    /// Gradient and Hessian of [`Lorentz::energy_to_lines`].
    fn derivatives_to_lines(
        pairs: Pairs<'_>,
        normals: &[Normal],
        phi: [f64; 3],
        two_s2: f64,
    ) -> ([f64; 3], [[f64; 3]; 3]) {
        let (src, dst) = pairs;
        let (s, c) = phi[0].sin_cos();
        let (mut g, mut h) = ([0.0; 3], [[0.0; 3]; 3]);
        for ((p, q), n) in src.iter().zip(dst).zip(normals) {
            let (r, e) = moved(p, q, (s, c), phi);
            add_pair((&mut g, &mut h), r, e, n, two_s2);
        }
        h[1][0] = h[0][1];
        h[2][0] = h[0][2];
        h[2][1] = h[1][2];
        (g, h)
    }

    /// [`Lorentz::energy_to_lines`] (or [`Lorentz::energy`], without `normals`) and its
    /// gradient and Hessian at `phi` in one pass over the pairs: the same numbers to the bit
    /// as the two apart, each pair moved once. Each NLM minimisation starts with both.
    fn energy_and_derivatives(
        pairs: Pairs<'_>,
        normals: Option<&[Normal]>,
        phi: [f64; 3],
        two_s2: f64,
    ) -> (f64, [f64; 3], [[f64; 3]; 3]) {
        let (src, dst) = pairs;
        let (s, c) = phi[0].sin_cos();
        let inv = 1.0 / two_s2;
        let none = [None; 8];
        let (mut energy, mut g, mut h) = (-0.0, [0.0; 3], [[0.0; 3]; 3]);
        for (k, (p, q)) in src.chunks(8).zip(dst.chunks(8)).enumerate() {
            let n = normals.map_or(&none[..p.len()], |n| &n[8 * k..8 * k + p.len()]);
            let mut product = 1.0;
            for ((p, q), n) in p.iter().zip(q).zip(n) {
                let (r, e) = moved(p, q, (s, c), phi);
                product *= factor(e, n, inv);
                add_pair((&mut g, &mut h), r, e, n, two_s2);
            }
            // Eight factors a logarithm, as in `energy`.
            energy += if product.is_finite() {
                product.ln()
            } else {
                let each = p.iter().zip(q).zip(n);
                each.map(|((p, q), n)| factor(moved(p, q, (s, c), phi).1, n, inv).ln())
                    .sum()
            };
        }
        h[1][0] = h[0][1];
        h[2][0] = h[0][2];
        h[2][1] = h[1][2];
        (energy, g, h)
    }

    /// Newton–Levenberg–Marquardt on fixed pairs, from `phi`: with point-to-line residuals
    /// where `normals` gives a pair one, else the thesis's product form.
    fn nlm(
        &self,
        pairs: Pairs<'_>,
        normals: Option<&[Normal]>,
        mut phi: [f64; 3],
        (sigma, steps): (f64, u32),
    ) -> [f64; 3] {
        let two_s2 = 2.0 * sigma * sigma;
        let energy = |phi| match normals {
            Some(normals) => Self::energy_to_lines(pairs, normals, phi, two_s2),
            None => Self::energy(pairs.0, pairs.1, phi, two_s2),
        };
        let tolerance = self.energy_tolerance * pairs.0.len() as f64;
        let (mut e, g, h) = Self::energy_and_derivatives(pairs, normals, phi, two_s2);
        // The derivatives at the start, taken with its energy.
        let mut at_start = Some((g, h));
        let mut lambda = self.lambda0;
        for _ in 0..steps {
            let (g, h) = match (at_start.take(), normals) {
                (Some(start), _) => start,
                (None, Some(normals)) => Self::derivatives_to_lines(pairs, normals, phi, two_s2),
                (None, None) => Self::derivatives(pairs.0, pairs.1, phi, two_s2),
            };
            let improvement = loop {
                let mut a = h;
                for (k, row) in a.iter_mut().enumerate() {
                    row[k] += lambda;
                }
                if let Some(d) = solve3(a, [-g[0], -g[1], -g[2]]) {
                    let trial = [phi[0] + d[0], phi[1] + d[1], phi[2] + d[2]];
                    let e1 = energy(trial);
                    if e1 < e {
                        lambda /= 10.0;
                        phi = trial;
                        let gain = e - e1;
                        e = e1;
                        break gain;
                    }
                }
                lambda *= 10.0;
                if lambda > self.lambda_max {
                    return phi;
                }
            };
            if improvement < tolerance {
                break;
            }
        }
        phi
    }
}

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

/// Line-assisted association: the reference's local lines ([`lines_of`]), the margin past a
/// segment's ends a projection may reach, and when the pairs projected inside a line count
/// their distance to it alone ([`Lorentz::line_residuals_spread`], for dense scans).
struct Assist<'a> {
    lines: &'a [Option<Line>],
    margin: f64,
    spread: Option<f64>,
}

/// Adds one pair's terms of the product form's gradient and Hessian (upper triangle and
/// diagonal): the current point rotated, `r`, and its residual `e`.
#[inline(always)]
fn add_product_pair(
    (g, h): (&mut [f64; 3], &mut [[f64; 3]; 3]),
    [rx, ry]: [f64; 2],
    [ex, ey]: [f64; 2],
    two_s2: f64,
) {
    let (dx, dy) = (two_s2 + ex * ex, two_s2 + ey * ey);
    // ρ'(e) = 2e / D, ρ''(e) = 2 (2σ² − e²) / D².
    let (wx1, wy1) = (2.0 * ex / dx, 2.0 * ey / dy);
    let (wx2, wy2) = (
        2.0 * (two_s2 - ex * ex) / (dx * dx),
        2.0 * (two_s2 - ey * ey) / (dy * dy),
    );
    g[0] += -wx1 * ry + wy1 * rx;
    g[1] += wx1;
    g[2] += wy1;
    h[0][0] += wx2 * ry * ry - wx1 * rx + wy2 * rx * rx - wy1 * ry;
    h[0][1] += -wx2 * ry;
    h[0][2] += wy2 * rx;
    h[1][1] += wx2;
    h[2][2] += wy2;
}

/// One pair under `phi` (its sine and cosine given): the current point `p` rotated, and its
/// residual from the target `q`.
#[inline(always)]
fn moved(p: &[f64; 2], q: &[f64; 2], (s, c): (f64, f64), phi: [f64; 3]) -> ([f64; 2], [f64; 2]) {
    let rx = c * p[0] - s * p[1];
    let ry = s * p[0] + c * p[1];
    ([rx, ry], [rx + phi[1] - q[0], ry + phi[2] - q[1]])
}

/// One pair's factor in the product whose logarithm is the error: `1 + (n · e)² / 2σ²` with a
/// line normal `n`, else `(1 + e_x² / 2σ²)(1 + e_y² / 2σ²)`; `inv` is `1 / 2σ²`.
#[inline(always)]
fn factor([ex, ey]: [f64; 2], n: &Normal, inv: f64) -> f64 {
    match n {
        Some(n) => {
            let e = n[0] * ex + n[1] * ey;
            1.0 + e * e * inv
        }
        None => (1.0 + ex * ex * inv) * (1.0 + ey * ey * inv),
    }
}

/// Adds one pair's terms of the gradient and Hessian (upper triangle and diagonal): by its
/// distance to a line with the normal `n`, else by the product form.
#[inline(always)]
fn add_pair(
    (g, h): (&mut [f64; 3], &mut [[f64; 3]; 3]),
    [rx, ry]: [f64; 2],
    [ex, ey]: [f64; 2],
    n: &Normal,
    two_s2: f64,
) {
    match n {
        Some(n) => {
            // e = n · (R p + t − q): ∂e/∂Φ = (n × R p, nx, ny), ∂²e/∂θ² = −n · R p.
            let e = n[0] * ex + n[1] * ey;
            let d = two_s2 + e * e;
            let (w1, w2) = (2.0 * e / d, 2.0 * (two_s2 - e * e) / (d * d));
            let j = [-n[0] * ry + n[1] * rx, n[0], n[1]];
            for a in 0..3 {
                g[a] += w1 * j[a];
                for b in a..3 {
                    h[a][b] += w2 * j[a] * j[b];
                }
            }
            h[0][0] -= w1 * (n[0] * rx + n[1] * ry);
        }
        None => add_product_pair((g, h), [rx, ry], [ex, ey], two_s2),
    }
}

/// Pairs of points: the current ones (in their own frame) and their targets in the
/// reference's.
type Pairs<'a> = (&'a [[f64; 2]], &'a [[f64; 2]]);

/// A pair's reference line normal, where its target is a projection inside a line.
type Normal = Option<[f64; 2]>;

/// Whether unit normals `normals` spread enough for point-to-line residuals: the smaller
/// eigenvalue of `Σ n nᵀ` at least `share` of the larger (none: no).
fn normals_spread(normals: &[Normal], share: f64) -> bool {
    let (mut xx, mut xy, mut yy) = (0.0, 0.0, 0.0);
    for n in normals.iter().flatten() {
        xx += n[0] * n[0];
        xy += n[0] * n[1];
        yy += n[1] * n[1];
    }
    let half_trace = 0.5 * (xx + yy);
    let radius = (0.25 * (xx - yy) * (xx - yy) + xy * xy).sqrt();
    let (small, large) = (half_trace - radius, half_trace + radius);
    large > 0.0 && small >= share * large
}

impl Default for Lorentz {
    fn default() -> Self {
        Lorentz {
            sigmas_m: THESIS_SIGMAS
                .iter()
                .map(|s| s * Lorentz::SIGMA_UNIT_M)
                .collect(),
            lambda0: 0.001,
            lambda_max: 1e12,
            energy_tolerance: 1e-9,
            max_steps: 30,
            convergence: Convergence {
                translation_m: 1e-5,
                rotation_rad: 1e-4_f64.to_radians(),
                max_iterations: 30,
            },
            early_convergence: None,
            lines: None,
            drop_edge_pairs: true,
            crowd_ratio: None,
            polish_rounds: 0,
            polish_more: None,
            before_last_margin: None,
            wide_sigmas_m: Vec::new(),
            wide_below: 0.7,
            restarts: Vec::new(),
            coarse: None,
            far_slide_m: None,
            dense_sigmas_m: Vec::new(),
            dense_below_rad: 0.0,
            line_residuals_spread: None,
            sparse_line_residuals_spread: None,
            first_spread: None,
            first_max_steps: None,
            first_pass_enough: None,
            stop_on_cycles: false,
            first_pass_surfaces: None,
            first_pass_convergence: None,
            sparse_early_convergence: None,
            sparse_finish: None,
            sparse_start: None,
            slide_check: None,
            sparse_slide_check: None,
        }
    }
}

impl ScanMatcher for Lorentz {
    fn name(&self) -> &'static str {
        if self.lines.is_some() {
            "lorentz-lines"
        } else {
            "lorentz"
        }
    }

    fn align_plausible(
        &self,
        reference: &Reference,
        current: &ScanPoints,
        guess: Pose2,
    ) -> MatchResult {
        // Each current point's last nearest reference point, for every search of the match.
        let mut last = vec![None; current.len()];
        let dense = self.is_dense(current);
        // The reference's lines, grown once for every match from here.
        let grown = self
            .lines
            .as_ref()
            .map(|params| lines_of(&reference.points.xy, params));
        let grown = grown.as_deref();
        let scans = (reference, current);
        let (start, rounds) = self.start(scans, dense, guess, &mut last);
        let mut matched = self.match_from(scans, grown, dense, start, &mut last);
        matched.iterations += rounds;
        let matched = self.finished(scans, dense, matched, &mut last);
        let check = if dense {
            &self.slide_check
        } else {
            &self.sparse_slide_check
        };
        match check {
            Some(check) => self.check_slide(check, scans, grown, dense, matched, &mut last),
            None => matched,
        }
    }
}

impl Lorentz {
    /// Where the σ passes start from `guess` ([`Lorentz::sparse_start`], on a sparse scan:
    /// not `dense`), and the rounds that took.
    fn start(
        &self,
        (reference, current): (&Reference, &ScanPoints),
        dense: bool,
        guess: Pose2,
        last: &mut [Option<LastNearest>],
    ) -> (Pose2, u32) {
        let Some(start) = self.sparse_start.filter(|_| !dense) else {
            return (guess, 0);
        };
        let (pose, rounds) = start.icp.refine(reference, current, guess, last);
        let moved = guess.relative(&pose);
        let near = moved.x.hypot(moved.y) <= start.reach_m && moved.theta.abs() <= start.reach_rad;
        (if near { pose } else { guess }, rounds)
    }

    /// The match from `guess`: the σ passes, and when their answer is loose or untrusted the
    /// wide schedule, the restarts and the coarse search's starts; `dense` as
    /// [`Lorentz::is_dense`] says of `current`, `last` as in [`Lorentz::passes`], `grown` the
    /// reference's lines ([`lines_of`]) when the matcher has `lines`.
    fn match_from(
        &self,
        (reference, current): (&Reference, &ScanPoints),
        grown: Option<&[Option<Line>]>,
        dense: bool,
        guess: Pose2,
        last: &mut [Option<LastNearest>],
    ) -> MatchResult {
        let spread = self.spread_for(dense);
        let first_spread = self.first_spread.filter(|_| dense && spread.is_some());
        let mut lines = self.assist(grown, first_spread.or(spread));
        let sigmas = self.schedule_for(dense);
        let crowd = self.crowd_ratio.filter(|_| dense);
        let first_steps = self.first_max_steps.unwrap_or(self.max_steps);
        let scans = (reference, current);
        // Every answer is judged by `passes`, by the rule `align` applies, so it carries its
        // quality and `align` does not judge it again.
        let mut first = self.passes(
            (sigmas, first_steps, crowd),
            scans,
            lines.as_ref(),
            guess,
            last,
        );
        let more = !self.restarts.is_empty() || !self.wide_sigmas_m.is_empty();
        if !more && first_spread.is_none() {
            return first;
        }
        let rule = TrustRule::default();
        // From here on every match asks the scan's own share of the spread
        // (`line_residuals_spread`, or `sparse_line_residuals_spread` on a sparse scan). A loose
        // first answer is matched again so, and that answer is kept unless the first fits
        // clearly more points.
        if let Some(assist) = &mut lines {
            assist.spread = spread;
        }
        if first_spread.is_some() && first.quality.inlier_share < self.wide_below {
            let again = self.passes(
                (sigmas, first_steps, crowd),
                scans,
                lines.as_ref(),
                guess,
                last,
            );
            let iterations = first.iterations + again.iterations;
            if rule.trusts(&again.quality)
                && again.quality.inlier_share + FIRST_SPREAD_MARGIN >= first.quality.inlier_share
            {
                first = again;
            }
            first.iterations = iterations;
        }
        if !more {
            return first;
        }
        let trusted = rule.trusts(&first.quality);
        let travelled = guess.relative(&first.pose);
        let far =
            travelled.x.hypot(travelled.y) > WIDE_AFTER.0 || travelled.theta.abs() > WIDE_AFTER.1;
        let loose = first.quality.inlier_share < self.wide_below;
        // The trusted answer with the most inliers so far, besides `first`.
        let mut best: Option<(MatchResult, f64)> = None;
        let mut iterations = first.iterations;
        if !self.wide_sigmas_m.is_empty() && (!trusted || (loose && far)) {
            let wide = self.passes(
                (&self.wide_sigmas_m, self.max_steps, None),
                scans,
                lines.as_ref(),
                guess,
                last,
            );
            iterations += wide.iterations;
            if rule.trusts(&wide.quality) {
                let share = wide.quality.inlier_share;
                if share > first.quality.inlier_share {
                    first = wide;
                } else if !trusted {
                    // Trusted, but fewer points fit it than fit the untrusted first answer:
                    // the wide pass may have slid to a look-alike place, so the restarts
                    // still run and it is kept only if none fits better.
                    best = Some((wide, share));
                }
            }
        }
        first.iterations = iterations;
        if self.restarts.is_empty() || rule.trusts(&first.quality) {
            let chosen = best.map_or(first, |(result, _)| MatchResult {
                iterations,
                ..result
            });
            // Trusted far from the guess: checked against the coarse search's best start, its
            // pairs held to their projections as the restarts' are (below).
            let travelled = guess.relative(&chosen.pose);
            let slid = rule.trusts(&chosen.quality)
                && self
                    .far_slide_m
                    .is_some_and(|far| travelled.x.hypot(travelled.y) > far);
            let Some((window, _)) = self.coarse.as_ref().filter(|_| slid) else {
                return chosen;
            };
            if let Some(assist) = &mut lines {
                assist.spread = None;
            }
            let floor = chosen.quality.inlier_share + COARSE_MARGIN;
            let (found, more) = self.match_coarse_starts(
                (sigmas, crowd),
                scans,
                lines.as_ref(),
                (guess, window, 1),
                floor,
                last,
            );
            let iterations = chosen.iterations + more;
            return MatchResult {
                iterations,
                ..found.unwrap_or(chosen)
            };
        }
        // Not trusted: start again from guesses around this one, and keep the trusted answer
        // that fits best (most inliers), if any. Started away from the guess, the pairs are
        // held to their projections (the product form): free to slide along the walls, a far
        // start can settle in a look-alike place that the trust rule accepts.
        if let Some(assist) = &mut lines {
            assist.spread = None;
        }
        let mut keep = |result: MatchResult, floor: f64, best: &mut Option<(MatchResult, f64)>| {
            iterations += result.iterations;
            let share = result.quality.inlier_share;
            if rule.trusts(&result.quality)
                && share > floor
                && best.as_ref().is_none_or(|(_, s)| share > *s)
            {
                *best = Some((result, share));
            }
        };
        for offset in &self.restarts {
            let start = guess.compose(offset);
            let result = self.passes(
                (sigmas, self.max_steps, crowd),
                scans,
                lines.as_ref(),
                start,
                last,
            );
            keep(result, f64::NEG_INFINITY, &mut best);
        }
        // Still nothing: the coarse search's starts, whose answers must fit clearly more
        // points than the first.
        if best.is_none()
            && let Some((window, count)) = &self.coarse
        {
            let floor = first.quality.inlier_share + COARSE_MARGIN;
            let (found, more) = self.match_coarse_starts(
                (sigmas, crowd),
                scans,
                lines.as_ref(),
                (guess, window, *count),
                floor,
                last,
            );
            iterations += more;
            best = found.map(|result| {
                let share = result.quality.inlier_share;
                (result, share)
            });
        }
        let mut chosen = best.map_or(first, |(result, _)| result);
        chosen.iterations = iterations;
        chosen
    }

    /// The σ passes of `sigmas` from each of the `count` best starts of the coarse search over
    /// `window` around `guess` ([`correlative::best_starts`]): of their trusted answers that
    /// fit more than `floor` of the current points, the one that fits most, and the iterations
    /// of all of them.
    fn match_coarse_starts(
        &self,
        (sigmas, crowd): (&[f64], Option<f64>),
        (reference, current): (&Reference, &ScanPoints),
        lines: Option<&Assist>,
        (guess, window, count): (Pose2, &correlative::Window, usize),
        floor: f64,
        last: &mut [Option<LastNearest>],
    ) -> (Option<MatchResult>, u32) {
        let rule = TrustRule::default();
        let (from, to) = (&reference.points.xy, &current.xy);
        let mut iterations = 0;
        let mut best: Option<MatchResult> = None;
        for start in correlative::best_starts(from, to, guess, window, (count, 3)) {
            let result = self.passes(
                (sigmas, self.max_steps, crowd),
                (reference, current),
                lines,
                start,
                last,
            );
            iterations += result.iterations;
            let share = result.quality.inlier_share;
            if rule.trusts(&result.quality)
                && share > floor
                && best.as_ref().is_none_or(|b| share > b.quality.inlier_share)
            {
                best = Some(result);
            }
        }
        (best, iterations)
    }

    /// Line-assisted association on the reference's lines `grown`, their residuals taken when
    /// the normals spread by `spread`; `None` without `lines`.
    fn assist<'a>(
        &self,
        grown: Option<&'a [Option<Line>]>,
        spread: Option<f64>,
    ) -> Option<Assist<'a>> {
        let (params, lines) = self.lines.as_ref().zip(grown)?;
        Some(Assist {
            lines,
            margin: params.end_margin_m,
            spread,
        })
    }

    /// The match's answer `matched` (finished, on a sparse scan), checked as `check` says
    /// ([`SlideCheck`]): where the points off their surfaces across its weakest direction would
    /// have it, and where the trust rule finds more inliers than at `matched`, the σ passes of
    /// a `dense` or sparse scan (on the lines `grown`) from there, finished as `matched` was,
    /// their answer kept when trusted, `check.min_shift_m` or more from `matched` and fitting
    /// `check.margin` more of the current points; the iterations of both.
    fn check_slide(
        &self,
        check: &SlideCheck,
        (reference, current): (&Reference, &ScanPoints),
        grown: Option<&[Option<Line>]>,
        dense: bool,
        matched: MatchResult,
        last: &mut [Option<LastNearest>],
    ) -> MatchResult {
        let rule = TrustRule::default();
        if !rule.trusts(&matched.quality) {
            return matched;
        }
        let vote = slide_vote(
            reference,
            &current.xy,
            &matched.pose,
            Some(&mut *last),
            rule.inlier_m,
            (check.min_shift_m, check.reach_m),
        );
        let Some(vote) = vote.filter(|v| v.recruits >= check.min_gain) else {
            return matched;
        };
        let p = matched.pose;
        let [ux, uy] = vote.direction;
        let start = Pose2::new(p.x + vote.shift_m * ux, p.y + vote.shift_m * uy, p.theta);
        // The vote counts only the points it recruits; the judgement there weighs them against
        // the points the shift carries off their surfaces (or onto others), before a match.
        let there = rule.assess_near(reference, &current.xy, &start, Some(&mut *last));
        if there.inliers <= matched.quality.inliers {
            return matched;
        }
        let spread = self.spread_for(dense);
        let lines = self.assist(grown, spread);
        let steps = self.first_max_steps.unwrap_or(self.max_steps);
        let crowd = self.crowd_ratio.filter(|_| dense);
        let again = self.passes(
            (self.schedule_for(dense), steps, crowd),
            (reference, current),
            lines.as_ref(),
            start,
            last,
        );
        let again = self.finished((reference, current), dense, again, last);
        let iterations = matched.iterations + again.iterations;
        let fits_more = again.quality.inlier_share > matched.quality.inlier_share + check.margin;
        let moved = matched.pose.relative(&again.pose);
        let slid_back = moved.x.hypot(moved.y) >= check.min_shift_m;
        let kept = if rule.trusts(&again.quality) && fits_more && slid_back {
            again
        } else {
            matched
        };
        MatchResult { iterations, ..kept }
    }

    /// `matched`, finished as [`Lorentz::finish`] says on a sparse scan (not `dense`) when the
    /// matcher has a `sparse_finish`, else as it is.
    fn finished(
        &self,
        scans: (&Reference, &ScanPoints),
        dense: bool,
        matched: MatchResult,
        last: &mut [Option<LastNearest>],
    ) -> MatchResult {
        match self.sparse_finish {
            Some(finish) if !dense => self.finish(&finish, scans, matched, last),
            _ => matched,
        }
    }

    /// The match's answer `matched`, finished by point-to-line ICP `finish` from it
    /// ([`Lorentz::sparse_finish`]) on `last`'s nearest points: the finish's answer when the
    /// trust rule trusts it and it fits no fewer of the current points, else `matched`;
    /// the iterations of both.
    fn finish(
        &self,
        finish: &PointToLine,
        (reference, current): (&Reference, &ScanPoints),
        matched: MatchResult,
        last: &mut [Option<LastNearest>],
    ) -> MatchResult {
        let (pose, steps) = finish.refine(reference, current, matched.pose, last);
        let iterations = matched.iterations + steps;
        let rule = TrustRule::default();
        let quality = rule.assess_near(reference, &current.xy, &pose, Some(last));
        if rule.trusts(&quality) && quality.inlier_share >= matched.quality.inlier_share {
            MatchResult {
                pose,
                quality,
                iterations,
                ..matched
            }
        } else {
            MatchResult {
                iterations,
                ..matched
            }
        }
    }

    /// The σ schedule for `current`: `dense_sigmas_m` when it has one and the scan's beams lie
    /// closer than `dense_below_rad`, else `sigmas_m`.
    pub fn schedule(&self, current: &ScanPoints) -> &[f64] {
        self.schedule_for(self.is_dense(current))
    }

    /// The σ schedule for a scan that is `dense` ([`Lorentz::is_dense`]) or not.
    fn schedule_for(&self, dense: bool) -> &[f64] {
        if dense {
            &self.dense_sigmas_m
        } else {
            &self.sigmas_m
        }
    }

    /// The share of the spread at which line residuals are taken, for a scan that is `dense`
    /// or not: `line_residuals_spread` or `sparse_line_residuals_spread`.
    fn spread_for(&self, dense: bool) -> Option<f64> {
        if dense {
            self.line_residuals_spread
        } else {
            self.sparse_line_residuals_spread
        }
    }

    /// Whether `current`'s beams lie closer than `dense_below_rad` and the matcher has a
    /// schedule for such scans.
    fn is_dense(&self, current: &ScanPoints) -> bool {
        !self.dense_sigmas_m.is_empty()
            && beam_step_below(current, self.dense_below_rad) == Some(true)
    }

    /// The σ passes of `sigmas`, at most `steps` NLM steps a search, leaving out crowded pairs
    /// when `crowd` gives a ratio ([`Lorentz::crowd_ratio`]), and the polish from `guess`; the
    /// answer judged by the trust rule. `last` keeps each current point's last nearest
    /// reference point from one search to the next, and from one call to the next of a match
    /// (the same answers, searched less).
    fn passes(
        &self,
        (sigmas, steps, crowd): (&[f64], u32, Option<f64>),
        (reference, current): (&Reference, &ScanPoints),
        lines: Option<&Assist>,
        guess: Pose2,
        last: &mut [Option<LastNearest>],
    ) -> MatchResult {
        let mut phi = [guess.theta, guess.x, guess.y];
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
        let enough = self
            .first_pass_enough
            .filter(|_| crowd.is_some())
            .map(|(distance, share)| (distance * distance, share));
        let mut close = 0;
        // With `first_pass_surfaces` on a dense scan: the fewest points a surface that holds a
        // pair must have been fitted to.
        let surfaces = self.first_pass_surfaces.filter(|_| crowd.is_some());
        // The passes of the schedule the sparse finish follows stop sooner: the finish takes
        // the answer on.
        let finished = self.sparse_finish.is_some() && crowd.is_none() && sigmas == self.sigmas_m;
        for (pass, &sigma) in sigmas.iter().enumerate() {
            if pass == 1
                && let Some((_, share)) = enough
                && close as f64 >= share * current.len() as f64
            {
                break;
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
                (Some(first), _, _) if pass == 0 && crowd.is_some() && more_passes => first,
                (_, Some(sparse), _) => sparse,
                (_, _, Some(early)) if more_passes => early,
                _ => self.convergence,
            };
            // The estimate before the search before the last, for `stop_on_cycles`.
            let mut two_back: Option<[f64; 3]> = None;
            for _ in 0..self.convergence.max_iterations {
                result.iterations += 1;
                let pose = Pose2::new(phi[1], phi[2], phi[0]);
                transform_all(&pose, &current.xy, &mut moved);
                sources.clear();
                targets.clear();
                normals.clear();
                close = 0;
                for (i, p) in moved.iter().enumerate() {
                    let (j, d2) = reference
                        .tree
                        .nearest_cached(*p, &mut last[i])
                        .expect("non-empty reference");
                    let mut target = reference.points.xy[j];
                    let mut normal = None;
                    if let Some(assist) = lines
                        && let Some(line) = &assist.lines[j]
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
                let to_lines = lines
                    .and_then(|assist| assist.spread)
                    .is_some_and(|share| normals_spread(&normals, share));
                let normals = to_lines.then_some(normals.as_slice());
                phi = self.nlm((&sources, &targets), normals, phi, (sigma, steps));
                let step = Pose2::new(
                    phi[1] - before[1],
                    phi[2] - before[2],
                    wrap_angle(phi[0] - before[0]),
                );
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
        }
        result.pose = Pose2::new(phi[1], phi[2], wrap_angle(phi[0]));
        // The polish and the judgement search near where the passes did: `last` goes on.
        let mut after_rounds = None;
        if self.polish_rounds > 0 {
            // The crowd rule marks a dense scan's schedules but the wide one, as above.
            let more = self.polish_more.filter(|_| crowd.is_some());
            (result.pose, after_rounds) = self.polish(reference, current, result.pose, more, last);
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
            let (earlier, _) = self.polish(reference, current, earlier, None, last);
            let quality = rule.assess_near(reference, &current.xy, &earlier, Some(&mut *last));
            if quality.inlier_share > result.quality.inlier_share + margin {
                (result.pose, result.quality) = (earlier, quality);
            }
        }
        result
    }

    /// The point-to-line polish of `pose`, `polish_rounds` rounds and, with `more`, those
    /// [`polish_near`] adds: the polished pose, and the pose after `polish_rounds` where more
    /// rounds moved it.
    fn polish(
        &self,
        reference: &Reference,
        current: &ScanPoints,
        pose: Pose2,
        more: Option<(f64, usize)>,
        last: &mut [Option<LastNearest>],
    ) -> (Pose2, Option<Pose2>) {
        let rounds = (self.polish_rounds, 0.01, 0.05);
        let (polished, after_rounds) =
            polish_near(reference, &current.xy, pose, rounds, more, last);
        let wrapped = |p: Pose2| Pose2::new(p.x, p.y, wrap_angle(p.theta));
        (wrapped(polished), after_rounds.map(wrapped))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::localization::{RangeScan, beam_step};

    /// A scan's beam step is read from its points: 0.5° for 361 beams over 180°, also with
    /// beams missing (no return) and ranges jumping from beam to beam; none without two
    /// neighbouring beams; and the schedule follows it (the sparse one without the thesis's
    /// last pass, which the finish replaces).
    #[test]
    fn the_beam_step_picks_the_schedule() {
        let scan = |beams: usize, fov_deg: f64, ranges: &dyn Fn(usize) -> f64| {
            let inc = fov_deg.to_radians() / (beams - 1) as f64;
            let ranges = (0..beams).map(ranges).collect();
            RangeScan::new(-fov_deg.to_radians() / 2.0, inc, 30.0, ranges).points()
        };
        let lms = scan(361, 180.0, &|k| {
            if k % 7 == 3 {
                f64::NAN
            } else {
                2.0 + (k % 5) as f64
            }
        });
        let step = beam_step(&lms).expect("neighbours");
        assert!(
            (step.to_degrees() - 0.5).abs() < 1e-9,
            "{}",
            step.to_degrees()
        );
        let sparse = scan(181, 180.0, &|_| 4.0);
        assert!((beam_step(&sparse).expect("neighbours").to_degrees() - 1.0).abs() < 1e-9);
        let lonely = scan(361, 180.0, &|k| if k % 2 == 0 { 3.0 } else { f64::NAN });
        assert_eq!(beam_step(&lonely), None);
        let m = Lorentz::with_lines();
        assert_eq!(m.schedule(&lms), DENSE_SIGMAS.as_slice());
        assert_eq!(m.schedule(&sparse), SPARSE_SIGMAS.as_slice());
        assert_eq!(m.schedule(&lonely), SPARSE_SIGMAS.as_slice());
        // Without a dense schedule every scan takes the thesis's three passes.
        let thesis = Lorentz::default();
        assert_eq!(thesis.sigmas_m.len(), THESIS_SIGMAS.len());
        assert_eq!(thesis.schedule(&lms), thesis.sigmas_m.as_slice());
    }

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

    /// The energy, a logarithm per eight points, is the sum of every point's logarithm to
    /// rounding — also with residuals so large against σ that eight factors overflow.
    #[test]
    fn the_energy_is_the_sum_of_the_logarithms() {
        let src: Vec<[f64; 2]> = (0..53)
            .map(|i| [1.0 + 0.1 * i as f64, (i as f64 * 0.7).sin()])
            .collect();
        let mut dst: Vec<[f64; 2]> = src
            .iter()
            .enumerate()
            .map(|(i, p)| [p[0] + 0.03 * (i as f64).cos(), p[1] - 0.02])
            .collect();
        let phi: [f64; 3] = [0.05, 0.02, -0.01];
        let each = |dst: &[[f64; 2]], two_s2: f64| {
            let (s, c) = phi[0].sin_cos();
            src.iter()
                .zip(dst)
                .map(|(p, q)| {
                    let ex = c * p[0] - s * p[1] + phi[1] - q[0];
                    let ey = s * p[0] + c * p[1] + phi[2] - q[1];
                    ((1.0 + ex * ex / two_s2) * (1.0 + ey * ey / two_s2)).ln()
                })
                .sum::<f64>()
        };
        let two_s2 = 2.0 * 0.005f64.powi(2);
        let (chunked, summed) = (Lorentz::energy(&src, &dst, phi, two_s2), each(&dst, two_s2));
        assert!(
            (chunked - summed).abs() <= 1e-12 * summed.abs(),
            "{chunked} {summed}"
        );
        // Points 100 km off at σ 1 µm: each factor near 10³⁰⁶, a product of two overflows.
        for q in dst.iter_mut().step_by(3) {
            *q = [1e5, -1e5];
        }
        let two_s2 = 2.0 * 1e-6f64.powi(2);
        let (chunked, summed) = (Lorentz::energy(&src, &dst, phi, two_s2), each(&dst, two_s2));
        assert!(chunked.is_finite() && summed.is_finite());
        assert!(
            (chunked - summed).abs() <= 1e-12 * summed.abs(),
            "{chunked} {summed}"
        );
    }

    /// Points and targets for the derivative tests, and a mix of line normals.
    /// The energy and derivatives taken in one pass are those taken apart, to the bit: in the
    /// product form and with line normals on some pairs, at σ 5 mm and at σ 1 µm with points
    /// 100 km off (products of eight factors that overflow), over pair counts that are and are
    /// not a multiple of eight.
    #[test]
    fn one_pass_gives_the_energy_and_derivatives_of_two() {
        let (src, mut dst, normals) = pairs_for_derivatives();
        let phi = [0.05, 0.02, -0.01];
        let mut compared = 0;
        for far in [false, true] {
            if far {
                for q in dst.iter_mut().step_by(3) {
                    *q = [1e5, -1e5];
                }
            }
            let two_s2 = 2.0 * if far { 1e-6f64 } else { 0.005 }.powi(2);
            for len in [40, 37, 8, 1] {
                let pairs = (&src[..len], &dst[..len]);
                let normals = &normals[..len];
                let apart = [
                    (
                        Lorentz::energy(pairs.0, pairs.1, phi, two_s2),
                        Lorentz::derivatives(pairs.0, pairs.1, phi, two_s2),
                    ),
                    (
                        Lorentz::energy_to_lines(pairs, normals, phi, two_s2),
                        Lorentz::derivatives_to_lines(pairs, normals, phi, two_s2),
                    ),
                ];
                for (normals, (energy, (g, h))) in [None, Some(normals)].into_iter().zip(apart) {
                    let (e1, g1, h1) = Lorentz::energy_and_derivatives(pairs, normals, phi, two_s2);
                    assert!(energy.is_finite(), "{far} {len}: {energy}");
                    assert_eq!(e1.to_bits(), energy.to_bits(), "{far} {len}");
                    assert_eq!((g1, h1), (g, h), "{far} {len}");
                    compared += 1;
                }
            }
        }
        assert_eq!(compared, 16);
    }

    fn pairs_for_derivatives() -> (Vec<[f64; 2]>, Vec<[f64; 2]>, Vec<Normal>) {
        let src: Vec<[f64; 2]> = (0..40)
            .map(|i| [1.0 + 0.1 * i as f64, (i as f64 * 0.7).sin()])
            .collect();
        let dst: Vec<[f64; 2]> = src
            .iter()
            .enumerate()
            .map(|(i, p)| {
                [
                    p[0] + 0.03 * (i as f64).cos(),
                    p[1] - 0.02 + 0.01 * (i % 3) as f64,
                ]
            })
            .collect();
        let normals = (0..40)
            .map(|i| {
                let a = 0.4 * i as f64;
                (i % 4 != 0).then(|| [a.cos(), a.sin()])
            })
            .collect();
        (src, dst, normals)
    }

    /// `g` and `h` are the gradient and Hessian of `e` at `phi`, by central differences
    /// (`grad` gives the gradient elsewhere).
    fn assert_derivatives(
        phi: [f64; 3],
        (g, h): ([f64; 3], [[f64; 3]; 3]),
        e: impl Fn([f64; 3]) -> f64,
        grad: impl Fn([f64; 3]) -> [f64; 3],
    ) {
        let eps = 1e-6;
        for k in 0..3 {
            let (mut up, mut down) = (phi, phi);
            up[k] += eps;
            down[k] -= eps;
            let numeric = (e(up) - e(down)) / (2.0 * eps);
            assert!(
                (numeric - g[k]).abs() < 1e-4 * g[k].abs().max(1.0),
                "g[{k}]: {numeric} vs {}",
                g[k]
            );
            let (gu, gd) = (grad(up), grad(down));
            for m in 0..3 {
                let numeric = (gu[m] - gd[m]) / (2.0 * eps);
                assert!(
                    (numeric - h[m][k]).abs() < 1e-3 * h[m][k].abs().max(1.0),
                    "h[{m}][{k}]: {numeric} vs {}",
                    h[m][k]
                );
            }
        }
    }

    /// The analytic gradient and Hessian agree with finite differences of the energy.
    #[test]
    fn derivatives_match_finite_differences() {
        let (src, dst, _) = pairs_for_derivatives();
        let phi = [0.05, 0.02, -0.01];
        let two_s2 = 2.0 * 0.03f64.powi(2);
        assert_derivatives(
            phi,
            Lorentz::derivatives(&src, &dst, phi, two_s2),
            |p| Lorentz::energy(&src, &dst, p, two_s2),
            |p| Lorentz::derivatives(&src, &dst, p, two_s2).0,
        );
    }

    /// With point-to-line residuals for some pairs the derivatives agree with finite
    /// differences too; with none, both forms give the same figures to the last bit.
    #[test]
    fn point_to_line_derivatives_match_finite_differences() {
        let (src, dst, normals) = pairs_for_derivatives();
        let phi = [0.05, 0.02, -0.01];
        for sigma in [0.005, 0.03, 0.2] {
            let two_s2 = 2.0 * sigma * sigma;
            let pairs = (src.as_slice(), dst.as_slice());
            assert_derivatives(
                phi,
                Lorentz::derivatives_to_lines(pairs, &normals, phi, two_s2),
                |p| Lorentz::energy_to_lines(pairs, &normals, p, two_s2),
                |p| Lorentz::derivatives_to_lines(pairs, &normals, p, two_s2).0,
            );
            let none = vec![None; src.len()];
            assert_eq!(
                Lorentz::energy_to_lines(pairs, &none, phi, two_s2).to_bits(),
                Lorentz::energy(&src, &dst, phi, two_s2).to_bits()
            );
            assert_eq!(
                Lorentz::derivatives_to_lines(pairs, &none, phi, two_s2),
                Lorentz::derivatives(&src, &dst, phi, two_s2)
            );
        }
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
