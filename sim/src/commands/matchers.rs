//! `twin matchers`: every scan matcher on the same pairs, synthetic and real, in one table —
//! success, median and 95th-percentile errors, median time, and how well each answer's
//! `converged` flag predicts its success (precision and recall).
//!
//! - **synthetic** pairs: the twin's SICK from two poses a short drive apart (up to ±30 cm and
//!   ±20°) in four worlds in turn (the lab, the orthogonal room, the glass-door room and the lab
//!   with 30 boxes), at 0 % and 20 % uniform outliers, with its beams 0.5° apart and in its 1°
//!   mode ([`SPARSE_BEAMS`]); the guess is the truth moved by Gaussian errors of σ 5 cm and 2°;
//!   success is within 5 cm and 1°;
//! - **real** pairs: consecutive scans of the SLAM-corrected CARMEN logs in
//!   `tests/data/corrected/` (Belgioioso castle, Freiburg building 101, Edmonton convention
//!   centre), whose corrected poses give the truth to about 2 cm; the guess is the truth moved by
//!   σ 5 cm and 2°, and in a last row by σ 20 cm and 10°; success is within 10 cm and 2°.
//!
//! A corrected log's poses are not perfect. For each pair the reference pose is judged by the
//! same rule as an answer (the share of current points within 5 cm of the reference scan's
//! surfaces, [`TrustRule::assess`]), and a failure is **disputed** when the matcher's answer is
//! trusted and fits at least [`DISPUTE_RATIO`] times that share: the scans then side with the
//! answer, not with the reference. A failure is **agreed** when another matcher of the same run,
//! started from the same guess, answers within [`AGREE`] of it and both answers fit at least
//! [`AGREE_MARGIN`] more of the current points than the reference pose: two matchers then
//! side with each other against the reference. Neither is turned into a success; `--show`
//! draws such a pair.
//!
//! Everything but the times is the same on every run and machine for a given seed.

pub mod plain;
pub mod reach;

use super::CommandError;
use super::map::PairLine;
use crate::commands::montecarlo::pairs::PairMaker;
use crate::config::{Outliers, RobotDescription, WorldDescription};
use crate::output::pair::{Placement, write_pair_svg};
use crate::rng::{self, SimRng};
use rand::RngExt;
use rand_distr::{Distribution, StandardNormal};
use robot::Pose2;
use robot::localization::{MatchResult, MatcherKind, RangeScan, Reference, TrustRule};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// One pair with its truth and the guess a matcher starts from.
#[derive(Clone, Debug)]
pub struct Case {
    /// The reference scan.
    pub reference: RangeScan,
    /// The current scan.
    pub current: RangeScan,
    /// The current laser frame in the reference laser frame.
    pub truth: Pose2,
    /// Where the matcher starts.
    pub guess: Pose2,
}

/// Three scans of a log in a row, `k`, `k + 1` and `k + 2`: the set's pairs `first` (`k` to
/// `k + 1`) and `second` (`k + 1` to `k + 2`), and the pair `skip` straight from `k` to `k + 2`.
/// A matcher's answer to `skip` should be its answers to `first` and `second` chained: how far
/// it is (the *closure*) measures the answers' own scatter without trusting any reference.
#[derive(Clone, Debug)]
pub struct Triangle {
    /// The index in the set's cases of the pair from scan `k` to `k + 1`.
    pub first: usize,
    /// The index of the pair from scan `k + 1` to `k + 2`.
    pub second: usize,
    /// The pair from scan `k` to `k + 2`, with its own guess.
    pub skip: Case,
}

/// Pairs of one kind, and when a match of them counts as a success.
#[derive(Clone, Debug)]
pub struct CaseSet {
    /// The row's name.
    pub name: String,
    /// The seed its guesses (and synthetic pairs) were drawn from.
    pub seed: u64,
    /// The pairs.
    pub cases: Vec<Case>,
    /// A log's consecutive pairs, two by two, with the pair that skips their middle scan (none
    /// for synthetic pairs, which are not a sequence).
    pub triangles: Vec<Triangle>,
    /// A match within this distance of the truth, metres …
    pub tolerance_m: f64,
    /// … and this angle, radians, is a success.
    pub tolerance_rad: f64,
}

/// The guess's errors: Gaussian with these standard deviations (metres on each axis, radians).
#[derive(Copy, Clone, Debug)]
pub struct GuessError {
    /// σ of x and of y, metres.
    pub sigma_m: f64,
    /// σ of θ, radians.
    pub sigma_rad: f64,
}

impl GuessError {
    /// The truth moved by a draw of the errors.
    fn guess(&self, truth: Pose2, rng: &mut SimRng) -> Pose2 {
        let mut n = || -> f64 { StandardNormal.sample(rng) };
        let (dx, dy, dt) = (n(), n(), n());
        Pose2::new(
            truth.x + self.sigma_m * dx,
            truth.y + self.sigma_m * dy,
            truth.theta + self.sigma_rad * dt,
        )
    }
}

/// `n` synthetic pairs with uniform outliers at `outlier_rate`, the worlds taken in turn.
pub fn synthetic_set(
    name: &str,
    worlds: &[WorldDescription],
    robot: &RobotDescription,
    outlier_rate: f64,
    n: usize,
    error: GuessError,
    seed: u64,
) -> Result<CaseSet, CommandError> {
    let outliers = Outliers {
        uniform: outlier_rate,
        ..Outliers::NONE
    };
    let makers: Vec<PairMaker> = worlds
        .iter()
        .map(|w| PairMaker::new(w, robot, outliers))
        .collect();
    let stream = rng::stream_seed(seed, &format!("matchers/{name}"));
    let cases = (0..n)
        .map(|k| {
            let (maker, world) = (&makers[k % makers.len()], &worlds[k % worlds.len()]);
            let mut rng = rng::substream(stream, k as u64);
            let start = maker
                .free_pose(0.4, &mut rng)
                .map_err(|why| {
                    CommandError::Pairs(format!(
                        "{}: {why}: the world must leave room for the robot 0.4 m from every wall, walled on as many sides as its start",
                        world.name
                    ))
                })?;
            let u = |rng: &mut SimRng| 2.0 * rng.random::<f64>() - 1.0;
            let motion = Pose2::new(
                0.3 * u(&mut rng),
                0.05 * u(&mut rng),
                20f64.to_radians() * u(&mut rng),
            );
            let pair = maker.pair(start, start.compose(&motion), &mut rng);
            Ok(Case {
                guess: error.guess(pair.truth, &mut rng),
                reference: pair.reference,
                current: pair.current,
                truth: pair.truth,
            })
        })
        .collect::<Result<_, CommandError>>()?;
    Ok(CaseSet {
        name: name.to_string(),
        seed,
        cases,
        triangles: Vec::new(),
        tolerance_m: 0.05,
        tolerance_rad: 1f64.to_radians(),
    })
}

/// Up to `n` consecutive pairs of a SLAM-corrected CARMEN log, whose scans' poses are the truth,
/// and their [`Triangle`]s (each skip pair's guess drawn from its own stream, so the pairs'
/// guesses are those of a set without them).
pub fn log_set(
    name: &str,
    log: &Path,
    n: usize,
    error: GuessError,
    seed: u64,
) -> Result<CaseSet, CommandError> {
    // Each scan with the pose its own FLASER line states: a corrected log's corrected pose,
    // which is the laser's (Freiburg 101's declared 4 cm offset is not applied: its scans fit
    // each other best without it, `the_corrected_logs_poses_are_their_lasers`).
    let scans = robot::logs::read_log(log)?.scans_with_logged_pose();
    let case = |(from, to): (&(RangeScan, Pose2), &(RangeScan, Pose2)), rng: &mut SimRng| {
        let truth = from.1.relative(&to.1);
        Case {
            reference: from.0.clone(),
            current: to.0.clone(),
            truth,
            guess: error.guess(truth, rng),
        }
    };
    let stream = rng::stream_seed(seed, &format!("matchers/{name}"));
    let cases: Vec<Case> = scans
        .windows(2)
        .take(n)
        .enumerate()
        .map(|(k, w)| case((&w[0], &w[1]), &mut rng::substream(stream, k as u64)))
        .collect();
    let skips = rng::stream_seed(seed, &format!("matchers/{name}/skips"));
    let triangles = scans
        .windows(3)
        .take(cases.len().saturating_sub(1))
        .enumerate()
        .map(|(k, w)| Triangle {
            first: k,
            second: k + 1,
            skip: case((&w[0], &w[2]), &mut rng::substream(skips, k as u64)),
        })
        .collect();
    Ok(CaseSet {
        name: name.to_string(),
        seed,
        cases,
        triangles,
        tolerance_m: 0.10,
        tolerance_rad: 2f64.to_radians(),
    })
}

/// How one matcher did on one set.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Row {
    /// The set's name.
    pub set: String,
    /// The matcher.
    pub matcher: MatcherKind,
    /// Pairs matched.
    pub pairs: usize,
    /// Share of pairs matched within the tolerance.
    pub success: f64,
    /// Median and 95th percentile of the translation error, metres.
    pub error_m: [f64; 2],
    /// Median and 95th percentile of the rotation error, radians.
    pub error_rad: [f64; 2],
    /// With the pairs of several seeds pooled: the lowest and the highest of the seeds' own
    /// median translation errors, metres (each seed's pairs alone, as `--seeds 1` from that
    /// seed gives them). The pooled median hides how far one run of the row's pairs can stray.
    pub error_by_seed_m: Option<[f64; 2]>,
    /// Median time per pair (preparing the reference included), microseconds.
    pub median_us: f64,
    /// Share of pairs flagged `converged`.
    pub flagged: f64,
    /// Of the flagged pairs, the share that succeeded (1 when none is flagged).
    pub flag_precision: f64,
    /// Of the successful pairs, the share flagged (1 when none succeeded).
    pub flag_recall: f64,
    /// Failures whose trusted answer fits at least [`DISPUTE_RATIO`] times the share of
    /// current points the reference pose fits: pairs where the scans side with the answer.
    pub disputed: usize,
    /// Failures another matcher of the run agrees with against the reference pose: set by
    /// [`mark_agreed`] (0 before it, and when one matcher runs).
    pub agreed: usize,
    /// Over the set's [`Triangle`]s (none for synthetic pairs): the median and 95th percentile
    /// of the closure's translation, metres, and of its rotation, radians.
    pub closure: Option<Closure>,
}

/// How far a matcher's answers to a log's pairs fail to chain: over [`Triangle`]s, the answer
/// to the pair skipping a scan against the answers to the two pairs through it. No reference
/// enters it, so it means the same on a log whose poses are loose or raw odometry; an error
/// every answer shares (a scale, a constant bias) chains and does not show.
#[derive(Copy, Clone, Debug, serde::Serialize)]
pub struct Closure {
    /// Triangles measured.
    pub triangles: usize,
    /// Median and 95th percentile of the closure's translation, metres.
    pub m: [f64; 2],
    /// Median and 95th percentile of the closure's rotation, radians.
    pub rad: [f64; 2],
}

/// One matcher's closure of one [`Triangle`]: what `closures.csv` lists.
#[derive(Clone, Debug)]
pub struct TriangleOutcome {
    /// The seed of the set's guesses.
    pub seed: u64,
    /// The set's name.
    pub set: String,
    /// The triangle's number in its set (the index of its first pair).
    pub triangle: usize,
    /// The matcher.
    pub matcher: MatcherKind,
    /// The closure's translation and rotation, metres and radians.
    pub closure: (f64, f64),
    /// Whether the matcher trusted all three answers.
    pub trusted: bool,
    /// The answer to the pair skipping the middle scan.
    pub skip: Pose2,
}

/// The header of `closures.csv` (the seed of a `--raw-log` row, whose guesses draw nothing, is
/// 0).
pub const CLOSURES_HEADER: &str =
    "seed,set,triangle,matcher,closure_mm,closure_deg,trusted,skip_x_m,skip_y_m,skip_theta_deg";

impl TriangleOutcome {
    /// The outcome as a line of `closures.csv`.
    pub fn csv(&self) -> String {
        format!(
            "{},\"{}\",{},{},{:.2},{:.3},{},{:.5},{:.5},{:.4}",
            self.seed,
            self.set,
            self.triangle,
            self.matcher,
            self.closure.0 * 1e3,
            self.closure.1.to_degrees(),
            u8::from(self.trusted),
            self.skip.x,
            self.skip.y,
            self.skip.theta.to_degrees(),
        )
    }
}

/// What [`evaluate`] reports as soon as it is known: a pair's match, or a triangle's closure.
#[derive(Clone, Debug)]
pub enum Matched {
    /// One match of one pair.
    Pair(Outcome),
    /// One matcher's closure of one triangle.
    Triangle(TriangleOutcome),
}

/// The closure of answers `first` (scan `k` to `k + 1`) and `second` (`k + 1` to `k + 2`)
/// against `skip` (`k` to `k + 2`): translation and rotation, metres and radians.
pub fn closure(first: &Pose2, second: &Pose2, skip: &Pose2) -> (f64, f64) {
    let off = first.compose(second).relative(skip);
    (off.x.hypot(off.y), off.theta.abs())
}

/// How many times the reference pose's share of fitting points a trusted answer must fit for
/// its failure to count as disputed by the scans.
pub const DISPUTE_RATIO: f64 = 2.0;

/// How near two matchers' answers to one pair must lie to count as the same answer: 3 cm and
/// 0.5° (a tenth of a real pair's tolerance, and a quarter of its heading's).
pub const AGREE: (f64, f64) = (0.03, 0.5 * std::f64::consts::PI / 180.0);

/// How much larger a share of the current points two agreeing answers must each fit than the
/// reference pose for a failure to count as agreed against it: 5 points in 100.
pub const AGREE_MARGIN: f64 = 0.05;

/// One match of one pair: what `pairs.csv` lists.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The seed of the set's guesses.
    pub seed: u64,
    /// The set's name.
    pub set: String,
    /// The pair's number in its set.
    pub pair: usize,
    /// The matcher.
    pub matcher: MatcherKind,
    /// Translation and rotation errors, metres and radians.
    pub error: (f64, f64),
    /// The guess's translation and rotation errors, metres and radians: how far the match
    /// started from the truth.
    pub guess_error: (f64, f64),
    /// Whether it was within the set's tolerance.
    pub success: bool,
    /// What the matcher answered.
    pub result: MatchResult,
    /// The share of current points within 5 cm of the reference scan's surfaces with the
    /// current scan at the reference (true) pose.
    pub truth_share: f64,
    /// A failure whose trusted answer fits at least [`DISPUTE_RATIO`] times `truth_share`.
    pub disputed: bool,
    /// A failure another matcher agrees with against the reference pose: set by
    /// [`mark_agreed`] (false before it).
    pub agreed: bool,
}

/// The header of `pairs.csv`.
pub const OUTCOMES_HEADER: &str = "seed,set,pair,matcher,success,error_mm,error_deg,converged,settled,iterations,inliers,inlier_share,rms_mm,sigma_x_mm,sigma_y_mm,sigma_theta_deg,step_mm,step_deg,truth_inlier_share,disputed,guess_error_mm,guess_error_deg,agreed,x_m,y_m,theta_deg,spread,held";

impl Outcome {
    /// The outcome as a line of `pairs.csv`.
    pub fn csv(&self) -> String {
        let q = &self.result.quality;
        format!(
            "{},\"{}\",{},{},{},{:.2},{:.3},{},{},{},{},{:.4},{:.2},{:.2},{:.2},{:.3},{:.2},{:.3},{:.4},{},{:.2},{:.3},{},{:.5},{:.5},{:.4},{:.4},{}",
            self.seed,
            self.set,
            self.pair,
            self.matcher,
            u8::from(self.success),
            self.error.0 * 1e3,
            self.error.1.to_degrees(),
            u8::from(self.result.converged),
            u8::from(self.result.settled),
            self.result.iterations,
            q.inliers,
            q.inlier_share,
            q.rms_m * 1e3,
            q.sigma[0] * 1e3,
            q.sigma[1] * 1e3,
            q.sigma[2].to_degrees(),
            q.step[0] * 1e3,
            q.step[1].to_degrees(),
            self.truth_share,
            u8::from(self.disputed),
            self.guess_error.0 * 1e3,
            self.guess_error.1.to_degrees(),
            u8::from(self.agreed),
            self.result.pose.x,
            self.result.pose.y,
            self.result.pose.theta.to_degrees(),
            q.spread,
            u8::from(q.held),
        )
    }
}

/// Marks each failure in `outcomes` that another matcher's answer to the same pair of the same
/// set and seed lies within [`AGREE`] of, when both answers fit at least [`AGREE_MARGIN`] more
/// of the current points than the reference pose; and counts them in the matching `rows`.
pub fn mark_agreed(outcomes: &mut [Outcome], rows: &mut [Row]) {
    let mut by_pair: std::collections::BTreeMap<(&str, u64, usize), Vec<usize>> =
        Default::default();
    for (k, o) in outcomes.iter().enumerate() {
        by_pair
            .entry((o.set.as_str(), o.seed, o.pair))
            .or_default()
            .push(k);
    }
    let fits = |o: &Outcome| o.result.quality.inlier_share >= o.truth_share + AGREE_MARGIN;
    let mut agreed = vec![false; outcomes.len()];
    for group in by_pair.values() {
        for &a in group {
            let oa = &outcomes[a];
            agreed[a] = !oa.success
                && fits(oa)
                && group.iter().any(|&b| {
                    let ob = &outcomes[b];
                    let off = oa.result.pose.relative(&ob.result.pose);
                    b != a
                        && fits(ob)
                        && off.x.hypot(off.y) <= AGREE.0
                        && off.theta.abs() <= AGREE.1
                });
        }
    }
    for (o, agreed) in outcomes.iter_mut().zip(agreed) {
        o.agreed = agreed;
    }
    for row in rows {
        row.agreed = outcomes
            .iter()
            .filter(|o| o.agreed && o.set == row.set && o.matcher == row.matcher)
            .count();
    }
}

/// Every matcher of `kinds` on every pair of `set`, one after the other on this thread, then on
/// the skip pair of each of its triangles; each match's outcome and each triangle's closure goes
/// to `record` as soon as it is known (so a caller can show progress). The skip pairs' times
/// are not in the row's. Agreement between matchers needs every answer to a pair first: the
/// rows and outcomes say none until [`mark_agreed`] is given them.
pub fn evaluate(set: &CaseSet, kinds: &[MatcherKind], record: &mut dyn FnMut(Matched)) -> Vec<Row> {
    tally(set, kinds, record)
        .into_iter()
        .map(Tally::row)
        .collect()
}

/// What one matcher's matches of one set add up to before their quantiles are taken, so that
/// the same row of several seeds pools into one ([`Tally::add`]).
#[derive(Clone, Debug)]
pub struct Tally {
    set: String,
    matcher: MatcherKind,
    errors_m: Vec<f64>,
    errors_rad: Vec<f64>,
    /// Each pooled seed's own median translation error, metres, in the order pooled.
    seed_medians_m: Vec<f64>,
    micros: Vec<f64>,
    success: usize,
    flagged: usize,
    flagged_success: usize,
    disputed: usize,
    closures_m: Vec<f64>,
    closures_rad: Vec<f64>,
}

impl Tally {
    /// The same row of another seed's pairs, pooled into this one.
    pub fn add(&mut self, other: Tally) {
        debug_assert!(self.set == other.set && self.matcher == other.matcher);
        self.errors_m.extend(other.errors_m);
        self.errors_rad.extend(other.errors_rad);
        self.seed_medians_m.extend(other.seed_medians_m);
        self.micros.extend(other.micros);
        self.success += other.success;
        self.flagged += other.flagged;
        self.flagged_success += other.flagged_success;
        self.disputed += other.disputed;
        self.closures_m.extend(other.closures_m);
        self.closures_rad.extend(other.closures_rad);
    }

    /// The row's figures.
    pub fn row(mut self) -> Row {
        let pairs = self.errors_m.len();
        let n = pairs.max(1) as f64;
        let share = |a: usize, b: usize| if b == 0 { 1.0 } else { a as f64 / b as f64 };
        let median_p95 = |v: &mut [f64]| [quantile(v, 0.5), quantile(v, 0.95)];
        let closure = (!self.closures_m.is_empty()).then(|| Closure {
            triangles: self.closures_m.len(),
            m: median_p95(&mut self.closures_m),
            rad: median_p95(&mut self.closures_rad),
        });
        Row {
            set: self.set,
            matcher: self.matcher,
            pairs,
            success: self.success as f64 / n,
            error_m: median_p95(&mut self.errors_m),
            error_rad: median_p95(&mut self.errors_rad),
            error_by_seed_m: (self.seed_medians_m.len() > 1).then(|| {
                let fold = |f: fn(f64, f64) -> f64, start| {
                    self.seed_medians_m.iter().copied().fold(start, f)
                };
                [
                    fold(f64::min, f64::INFINITY),
                    fold(f64::max, f64::NEG_INFINITY),
                ]
            }),
            median_us: quantile(&mut self.micros, 0.5),
            flagged: self.flagged as f64 / n,
            flag_precision: share(self.flagged_success, self.flagged),
            flag_recall: share(self.flagged_success, self.success),
            disputed: self.disputed,
            agreed: 0,
            closure,
        }
    }
}

/// [`evaluate`]'s work, its figures still unreduced: one [`Tally`] for each of `kinds`.
pub fn tally(set: &CaseSet, kinds: &[MatcherKind], record: &mut dyn FnMut(Matched)) -> Vec<Tally> {
    let truth_shares: Vec<f64> = set
        .cases
        .iter()
        .map(|case| truth_share(&Reference::new(case.reference.points()), case))
        .collect();
    kinds
        .iter()
        .map(|&kind| {
            let matcher = kind.build();
            let mut tally = Tally {
                set: set.name.clone(),
                matcher: kind,
                errors_m: Vec::with_capacity(set.cases.len()),
                errors_rad: Vec::with_capacity(set.cases.len()),
                seed_medians_m: Vec::with_capacity(1),
                micros: Vec::with_capacity(set.cases.len()),
                success: 0,
                flagged: 0,
                flagged_success: 0,
                disputed: 0,
                closures_m: Vec::with_capacity(set.triangles.len()),
                closures_rad: Vec::with_capacity(set.triangles.len()),
            };
            let mut answers = Vec::with_capacity(set.cases.len());
            for (pair, case) in set.cases.iter().enumerate() {
                let clock = Instant::now();
                let reference = Reference::new(case.reference.points());
                let result = matcher.align(&reference, &case.current.points(), case.guess);
                tally.micros.push(clock.elapsed().as_secs_f64() * 1e6);
                let (em, er) = off_truth(case, &result.pose);
                let ok = em <= set.tolerance_m && er <= set.tolerance_rad;
                tally.success += usize::from(ok);
                tally.flagged += usize::from(result.converged);
                tally.flagged_success += usize::from(ok && result.converged);
                tally.errors_m.push(em);
                tally.errors_rad.push(er);
                let truth_share = truth_shares[pair];
                let disputed = !ok
                    && result.converged
                    && result.quality.inlier_share >= DISPUTE_RATIO * truth_share;
                tally.disputed += usize::from(disputed);
                answers.push((result.pose, result.converged));
                record(Matched::Pair(Outcome {
                    seed: set.seed,
                    set: set.name.clone(),
                    pair,
                    matcher: kind,
                    error: (em, er),
                    guess_error: off_truth(case, &case.guess),
                    success: ok,
                    result,
                    truth_share,
                    disputed,
                    agreed: false,
                }));
            }
            for (k, triangle) in set.triangles.iter().enumerate() {
                let (Some(&first), Some(&second)) =
                    (answers.get(triangle.first), answers.get(triangle.second))
                else {
                    continue; // a triangle of pairs the set no longer holds
                };
                let skip = &triangle.skip;
                let reference = Reference::new(skip.reference.points());
                let result = matcher.align(&reference, &skip.current.points(), skip.guess);
                let (m, rad) = closure(&first.0, &second.0, &result.pose);
                tally.closures_m.push(m);
                tally.closures_rad.push(rad);
                record(Matched::Triangle(TriangleOutcome {
                    seed: set.seed,
                    set: set.name.clone(),
                    triangle: k,
                    matcher: kind,
                    closure: (m, rad),
                    trusted: first.1 && second.1 && result.converged,
                    skip: result.pose,
                }));
            }
            if !tally.errors_m.is_empty() {
                let median = quantile(&mut tally.errors_m.clone(), 0.5);
                tally.seed_medians_m.push(median);
            }
            tally
        })
        .collect()
}

/// How far `pose` lies from `case`'s truth: translation and rotation errors, metres and
/// radians.
fn off_truth(case: &Case, pose: &Pose2) -> (f64, f64) {
    let off = case.truth.relative(pose);
    (off.x.hypot(off.y), off.theta.abs())
}

/// The share of the current points within 5 cm of the reference scan's surfaces with the
/// current scan at the pair's true pose (the default [`TrustRule`]'s inliers); `reference` is
/// the pair's reference scan, prepared.
pub fn truth_share(reference: &Reference, case: &Case) -> f64 {
    TrustRule::default()
        .assess(reference, &case.current.points().xy, &case.truth)
        .inlier_share
}

/// The `q` quantile of `values` (nearest rank; 0 for none).
fn quantile(values: &mut [f64], q: f64) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    let rank = ((q * values.len() as f64).ceil() as usize).clamp(1, values.len());
    values[rank - 1]
}

/// The rows as a Markdown table, with each matcher's time as a ratio to the first matcher's in
/// the same set (the same run, so the ratio travels between machines).
pub fn table(rows: &[Row]) -> String {
    let mut out = String::from(
        "| pairs | matcher | success | median / p95 error | median time | × first | flagged | flag precision / recall | failures disputed | failures agreed | closure median / p95 |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let ratios = ratios_to_first(rows.iter().map(|r| (r.set.as_str(), r.median_us)));
    for (r, ratio) in rows.iter().zip(ratios) {
        out.push_str(&format!(
            "| {} ({}) | {} | {:.3} | {:.1} / {:.1} mm, {:.2} / {:.2}° | {:.2} ms | {:.2} | {:.3} | {:.3} / {:.3} | {} | {} | {} |\n",
            r.set,
            r.pairs,
            r.matcher,
            r.success,
            r.error_m[0] * 1e3,
            r.error_m[1] * 1e3,
            r.error_rad[0].to_degrees(),
            r.error_rad[1].to_degrees(),
            r.median_us / 1e3,
            ratio,
            r.flagged,
            r.flag_precision,
            r.flag_recall,
            r.disputed,
            r.agreed,
            closure_cell(r.closure),
        ));
    }
    out
}

/// With several seeds pooled: each row's lowest and highest median translation error of one
/// seed's pairs alone ([`Row::error_by_seed_m`]) as a Markdown table; `None` with one seed.
pub fn seed_table(rows: &[Row]) -> Option<String> {
    let mut out = String::from(
        "| pairs | matcher | median error of one seed's pairs: lowest – highest |\n|---|---|---|\n",
    );
    let mut any = false;
    for r in rows {
        if let Some([low, high]) = r.error_by_seed_m {
            any = true;
            out.push_str(&format!(
                "| {} | {} | {:.2} – {:.2} mm |\n",
                r.set,
                r.matcher,
                low * 1e3,
                high * 1e3
            ));
        }
    }
    any.then_some(out)
}

/// The beams of the synthetic rows' sparse scans: the LMS in its 1° mode, 181 over 180°, as
/// sparse as the 180 readings of the Edmonton log (and of the Intel lab's, which the issue's
/// campaign used), but with the twin's exact truth.
pub const SPARSE_BEAMS: u16 = 181;

/// The standard sets: synthetic at 0 % and 20 % outliers, with the robot's LMS at 0.5° and in
/// its 1° mode ([`SPARSE_BEAMS`]), each corrected log, and the large guess over the three
/// logs; `n` pairs each (a log gives at most its scans less one).
pub fn standard_sets(root: &Path, n: usize, seed: u64) -> Result<Vec<CaseSet>, CommandError> {
    if !root.join("worlds").is_dir() || !root.join("tests/data/corrected").is_dir() {
        return Err(CommandError::option(
            "--root",
            "must be the repository's folder, holding worlds/ and tests/data/corrected/ (run from there or give --root)",
            root.display(),
        ));
    }
    let load = |p: &str| WorldDescription::load(root.join(p));
    let lab_text = std::fs::read_to_string(root.join("worlds/lab.toml")).map_err(|source| {
        CommandError::Read {
            path: root.join("worlds/lab.toml"),
            source,
        }
    })?;
    let worlds = vec![
        load("worlds/lab.toml")?,
        load("worlds/orthogonal.toml")?,
        load("worlds/glass-door.toml")?,
        WorldDescription::parse(
            &crate::world::clutter::lab_with_boxes(&lab_text, 30),
            "lab with 30 boxes",
        )?,
    ];
    let robot = RobotDescription::load(root.join("scenarios/robots/pioneer-3dx.toml"))?;
    let (small, large) = (SMALL_GUESS, LARGE_GUESS);
    let logs = ["belgioioso", "freiburg-101", "edmonton"];
    let log = |name: &str| -> PathBuf {
        root.join(format!("tests/data/corrected/{name}-corrected.log.gz"))
    };
    // The same laser in its 1° mode: sparse scans, as the Edmonton log's, with exact truth.
    let mut sparse = robot.clone();
    sparse.laser.beams = SPARSE_BEAMS;
    let mut sets = vec![
        synthetic_set("synthetic, 0 %", &worlds, &robot, 0.0, n, small, seed)?,
        synthetic_set("synthetic, 20 %", &worlds, &robot, 0.2, n, small, seed)?,
        synthetic_set("synthetic 1°, 0 %", &worlds, &sparse, 0.0, n, small, seed)?,
        synthetic_set("synthetic 1°, 20 %", &worlds, &sparse, 0.2, n, small, seed)?,
    ];
    for name in logs {
        sets.push(log_set(
            &format!("real, {name}"),
            &log(name),
            n,
            small,
            seed,
        )?);
    }
    let mut pooled = CaseSet {
        name: "real, guess σ 20 cm / 10°".to_string(),
        seed,
        cases: Vec::new(),
        triangles: Vec::new(),
        tolerance_m: 0.10,
        tolerance_rad: 2f64.to_radians(),
    };
    for name in logs {
        let set = log_set(
            &format!("large/{name}"),
            &log(name),
            n.div_ceil(3),
            large,
            seed,
        )?;
        let offset = pooled.cases.len();
        pooled
            .triangles
            .extend(set.triangles.into_iter().map(|t| Triangle {
                first: t.first + offset,
                second: t.second + offset,
                ..t
            }));
        pooled.cases.extend(set.cases);
    }
    sets.push(pooled);
    Ok(sets)
}

/// The two rows of a corrected log given with `--log`: its consecutive pairs from guesses σ 5 cm
/// / 2° off (`real, NAME`) and σ 20 cm / 10° off (`real, NAME, guess σ 20 cm / 10°`), `n` pairs
/// each; NAME is the file's name without `.gz`, `.log` or `.clf` and `-corrected`.
pub fn extra_log_sets(path: &Path, n: usize, seed: u64) -> Result<[CaseSet; 2], CommandError> {
    let name = log_name(path);
    let small = log_set(&format!("real, {name}"), path, n, SMALL_GUESS, seed)?;
    if small.cases.is_empty() {
        return Err(CommandError::option(
            "--log",
            "must hold at least two scans with poses",
            path.display(),
        ));
    }
    let large = log_set(
        &format!("real, {name}, guess σ 20 cm / 10°"),
        path,
        n,
        LARGE_GUESS,
        seed,
    )?;
    Ok([small, large])
}

/// The four synthetic rows of a world given with `--world`, in it alone: the robot's LMS at
/// 0.5° and in its 1° mode ([`SPARSE_BEAMS`]), each at 0 % and 20 % outliers, from the same
/// guesses as the standard synthetic rows (`synthetic, NAME, 0 %` and so on; NAME is the file's
/// name without `.toml`). Geometry no constant was chosen on, to hold the matchers out on.
pub fn extra_world_sets(
    root: &Path,
    path: &Path,
    n: usize,
    seed: u64,
) -> Result<[CaseSet; 4], CommandError> {
    let world = [WorldDescription::load(path)?];
    let name = path
        .file_stem()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_default();
    let robot = RobotDescription::load(root.join("scenarios/robots/pioneer-3dx.toml"))?;
    let mut sparse = robot.clone();
    sparse.laser.beams = SPARSE_BEAMS;
    let set = |laser: &str, robot: &RobotDescription, rate: f64, percent: u32| {
        synthetic_set(
            &format!("synthetic{laser}, {name}, {percent} %"),
            &world,
            robot,
            rate,
            n,
            SMALL_GUESS,
            seed,
        )
    };
    Ok([
        set("", &robot, 0.0, 0)?,
        set("", &robot, 0.2, 20)?,
        set(" 1°", &sparse, 0.0, 0)?,
        set(" 1°", &sparse, 0.2, 20)?,
    ])
}

/// The row of a log without a reference given with `--raw-log` (`raw, NAME`): its first `n`
/// consecutive pairs and their triangles, each guess the log's own relative pose (its
/// odometry), as a map builder would start. Its `truth` is that guess too, so of its row only
/// the flag, the time and the closure mean something ([`raw_table`]); its seed is 0, as its
/// guesses draw nothing.
pub fn raw_log_set(path: &Path, n: usize) -> Result<CaseSet, CommandError> {
    let exact = GuessError {
        sigma_m: 0.0,
        sigma_rad: 0.0,
    };
    let set = log_set(&format!("raw, {}", log_name(path)), path, n, exact, 0)?;
    if set.triangles.is_empty() {
        return Err(CommandError::option(
            "--raw-log",
            "must hold at least three scans with poses",
            path.display(),
        ));
    }
    Ok(set)
}

/// A log's name in a row: its file's name without `.gz`, `.log` or `.clf` and `-corrected`.
fn log_name(path: &Path) -> String {
    let file = path
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_default();
    let stem = file.strip_suffix(".gz").unwrap_or(&file);
    let stem = [".log", ".clf"]
        .iter()
        .find_map(|ext| stem.strip_suffix(ext))
        .unwrap_or(stem);
    stem.strip_suffix("-corrected").unwrap_or(stem).to_string()
}

/// What a row of a log without a reference can say: how often the matcher trusted its answer,
/// how long it took, and how well its answers chain.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RawRow {
    /// The set's name.
    pub set: String,
    /// The matcher.
    pub matcher: MatcherKind,
    /// Pairs matched.
    pub pairs: usize,
    /// Share of pairs flagged `converged`.
    pub flagged: f64,
    /// Median time per pair (preparing the reference included), microseconds.
    pub median_us: f64,
    /// The closure over the log's triangles.
    pub closure: Option<Closure>,
}

impl From<&Row> for RawRow {
    fn from(row: &Row) -> Self {
        RawRow {
            set: row.set.clone(),
            matcher: row.matcher,
            pairs: row.pairs,
            flagged: row.flagged,
            median_us: row.median_us,
            closure: row.closure,
        }
    }
}

/// The rows of logs without a reference as a Markdown table: the flagged share, the time (with
/// its ratio to the first matcher's on the same pairs) and the closure.
pub fn raw_table(rows: &[RawRow]) -> String {
    let mut out = String::from(
        "| pairs without a reference | matcher | flagged | median time | × first | closure median / p95 |\n|---|---|---|---|---|---|\n",
    );
    let ratios = ratios_to_first(rows.iter().map(|r| (r.set.as_str(), r.median_us)));
    for (r, ratio) in rows.iter().zip(ratios) {
        out.push_str(&format!(
            "| {} ({}) | {} | {:.3} | {:.2} ms | {:.2} | {} |\n",
            r.set,
            r.pairs,
            r.matcher,
            r.flagged,
            r.median_us / 1e3,
            ratio,
            closure_cell(r.closure),
        ));
    }
    out
}

/// Each time as a ratio to the first time of its set (a set's rows come one after another).
fn ratios_to_first<'a>(times: impl Iterator<Item = (&'a str, f64)>) -> Vec<f64> {
    let (mut first, mut last) = (f64::NAN, "");
    times
        .map(|(set, us)| {
            if set != last {
                (first, last) = (us, set);
            }
            us / first
        })
        .collect()
}

/// A table's closure cell: median / p95 in millimetres and degrees, or a dash.
fn closure_cell(closure: Option<Closure>) -> String {
    closure.map_or("—".to_string(), |c| {
        format!(
            "{:.1} / {:.1} mm, {:.2} / {:.2}°",
            c.m[0] * 1e3,
            c.m[1] * 1e3,
            c.rad[0].to_degrees(),
            c.rad[1].to_degrees()
        )
    })
}

/// The guesses of the synthetic rows and of the logs' own rows: σ 5 cm and 2° off the truth.
const SMALL_GUESS: GuessError = GuessError {
    sigma_m: 0.05,
    sigma_rad: 2f64.to_radians(),
};

/// The guesses of the large-guess rows: σ 20 cm and 10° off the truth.
const LARGE_GUESS: GuessError = GuessError {
    sigma_m: 0.20,
    sigma_rad: 10f64.to_radians(),
};

/// Arguments of `twin matchers`.
#[derive(clap::Args, Debug)]
pub struct MatchersArgs {
    /// Pairs per row.
    #[arg(long, default_value_t = 300)]
    pub pairs: usize,
    /// Seed of the pairs and guesses.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// How many seeds, from `--seed` on: each row pools its pairs of every seed (the rows of
    /// `--raw-log`, whose guesses are the log's own, are matched once).
    #[arg(long, default_value_t = 1)]
    pub seeds: u64,
    /// Matchers to compare (comma-separated); all by default.
    #[arg(long, value_delimiter = ',')]
    pub matchers: Vec<MatcherKind>,
    /// The repository's folder, holding `worlds/`, `scenarios/robots/` and `tests/data/corrected/`.
    #[arg(long, default_value = ".")]
    pub root: PathBuf,
    /// Also two rows of this SLAM-corrected CARMEN log (repeatable), each line's stated pose
    /// the truth: its consecutive pairs from guesses σ 5 cm / 2° off and σ 20 cm / 10° off.
    /// The standard rows stay as they are.
    #[arg(long, value_name = "PATH")]
    pub log: Vec<PathBuf>,
    /// Also four synthetic rows in this world alone (a world file, repeatable; say
    /// `worlds/l-corridor.toml`): the LMS at 0.5° and 1°, each at 0 % and 20 % outliers, from
    /// the standard rows' guesses. The standard rows stay as they are.
    #[arg(long, value_name = "PATH")]
    pub world: Vec<PathBuf>,
    /// Also a row of this log without a reference (repeatable), such as a CARMEN log whose
    /// poses are raw odometry (`tests/data/mit-csail.clf`): its consecutive pairs from the
    /// odometry's guesses, in a table of its own with what needs no truth: the flagged share,
    /// the time and the closure over three scans in a row.
    #[arg(long, value_name = "PATH")]
    pub raw_log: Vec<PathBuf>,
    /// Write `matchers.json` (every row's figures), `pairs.csv` (every match: errors, flag,
    /// quality figures), `closures.csv` (every log triangle's closure) and, with `--raw-log`,
    /// `raw-logs.json` (those rows' figures) into this folder too.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Draw one pair into `--out` as `pair-SET-PAIR.svg`: the reference scan, and the current
    /// scan at the true pose and at each matcher's answer, and the pair as `twin match` reads it
    /// (`pair-SET-PAIR.jsonl`). `SET/PAIR`, where SET is part of a
    /// row's name (`freiburg-101/248`, `20 %/7`).
    #[arg(long, value_name = "SET/PAIR")]
    pub show: Option<String>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// Draws pair `pair` of the set whose name contains `name` (`--show NAME/PAIR`) into `dir`, and
/// writes it beside the picture as `twin match` reads it: the two files written.
fn show(
    sets: &[CaseSet],
    kinds: &[MatcherKind],
    spec: &str,
    dir: &Path,
) -> Result<[PathBuf; 2], CommandError> {
    let bad = |why: &'static str| CommandError::option("--show", why, spec);
    let (name, pair) = spec
        .rsplit_once('/')
        .ok_or_else(|| bad("must be SET/PAIR, e.g. freiburg-101/248"))?;
    let pair: usize = pair
        .trim()
        .parse()
        .map_err(|_| bad("must end in a pair number after the slash"))?;
    let set = sets
        .iter()
        .find(|s| !name.is_empty() && s.name.contains(name))
        .ok_or_else(|| bad("must begin with part of a row's name (freiburg-101, 20 %)"))?;
    let case = set.cases.get(pair).ok_or_else(|| {
        CommandError::option(
            "--show",
            "must name a pair the row has (numbered from 0)",
            format!("{spec}, of {} pairs", set.cases.len()),
        )
    })?;
    let reference = Reference::new(case.reference.points());
    let current = case.current.points();
    let mut placements = vec![Placement {
        label: "the pose given as truth".to_string(),
        pose: case.truth,
        share: truth_share(&reference, case),
    }];
    for &kind in kinds.iter().take(4) {
        // `align` judges every answer by the default rule: its quality is the share drawn.
        let result = kind.build().align(&reference, &current, case.guess);
        placements.push(Placement {
            label: format!("the answer of {kind}"),
            pose: result.pose,
            share: result.quality.inlier_share,
        });
    }
    let slug = set
        .name
        .split(|c: char| !c.is_ascii_alphanumeric())
        .filter(|part| !part.is_empty())
        .collect::<Vec<_>>()
        .join("-");
    let stem = dir.join(format!("pair-{slug}-{pair}"));
    let path = stem.with_extension("svg");
    let title = format!(
        "{}, pair {pair}: current scan placed in the reference laser frame",
        set.name
    );
    write_pair_svg(
        &path,
        &title,
        &reference.points.xy,
        &current.xy,
        &placements,
    )
    .map_err(|source| CommandError::Write {
        dir: dir.to_path_buf(),
        source,
    })?;
    // The pair as `twin match` reads it, to run it again through any matcher.
    let line = PairLine {
        reference: &case.reference,
        cur: &case.current,
        guess: [case.guess.x, case.guess.y, case.guess.theta],
    };
    let jsonl = stem.with_extension("jsonl");
    let text = serde_json::to_string(&line).map_err(|e| CommandError::Write {
        dir: dir.to_path_buf(),
        source: e.into(),
    })?;
    std::fs::write(&jsonl, text + "\n").map_err(|source| CommandError::Write {
        dir: dir.to_path_buf(),
        source,
    })?;
    Ok([path, jsonl])
}

/// `twin matchers`: the table on standard output.
pub fn main(args: MatchersArgs) -> Result<(), CommandError> {
    if args.pairs == 0 || args.pairs > 100_000 {
        return Err(CommandError::option(
            "--pairs",
            "must be between 1 and 100000",
            args.pairs,
        ));
    }
    let kinds = if args.matchers.is_empty() {
        MatcherKind::ALL.to_vec()
    } else {
        args.matchers.clone()
    };
    let seeds = match args.seed.checked_add(args.seeds) {
        Some(end) if (1..=1000).contains(&args.seeds) => args.seed..end,
        _ => {
            return Err(CommandError::option(
                "--seeds",
                "must be between 1 and 1000, and --seed + --seeds within 2^64",
                args.seeds,
            ));
        }
    };
    let seed_sets = |seed: u64| -> Result<Vec<CaseSet>, CommandError> {
        let mut sets = standard_sets(&args.root, args.pairs, seed)?;
        for path in &args.log {
            sets.extend(extra_log_sets(path, args.pairs, seed)?);
        }
        for path in &args.world {
            sets.extend(extra_world_sets(&args.root, path, args.pairs, seed)?);
        }
        Ok(sets)
    };
    let sets = seed_sets(args.seed)?;
    let raw_sets = args
        .raw_log
        .iter()
        .map(|path| raw_log_set(path, args.pairs))
        .collect::<Result<Vec<_>, _>>()?;
    if let Some(spec) = &args.show {
        let dir = args.out.as_ref().ok_or_else(|| {
            CommandError::option("--show", "needs --out DIR to write the picture in", spec)
        })?;
        std::fs::create_dir_all(dir).map_err(|source| CommandError::Write {
            dir: dir.clone(),
            source,
        })?;
        for path in show(&sets, &kinds, spec, dir)? {
            say!("{}", path.display());
        }
        return Ok(());
    }
    // Every seed's sets hold as many pairs as the first's.
    let count = |sets: &[CaseSet]| -> usize {
        sets.iter()
            .map(|s| (s.cases.len() + s.triangles.len()) * kinds.len())
            .sum()
    };
    let total = count(&sets) * args.seeds as usize + count(&raw_sets);
    let bar = super::bar(
        args.quiet,
        total as u64,
        "{spinner} matching [{bar:30}] {pos}/{len} pairs {rate} {eta}",
    );
    let (mut outcomes, mut triangles) = (Vec::with_capacity(total), Vec::new());
    let mut record = |matched| {
        bar.inc(1);
        match matched {
            Matched::Pair(outcome) => outcomes.push(outcome),
            Matched::Triangle(outcome) => triangles.push(outcome),
        }
    };
    let mut pooled: Vec<Tally> = Vec::new();
    let mut next = Some(sets);
    for seed in seeds {
        let sets = match next.take() {
            Some(sets) => sets,
            None => seed_sets(seed)?,
        };
        let tallies = sets.iter().flat_map(|set| tally(set, &kinds, &mut record));
        if pooled.is_empty() {
            pooled = tallies.collect();
        } else {
            for (pool, tally) in pooled.iter_mut().zip(tallies) {
                pool.add(tally);
            }
        }
    }
    let mut rows: Vec<Row> = pooled.into_iter().map(Tally::row).collect();
    let raw_rows: Vec<RawRow> = raw_sets
        .iter()
        .flat_map(|set| {
            evaluate(set, &kinds, &mut |matched| {
                bar.inc(1);
                if let Matched::Triangle(outcome) = matched {
                    triangles.push(outcome);
                }
            })
        })
        .map(|row| RawRow::from(&row))
        .collect();
    bar.finish_and_clear();
    mark_agreed(&mut outcomes, &mut rows);
    let lines: Vec<String> = std::iter::once(OUTCOMES_HEADER.to_string())
        .chain(outcomes.iter().map(Outcome::csv))
        .collect();
    say!("{}", table(&rows));
    if let Some(seeds) = seed_table(&rows) {
        say!("{seeds}");
    }
    if !raw_rows.is_empty() {
        say!("{}", raw_table(&raw_rows));
    }
    if let Some(dir) = &args.out {
        let write = |source| CommandError::Write {
            dir: dir.clone(),
            source,
        };
        std::fs::create_dir_all(dir).map_err(write)?;
        let json = serde_json::to_string_pretty(&rows).expect("rows serialise");
        robot::logs::write_file(dir.join("matchers.json"), json + "\n").map_err(write)?;
        if !raw_rows.is_empty() {
            let json = serde_json::to_string_pretty(&raw_rows).expect("rows serialise");
            robot::logs::write_file(dir.join("raw-logs.json"), json + "\n").map_err(write)?;
        }
        robot::logs::write_file(dir.join("pairs.csv"), lines.join("\n") + "\n").map_err(write)?;
        let closures: Vec<String> = std::iter::once(CLOSURES_HEADER.to_string())
            .chain(triangles.iter().map(TriangleOutcome::csv))
            .collect();
        robot::logs::write_file(dir.join("closures.csv"), closures.join("\n") + "\n")
            .map_err(write)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A failure of `matcher` on `pair` answering `pose`, fitting `share` of the current points
    /// where the reference pose fits 0.3.
    fn failure(pair: usize, matcher: MatcherKind, pose: Pose2, share: f64) -> Outcome {
        let mut result = MatchResult::unmatched(pose);
        result.quality.inlier_share = share;
        Outcome {
            seed: 1,
            set: "real".into(),
            pair,
            matcher,
            error: (0.12, 0.0),
            guess_error: (0.05, 0.01),
            success: false,
            result,
            truth_share: 0.3,
            disputed: false,
            agreed: false,
        }
    }

    fn row(matcher: MatcherKind) -> Row {
        Row {
            set: "real".into(),
            matcher,
            pairs: 3,
            success: 0.0,
            error_m: [0.0; 2],
            error_rad: [0.0; 2],
            error_by_seed_m: None,
            median_us: 1.0,
            flagged: 0.0,
            flag_precision: 1.0,
            flag_recall: 1.0,
            disputed: 0,
            agreed: 0,
            closure: None,
        }
    }

    /// The closure is how far the skip pair's answer lies from the two pairs' answers chained:
    /// none when they chain, and a skip answer moved by 3 cm sideways and 0.5° shows as that.
    #[test]
    fn the_closure_measures_how_far_the_answers_fail_to_chain() {
        let (first, second) = (
            Pose2::new(0.5, 0.1, 10f64.to_radians()),
            Pose2::new(0.4, -0.2, -25f64.to_radians()),
        );
        let chained = first.compose(&second);
        let (m, rad) = closure(&first, &second, &chained);
        assert!(m < 1e-12 && rad < 1e-12, "{m} {rad}");
        let off = chained.compose(&Pose2::new(0.0, 0.03, 0.5f64.to_radians()));
        let (m, rad) = closure(&first, &second, &off);
        assert!((m - 0.03).abs() < 1e-12, "{m}");
        assert!((rad - 0.5f64.to_radians()).abs() < 1e-12, "{rad}");
    }

    /// A failure is agreed when another matcher's answer to the same pair lies within 3 cm and
    /// 0.5° and both fit 5 points in 100 more than the reference pose; not when the answers lie
    /// apart, when either fits too little, when the other is another pair's, or for a success.
    #[test]
    fn agreement_needs_a_near_answer_that_fits_better() {
        let (ll, pl, mb) = (
            MatcherKind::LorentzLines,
            MatcherKind::PointToLine,
            MatcherKind::Mbicp,
        );
        let at = |x: f64, theta_deg: f64| Pose2::new(x, 0.0, theta_deg.to_radians());
        let mut outcomes = vec![
            // Pair 0: the first two agree (2.9 cm, 0.4° apart); the third is 4 cm from the
            // second and 7 cm from the first.
            failure(0, ll, at(0.100, 0.0), 0.50),
            failure(0, pl, at(0.129, 0.4), 0.40),
            failure(0, mb, at(0.170, 0.0), 0.60),
            // Pair 1: together, but one fits only 4 points in 100 more than the reference pose.
            failure(1, ll, at(0.1, 0.0), 0.50),
            failure(1, pl, at(0.1, 0.0), 0.34),
            // Pair 2: together on the pose, but one is a success.
            failure(2, ll, at(0.1, 0.0), 0.50),
            Outcome {
                success: true,
                ..failure(2, pl, at(0.1, 0.0), 0.50)
            },
        ];
        let mut rows = vec![row(ll), row(pl), row(mb)];
        mark_agreed(&mut outcomes, &mut rows);
        let agreed: Vec<bool> = outcomes.iter().map(|o| o.agreed).collect();
        assert_eq!(agreed, vec![true, true, false, false, false, true, false]);
        assert_eq!(
            rows.iter().map(|r| r.agreed).collect::<Vec<_>>(),
            vec![2, 1, 0]
        );
        // Its line in `pairs.csv` says so, with the answer.
        let line = outcomes[0].csv();
        assert!(
            line.ends_with(",1,0.10000,0.00000,0.0000,0.0000,0"),
            "{line}"
        );
        assert!(line.starts_with("1,\"real\",0,"), "{line}");
        assert_eq!(line.split(',').count(), OUTCOMES_HEADER.split(',').count());
    }
}
