//! The Lorentzian scan matcher of the thesis (§3.4, App. F): the robust error
//! `E = Σ ρσ(e_x,i) + ρσ(e_y,i)`, `ρσ(e) = log(1 + ½ (e/σ)²)`, minimised over `Φ = (θ, tx, ty)` by
//! Newton–Levenberg–Marquardt, three times with σ = 2, 5 and 0.5 (§5.2); optionally with
//! line-assisted association (§3.4.3).
//!
//! The constants' docs quote what each step measured when it was chosen. Edmonton's figures
//! dated before 2026-11-28's beam-step fix of the CARMEN reader were measured with its 180
//! readings spread over 180° instead of 1° apart ([`SPARSE_FINISH`] gives both).
//!
//! The folder: the matcher and a match's course from guess to answer here; the constants it is
//! tuned with, each with what it measured ([`settings`]); the σ passes and the polish
//! ([`passes`]); the Lorentzian's energy and its Newton–Levenberg–Marquardt steps ([`energy`]).

mod energy;
mod passes;
mod settings;

pub use settings::{
    BOTH_WAYS, CLEAN_PASS_ENOUGH, COARSE, COARSE_FIRST_BELOW, CROWD_RATIO, DENSE_SIGMAS,
    EARLY_CONVERGENCE, FAR_SLIDE_M, FAR_SLIDE_SPREAD, FIRST_MATCH_CONVERGENCE,
    FIRST_PASS_CONVERGENCE, FIRST_PASS_ENOUGH, FIRST_PASS_SURFACE_POINTS, FIRST_PASS_THINNING,
    FIRST_SPREAD, FIRST_SPREAD_MARGIN, FIRST_STEPS, GUESS_ALONG_FREE, LINE_RESIDUALS_SPREAD,
    LONELY_PASS_ENOUGH, LonelyEnough, MERGE_REACH, POLISH_MORE, QuickFinish, RESTART_SHORTFALL,
    RESTARTS, RESTARTS_AGREE, RestartsAgree, SLIDE_CHECK, SPARSE_EARLY_CONVERGENCE, SPARSE_FINISH,
    SPARSE_LINE_RESIDUALS_SPREAD, SPARSE_QUICK, SPARSE_SIGMAS, SPARSE_START, SlideCheck,
    StartRounds, THESIS_SIGMAS, Thinning, WIDE_SIGMAS,
};

use super::correlative;
use super::kdtree::LastNearest;
use super::lines::{LazyLines, LineParams};
use super::matcher::{Convergence, MatchResult, Reference, ScanMatcher};
use super::plicp::PointToLine;
use super::quality::{GuessAlongFree, TrustRule, polish_both_ways, slide_vote};
use super::scan::{SPARSE_BEAM_STEP_RAD, ScanPoints, beam_step_below};
use crate::geometry::{Pose2, wrap_angle};
use passes::{Assist, BOTH_WAYS_WIDTH_M, POLISH_GATE_M, Visits};
use settings::{COARSE_MARGIN, WIDE_AFTER};
use std::cell::Cell;

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
    /// points inliers) after going more than 10 cm or 3° from the guess (on a sparse scan only
    /// with [`Lorentz::sparse_loose_wide`]): the trusted answer
    /// with the larger inlier share is kept. A trusted wide answer that fits fewer points than
    /// an untrusted first one may have slid to a look-alike place, so the restarts still run
    /// and it is kept only if none fits better. Not in the thesis; empty (the default) leaves
    /// it out, and [`Lorentz::with_lines`] has [`WIDE_SIGMAS`].
    pub wide_sigmas_m: Vec<f64>,
    /// The inlier share under which a trusted answer also tries `wide_sigmas_m`. Default 0.7.
    pub wide_below: f64,
    /// Whether a sparse scan's trusted answer (its beams not closer than `dense_below_rad`) that fits
    /// loosely after going far from the guess tries `wide_sigmas_m` too, as a dense scan's
    /// does; false leaves the wide schedule to untrusted answers there. Not in the thesis; true
    /// (the default) treats both alike, and [`Lorentz::with_lines`] has false: a real sparse
    /// scan fits loosely almost always (Edmonton's pairs a median of half their points, under
    /// `wide_below`), and from guesses 20 cm / 10° off almost every answer has gone far, so the
    /// wide schedule ran on nearly every such pair. Left to untrusted answers (2026-12-03,
    /// `twin matchers --matchers lorentz-lines --seeds 20` from seeds 1 and 21): the large
    /// guesses right on 5,929 → 5,926 and 5,924 → 5,917 pairs of 6,000, Edmonton on the same
    /// 5,822 and 5,826, the twin's 1° pairs with 20 % outliers +1 and ±0, the dense rows the
    /// same answers to the bit; the large guesses 1.12–1.16 → 0.91 of `pl-icp`'s time by the
    /// median pair (`cargo bench --bench matcher_race`), their Edmonton third 965 → 437 µs.
    /// Only answers within 30 cm and 10° of the guess kept so: −2 and −2 pairs, 0.99 of the
    /// time; within 20 cm and 6°: −1 and ±0, 1.11.
    pub sparse_loose_wide: bool,
    /// Where to start again, relative to the guess, when the answer is still not trusted
    /// ([`TrustRule`]) after `wide_sigmas_m`: the trusted answer with the most inliers is
    /// kept (if it fits nearly as many as the first, `restart_shortfall`). Not in the thesis;
    /// empty (the default) leaves it out, and [`Lorentz::with_lines`] has `RESTARTS`.
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
    /// With `far_slide_m`: only an answer whose inliers' surfaces spread less than this
    /// ([`MatchQuality::spread`](super::MatchQuality::spread)) is checked. A slide to a
    /// look-alike place runs along a direction the surfaces leave free; where they face every
    /// way they hold the answer in every direction, and a trusted answer far from the guess
    /// means the guess was far off. Not in the thesis; `None` (the default) checks every far
    /// answer, and [`Lorentz::with_lines`] has [`FAR_SLIDE_SPREAD`].
    pub far_slide_spread: Option<f64>,
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
    /// With `first_spread`: whether the loose answer's second match runs even when every
    /// search of the first would have counted its line pairs' residuals the same way with
    /// `line_residuals_spread`, the line normals' spread never between the two shares. That
    /// match then makes the same searches and steps as the first and ends on its answer, to
    /// the bit, so `false` (every constructor's) leaves it out; `true` only shows that leaving
    /// it out changes no answer.
    pub rematch_alike: bool,
    /// For dense scans (as `dense_sigmas_m`), in every schedule but the wide one: when, in the
    /// last search of the first σ pass, at least this share (`.1`) of the current points were
    /// paired within this distance (`.0`, metres) of their targets, the narrower passes are
    /// left out and the polish finishes the answer. Not in the thesis; `None` (the default)
    /// runs every pass, and [`Lorentz::with_lines`] has [`FIRST_PASS_ENOUGH`].
    pub first_pass_enough: Option<(f64, f64)>,
    /// `first_pass_enough` for a dense scan that looks clean (the test of
    /// `first_pass_thinning`, which it needs): few points far from both neighbours, as a real
    /// log's scans and the twin's without outliers are, and a scan with 20 % outliers is not.
    /// There the points that pull the estimate aside are few, and the narrower passes seldom
    /// move it. Not in the thesis; `None` (the default) asks `first_pass_enough` of every
    /// scan, and [`Lorentz::with_lines`] has [`CLEAN_PASS_ENOUGH`].
    pub clean_pass_enough: Option<(f64, f64)>,
    /// `first_pass_enough` for a dense scan that does not look clean (the test of
    /// `first_pass_thinning`, which it needs): its share counted over the current points that
    /// are not lonely, when the first pass's last search's line normals spread as
    /// [`LonelyEnough`] says; a match whose narrower passes that leaves out (and the count over
    /// every point would not) takes more polish rounds. A lonely point (an outlier out to
    /// 32 m) is never within the distance of its target, so counted over every point the share
    /// asks four in five of the others on a scan with 20 % outliers. Not in the thesis; `None`
    /// (the default) counts every point, and [`Lorentz::with_lines`] has
    /// [`LONELY_PASS_ENOUGH`].
    pub lonely_pass_enough: Option<LonelyEnough>,
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
    /// With `first_pass_convergence`: when the first σ pass of a dense scan stops in the
    /// matches that take `first_max_steps` (the first match from the guess, a loose answer's
    /// second match and the slide check's), instead of `first_pass_convergence`, which the
    /// restarts and the coarse search's starts keep. Not in the thesis; `None` (the default)
    /// leaves `first_pass_convergence` to every schedule, and [`Lorentz::with_lines`] has
    /// [`FIRST_MATCH_CONVERGENCE`].
    pub first_match_convergence: Option<Convergence>,
    /// How near (metres, radians) a restart's or a coarse search's start's estimate must come
    /// to where an earlier one of the same match ended the same σ pass to take that one's
    /// answer. From there the passes would follow nearly the same path to the same answer, so
    /// the searches are saved, and the restarts that come back are cheap. Not in the thesis;
    /// `None` (the default) runs every start to its end, and [`Lorentz::with_lines`] has
    /// [`MERGE_REACH`].
    pub merge_reach: Option<(f64, f64)>,
    /// When an untrusted answer fits its points well and is pinned down, its only fault being
    /// that too few of the current points fit (the scans overlap little), and enough of the
    /// restarts come back to it: the other restarts and the coarse search are left out,
    /// and it is the answer. Its basin holds the guess's neighbourhood on both sides, and no
    /// start finds a trusted answer where the scans overlap too little for one. With
    /// [`RestartsAgree::sigma`], also when its only fault is σ, which the scans' geometry
    /// sets and no start changes. Not in the thesis; `None` (the default) runs every restart,
    /// and [`Lorentz::with_lines`] has [`RESTARTS_AGREE`].
    pub restarts_agree: Option<RestartsAgree>,
    /// How much smaller a share of the current points than the untrusted first answer fits a
    /// restart's trusted answer may fit and still replace it (and so may the wide schedule's,
    /// which waits for the restarts). An answer that fits clearly fewer points than one the
    /// same match found nearer the guess has slid to a look-alike place more often than the
    /// first was wrong: the first stays, untrusted, and the caller falls back to odometry.
    /// Not in the thesis; `None` (the default) keeps the trusted answer that fits most
    /// however little, and [`Lorentz::with_lines`] has [`RESTART_SHORTFALL`].
    pub restart_shortfall: Option<f64>,
    /// When the restarts and the coarse search's starts find no trusted answer either, the
    /// untrusted answer among theirs that fits clearly most of the current points (8 in 100
    /// more than the first answer, as a coarse start's must, and than any other kept) and whose
    /// surfaces face every way (a [`spread`](super::MatchQuality::spread) of at least the trust
    /// rule's `hold_below_spread`) is the match's answer in place of the untrusted first, both
    /// finished on a sparse scan: still untrusted, but where the scans fit best. Where the scans
    /// overlap too little for any answer to be trusted, a first answer that slid away from a
    /// guess 20 cm / 10° off fits a sixth of the points while a coarse start's fits a third, and
    /// is right (Belgioioso's pair 89). Seeds 1–60 of `twin matchers`: the large guesses right
    /// on 78 more pairs of 18,000, Belgioioso on 5 and Edmonton on 1, none fewer, no trusted
    /// answer changed. Without the spread's test, the L-corridor's rows (`--world
    /// worlds/l-corridor.toml`, seeds 1–5) lost 8 right answers of 6,000: along a corridor the
    /// answer that fits most lies anywhere along it, and the first lies nearest the guess. Not
    /// in the thesis; false (the default) answers the first, and [`Lorentz::with_lines`] has
    /// true.
    pub untrusted_best: bool,
    /// On a dense scan, when the untrusted first answer fits less than this share of the
    /// current points, the rescue runs the coarse search's starts before the restarts, and a
    /// trusted answer of theirs (fitting 8 in 100 more of the points than the first, as a
    /// coarse start's must) ends it. A first answer that fits so little says the guess is far
    /// off, often in heading beyond the restarts' ±16°, where the coarse search's ±30° look:
    /// from guesses σ 20 cm / 10° off, such pairs ran the eight restarts to nothing and then
    /// found the answer from a coarse start, 500–1,100 searches in all. Seeds 1–40 of `twin
    /// matchers`: the large guesses' searches −2.4 % and −2.5 %, 20 answers moved (every one
    /// right both ways but one wrong and untrusted made right and trusted, and one wrong and
    /// trusted left wrong and untrusted), every other row's answers the same. Not in the
    /// thesis; `None` (the default) runs the restarts first, and [`Lorentz::with_lines`] has
    /// [`COARSE_FIRST_BELOW`].
    pub coarse_first_below: Option<f64>,
    /// With `coarse_first_below`, when the coarse search's starts, tried first, found no
    /// trusted answer but all came to one place (within [`Lorentz::restarts_agree`]'s reach of
    /// each other), the rescue ends there: the restarts, nearer the guess, are not run. The
    /// answer is the untrusted first, or the untrusted answer that fits clearly most
    /// ([`Lorentz::untrusted_best`]). On Belgioioso's pair 89, where the log's pose fits a
    /// third of the points and nothing can be trusted, that spares 500–600 searches from
    /// large guesses. Seeds 1–40 of `twin matchers`: every answer the same to the bit, the
    /// large guesses' searches −2.3 % and −2.6 %. Not in the thesis; false (the default) runs
    /// the restarts, and [`Lorentz::with_lines`] has true.
    pub coarse_agreement_ends: bool,
    /// With `coarse` and `far_slide_m`, an untrusted first answer on a dense scan that lies
    /// farther than `far_slide_m` from the guess, its surfaces spread under `far_slide_spread`
    /// (the slide check's test, asked of trusted answers by `far_slide_m`), has the coarse
    /// search's starts tried before the restarts, as `coarse_first_below` does: a trusted
    /// answer of theirs (or with `coarse_agreement_ends` their agreement) ends the rescue.
    /// Along a corridor the restarts (±8°, ±16°, ±15 cm around the guess) slide to other
    /// places along it as the first did; the coarse search scores every place of its window
    /// at once. From guesses σ 20 cm / 10° off, Freiburg 101's
    /// pair 44 ran 730–840 searches, the first answer 1.8 m along its corridor: now 360–420.
    /// Seeds 1–60 of `twin matchers`: only the large guesses' row moved (and one Freiburg 101
    /// answer, wrong both ways); searches −1.5 to −2.4 % there, no pair more, 23 answers moved,
    /// all right both ways but three wrong made right and trusted. Not in the thesis; false
    /// (the default) runs the restarts first, and [`Lorentz::with_lines`] has true.
    pub coarse_first_slid: bool,
    /// For dense scans (as `dense_sigmas_m`), in the first σ pass of every schedule but the
    /// wide one, when the current scan looks clean ([`Thinning`]: few points far from both
    /// neighbours, as outliers are): its first searches pair every second current point only,
    /// until a search moves the estimate by less than `searches`' step (or after its
    /// `max_iterations` such searches); the searches after it take every point, and only they
    /// can end the pass. Those first searches are the ones whose queries miss the k-d tree's
    /// cache, the estimate still some centimetres off. Not in the thesis; `None` (the default)
    /// searches every point, and [`Lorentz::with_lines`] has [`FIRST_PASS_THINNING`].
    pub first_pass_thinning: Option<Thinning>,
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
    /// For sparse scans (not dense, as `dense_sigmas_m`): before anything else, this
    /// point-to-line ICP runs from the guess, and its answer ends the match when it passes the
    /// [`QuickFinish`]'s tests (checked for a slide as `sparse_slide_check` says); otherwise
    /// the match goes on from `sparse_start`'s round, which is that ICP's first. Not in the
    /// thesis; `None` (the default) always runs the whole match, and [`Lorentz::with_lines`]
    /// has [`SPARSE_QUICK`].
    pub sparse_quick: Option<QuickFinish>,
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
    /// For a current scan that does not look clean (the test of `first_pass_thinning`, dense
    /// or sparse; every scan without it): when the match has its answer (checked for a slide),
    /// this many rounds of the point-to-line polish both ways, the reference's points held to
    /// the current scan's surfaces as well as the current points to the reference's. The
    /// answer so polished is judged again, and kept unless the first was trusted and it is not.
    /// Not in the thesis; `None` (the default) leaves the answer as it is, and
    /// [`Lorentz::with_lines`] has [`BOTH_WAYS`].
    pub both_ways: Option<usize>,
    /// An answer the trust rule refuses only along its free direction (a corridor's advance,
    /// [`TrustRule::trusts_across`]) is moved along it toward the guess as far as the scans fit
    /// alike ([`GuessAlongFree`], by [`ScanMatcher::align`]); it stays untrusted. Not in the
    /// thesis; `None` (the default) leaves it where the match ended, and
    /// [`Lorentz::with_lines`] has [`GUESS_ALONG_FREE`].
    pub guess_along_free: Option<GuessAlongFree>,
}

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
            sparse_loose_wide: false,
            restarts: RESTARTS.to_vec(),
            coarse: Some(COARSE),
            far_slide_m: Some(FAR_SLIDE_M),
            far_slide_spread: Some(FAR_SLIDE_SPREAD),
            dense_sigmas_m: DENSE_SIGMAS.to_vec(),
            dense_below_rad: SPARSE_BEAM_STEP_RAD,
            line_residuals_spread: Some(LINE_RESIDUALS_SPREAD),
            sparse_line_residuals_spread: Some(SPARSE_LINE_RESIDUALS_SPREAD),
            first_spread: Some(FIRST_SPREAD),
            rematch_alike: false,
            first_max_steps: Some(FIRST_STEPS),
            first_pass_enough: Some(FIRST_PASS_ENOUGH),
            clean_pass_enough: Some(CLEAN_PASS_ENOUGH),
            lonely_pass_enough: Some(LONELY_PASS_ENOUGH),
            stop_on_cycles: true,
            first_pass_surfaces: Some(FIRST_PASS_SURFACE_POINTS),
            early_convergence: Some(EARLY_CONVERGENCE),
            first_pass_convergence: Some(FIRST_PASS_CONVERGENCE),
            first_match_convergence: Some(FIRST_MATCH_CONVERGENCE),
            merge_reach: Some(MERGE_REACH),
            restarts_agree: Some(RESTARTS_AGREE),
            restart_shortfall: Some(RESTART_SHORTFALL),
            untrusted_best: true,
            coarse_first_below: Some(COARSE_FIRST_BELOW),
            coarse_agreement_ends: true,
            coarse_first_slid: true,
            first_pass_thinning: Some(FIRST_PASS_THINNING),
            sparse_early_convergence: Some(SPARSE_EARLY_CONVERGENCE),
            sigmas_m: SPARSE_SIGMAS.to_vec(),
            crowd_ratio: Some(CROWD_RATIO),
            sparse_finish: Some(SPARSE_FINISH),
            sparse_start: Some(SPARSE_START),
            sparse_quick: Some(SPARSE_QUICK),
            slide_check: Some(SLIDE_CHECK),
            sparse_slide_check: Some(SLIDE_CHECK),
            both_ways: Some(BOTH_WAYS),
            guess_along_free: Some(GUESS_ALONG_FREE),
            ..Lorentz::default()
        }
    }
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
            sparse_loose_wide: true,
            restarts: Vec::new(),
            coarse: None,
            far_slide_m: None,
            far_slide_spread: None,
            dense_sigmas_m: Vec::new(),
            dense_below_rad: 0.0,
            line_residuals_spread: None,
            sparse_line_residuals_spread: None,
            first_spread: None,
            rematch_alike: false,
            first_max_steps: None,
            first_pass_enough: None,
            clean_pass_enough: None,
            lonely_pass_enough: None,
            stop_on_cycles: false,
            first_pass_surfaces: None,
            first_pass_convergence: None,
            first_match_convergence: None,
            merge_reach: None,
            restarts_agree: None,
            restart_shortfall: None,
            untrusted_best: false,
            coarse_first_below: None,
            coarse_agreement_ends: false,
            coarse_first_slid: false,
            first_pass_thinning: None,
            sparse_early_convergence: None,
            sparse_finish: None,
            sparse_start: None,
            sparse_quick: None,
            slide_check: None,
            sparse_slide_check: None,
            both_ways: None,
            guess_along_free: None,
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

    fn guess_along_free(&self) -> Option<GuessAlongFree> {
        self.guess_along_free
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
        let scans = (reference, current);
        // The reference's lines, each grown when a search first asks for it, for every match
        // from here.
        let lazy = self
            .lines
            .map(|params| LazyLines::new(&reference.points.xy, params));
        let grown = lazy.as_ref();
        // A sparse pair that point-to-line ICP alone settles ends here; else its first round
        // is the start's.
        let mut first_round = None;
        if let Some(quick) = self.sparse_quick.filter(|_| !dense) {
            match self.quick(&quick, scans, guess, &mut last) {
                Ok(matched) => return self.checked(scans, grown, dense, matched, &mut last),
                Err(left) => first_round = Some(left),
            }
        }
        let (start, rounds) = self.start(scans, dense, guess, first_round, &mut last);
        let mut untrusted = None;
        let mut matched = self.match_from(scans, grown, dense, start, (&mut last, &mut untrusted));
        matched.iterations += rounds;
        let mut matched = self.finished(scans, dense, matched, &mut last);
        // Finished and still not trusted: the rescue's untrusted answer that fits clearly most
        // (`untrusted_best`), finished too, when it still fits clearly more than the first.
        if let Some(other) = untrusted.filter(|_| !TrustRule::default().trusts(&matched.quality)) {
            let done = self.finished(scans, dense, other, &mut last);
            let iterations = matched.iterations + (done.iterations - other.iterations);
            if done.quality.inlier_share > matched.quality.inlier_share + COARSE_MARGIN {
                matched = done;
            }
            matched.iterations = iterations;
        }
        let checked = self.checked(scans, grown, dense, matched, &mut last);
        self.polished_both_ways(scans, checked, &mut last)
    }
}

/// With [`Lorentz::untrusted_best`], the rescue's untrusted answer that fits clearly most: more
/// than [`COARSE_MARGIN`] beyond the untrusted first answer's share of the current points and
/// beyond any answer kept here before, its surfaces facing every way.
struct BestUntrusted {
    /// The first answer's share.
    first_share: f64,
    /// The answer kept so far.
    best: Option<MatchResult>,
}

impl BestUntrusted {
    /// The share an untrusted answer must fit beyond to be kept.
    fn floor(&self) -> f64 {
        self.best
            .as_ref()
            .map_or(self.first_share, |b| b.quality.inlier_share)
            + COARSE_MARGIN
    }

    /// Keeps `result` if it is untrusted, its surfaces spread as the trust rule's hold test
    /// asks ([`TrustRule::hold_below_spread`]), and it fits beyond [`floor`](Self::floor).
    fn offer(&mut self, rule: &TrustRule, result: &MatchResult) {
        if !rule.trusts(&result.quality)
            && result.quality.spread >= rule.hold_below_spread
            && result.quality.inlier_share > self.floor()
        {
            self.best = Some(*result);
        }
    }
}

/// What a quick finish that did not end the match leaves the rest of it: the estimate after
/// its first round, and the rounds it made.
#[derive(Copy, Clone, Debug)]
struct FirstRound {
    pose: Pose2,
    rounds: u32,
}

impl Lorentz {
    /// Where the σ passes start from `guess` ([`Lorentz::sparse_start`], on a sparse scan:
    /// not `dense`), and the rounds that took. A quick finish's `first_round` counts as the
    /// start's round when the start is that round of the same ICP.
    fn start(
        &self,
        (reference, current): (&Reference, &ScanPoints),
        dense: bool,
        guess: Pose2,
        first_round: Option<FirstRound>,
        last: &mut [Option<LastNearest>],
    ) -> (Pose2, u32) {
        let Some(start) = self.sparse_start.filter(|_| !dense) else {
            return (guess, first_round.map_or(0, |f| f.rounds));
        };
        let reusable = self
            .sparse_quick
            .is_some_and(|quick| is_first_round_of(&start.icp, &quick.icp));
        let (pose, rounds) = match first_round {
            Some(first) if reusable => (first.pose, first.rounds),
            earlier => {
                let (pose, rounds) = start.icp.refine(reference, current, guess, last);
                (pose, rounds + earlier.map_or(0, |f| f.rounds))
            }
        };
        let moved = guess.relative(&pose);
        let near = moved.x.hypot(moved.y) <= start.reach_m && moved.theta.abs() <= start.reach_rad;
        (if near { pose } else { guess }, rounds)
    }

    /// The quick finish ([`Lorentz::sparse_quick`]): `quick.icp` from `guess`, judged by the
    /// trust rule; its answer when it passes `quick`'s tests, else its first round.
    fn quick(
        &self,
        quick: &QuickFinish,
        (reference, current): (&Reference, &ScanPoints),
        guess: Pose2,
        last: &mut [Option<LastNearest>],
    ) -> Result<MatchResult, FirstRound> {
        let found = quick
            .icp
            .refine_settled(reference, current, guess, Some(quick.give_up), last);
        let left = FirstRound {
            pose: found.first,
            rounds: found.iterations,
        };
        if found.given_up {
            return Err(left);
        }
        let rule = TrustRule::default();
        let (quality, weakest_m) =
            rule.assess_near_weakest(reference, &current.xy, &found.pose, Some(last));
        let pinned = weakest_m <= quick.max_sigma_m && quality.sigma[2] <= quick.max_sigma_rad;
        if rule.trusts(&quality) && quality.inlier_share >= quick.min_inlier_share && pinned {
            Ok(MatchResult {
                pose: found.pose,
                iterations: found.iterations,
                settled: found.settled,
                correspondences: found.kept,
                quality,
                ..MatchResult::unmatched(guess)
            })
        } else {
            Err(left)
        }
    }

    /// `matched`, checked for a slide as [`Lorentz::slide_check`] (on a `dense` scan) or
    /// [`Lorentz::sparse_slide_check`] says, when the matcher has one; `grown` as in
    /// [`Lorentz::check_slide`].
    fn checked(
        &self,
        scans: (&Reference, &ScanPoints),
        grown: Option<&LazyLines>,
        dense: bool,
        matched: MatchResult,
        last: &mut [Option<LastNearest>],
    ) -> MatchResult {
        let check = if dense {
            &self.slide_check
        } else {
            &self.sparse_slide_check
        };
        match check {
            Some(check) => self.check_slide(check, scans, grown, dense, matched, last),
            None => matched,
        }
    }

    /// `matched`, polished both ways as [`Lorentz::both_ways`] says when the current scan does
    /// not look clean; judged again, and kept unless `matched` was trusted
    /// (by the rule's figures and its hold test, as [`ScanMatcher::align`] judges) and the
    /// polished answer is not.
    fn polished_both_ways(
        &self,
        (reference, current): (&Reference, &ScanPoints),
        matched: MatchResult,
        last: &mut [Option<LastNearest>],
    ) -> MatchResult {
        let Some(rounds) = self.both_ways else {
            return matched;
        };
        if self
            .first_pass_thinning
            .is_some_and(|thinning| passes::looks_clean(&current.xy, &thinning))
        {
            return matched;
        }
        let pose = polish_both_ways(
            reference,
            &current.xy,
            matched.pose,
            (rounds, BOTH_WAYS_WIDTH_M, POLISH_GATE_M),
            last,
        );
        let pose = Pose2::new(pose.x, pose.y, wrap_angle(pose.theta));
        let rule = TrustRule::default();
        let mut quality = rule.assess_near(reference, &current.xy, &pose, Some(last));
        let mut before = matched.quality;
        if !rule.confirms(reference, &current.xy, &pose, &mut quality)
            && rule.confirms(reference, &current.xy, &matched.pose, &mut before)
        {
            return matched;
        }
        MatchResult {
            pose,
            quality,
            ..matched
        }
    }

    /// The match from `guess`: the σ passes, and when their answer is loose or untrusted the
    /// wide schedule ([`Lorentz::widened`]), then either the check of a trusted answer far
    /// from the guess ([`Lorentz::far_checked`]) or the rescue of an untrusted one
    /// ([`Lorentz::rescued`]); `dense` as [`Lorentz::is_dense`] says of `current`, `last` as in
    /// [`Lorentz::passes`], `grown` the reference's lines ([`LazyLines`]) when the matcher has
    /// `lines`. With `untrusted_best`, when the rescue kept no trusted answer, its untrusted
    /// answer that fits clearly most ([`BestUntrusted`]) is left in `untrusted`, for after the
    /// finish.
    fn match_from(
        &self,
        scans: (&Reference, &ScanPoints),
        grown: Option<&LazyLines>,
        dense: bool,
        guess: Pose2,
        (last, untrusted): (&mut [Option<LastNearest>], &mut Option<MatchResult>),
    ) -> MatchResult {
        let spread = self.spread_for(dense);
        let first_spread = self.first_spread.filter(|_| dense && spread.is_some());
        let mut lines = self.assist(grown, first_spread.or(spread));
        // Whether every search of the first match would have decided as it did with `spread`:
        // then the loose answer's second match (below) would be the first again, to the bit.
        if let Some(assist) = lines.as_mut().filter(|_| first_spread.is_some()) {
            assist.compare = spread;
        }
        let sigmas = self.schedule_for(dense);
        let crowd = self.crowd_ratio.filter(|_| dense);
        let first_steps = self.first_max_steps.unwrap_or(self.max_steps);
        // Every answer is judged by `passes`, by the rule `align` applies, so it carries its
        // quality and `align` does not judge it again.
        let mut first = self.passes(
            (sigmas, first_steps, crowd, true),
            scans,
            lines.as_ref(),
            guess,
            last,
            None,
        );
        let more = !self.restarts.is_empty() || !self.wide_sigmas_m.is_empty();
        if !more && first_spread.is_none() {
            return first;
        }
        let rule = TrustRule::default();
        // From here on every match asks the scan's own share of the spread
        // (`line_residuals_spread`, or `sparse_line_residuals_spread` on a sparse scan). A loose
        // first answer is matched again so, and that answer is kept unless the first fits
        // clearly more points; not when that match would be the first again
        // ([`Lorentz::rematch_alike`]).
        let same_again =
            !self.rematch_alike && lines.as_ref().is_some_and(|assist| assist.alike.get());
        if let Some(assist) = &mut lines {
            assist.spread = spread;
            assist.compare = None;
        }
        if first_spread.is_some() && first.quality.inlier_share < self.wide_below && !same_again {
            let again = self.passes(
                (sigmas, first_steps, crowd, true),
                scans,
                lines.as_ref(),
                guess,
                last,
                None,
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
        let (first, best) = self.widened(scans, lines.as_ref(), dense, guess, first, last);
        // Past the first match and the wide schedule, the pairs are held to their projections
        // (the product form): started away from the guess and free to slide along the walls,
        // a match can settle in a look-alike place that the trust rule accepts.
        if let Some(assist) = &mut lines {
            assist.spread = None;
        }
        if self.restarts.is_empty() || rule.trusts(&first.quality) {
            let chosen = best.map_or(first, |(result, _)| MatchResult {
                iterations: first.iterations,
                ..result
            });
            return self.far_checked(scans, lines.as_ref(), dense, guess, chosen, last);
        }
        self.rescued(
            scans,
            lines.as_ref(),
            dense,
            (guess, first, best),
            (last, untrusted),
        )
    }

    /// The first match's answer `first` from `guess`, and the wide schedule's when `first` is
    /// untrusted, or trusted but loose (under `wide_below`) after going far (more than
    /// [`WIDE_AFTER`]) on a scan dense by its beams, or any with [`Lorentz::sparse_loose_wide`]: the
    /// wide answer replaces `first` when trusted and fitting more points; trusted but fitting
    /// fewer than an untrusted `first`, it is returned beside it with its share, for the
    /// rescue to weigh. `first`'s iterations count the wide schedule's.
    fn widened(
        &self,
        scans: (&Reference, &ScanPoints),
        lines: Option<&Assist>,
        dense: bool,
        guess: Pose2,
        mut first: MatchResult,
        last: &mut [Option<LastNearest>],
    ) -> (MatchResult, Option<(MatchResult, f64)>) {
        let rule = TrustRule::default();
        let trusted = rule.trusts(&first.quality);
        let travelled = guess.relative(&first.pose);
        let far =
            travelled.x.hypot(travelled.y) > WIDE_AFTER.0 || travelled.theta.abs() > WIDE_AFTER.1;
        let loose = first.quality.inlier_share < self.wide_below;
        // The trusted answer with the most inliers so far, besides `first`.
        let mut best: Option<(MatchResult, f64)> = None;
        let mut iterations = first.iterations;
        // A loose far answer tries the wide schedule on a scan dense by its beams (whether or
        // not the matcher has a dense schedule), or anywhere with `sparse_loose_wide`; the
        // beams are only looked at when it comes to that.
        let loose_wide = || {
            self.sparse_loose_wide
                || dense
                || beam_step_below(scans.1, self.dense_below_rad) == Some(true)
        };
        if !self.wide_sigmas_m.is_empty() && (!trusted || (loose && far && loose_wide())) {
            let wide = self.passes(
                (&self.wide_sigmas_m, self.max_steps, None, false),
                scans,
                lines,
                guess,
                last,
                None,
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
        (first, best)
    }

    /// Whether `answer` lies farther than [`Lorentz::far_slide_m`] from `guess` and its
    /// inliers' surfaces spread less than [`Lorentz::far_slide_spread`]: it may have slid along
    /// the direction they leave free to a look-alike place.
    fn slid_far(&self, guess: Pose2, answer: &MatchResult) -> bool {
        let travelled = guess.relative(&answer.pose);
        self.far_slide_m
            .is_some_and(|far| travelled.x.hypot(travelled.y) > far)
            && self
                .far_slide_spread
                .is_none_or(|below| answer.quality.spread < below)
    }

    /// The answer `chosen`, trusted or without restarts to rescue it: when trusted more than
    /// `far_slide_m` from `guess` with surfaces that spread less than `far_slide_spread`,
    /// checked against the coarse search's best start ([`Lorentz::match_coarse_starts`]),
    /// whose answer replaces it when trusted and fitting clearly more points
    /// ([`COARSE_MARGIN`]); the iterations of both.
    fn far_checked(
        &self,
        scans: (&Reference, &ScanPoints),
        lines: Option<&Assist>,
        dense: bool,
        guess: Pose2,
        chosen: MatchResult,
        last: &mut [Option<LastNearest>],
    ) -> MatchResult {
        let rule = TrustRule::default();
        let slid = rule.trusts(&chosen.quality) && self.slid_far(guess, &chosen);
        let Some((window, _)) = self.coarse.as_ref().filter(|_| slid) else {
            return chosen;
        };
        let floor = chosen.quality.inlier_share + COARSE_MARGIN;
        let (found, more, _) = self.match_coarse_starts(
            (self.schedule_for(dense), self.crowd_ratio.filter(|_| dense)),
            scans,
            lines,
            (guess, window, 1),
            floor,
            (last, &mut Visits::default(), None),
        );
        let iterations = chosen.iterations + more;
        MatchResult {
            iterations,
            ..found.unwrap_or(chosen)
        }
    }

    /// The rescue of the untrusted answer `first` from `guess`: the restarts (guesses around
    /// this one), then, when none is trusted, the coarse search's starts (those first, a
    /// trusted answer of theirs, or with [`Lorentz::coarse_agreement_ends`] their agreement,
    /// ending the rescue, for a dense `first` that fits under
    /// [`Lorentz::coarse_first_below`] or, with [`Lorentz::coarse_first_slid`], slid far along
    /// its surfaces); the trusted answer
    /// that fits most (most inliers, `best` the wide schedule's kept beside `first`), else
    /// `first`, with the iterations of all. With `untrusted_best` and nothing trusted, the
    /// untrusted answer that fits clearly most is left in `untrusted`.
    fn rescued(
        &self,
        scans: (&Reference, &ScanPoints),
        lines: Option<&Assist>,
        dense: bool,
        (guess, first, mut best): (Pose2, MatchResult, Option<(MatchResult, f64)>),
        (last, untrusted): (&mut [Option<LastNearest>], &mut Option<MatchResult>),
    ) -> MatchResult {
        let rule = TrustRule::default();
        let sigmas = self.schedule_for(dense);
        let crowd = self.crowd_ratio.filter(|_| dense);
        let mut iterations = first.iterations;
        // The restarts and the coarse search's starts run one schedule: one that comes to where
        // an earlier one ended a pass takes its answer.
        let mut visits = Visits::default();
        // With `restart_shortfall`, what a restart's answer (and the wide schedule's, kept
        // above) must fit: no less than that below what the untrusted first answer fits.
        let floor = self
            .restart_shortfall
            .map_or(f64::NEG_INFINITY, |shortfall| {
                first.quality.inlier_share - shortfall
            });
        best = best.filter(|(_, share)| *share > floor);
        // With `restarts_agree`, for a first answer whose only fault is its overlap (or σ):
        // how many restarts came back to it (with `in_turn`, in a row from the first). Enough,
        // and the rescue ends.
        let agree = self.restarts_agree.filter(|agree| {
            rule.trusts_but_overlap(&first.quality)
                || (agree.sigma && rule.trusts_but_sigma(&first.quality))
        });
        let mut back = 0;
        let agreed = |back: usize| agree.is_some_and(|agree| back >= agree.restarts);
        let mut fallback = self.untrusted_best.then_some(BestUntrusted {
            first_share: first.quality.inlier_share,
            best: None,
        });
        // The coarse search's starts, whose answers must fit clearly more points than the
        // first (none without `coarse`).
        let coarse_starts = |last: &mut [Option<LastNearest>],
                             visits: &mut Visits,
                             fallback: Option<&mut BestUntrusted>| {
            self.coarse.as_ref().map(|(window, count)| {
                self.match_coarse_starts(
                    (sigmas, crowd),
                    scans,
                    lines,
                    (guess, window, *count),
                    first.quality.inlier_share + COARSE_MARGIN,
                    (last, visits, fallback),
                )
            })
        };
        // A dense first answer that fits very little, or (with `coarse_first_slid`) that slid
        // far from the guess along a direction its surfaces leave free: the coarse search's
        // starts first.
        let coarse_first = dense
            && (self
                .coarse_first_below
                .is_some_and(|below| first.quality.inlier_share < below)
                || (self.coarse_first_slid && self.slid_far(guess, &first)));
        let mut coarse_tried = false;
        if coarse_first
            && let Some((found, more, agree)) = coarse_starts(last, &mut visits, fallback.as_mut())
        {
            coarse_tried = true;
            iterations += more;
            if let Some(mut found) = found {
                found.iterations = iterations;
                return found;
            }
            // The coarse starts agree on one place, and it cannot be trusted: the restarts,
            // nearer the guess, are not asked.
            if agree && self.coarse_agreement_ends {
                *untrusted = fallback.and_then(|l| l.best);
                return MatchResult {
                    iterations,
                    ..first
                };
            }
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
        for (tried, offset) in self.restarts.iter().enumerate() {
            if agreed(back) {
                break;
            }
            let start = guess.compose(offset);
            let result = self.passes(
                (sigmas, self.max_steps, crowd, false),
                scans,
                lines,
                start,
                last,
                Some(&mut visits),
            );
            let came_back = agree.is_some_and(|agree| {
                (back == tried || !agree.in_turn) && agree.came_back(&first.pose, &result.pose)
            });
            back += usize::from(came_back);
            if let Some(fallback) = &mut fallback {
                fallback.offer(&rule, &result);
            }
            keep(result, floor, &mut best);
        }
        // Still nothing: the coarse search's starts (unless the restarts agreed with the first,
        // or they ran before the restarts).
        if best.is_none()
            && !agreed(back)
            && !coarse_tried
            && let Some((found, more, _)) = coarse_starts(last, &mut visits, fallback.as_mut())
        {
            iterations += more;
            best = found.map(|result| {
                let share = result.quality.inlier_share;
                (result, share)
            });
        }
        // Nothing trusted: the untrusted answer that fits clearly most, with `untrusted_best`,
        // for the caller to weigh after the finish.
        if best.is_none() {
            *untrusted = fallback.and_then(|l| l.best);
        }
        let mut chosen = best.map_or(first, |(result, _)| result);
        chosen.iterations = iterations;
        chosen
    }

    /// The σ passes of `sigmas` from each of the `count` best starts of the coarse search over
    /// `window` around `guess` ([`correlative::best_starts`]): of their trusted answers that
    /// fit more than `floor` of the current points, the one that fits most, the iterations
    /// of all of them, and whether there were two answers or more, all within
    /// [`Lorentz::restarts_agree`]'s reach of the first. A start that comes to where one noted
    /// in `visits` ended a pass takes that one's answer ([`Lorentz::merge_reach`]). With
    /// `untrusted`, each untrusted answer is offered to it.
    fn match_coarse_starts(
        &self,
        (sigmas, crowd): (&[f64], Option<f64>),
        (reference, current): (&Reference, &ScanPoints),
        lines: Option<&Assist>,
        (guess, window, count): (Pose2, &correlative::Window, usize),
        floor: f64,
        (last, visits, mut untrusted): (
            &mut [Option<LastNearest>],
            &mut Visits,
            Option<&mut BestUntrusted>,
        ),
    ) -> (Option<MatchResult>, u32, bool) {
        let rule = TrustRule::default();
        let (from, to) = (&reference.points.xy, &current.xy);
        let mut iterations = 0;
        let mut best: Option<MatchResult> = None;
        // The first start's answer, and whether every other came to it.
        let mut first: Option<Pose2> = None;
        let mut answers = 0;
        let mut agree = self.restarts_agree.is_some();
        for start in correlative::best_starts(from, to, guess, window, (count, 3)) {
            let result = self.passes(
                (sigmas, self.max_steps, crowd, false),
                (reference, current),
                lines,
                start,
                last,
                Some(&mut *visits),
            );
            iterations += result.iterations;
            answers += 1;
            match (&first, &self.restarts_agree) {
                (None, _) => first = Some(result.pose),
                (Some(pose), Some(reach)) => agree &= reach.came_back(pose, &result.pose),
                (Some(_), None) => agree = false,
            }
            if let Some(untrusted) = untrusted.as_mut() {
                untrusted.offer(&rule, &result);
            }
            let share = result.quality.inlier_share;
            if rule.trusts(&result.quality)
                && share > floor
                && best.as_ref().is_none_or(|b| share > b.quality.inlier_share)
            {
                best = Some(result);
            }
        }
        (best, iterations, agree && answers >= 2)
    }

    /// Line-assisted association on the reference's lines `grown`, their residuals taken when
    /// the normals spread by `spread`; `None` without `lines`.
    fn assist<'a>(
        &self,
        grown: Option<&'a LazyLines<'a>>,
        spread: Option<f64>,
    ) -> Option<Assist<'a>> {
        let (params, lines) = self.lines.as_ref().zip(grown)?;
        Some(Assist {
            lines,
            margin: params.end_margin_m,
            spread,
            compare: None,
            alike: Cell::new(true),
        })
    }

    /// The match's answer `matched` (finished, on a sparse scan; or a quick finish's), checked
    /// as `check` says
    /// ([`SlideCheck`]): where the points off their surfaces across its weakest direction would
    /// have it, and where the trust rule finds more inliers than at `matched`, the σ passes of
    /// a `dense` or sparse scan (on the lines `grown`) from there, finished as `matched` was,
    /// their answer kept when trusted, `check.min_shift_m` or more from `matched` and fitting
    /// `check.margin` more of the current points; the iterations of both.
    fn check_slide(
        &self,
        check: &SlideCheck,
        (reference, current): (&Reference, &ScanPoints),
        grown: Option<&LazyLines>,
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
        let floor = matched.quality.inliers;
        if rule
            .assess_near_above(reference, &current.xy, &start, Some(&mut *last), floor)
            .is_none()
        {
            return matched;
        }
        let spread = self.spread_for(dense);
        let lines = self.assist(grown, spread);
        let steps = self.first_max_steps.unwrap_or(self.max_steps);
        let crowd = self.crowd_ratio.filter(|_| dense);
        let again = self.passes(
            (self.schedule_for(dense), steps, crowd, true),
            (reference, current),
            lines.as_ref(),
            start,
            last,
            None,
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
}

/// Whether `start`'s single round is `icp`'s first: the same loop, capped at one iteration.
fn is_first_round_of(start: &PointToLine, icp: &PointToLine) -> bool {
    let capped = PointToLine {
        convergence: Convergence {
            max_iterations: 1,
            ..icp.convergence
        },
        ..*icp
    };
    start.convergence.max_iterations == 1 && *start == capped
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

    /// A corridor 2 m wide and longer than the laser's reach, each scan with a centimetre of
    /// range noise: the scans place the current laser across the corridor and in heading, and
    /// nothing in them says where along it. `lorentz-lines`' answer is not trusted, and takes
    /// the guess's place along the corridor, its place across and its heading the scans'
    /// ([`GUESS_ALONG_FREE`]); without it the answer ends wherever the match stopped.
    #[test]
    fn along_a_corridor_the_answer_takes_the_guess_place() {
        let scan = |at: Pose2, salt: usize| {
            let inc = 0.5f64.to_radians();
            let ranges = (0..361)
                .map(|k| {
                    let a = at.theta - std::f64::consts::FRAC_PI_2 + k as f64 * inc;
                    let wall = if a.sin() > 0.0 { 1.0 } else { -1.0 };
                    let r = (wall - at.y) / a.sin();
                    let noise = 0.02 * (((k + salt) as f64 * 0.754_877_666).fract() - 0.5);
                    if r.is_finite() && r > 0.0 && r < 30.0 {
                        r + noise
                    } else {
                        f64::NAN
                    }
                })
                .collect();
            RangeScan::new(-std::f64::consts::FRAC_PI_2, inc, 30.0, ranges)
        };
        let reference = Reference::new(scan(Pose2::IDENTITY, 0).points());
        let truth = Pose2::new(0.30, 0.12, 3f64.to_radians());
        let current = scan(truth, 1000).points();
        let guess = Pose2::new(0.36, 0.16, 4f64.to_radians());
        let matcher = Lorentz::with_lines();
        let found = matcher.align(&reference, &current, guess);
        assert!(!found.converged, "{found:?}");
        // The corridor runs along x: along it the guess's place, across it and in heading the
        // truth's.
        assert!((found.pose.x - guess.x).abs() < 1e-3, "{found:?}");
        assert!((found.pose.y - truth.y).abs() < 0.01, "{found:?}");
        assert!(
            (found.pose.theta - truth.theta).abs() < 0.3f64.to_radians(),
            "{found:?}"
        );

        // Without the rule the match stops where its searches left it; the rule walks that
        // answer along its free direction, and judges it again there.
        let without = Lorentz {
            guess_along_free: None,
            ..Lorentz::with_lines()
        };
        let left = without.align(&reference, &current, guess);
        assert!(
            TrustRule::default().trusts_across(&left.quality),
            "{left:?}"
        );
        let walked =
            GUESS_ALONG_FREE.place(&reference, &current.xy, &left.pose, &left.quality, &guess);
        assert_ne!(left.pose, found.pose);
        assert_eq!(found.pose, walked);
        assert!(!found.quality.held);
    }
}
