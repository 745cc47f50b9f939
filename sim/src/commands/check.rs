//! Scenario checks evaluated on a run's record, and `twin check`.
//!
//! A scenario lists its checks as `[[check]]` tables ([`crate::config::checks`], and
//! `scenarios/README.md`); `twin run` evaluates them after the run and fails with a report naming
//! each check that is out of bounds, and every scenario under `scenarios/` runs as a test case of
//! `cargo test`.

use crate::config::Scenario;
use crate::config::checks::{Check, CheckKind, ModelPlacement};
use crate::record::Placement;
use crate::record::{RunRecord, WRONG_MATCH};
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
    /// What was measured, as numbers in the check's units (the heading part second, in degrees);
    /// empty when nothing could be measured.
    pub values: Vec<f64>,
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
    let map = &*record.world_map;
    let outcomes = scenario
        .checks
        .iter()
        .enumerate()
        .map(|(i, check)| evaluate_one(i, check, scenario, record, map))
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
    let measured_as =
        |values: Vec<f64>, measured: String, expected: String, passed: bool| CheckOutcome {
            name: name.clone(),
            measured,
            expected,
            values,
            passed,
            note: check.note.clone(),
        };
    let outcome = |measured: String, expected: String, passed: bool| {
        measured_as(Vec::new(), measured, expected, passed)
    };
    // A quantity with an optional heading part.
    let pair = |metres: f64, degrees: Option<f64>| {
        let mut measured = format!("{metres:.4}{unit}");
        let mut expected = Vec::new();
        let mut passed = check.bounds.holds(metres);
        let mut values = vec![metres];
        if !check.bounds.is_empty() {
            expected.push(format!("{}{unit}", check.bounds));
        }
        if let Some(deg) = degrees {
            values.push(deg);
            measured.push_str(&format!(", {deg:.3}°"));
            if !check.degrees.is_empty() {
                expected.push(format!("{}°", check.degrees));
                passed &= check.degrees.holds(deg);
            }
        }
        measured_as(values, measured, expected.join(", "), passed)
    };
    let single = |value: f64, shown: String| {
        measured_as(
            vec![value],
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
        CheckKind::GoalError => {
            let results = record.navigation_results();
            let worst = results
                .iter()
                .filter_map(|r| r.true_distance_m.map(|d| (d, r)))
                .max_by(|a, b| a.0.total_cmp(&b.0));
            match worst {
                Some((d, r)) => single(
                    d,
                    format!(
                        "{d:.3} m (goal {:?}, {} goto steps; {})",
                        r.goal.unwrap_or_default(),
                        results.iter().filter(|r| r.goal.is_some()).count(),
                        r.outcome
                    ),
                ),
                None => outcome("no goto step ended".into(), "goto steps".into(), false),
            }
        }
        CheckKind::NavigationFailures => {
            let results = record.navigation_results();
            let failed: Vec<String> = results
                .iter()
                .filter(|r| !r.outcome.succeeded())
                .map(|r| format!("{:.1} s: {}", r.t, r.outcome))
                .collect();
            let n = failed.len();
            let shown = if failed.is_empty() {
                format!("0 of {}", results.len())
            } else {
                format!("{n} of {} ({})", results.len(), failed.join("; "))
            };
            single(n as f64, shown)
        }
        CheckKind::MinClearance => {
            let body = &scenario.robot.body;
            match record.closest_approach(map, body.radius_m.get(), body.center_x_m.get()) {
                Some(a) => single(
                    a.clearance_m,
                    format!(
                        "{:.3} m at {:.1} s, base at ({:.2}, {:.2})",
                        a.clearance_m, a.t, a.pose[0], a.pose[1]
                    ),
                ),
                None => outcome("no path".into(), "a run that moved".into(), false),
            }
        }
        CheckKind::Duration => {
            let t = record.sim_seconds();
            single(t, format!("{t:.1} s"))
        }
        CheckKind::OutlierShare => {
            let (mut ghosts, mut total) = (0usize, 0usize);
            let mut kinds = crate::world::PointKinds::new(map);
            for r in &record.scans {
                for k in 0..r.scan.len() {
                    if let Some(range) = r.scan.range_m(k) {
                        total += 1;
                        let p = r.frame.point(r.scan.angle(k), range);
                        ghosts += usize::from(kinds.of(p) == PointKind::Ghost);
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
        CheckKind::WrongTrustedMatches => {
            let Some(loc) = &record.localisation else {
                return outcome("no matches".into(), "a [localisation] table".into(), false);
            };
            let judged = loc.judge_trusted(&record.scans, WRONG_MATCH);
            let across = loc.judge_held_across(&record.scans, WRONG_MATCH);
            single(
                (judged.wrong + across.wrong) as f64,
                format!(
                    "{} of {} trusted (the worst {:.3} m, {:.2}° from the true motion), \
                     {} of {} relied on across a corridor (the worst {:.3} m across, {:.2}°)",
                    judged.wrong,
                    judged.trusted,
                    judged.worst_m,
                    judged.worst_rad.to_degrees(),
                    across.wrong,
                    across.trusted,
                    across.worst_m,
                    across.worst_rad.to_degrees()
                ),
            )
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

/// `twin check`: run every scenario of a folder (or one file) and evaluate its checks; print a
/// table, fail if any check fails. With `--seeds N`, run each scenario with seeds 1..=N instead of
/// its own and print, per check, the distribution of what it measured over the seeds.
#[derive(Clone, Debug, clap::Args)]
pub struct CheckArgs {
    /// The folder (e.g. scenarios/) or one scenario file.
    pub path: std::path::PathBuf,
    /// Run each scenario with N seeds (FIRST..FIRST+N) instead of its own seed, and report each
    /// check's distribution over them.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=100_000))]
    pub seeds: Option<u64>,
    /// The first seed of `--seeds`.
    #[arg(long, value_name = "SEED", default_value_t = 1, requires = "seeds")]
    pub first_seed: u64,
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

/// The scenario files a `twin check` path names: the path itself if it is a file, else the
/// `.toml` files of the folder, sorted.
pub fn scenario_files(
    path: &std::path::Path,
) -> Result<Vec<std::path::PathBuf>, super::CommandError> {
    use super::CommandError;
    if path.is_file() {
        return Ok(vec![path.to_path_buf()]);
    }
    let mut files: Vec<std::path::PathBuf> = std::fs::read_dir(path)
        .map_err(|source| CommandError::Folder {
            dir: path.to_path_buf(),
            source,
        })?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(CommandError::NoScenarios(path.to_path_buf()));
    }
    Ok(files)
}

/// One scenario run with its check report and wall seconds, or why it could not run (a load
/// error, a failed run, a crash: each is one failed row, not the end of the table).
pub fn check_file(path: &std::path::Path, seed: Option<u64>) -> Result<(CheckReport, f64), String> {
    use super::run::{RunOptions, run_scenario};
    let started = std::time::Instant::now();
    let check = || {
        Scenario::load(path)
            .map_err(|e| e.to_string())
            .and_then(|scenario| {
                let options = RunOptions {
                    seed,
                    ..RunOptions::default()
                };
                let record =
                    run_scenario(&scenario, &options, |_, _| {}).map_err(|e| e.to_string())?;
                Ok((
                    evaluate(&scenario, &record),
                    started.elapsed().as_secs_f64(),
                ))
            })
    };
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(check))
        .unwrap_or_else(|panic| Err(format!("the run crashed: {}", panic_message(&*panic))))
}

/// The name a report gives a scenario file.
fn stem(path: &std::path::Path) -> String {
    path.file_stem()
        .map_or("?".into(), |s| s.to_string_lossy().into_owned())
}

/// Runs `twin check`.
pub fn main(args: CheckArgs) -> Result<(), super::CommandError> {
    use rayon::prelude::*;
    let files = scenario_files(&args.path)?;
    let seeds: Vec<Option<u64>> = match args.seeds {
        None => vec![None],
        Some(n) => (0..n)
            .map(|k| Some(args.first_seed.wrapping_add(k)))
            .collect(),
    };
    let runs: Vec<(usize, Option<u64>)> = (0..files.len())
        .flat_map(|f| seeds.iter().map(move |&s| (f, s)))
        .collect();
    let bar = super::bar(
        args.quiet,
        runs.len() as u64,
        "check [{bar:30}] {pos}/{len} runs {elapsed_precise} (ETA {eta})",
    );
    // Each run: its scenario file's number, the seed it ran with, and its report or error.
    type Outcome = (usize, Option<u64>, Result<(CheckReport, f64), String>);
    let results: Vec<Outcome> = runs
        .par_iter()
        .map(|&(f, seed)| {
            let outcome = check_file(&files[f], seed);
            bar.inc(1);
            (f, seed, outcome)
        })
        .collect();
    bar.finish_and_clear();
    let failed = if args.seeds.is_some() {
        print_spread(&files, &seeds, &results)
    } else {
        print_table(&files, &results)
    };
    if failed > 0 {
        return Err(super::CommandError::ScenariosFailed {
            failed,
            total: results.len(),
        });
    }
    Ok(())
}

type Results = [(usize, Option<u64>, Result<(CheckReport, f64), String>)];

/// The table of a plain `twin check`; returns the number of scenarios that failed.
fn print_table(files: &[std::path::PathBuf], results: &Results) -> usize {
    say!("| scenario | checks | passed | failed | seconds |");
    say!("|---|---|---|---|---|");
    let mut failed = 0;
    for (f, _, result) in results {
        let name = stem(&files[*f]);
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
    for (f, _, result) in results {
        match result {
            Ok((report, _)) if !report.passed() => {
                say!();
                say!("{}", report.to_string().trim_end_matches('\n'));
            }
            Err(e) => say!("\n{}: {e}", files[*f].display()),
            _ => {}
        }
    }
    failed
}

/// A value of a distribution, readably.
fn show(x: f64) -> String {
    if x.is_finite() {
        let a = x.abs();
        if a != 0.0 && !(0.001..100_000.0).contains(&a) {
            format!("{x:.3e}")
        } else if a >= 100.0 {
            format!("{x:.0}")
        } else {
            format!("{x:.4}")
        }
    } else {
        "none".into()
    }
}

/// The `q` quantile (0..=1) of sorted values, by the nearest rank.
fn quantile(sorted: &[f64], q: f64) -> f64 {
    let rank = (q * sorted.len() as f64).ceil() as usize;
    sorted[rank.clamp(1, sorted.len()) - 1]
}

/// The seed-spread report of `twin check --seeds`: per scenario, per check and quantity, the
/// distribution over the seeds and how many seeds passed; then each failing (scenario, seed).
/// Returns the number of runs that failed.
fn print_spread(files: &[std::path::PathBuf], seeds: &[Option<u64>], results: &Results) -> usize {
    let first = seeds.first().copied().flatten().unwrap_or(0);
    let last = seeds.last().copied().flatten().unwrap_or(0);
    let mut failed = 0;
    for (f, path) in files.iter().enumerate() {
        let runs: Vec<_> = results.iter().filter(|r| r.0 == f).collect();
        let reports: Vec<&CheckReport> = runs
            .iter()
            .filter_map(|r| r.2.as_ref().ok().map(|(report, _)| report))
            .collect();
        let bad = runs
            .iter()
            .filter(|r| r.2.as_ref().map_or(true, |(report, _)| !report.passed()))
            .count();
        failed += bad;
        say!(
            "## {} — seeds {first}..={last}: {} of {} runs pass every check",
            stem(path),
            runs.len() - bad,
            runs.len()
        );
        say!();
        let Some(model) = reports.first() else {
            say!("(no run completed)");
            say!();
            continue;
        };
        say!("| check | bound | min | median | 95 % | max | seeds passing |");
        say!("|---|---|---|---|---|---|---|");
        for (i, outcome) in model.outcomes.iter().enumerate() {
            let parts = outcome.values.len().max(1);
            for part in 0..parts {
                let mut values: Vec<f64> = reports
                    .iter()
                    .filter_map(|r| r.outcomes.get(i)?.values.get(part).copied())
                    .map(|v| if v.is_nan() { f64::INFINITY } else { v })
                    .collect();
                values.sort_by(f64::total_cmp);
                let passing = reports
                    .iter()
                    .filter(|r| r.outcomes.get(i).is_some_and(|o| o.passed))
                    .count();
                let (name, bound) = if part == 0 {
                    (outcome.name.clone(), outcome.expected.clone())
                } else {
                    (format!("{} (°)", outcome.name), String::from("″"))
                };
                if values.is_empty() {
                    say!(
                        "| {name} | {bound} | - | - | - | - | {passing}/{} |",
                        runs.len()
                    );
                } else {
                    say!(
                        "| {name} | {bound} | {} | {} | {} | {} | {passing}/{} |",
                        show(values[0]),
                        show(quantile(&values, 0.5)),
                        show(quantile(&values, 0.95)),
                        show(values[values.len() - 1]),
                        runs.len()
                    );
                }
            }
        }
        say!();
    }
    for (f, seed, result) in results {
        let seed = seed.unwrap_or_default();
        match result {
            Ok((report, _)) if !report.passed() => {
                for o in report.failures() {
                    say!("{} --seed {seed}: {o}", files[*f].display());
                }
            }
            Err(e) => say!("{} --seed {seed}: {e}", files[*f].display()),
            _ => {}
        }
    }
    failed
}
