//! Localisation by scan matching, and 2D maps — the same code on the twin and the real robot.
//!
//! The problem (thesis §3.3): given a reference scan `l_j`, a current scan `l_{j+1}` and a guess
//! from odometry, find the rigid transform `Φ = (θ, tx, ty)` of the current scan's frame in the
//! reference's frame. Five matchers implement [`ScanMatcher`]:
//!
//! | name | what | source |
//! |---|---|---|
//! | `ls` | [`LeastSquares`] point-to-point ICP, the baseline | thesis §5.2 |
//! | `lorentz` | [`Lorentz`]: Lorentzian error, Newton–Levenberg–Marquardt, σ 2 → 5 → 0.5 cm | thesis §3.4, App. F |
//! | `lorentz-lines` | the same with line-assisted association; on dense scans point-to-line residuals where the lines spread, σ narrowing from 5 cm and pairs crowded onto one reference point left out, one NLM step a search in the first match, a point-to-line polish, a wide second σ schedule, restarts and a coarse correlative search when an answer is not trusted, cut short when the first restarts come back to an answer whose only fault is too little overlap (not in the thesis) | thesis §3.4.3, App. E.3 |
//! | `mbicp` | [`Mbicp`]: metric-based ICP | 002 §2.2 |
//! | `pl-icp` | [`PointToLine`]: point-to-line ICP with CSM's defaults, the reference | Censi 2008 |
//!
//! Correspondences come from a [`KdTree`] over the reference's points. [`MapBuilder`] chains
//! matches into a trajectory and a point map (§3.5), with odometry queued and interpolated to
//! each scan's stamp (002 §7.3.3). Everything is in metres and radians, in REP-103 axes.

pub mod correlative;
mod grid;
mod icp;
mod kdtree;
mod level;
pub mod lines;
mod lorentz;
mod map;
mod matcher;
mod mbicp;
mod plicp;
mod quality;
mod scan;

pub use grid::{Cell, GridBuilder, GridConfig, OccupancyGrid};
pub use icp::LeastSquares;
pub use kdtree::{KdTree, LastNearest};
pub use level::{LEVEL_TOLERANCE_RAD, LevelLocaliser};
pub use lorentz::{
    BOTH_WAYS, CLEAN_PASS_ENOUGH, COARSE, COARSE_FIRST_BELOW, CROWD_RATIO, DENSE_SIGMAS,
    EARLY_CONVERGENCE, FAR_SLIDE_M, FAR_SLIDE_SPREAD, FIRST_MATCH_CONVERGENCE,
    FIRST_PASS_CONVERGENCE, FIRST_PASS_ENOUGH, FIRST_PASS_SURFACE_POINTS, FIRST_PASS_THINNING,
    FIRST_SPREAD, FIRST_SPREAD_MARGIN, FIRST_STEPS, GUESS_ALONG_FREE, LINE_RESIDUALS_SPREAD,
    LONELY_PASS_ENOUGH, LonelyEnough, Lorentz, MERGE_REACH, POLISH_MORE, QuickFinish,
    RESTART_SHORTFALL, RESTARTS_AGREE, RestartsAgree, SLIDE_CHECK, SPARSE_EARLY_CONVERGENCE,
    SPARSE_FINISH, SPARSE_LINE_RESIDUALS_SPREAD, SPARSE_QUICK, SPARSE_SIGMAS, SPARSE_START,
    SlideCheck, StartRounds, THESIS_SIGMAS, Thinning, WIDE_SIGMAS,
};
pub use map::{MapBuilder, MapConfig, MatchStats, Placed};
pub use matcher::{
    Convergence, MAX_COORDINATE_M, MatchResult, MatcherKind, Reference, ScanMatcher,
    UnknownMatcher, plausible,
};
pub use mbicp::Mbicp;
pub use plicp::{GiveUp, PointToLine};
pub use quality::{GuessAlongFree, MatchQuality, TrustRule, polish};
pub use scan::{
    RangeScan, SPARSE_BEAM_STEP_RAD, ScanPoints, beam_step, beam_step_below, fan_within_a_turn,
};
