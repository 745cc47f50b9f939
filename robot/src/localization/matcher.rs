//! The one interface every scan matcher implements, and the pieces they share.

use super::kdtree::KdTree;
use super::quality::{GuessAlongFree, MatchQuality, Surface, TrustRule, surfaces, unresolved};
use super::scan::{RangeScan, SPARSE_BEAM_STEP_RAD, ScanPoints, beam_step_below};
use crate::geometry::Pose2;
use std::fmt;
use std::str::FromStr;

/// The farthest a point or a guess may lie from its frame's origin, metres (100 km): beyond it
/// a reading is not one (no laser reaches that far) and a guess is not a guess. Squares and sums
/// of such numbers stay far from overflow.
pub const MAX_COORDINATE_M: f64 = 1e5;

/// Whether `p` is finite and within [`MAX_COORDINATE_M`] of the origin on each axis.
pub fn plausible(p: [f64; 2]) -> bool {
    p[0].abs() <= MAX_COORDINATE_M && p[1].abs() <= MAX_COORDINATE_M
}

/// What a match found.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct MatchResult {
    /// The pose of the current scan's frame in the reference scan's frame.
    pub pose: Pose2,
    /// Correspondence searches made (each followed by a minimisation).
    pub iterations: u32,
    /// Whether the answer can be trusted: its [`quality`](Self::quality) passes the
    /// [`TrustRule`] (a good fit, enough of the scan on the reference's surface, every direction
    /// pinned down). Set by [`ScanMatcher::align`] for every matcher alike.
    pub converged: bool,
    /// Whether the matcher's own iterations stopped on a tiny step before their cap (which
    /// says nothing about being right: a wrong minimum settles too).
    pub settled: bool,
    /// Correspondences used by the last minimisation.
    pub correspondences: usize,
    /// How well the answer fits, the figures [`converged`](Self::converged) is decided by.
    pub quality: MatchQuality,
}

impl MatchResult {
    /// The answer when there is nothing to match: the guess, not converged.
    pub fn unmatched(guess: Pose2) -> Self {
        MatchResult {
            pose: guess,
            iterations: 0,
            converged: false,
            settled: false,
            correspondences: 0,
            quality: MatchQuality::NONE,
        }
    }
}

/// A reference scan prepared for matching: its points and a k-d tree over them.
#[derive(Clone, Debug, Default)]
pub struct Reference {
    /// The points, in beam order.
    pub points: ScanPoints,
    /// A k-d tree over `points.xy`.
    pub tree: KdTree,
    /// The surface at each point, for point-to-line residuals.
    surfaces: Vec<Option<Surface>>,
    /// Which points have no surface because the beams lie too far apart there.
    unresolved: Vec<bool>,
    /// Whether its beams lie 0.75° apart or more ([`SPARSE_BEAM_STEP_RAD`]).
    sparse: bool,
}

impl Reference {
    /// Prepares `points` as a reference.
    pub fn new(points: ScanPoints) -> Self {
        let tree = KdTree::new(&points.xy);
        let surfaces = surfaces(&points.xy);
        let unresolved = unresolved(&points.xy, &points.beam, &surfaces);
        let sparse = beam_step_below(&points, SPARSE_BEAM_STEP_RAD) == Some(false);
        Reference {
            sparse,
            points,
            tree,
            surfaces,
            unresolved,
        }
    }

    /// Whether point `j` has no surface because the reference's beams lie farther apart there
    /// than a surface may span (far readings of a sparse scan): the trust rule does not judge
    /// a current point by it.
    pub fn unresolved(&self, j: usize) -> bool {
        self.unresolved.get(j).copied().unwrap_or(false)
    }

    /// Whether the reference's beams lie 0.75° apart or more (a SICK in its 1° mode,
    /// [`SPARSE_BEAM_STEP_RAD`]): its surfaces are sampled
    /// coarsely, and the trust rule asks a smaller share of inliers.
    pub fn is_sparse(&self) -> bool {
        self.sparse
    }

    /// The reference's surface at point `j`, if its neighbours give it a direction.
    pub(super) fn surface(&self, j: usize) -> Option<&Surface> {
        self.surfaces.get(j)?.as_ref()
    }

    /// Whether point `j` is the first or last point of the scan: the edge of what the reference
    /// saw. A current point whose nearest reference point is an edge usually lies beyond it,
    /// where the reference did not look — after a 0.5 m retreat down a corridor, half the
    /// current scan.
    pub fn is_edge(&self, j: usize) -> bool {
        j == 0 || j + 1 == self.points.len()
    }
}

/// A scan matcher: given a reference scan, a current scan and an initial guess, the rigid
/// transform of the current scan's frame in the reference frame.
///
/// Implementations are plain data (their parameters) and may be shared between threads.
pub trait ScanMatcher: Send + Sync + fmt::Debug {
    /// The short name (`ls`, `lorentz`, `lorentz-lines`, `mbicp`, `pl-icp`).
    fn name(&self) -> &'static str;

    /// Aligns `current` (points in its own laser frame) to a prepared `reference`, starting
    /// from `guess` (the pose of the current frame in the reference frame).
    ///
    /// Any input is answered: an empty scan, or a guess or a point that is not finite or lies
    /// farther than [`MAX_COORDINATE_M`], gives the guess back, not converged, without calling
    /// [`align_plausible`](Self::align_plausible). Every answer's quality is then judged by the
    /// default [`TrustRule`], which sets [`MatchResult::converged`].
    fn align(&self, reference: &Reference, current: &ScanPoints, guess: Pose2) -> MatchResult {
        let pose_ok = plausible([guess.x, guess.y]) && guess.theta.abs() <= MAX_COORDINATE_M;
        let filled = !reference.points.is_empty() && !current.is_empty();
        if !(pose_ok && filled && reference.points.is_plausible() && current.is_plausible()) {
            return MatchResult::unmatched(guess);
        }
        let mut result = self.align_plausible(reference, current, guess);
        let rule = TrustRule::default();
        // A matcher that judged its own answer by this rule (to decide whether to start again)
        // hands its quality back; any other answer is judged here.
        if result.quality == MatchQuality::NONE {
            result.quality = rule.assess(reference, &current.xy, &result.pose);
        }
        result.converged = rule.confirms(reference, &current.xy, &result.pose, &mut result.quality);
        // Refused only along its free direction: the scans place the answer across it and in
        // heading, the guess (as far as the scans allow) along it.
        if let Some(along) = self.guess_along_free()
            && rule.trusts_across(&result.quality)
        {
            let pose = along.place(
                reference,
                &current.xy,
                &result.pose,
                &result.quality,
                &guess,
            );
            if pose != result.pose {
                result.pose = pose;
                result.quality = MatchQuality {
                    held: false,
                    ..rule.assess(reference, &current.xy, &pose)
                };
            }
        }
        result
    }

    /// Whether an answer the trust rule refuses only along its free direction
    /// ([`TrustRule::trusts_across`]) is moved along it toward the guess ([`GuessAlongFree`]),
    /// by [`align`](Self::align), and judged again there; it stays untrusted. None by default.
    fn guess_along_free(&self) -> Option<GuessAlongFree> {
        None
    }

    /// [`align`](Self::align) for inputs known to be non-empty, finite and within
    /// [`MAX_COORDINATE_M`]: what each matcher implements.
    fn align_plausible(
        &self,
        reference: &Reference,
        current: &ScanPoints,
        guess: Pose2,
    ) -> MatchResult;

    /// Aligns two range scans: only beams that returned enter the match.
    fn match_scans(&self, reference: &RangeScan, current: &RangeScan, guess: Pose2) -> MatchResult {
        self.align(
            &Reference::new(reference.points()),
            &current.points(),
            guess,
        )
    }
}

/// When an iterative matcher stops.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Convergence {
    /// A step shorter than this (metres) …
    pub translation_m: f64,
    /// … and turning less than this (radians) ends the iterations.
    pub rotation_rad: f64,
    /// Correspondence searches allowed.
    pub max_iterations: u32,
}

impl Convergence {
    /// Whether a step is small enough to stop.
    pub fn reached(&self, step: &Pose2) -> bool {
        step.x.hypot(step.y) < self.translation_m && step.theta.abs() < self.rotation_rad
    }
}

/// The matchers by name.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum MatcherKind {
    /// Point-to-point least-squares ICP.
    #[serde(rename = "ls")]
    LeastSquares,
    /// The Lorentzian estimator minimised by Newton–Levenberg–Marquardt (thesis §3.4).
    #[serde(rename = "lorentz")]
    Lorentz,
    /// The Lorentzian with line-assisted association (thesis §3.4.3, App. E.3).
    #[serde(rename = "lorentz-lines")]
    LorentzLines,
    /// Metric-based ICP (Minguez et al.; 002 §2.2).
    #[serde(rename = "mbicp")]
    Mbicp,
    /// Point-to-line ICP with the defaults of Censi's CSM: the reference (Censi 2008).
    #[serde(rename = "pl-icp")]
    PointToLine,
}

impl MatcherKind {
    /// Every matcher, in the order of the issue.
    pub const ALL: [MatcherKind; 5] = [
        MatcherKind::LeastSquares,
        MatcherKind::Lorentz,
        MatcherKind::LorentzLines,
        MatcherKind::Mbicp,
        MatcherKind::PointToLine,
    ];

    /// The short name.
    pub fn name(self) -> &'static str {
        match self {
            MatcherKind::LeastSquares => "ls",
            MatcherKind::Lorentz => "lorentz",
            MatcherKind::LorentzLines => "lorentz-lines",
            MatcherKind::Mbicp => "mbicp",
            MatcherKind::PointToLine => "pl-icp",
        }
    }

    /// The matcher with its default parameters.
    pub fn build(self) -> Box<dyn ScanMatcher> {
        match self {
            MatcherKind::LeastSquares => Box::new(super::LeastSquares::default()),
            MatcherKind::Lorentz => Box::new(super::Lorentz::default()),
            MatcherKind::LorentzLines => Box::new(super::Lorentz::with_lines()),
            MatcherKind::Mbicp => Box::new(super::Mbicp::default()),
            MatcherKind::PointToLine => Box::new(super::PointToLine::default()),
        }
    }
}

impl fmt::Display for MatcherKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A matcher name that is not one of the five.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown matcher `{0}`: expected one of ls, lorentz, lorentz-lines, mbicp, pl-icp")]
pub struct UnknownMatcher(pub String);

impl FromStr for MatcherKind {
    type Err = UnknownMatcher;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        MatcherKind::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| UnknownMatcher(s.to_string()))
    }
}

/// Solves the 3×3 system `a · x = b` by Gaussian elimination with partial pivoting; `None` when
/// it is singular (or not finite).
pub(crate) fn solve3(mut a: [[f64; 3]; 3], mut b: [f64; 3]) -> Option<[f64; 3]> {
    let scale = a
        .iter()
        .flatten()
        .fold(0.0f64, |m, v| m.max(v.abs()))
        .max(f64::MIN_POSITIVE);
    for col in 0..3 {
        let pivot = (col..3).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col].abs().is_nan() || a[pivot][col].abs() <= 1e-13 * scale {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        for row in col + 1..3 {
            let f = a[row][col] / a[col][col];
            let pivot_row = a[col];
            for (v, p) in a[row].iter_mut().zip(pivot_row).skip(col) {
                *v -= f * p;
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = [0.0; 3];
    for row in (0..3).rev() {
        let tail: f64 = (row + 1..3).map(|k| a[row][k] * x[k]).sum();
        x[row] = (b[row] - tail) / a[row][row];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Applies a pose to every point: `out[i] = pose ⊕ points[i]`.
pub(crate) fn transform_all(pose: &Pose2, points: &[[f64; 2]], out: &mut Vec<[f64; 2]>) {
    let (s, c) = pose.theta.sin_cos();
    out.clear();
    out.extend(
        points
            .iter()
            .map(|p| [pose.x + c * p[0] - s * p[1], pose.y + s * p[0] + c * p[1]]),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solve3_solves_and_refuses_singular() {
        let a = [[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]];
        let x = [1.0, -2.0, 0.5];
        let b = [0, 1, 2].map(|r| (0..3).map(|k| a[r][k] * x[k]).sum::<f64>());
        let got = solve3(a, b).unwrap();
        for k in 0..3 {
            assert!((got[k] - x[k]).abs() < 1e-12);
        }
        assert!(
            solve3(
                [[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [0.0, 0.0, 1.0]],
                [1.0; 3]
            )
            .is_none()
        );
    }

    #[test]
    fn names_round_trip() {
        for kind in MatcherKind::ALL {
            assert_eq!(kind.name().parse::<MatcherKind>(), Ok(kind));
            assert_eq!(kind.build().name(), kind.name());
        }
        let err = "icp".parse::<MatcherKind>().unwrap_err();
        assert!(err.to_string().contains("lorentz-lines"), "{err}");
    }
}
