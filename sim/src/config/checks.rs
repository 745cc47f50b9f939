//! Scenario checks as a scenario file writes them: `[[check]]` tables naming what a run must
//! show and the bounds it must stay within. [`crate::commands::check`] evaluates them on a run.

use super::error::{ConfigError, Source};
use core::fmt;
use serde::Deserialize;
use toml::Spanned;

/// What a check measures.
#[derive(Clone, Debug, PartialEq)]
pub enum CheckKind {
    /// Position (m) and heading (°) error of the scan-matching estimate at the last scan.
    FinalEstimateError,
    /// RMS position (m) and heading (°) error of the estimate over all scans.
    RmsEstimateError,
    /// Distance (m) and heading difference (°) between the final odometry and the truth: a lower
    /// bound proves slip is on, an upper bound that the odometry is sane.
    OdometryDrift,
    /// Contacts with walls.
    Collisions,
    /// Scans kept.
    Scans,
    /// Share of returned laser readings farther than 15 cm from every surface (outliers, mirror
    /// images).
    OutlierShare,
    /// Share of laser readings with no return (black surfaces at an angle, glass, open space
    /// beyond range).
    NoReturnShare,
    /// Share of the estimate's map points within 5 cm of a true surface.
    MapQuality,
    /// Scan matches the localisation relied on that lie more than 5 cm or 1° from the true
    /// motion between their scans: trusted ones (a `converged` flag that lied), and those it
    /// relied on across a corridor only, judged across it and in heading.
    WrongTrustedMatches,
    /// Largest error (m) of the listed sonar transducers' last echoes against the true distance
    /// along their axes.
    SonarError {
        /// Transducer numbers.
        transducers: Vec<u8>,
    },
    /// Length of the true path, metres.
    DistanceTravelled,
    /// Median distance (m) of the 3D model's vertices to the nearest true surface.
    PointError(ModelPlacement),
    /// 95th percentile of that distance, metres.
    PointErrorP95(ModelPlacement),
    /// Mesh area farther than 5 cm from every true surface, square metres.
    PhantomArea(ModelPlacement),
    /// Share of the true wall, box and table area within 5 cm of a vertex.
    Coverage(ModelPlacement),
    /// Share of the triangles the scenes' grids offer that the validity rule keeps.
    ValidShare,
    /// Median distance (m) between the meshes of two stations where they overlap.
    SeamError(ModelPlacement),
    /// The largest true distance (m) between the robot and a `goto` step's goal when the step
    /// ended (whether the controller said it had reached it or stopped short).
    GoalError,
    /// `goto` and `explore` steps that stopped short (blocked, no way, lost, out of decisions).
    NavigationFailures,
    /// The smallest clearance (m) between the robot's footprint and the world's walls and boxes
    /// along the true path.
    MinClearance,
    /// Simulated seconds the run took.
    Duration,
}

/// Which of a run's 3D models a check measures.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub enum ModelPlacement {
    /// The main model: placed by the estimate if the run localised, else by odometry.
    #[default]
    Main,
    /// Placed by the 2D localisation's estimate.
    Estimate,
    /// Placed by odometry.
    Odometry,
    /// Placed by the twin's truth.
    Truth,
}

impl CheckKind {
    /// The names accepted in `kind = "…"`.
    pub const NAMES: [&'static str; 21] = [
        "final_estimate_error",
        "rms_estimate_error",
        "odometry_drift",
        "collisions",
        "scans",
        "outlier_share",
        "no_return_share",
        "map_quality",
        "wrong_trusted_matches",
        "sonar_error",
        "distance_travelled",
        "point_error",
        "point_error_p95",
        "phantom_area",
        "coverage",
        "valid_share",
        "seam_error",
        "goal_error",
        "navigation_failures",
        "min_clearance",
        "duration",
    ];

    /// The name used in files and reports.
    pub fn name(&self) -> &'static str {
        match self {
            CheckKind::FinalEstimateError => "final_estimate_error",
            CheckKind::RmsEstimateError => "rms_estimate_error",
            CheckKind::OdometryDrift => "odometry_drift",
            CheckKind::Collisions => "collisions",
            CheckKind::Scans => "scans",
            CheckKind::OutlierShare => "outlier_share",
            CheckKind::NoReturnShare => "no_return_share",
            CheckKind::MapQuality => "map_quality",
            CheckKind::WrongTrustedMatches => "wrong_trusted_matches",
            CheckKind::SonarError { .. } => "sonar_error",
            CheckKind::DistanceTravelled => "distance_travelled",
            CheckKind::PointError(_) => "point_error",
            CheckKind::PointErrorP95(_) => "point_error_p95",
            CheckKind::PhantomArea(_) => "phantom_area",
            CheckKind::Coverage(_) => "coverage",
            CheckKind::ValidShare => "valid_share",
            CheckKind::SeamError(_) => "seam_error",
            CheckKind::GoalError => "goal_error",
            CheckKind::NavigationFailures => "navigation_failures",
            CheckKind::MinClearance => "min_clearance",
            CheckKind::Duration => "duration",
        }
    }

    /// The 3D model the check measures, if it measures one.
    pub fn model(&self) -> Option<ModelPlacement> {
        match *self {
            CheckKind::PointError(p)
            | CheckKind::PointErrorP95(p)
            | CheckKind::PhantomArea(p)
            | CheckKind::Coverage(p)
            | CheckKind::SeamError(p) => Some(p),
            CheckKind::ValidShare => Some(ModelPlacement::Main),
            _ => None,
        }
    }

    /// The unit of the main quantity.
    pub(crate) fn unit(&self) -> &'static str {
        match self {
            CheckKind::FinalEstimateError
            | CheckKind::RmsEstimateError
            | CheckKind::OdometryDrift
            | CheckKind::SonarError { .. }
            | CheckKind::DistanceTravelled
            | CheckKind::PointError(_)
            | CheckKind::PointErrorP95(_)
            | CheckKind::SeamError(_)
            | CheckKind::GoalError
            | CheckKind::MinClearance => " m",
            CheckKind::PhantomArea(_) => " m²",
            CheckKind::Duration => " s",
            CheckKind::Collisions
            | CheckKind::Scans
            | CheckKind::NavigationFailures
            | CheckKind::WrongTrustedMatches => "",
            CheckKind::OutlierShare
            | CheckKind::NoReturnShare
            | CheckKind::MapQuality
            | CheckKind::Coverage(_)
            | CheckKind::ValidShare => "",
        }
    }
}

/// A bound on a quantity: at least `min`, at most `max`.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct Bounds {
    /// Lower bound.
    pub min: Option<f64>,
    /// Upper bound.
    pub max: Option<f64>,
}

impl Bounds {
    pub(crate) fn holds(&self, value: f64) -> bool {
        self.min.is_none_or(|m| value >= m) && self.max.is_none_or(|m| value <= m)
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.min.is_none() && self.max.is_none()
    }
}

impl fmt::Display for Bounds {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.min, self.max) {
            (Some(a), Some(b)) => write!(f, "in [{a}, {b}]"),
            (Some(a), None) => write!(f, ">= {a}"),
            (None, Some(b)) => write!(f, "<= {b}"),
            (None, None) => write!(f, "(no bound)"),
        }
    }
}

/// One check of a scenario.
#[derive(Clone, Debug, PartialEq)]
pub struct Check {
    /// What it measures.
    pub kind: CheckKind,
    /// Bounds on the main quantity (metres, a count or a share).
    pub bounds: Bounds,
    /// Bounds on the heading part, degrees (estimate errors, odometry drift).
    pub degrees: Bounds,
    /// Why the check is there, shown in reports.
    pub note: String,
}

/// Validates the `[[check]]` tables: a known kind, and the bounds that kind takes.
/// `navigation` says whether the script has `goto` steps and whether it has any navigating
/// step (`goto` or `explore`).
pub(super) fn parse_checks(
    files: &[Spanned<CheckFile>],
    source: &Source,
    localises: bool,
    fires_sonar: bool,
    takes_scenes: bool,
    navigation: (bool, bool),
) -> Result<Vec<Check>, ConfigError> {
    let mut checks = Vec::new();
    for (i, spanned) in files.iter().enumerate() {
        let f = spanned.get_ref();
        let field = |name: &str| Some(format!("check[{i}].{name}"));
        // At the key's own line when the table writes it, else at the table.
        let error = |name: &str, message: String| {
            let span = source
                .key_in(spanned.span(), name)
                .unwrap_or_else(|| spanned.span());
            source.error(span, field(name), message)
        };
        let placement = match f.placement.as_deref() {
            None => ModelPlacement::Main,
            Some("estimate") => ModelPlacement::Estimate,
            Some("odometry") => ModelPlacement::Odometry,
            Some("truth") => ModelPlacement::Truth,
            Some(other) => {
                return Err(error(
                    "placement",
                    format!(
                        "unknown placement {other:?}: expected \"estimate\", \"odometry\" or \"truth\""
                    ),
                ));
            }
        };
        let kind = match f.kind.as_str() {
            "point_error" => CheckKind::PointError(placement),
            "point_error_p95" => CheckKind::PointErrorP95(placement),
            "phantom_area" => CheckKind::PhantomArea(placement),
            "coverage" => CheckKind::Coverage(placement),
            "valid_share" => CheckKind::ValidShare,
            "seam_error" => CheckKind::SeamError(placement),
            "final_estimate_error" => CheckKind::FinalEstimateError,
            "rms_estimate_error" => CheckKind::RmsEstimateError,
            "odometry_drift" => CheckKind::OdometryDrift,
            "collisions" => CheckKind::Collisions,
            "scans" => CheckKind::Scans,
            "outlier_share" => CheckKind::OutlierShare,
            "no_return_share" => CheckKind::NoReturnShare,
            "map_quality" => CheckKind::MapQuality,
            "wrong_trusted_matches" => CheckKind::WrongTrustedMatches,
            "distance_travelled" => CheckKind::DistanceTravelled,
            "goal_error" => CheckKind::GoalError,
            "navigation_failures" => CheckKind::NavigationFailures,
            "min_clearance" => CheckKind::MinClearance,
            "duration" => CheckKind::Duration,
            "sonar_error" => CheckKind::SonarError {
                transducers: f.transducers.clone().unwrap_or_else(|| vec![0]),
            },
            other => {
                return Err(error(
                    "kind",
                    format!(
                        "unknown check {other:?}: expected one of {}",
                        CheckKind::NAMES.join(", ")
                    ),
                ));
            }
        };
        // Which bounds each kind takes: metres, degrees, counts, shares, square metres or
        // seconds.
        let (metres, degrees, counts, shares, areas, seconds) = match kind {
            CheckKind::FinalEstimateError | CheckKind::RmsEstimateError => {
                (true, true, false, false, false, false)
            }
            CheckKind::OdometryDrift => (true, true, false, false, false, false),
            CheckKind::SonarError { .. }
            | CheckKind::DistanceTravelled
            | CheckKind::PointError(_)
            | CheckKind::PointErrorP95(_)
            | CheckKind::SeamError(_)
            | CheckKind::GoalError
            | CheckKind::MinClearance => (true, false, false, false, false, false),
            CheckKind::Collisions
            | CheckKind::Scans
            | CheckKind::NavigationFailures
            | CheckKind::WrongTrustedMatches => (false, false, true, false, false, false),
            CheckKind::OutlierShare
            | CheckKind::NoReturnShare
            | CheckKind::MapQuality
            | CheckKind::Coverage(_)
            | CheckKind::ValidShare => (false, false, false, true, false, false),
            CheckKind::PhantomArea(_) => (false, false, false, false, true, false),
            CheckKind::Duration => (false, false, false, false, false, true),
        };
        let given = [
            (
                "min_m / max_m",
                f.min_m.is_some() || f.max_m.is_some(),
                metres,
            ),
            (
                "min_deg / max_deg",
                f.min_deg.is_some() || f.max_deg.is_some(),
                degrees,
            ),
            ("min / max", f.min.is_some() || f.max.is_some(), counts),
            (
                "min_share / max_share",
                f.min_share.is_some() || f.max_share.is_some(),
                shares,
            ),
            (
                "min_m2 / max_m2",
                f.min_m2.is_some() || f.max_m2.is_some(),
                areas,
            ),
            (
                "min_s / max_s",
                f.min_s.is_some() || f.max_s.is_some(),
                seconds,
            ),
        ];
        for (name, present, allowed) in given {
            if present && !allowed {
                // The key actually written, of the pair.
                let (lo, hi) = name.split_once(" / ").unwrap_or((name, name));
                let key = if source.key_in(spanned.span(), lo).is_some() {
                    lo
                } else {
                    hi
                };
                return Err(error(key, format!("a `{}` check takes no {name}", f.kind)));
            }
        }
        if !given.iter().any(|(_, present, _)| *present) {
            let takes: Vec<&str> = given
                .iter()
                .filter(|(_, _, allowed)| *allowed)
                .map(|(n, _, _)| *n)
                .collect();
            return Err(error(
                "kind",
                format!("a `{}` check needs a bound: {}", f.kind, takes.join(" or ")),
            ));
        }
        if f.transducers.is_some() && !matches!(kind, CheckKind::SonarError { .. }) {
            return Err(error(
                "transducers",
                "only a `sonar_error` check names transducers".into(),
            ));
        }
        if f.placement.is_some()
            && !matches!(
                kind,
                CheckKind::PointError(_)
                    | CheckKind::PointErrorP95(_)
                    | CheckKind::PhantomArea(_)
                    | CheckKind::Coverage(_)
                    | CheckKind::SeamError(_)
            )
        {
            return Err(error(
                "placement",
                format!("a `{}` check takes no placement", f.kind),
            ));
        }
        let needs = match kind {
            _ if kind.model().is_some() && !takes_scenes => {
                Some("`scene` or `survey` steps in the script (the 3D model it measures)")
            }
            _ if kind.model() == Some(ModelPlacement::Estimate) && !localises => {
                Some("a [localisation] table (the model placed by the estimate)")
            }
            CheckKind::FinalEstimateError
            | CheckKind::RmsEstimateError
            | CheckKind::MapQuality
            | CheckKind::WrongTrustedMatches
                if !localises =>
            {
                Some("a [localisation] table")
            }
            CheckKind::SonarError { .. } if !fires_sonar => {
                Some("a [sonar] table with fire = true")
            }
            CheckKind::GoalError if !navigation.0 => Some("`goto X Y` steps in the script"),
            CheckKind::NavigationFailures if !navigation.1 => {
                Some("`goto X Y` or `explore SECONDS` steps in the script")
            }
            _ => None,
        };
        if let Some(what) = needs {
            return Err(error("kind", format!("a `{}` check needs {what}", f.kind)));
        }
        let bounds = if counts {
            Bounds {
                min: f.min,
                max: f.max,
            }
        } else if shares {
            Bounds {
                min: f.min_share,
                max: f.max_share,
            }
        } else if areas {
            Bounds {
                min: f.min_m2,
                max: f.max_m2,
            }
        } else if seconds {
            Bounds {
                min: f.min_s,
                max: f.max_s,
            }
        } else {
            Bounds {
                min: f.min_m,
                max: f.max_m,
            }
        };
        let pairs = [
            (("min_m", f.min_m), ("max_m", f.max_m)),
            (("min_deg", f.min_deg), ("max_deg", f.max_deg)),
            (("min", f.min), ("max", f.max)),
            (("min_share", f.min_share), ("max_share", f.max_share)),
            (("min_m2", f.min_m2), ("max_m2", f.max_m2)),
            (("min_s", f.min_s), ("max_s", f.max_s)),
        ];
        for ((min_name, min), (max_name, max)) in pairs {
            for (name, value) in [(min_name, min), (max_name, max)] {
                if let Some(v) = value
                    && !(0.0..=1e9).contains(&v)
                {
                    return Err(error(
                        name,
                        format!(
                            "expected a bound from 0 to 1e9, found {}",
                            super::values::show(v)
                        ),
                    ));
                }
            }
            if let (Some(lo), Some(hi)) = (min, max)
                && lo > hi
            {
                return Err(error(
                    min_name,
                    format!(
                        "{min_name} = {lo} is above {max_name} = {hi}: the check could never pass"
                    ),
                ));
            }
        }
        checks.push(Check {
            kind,
            bounds,
            degrees: Bounds {
                min: f.min_deg,
                max: f.max_deg,
            },
            note: f.note.clone().unwrap_or_default(),
        });
    }
    Ok(checks)
}

/// One `[[check]]` table.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CheckFile {
    kind: String,
    min_m: Option<f64>,
    max_m: Option<f64>,
    min_deg: Option<f64>,
    max_deg: Option<f64>,
    min: Option<f64>,
    max: Option<f64>,
    min_share: Option<f64>,
    max_share: Option<f64>,
    min_m2: Option<f64>,
    max_m2: Option<f64>,
    min_s: Option<f64>,
    max_s: Option<f64>,
    placement: Option<String>,
    transducers: Option<Vec<u8>>,
    note: Option<String>,
}
