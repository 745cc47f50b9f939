//! Scenario checks: what a run must show, with bounds, evaluated on its record.
//!
//! A scenario lists them as `[[check]]` tables (see `scenarios/README.md`); `twin run` evaluates
//! them after the run and fails with a report naming each check that is out of bounds, and every
//! scenario under `scenarios/` runs as a test case of `cargo test`.

use crate::config::Scenario;
use crate::output::PointKind;
use crate::run::RunRecord;
use crate::world_map::WorldMap;
use core::fmt;

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
    /// Largest error (m) of the listed sonar transducers' last echoes against the true distance
    /// along their axes.
    SonarError {
        /// Transducer numbers.
        transducers: Vec<u8>,
    },
    /// Length of the true path, metres.
    DistanceTravelled,
}

impl CheckKind {
    /// The names accepted in `kind = "…"`.
    pub const NAMES: [&'static str; 10] = [
        "final_estimate_error",
        "rms_estimate_error",
        "odometry_drift",
        "collisions",
        "scans",
        "outlier_share",
        "no_return_share",
        "map_quality",
        "sonar_error",
        "distance_travelled",
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
            CheckKind::SonarError { .. } => "sonar_error",
            CheckKind::DistanceTravelled => "distance_travelled",
        }
    }

    /// The unit of the main quantity.
    fn unit(&self) -> &'static str {
        match self {
            CheckKind::FinalEstimateError
            | CheckKind::RmsEstimateError
            | CheckKind::OdometryDrift
            | CheckKind::SonarError { .. }
            | CheckKind::DistanceTravelled => " m",
            CheckKind::Collisions | CheckKind::Scans => "",
            CheckKind::OutlierShare | CheckKind::NoReturnShare | CheckKind::MapQuality => "",
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
    fn holds(&self, value: f64) -> bool {
        self.min.is_none_or(|m| value >= m) && self.max.is_none_or(|m| value <= m)
    }

    fn is_empty(&self) -> bool {
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

/// The outcome of one check.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckOutcome {
    /// The check's name (`collisions`, …) and its number in the file.
    pub name: String,
    /// What was measured, readably.
    pub measured: String,
    /// The bounds, readably.
    pub expected: String,
    /// Whether it holds.
    pub passed: bool,
    /// The check's note.
    pub note: String,
}

impl fmt::Display for CheckOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} {}: measured {}, expected {}",
            if self.passed { "ok  " } else { "FAIL" },
            self.name,
            self.measured,
            self.expected
        )?;
        if !self.note.is_empty() {
            write!(f, " — {}", self.note)?;
        }
        Ok(())
    }
}

/// The checks of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckReport {
    /// The scenario.
    pub scenario: String,
    /// One outcome per check, in file order.
    pub outcomes: Vec<CheckOutcome>,
}

impl CheckReport {
    /// Whether every check holds.
    pub fn passed(&self) -> bool {
        self.outcomes.iter().all(|o| o.passed)
    }

    /// The failed checks.
    pub fn failures(&self) -> impl Iterator<Item = &CheckOutcome> {
        self.outcomes.iter().filter(|o| !o.passed)
    }
}

impl fmt::Display for CheckReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let failed = self.failures().count();
        writeln!(
            f,
            "{}: {} check(s), {}",
            self.scenario,
            self.outcomes.len(),
            if failed == 0 {
                "all passed".to_string()
            } else {
                format!("{failed} FAILED")
            }
        )?;
        for o in &self.outcomes {
            writeln!(f, "  {o}")?;
        }
        Ok(())
    }
}

/// Evaluates `scenario`'s checks on the run `record`.
pub fn evaluate(scenario: &Scenario, record: &RunRecord) -> CheckReport {
    let map = WorldMap::new(&scenario.world);
    let outcomes = scenario
        .checks
        .iter()
        .enumerate()
        .map(|(i, check)| evaluate_one(i, check, scenario, record, &map))
        .collect();
    CheckReport {
        scenario: scenario.name.clone(),
        outcomes,
    }
}

fn evaluate_one(
    i: usize,
    check: &Check,
    scenario: &Scenario,
    record: &RunRecord,
    map: &WorldMap,
) -> CheckOutcome {
    let name = format!("check[{i}] {}", check.kind.name());
    let unit = check.kind.unit();
    let outcome = |measured: String, expected: String, passed: bool| CheckOutcome {
        name: name.clone(),
        measured,
        expected,
        passed,
        note: check.note.clone(),
    };
    // A quantity with an optional heading part.
    let pair = |metres: f64, degrees: Option<f64>| {
        let mut measured = format!("{metres:.4}{unit}");
        let mut expected = Vec::new();
        let mut passed = check.bounds.holds(metres);
        if !check.bounds.is_empty() {
            expected.push(format!("{}{unit}", check.bounds));
        }
        if let Some(deg) = degrees {
            measured.push_str(&format!(", {deg:.3}°"));
            if !check.degrees.is_empty() {
                expected.push(format!("{}°", check.degrees));
                passed &= check.degrees.holds(deg);
            }
        }
        outcome(measured, expected.join(", "), passed)
    };
    let single = |value: f64, shown: String| {
        outcome(
            shown,
            format!("{}{unit}", check.bounds),
            check.bounds.holds(value),
        )
    };
    match &check.kind {
        CheckKind::FinalEstimateError | CheckKind::RmsEstimateError => {
            let Some(loc) = &record.localisation else {
                return outcome("no estimate".into(), "a [localisation] table".into(), false);
            };
            let (final_m, final_deg, rms_m, rms_deg) = crate::output::estimate_errors(record, loc);
            if check.kind == CheckKind::FinalEstimateError {
                pair(final_m, Some(final_deg))
            } else {
                pair(rms_m, Some(rms_deg))
            }
        }
        CheckKind::OdometryDrift => pair(
            record.final_odometry_error_m(),
            Some(record.final_odometry_error_deg()),
        ),
        CheckKind::Collisions => {
            single(f64::from(record.collisions), record.collisions.to_string())
        }
        CheckKind::Scans => single(record.scans.len() as f64, record.scans.len().to_string()),
        CheckKind::DistanceTravelled => {
            single(record.distance_m, format!("{:.3} m", record.distance_m))
        }
        CheckKind::OutlierShare => {
            let (mut ghosts, mut total) = (0usize, 0usize);
            for r in &record.scans {
                for k in 0..r.scan.len() {
                    if let Some(range) = r.scan.range_m(k) {
                        total += 1;
                        let p = r.frame.point(r.scan.angle(k), range);
                        ghosts += usize::from(PointKind::of(map, p) == PointKind::Ghost);
                    }
                }
            }
            let share = ghosts as f64 / total.max(1) as f64;
            single(share, format!("{share:.4} ({ghosts} of {total} readings)"))
        }
        CheckKind::NoReturnShare => {
            let total: usize = record.scans.iter().map(|r| r.scan.len()).sum();
            let lost: usize = record
                .scans
                .iter()
                .map(|r| {
                    (0..r.scan.len())
                        .filter(|&k| r.scan.range_m(k).is_none())
                        .count()
                })
                .sum();
            let share = lost as f64 / total.max(1) as f64;
            single(share, format!("{share:.4} ({lost} of {total} readings)"))
        }
        CheckKind::MapQuality => {
            let Some(loc) = &record.localisation else {
                return outcome("no map".into(), "a [localisation] table".into(), false);
            };
            let z = scenario.robot.laser.z_m.get();
            let near = loc
                .map
                .iter()
                .filter(|p| map.distance_3d([p[0], p[1], z]) <= 0.05)
                .count();
            let share = near as f64 / loc.map.len().max(1) as f64;
            single(
                share,
                format!("{share:.4} ({near} of {} map points)", loc.map.len()),
            )
        }
        CheckKind::SonarError { transducers } => {
            let Some(sonar) = &record.sonar else {
                return outcome("no sonar reading".into(), "a [sonar] table".into(), false);
            };
            let mut worst: f64 = 0.0;
            let mut details = Vec::new();
            for &t in transducers {
                let Some(pos) = sonar.echoes.sequence.iter().position(|&s| s == t) else {
                    return outcome(
                        format!("transducer {t} not in the firing sequence"),
                        format!("{}{unit}", check.bounds),
                        false,
                    );
                };
                let pose = sonar.truth.compose(&sonar.transducers[usize::from(t)]);
                let truth = map
                    .cast_level(
                        [pose.x, pose.y],
                        0.2,
                        [pose.theta.cos(), pose.theta.sin()],
                        12.0,
                    )
                    .map(|h| h.distance);
                let echo = sonar
                    .echoes
                    .distance_m(pos, robot::hardware::SPEED_OF_SOUND);
                let error = match (echo, truth) {
                    (Some(e), Some(t)) => (e - t).abs(),
                    _ => f64::INFINITY,
                };
                details.push(format!(
                    "#{t}: echo {} vs {}",
                    echo.map_or("none".into(), |e| format!("{e:.3} m")),
                    truth.map_or("nothing".into(), |t| format!("{t:.3} m"))
                ));
                worst = worst.max(error);
            }
            single(worst, format!("{worst:.4} m ({})", details.join("; ")))
        }
    }
}
