//! Scenario checks evaluated on a run's record, and `twin check`.
//!
//! A scenario lists its checks as `[[check]]` tables ([`crate::config::checks`], and
//! `scenarios/README.md`); `twin run` evaluates them after the run and fails with a report naming
//! each check that is out of bounds, and every scenario under `scenarios/` runs as a test case of
//! `cargo test`.

use crate::config::Scenario;
use crate::config::checks::{Check, CheckKind, ModelPlacement};
use crate::record::Placement;
use crate::record::RunRecord;
use crate::world::PointKind;
use crate::world::WorldMap;
use core::fmt;

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
        kind @ (CheckKind::PointError(_)
        | CheckKind::PointErrorP95(_)
        | CheckKind::PhantomArea(_)
        | CheckKind::Coverage(_)
        | CheckKind::ValidShare
        | CheckKind::SeamError(_)) => {
            let wanted = kind.model().expect("a model check");
            let Some(recon) = &record.reconstruction else {
                return outcome(
                    "no 3D model".into(),
                    "`scene` or `survey` steps".into(),
                    false,
                );
            };
            let placed = match wanted {
                ModelPlacement::Main => Some(recon.main()),
                ModelPlacement::Estimate => recon.placed(Placement::Estimate),
                ModelPlacement::Odometry => recon.placed(Placement::Odometry),
                ModelPlacement::Truth => recon.placed(Placement::Truth),
            };
            let Some(placed) = placed else {
                return outcome(
                    "no such model".into(),
                    format!("a model placed by {wanted:?}"),
                    false,
                );
            };
            let which = placed.placement.name();
            if *kind == CheckKind::ValidShare {
                let (_, (valid, of)) = placed.model.counts();
                let share = valid as f64 / of.max(1) as f64;
                return single(
                    share,
                    format!("{share:.4} ({valid} of {of} triangles, {which})"),
                );
            }
            let Some(a) = &placed.accuracy else {
                return outcome("no score".into(), "the world's truth".into(), false);
            };
            match kind {
                CheckKind::PointError(_) => {
                    single(a.median_m, format!("{:.4} m (median, {which})", a.median_m))
                }
                CheckKind::PointErrorP95(_) => single(
                    a.p95_m,
                    format!("{:.4} m (95th percentile, {which})", a.p95_m),
                ),
                CheckKind::PhantomArea(_) => single(
                    a.phantom_area_m2,
                    format!(
                        "{:.3} m² of {:.1} m² ({which})",
                        a.phantom_area_m2, a.mesh_area_m2
                    ),
                ),
                CheckKind::Coverage(_) => single(
                    a.coverage,
                    format!("{:.4} of {:.1} m² ({which})", a.coverage, a.surface_area_m2),
                ),
                _ => match a.seam_m {
                    Some(seam) => single(
                        seam,
                        format!(
                            "{seam:.4} m ({} of {} vertices overlapped, {which})",
                            a.seam_pairs.1, a.seam_pairs.0
                        ),
                    ),
                    None => outcome(
                        "no overlap between stations".into(),
                        format!("{}{unit}", check.bounds),
                        false,
                    ),
                },
            }
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

/// `twin check`: run every scenario of a folder and evaluate its checks; print a table, fail if
/// any check fails.
#[derive(Clone, Debug, clap::Args)]
pub struct CheckArgs {
    /// The folder (e.g. scenarios/).
    pub dir: std::path::PathBuf,
    /// Print only the table and failures.
    #[arg(long, short)]
    pub quiet: bool,
}

/// The message a panic carried.
fn panic_message(panic: &(dyn std::any::Any + Send)) -> String {
    panic
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| panic.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "(no message)".into())
}

/// Runs `twin check`.
pub fn main(args: CheckArgs) -> Result<(), super::CommandError> {
    use super::CommandError;
    use super::run::{RunOptions, run_scenario};
    use rayon::prelude::*;
    use std::path::PathBuf;
    let dir = args.dir;
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .map_err(|source| CommandError::Folder {
            dir: dir.clone(),
            source,
        })?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(CommandError::NoScenarios(dir));
    }
    let bar = super::bar(
        args.quiet,
        files.len() as u64,
        "check [{bar:30}] {pos}/{len} scenarios {elapsed_precise}",
    );
    // Per file: its check report and wall seconds, or why it could not run.
    type Outcome = Result<(CheckReport, f64), String>;
    let results: Vec<(PathBuf, Outcome)> = files
        .par_iter()
        .map(|path| {
            let started = std::time::Instant::now();
            let check = || {
                Scenario::load(path)
                    .map_err(|e| e.to_string())
                    .and_then(|scenario| {
                        let record = run_scenario(&scenario, &RunOptions::default(), |_, _| {})
                            .map_err(|e| e.to_string())?;
                        Ok((
                            evaluate(&scenario, &record),
                            started.elapsed().as_secs_f64(),
                        ))
                    })
            };
            // One scenario that crashes is one failed row, not the end of the table.
            let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(check))
                .unwrap_or_else(|panic| {
                    Err(format!("the run crashed: {}", panic_message(&*panic)))
                });
            bar.inc(1);
            (path.clone(), outcome)
        })
        .collect();
    bar.finish_and_clear();
    say!("| scenario | checks | passed | failed | seconds |");
    say!("|---|---|---|---|---|");
    let mut failed = 0;
    for (path, result) in &results {
        let name = path.file_stem().map_or("?".into(), |s| s.to_string_lossy());
        match result {
            Ok((report, seconds)) => {
                let bad = report.failures().count();
                failed += usize::from(bad > 0);
                say!(
                    "| {name} | {} | {} | {bad} | {seconds:.1} |",
                    report.outcomes.len(),
                    report.outcomes.len() - bad
                );
            }
            Err(_) => {
                failed += 1;
                say!("| {name} | - | - | error | - |");
            }
        }
    }
    for (path, result) in &results {
        match result {
            Ok((report, _)) if !report.passed() => {
                say!();
                say!("{}", report.to_string().trim_end_matches('\n'));
            }
            Err(e) => say!("\n{}: {e}", path.display()),
            _ => {}
        }
    }
    if failed > 0 {
        return Err(CommandError::ScenariosFailed {
            failed,
            total: results.len(),
        });
    }
    Ok(())
}
