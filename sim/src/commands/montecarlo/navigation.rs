//! The closed-loop study: a `goto` scenario run over many seeds, start poses and noise
//! conditions (`twin montecarlo studies/goto-lab.toml`), with the scan-matching study's
//! machinery — trial `i` draws everything from substream `i` of the study's seed, a progress log
//! of sealed rows makes it resumable, `--shard K/N` splits it, `merge` joins the shards — so
//! `trials.csv`, `paths.csv`, `summary.json`, `table.md` and `trajectories.svg` are
//! byte-identical whatever the threads, shards or interruptions.
//!
//! A trial is one whole run of the scenario (`run_scenario`, the twin with its firmware,
//! physics, laser, sonar and slip) from a start drawn near the scenario's, with its own seed:
//! each goal counts as reached when the controller said so and the robot truly stands within
//! the study's `success_m` of it.

use super::{
    RunOptions, StudyError, claim, io_error, read_lines, read_shards, sealed, trial_of, verified,
    write_atomically,
};
use crate::commands::run::{RunOptions as ScenarioOptions, run_scenario};
use crate::config::NavStudy;
use crate::output::figure::{Layers, Plan, Swatch, open_svg, xml_escape};
use crate::rng::{self, SimRng};
use crate::world::WorldMap;
use rand::RngExt;
use rayon::prelude::*;
use robot::Pose2;
use robot::control::NavOutcome;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The header of `trials.csv`.
pub const HEADER: &str = "trial,condition,seed,start_x,start_y,start_theta,goals,reached,failures,first_failure,collisions,min_clearance_m,sim_s,distance_m";
/// The header of `paths.csv`: each trial's true path, a point a second.
pub const PATHS_HEADER: &str = "trial,x y ...";

/// One finished trial: its row and its path line.
#[derive(Clone, Debug, PartialEq)]
pub struct NavTrial {
    /// The trial's number.
    pub index: u64,
    /// Its row of `trials.csv` (no newline).
    pub row: String,
    /// Its line of `paths.csv` (no newline).
    pub path: String,
}

/// The short name of an outcome in `trials.csv`.
fn outcome_name(outcome: &NavOutcome) -> &'static str {
    match outcome {
        NavOutcome::Reached { .. } => "reached",
        NavOutcome::Explored => "explored",
        NavOutcome::Blocked { .. } => "blocked",
        NavOutcome::NoWay { .. } => "no-way",
        NavOutcome::Lost { .. } => "lost",
        NavOutcome::OutOfDecisions { .. } => "out-of-decisions",
    }
}

/// Runs trial `index` of `study`.
pub fn run_trial(study: &NavStudy, map: &WorldMap, index: u64) -> Result<NavTrial, StudyError> {
    let per = study.trials_per_condition.max(1);
    let c = ((index / per) as usize).min(study.conditions.len() - 1);
    let condition = &study.conditions[c];
    let mut rng: SimRng = rng::substream(rng::stream_seed(study.seed, "navigation"), index);
    let seed: u64 = rng.random();
    let start = draw_start(study, map, &mut rng).ok_or_else(|| StudyError::Trial {
        trial: index,
        message: format!(
            "no start within {} m of the scenario's start is {} m from every wall",
            study.start_radius_m, study.clearance_m
        ),
    })?;
    let mut scenario = condition.scenario.clone();
    scenario.world.start = start;
    scenario.seed = seed;
    let record = run_scenario(&scenario, &ScenarioOptions::default(), |_, _| {}).map_err(|e| {
        StudyError::Trial {
            trial: index,
            message: e.to_string(),
        }
    })?;
    let results = record.navigation_results();
    let goals = results.iter().filter(|r| r.goal.is_some()).count();
    let reached = results
        .iter()
        .filter(|r| {
            matches!(r.outcome, NavOutcome::Reached { .. })
                && r.true_distance_m.is_some_and(|d| d <= study.success_m)
        })
        .count();
    let failed: Vec<&NavOutcome> = results
        .iter()
        .map(|r| &r.outcome)
        .filter(|o| !o.succeeded())
        .collect();
    let body = &scenario.robot.body;
    let clearance = record
        .closest_approach(map, body.radius_m.get(), body.center_x_m.get())
        .map_or(f64::NAN, |a| a.clearance_m);
    let row = format!(
        "{index},{},{seed},{:.4},{:.4},{:.4},{goals},{reached},{},{},{},{:.4},{:.3},{:.3}",
        condition.name,
        start.x,
        start.y,
        start.theta,
        failed.len(),
        failed.first().map_or("", |o| outcome_name(o)),
        record.collisions,
        clearance,
        record.sim_seconds(),
        record.distance_m,
    );
    let mut path = format!("{index},");
    let mut next = 0.0;
    for (t, p) in &record.true_path {
        if t.secs_f64() >= next {
            let _ = write!(path, "{:.3} {:.3} ", p.x, p.y);
            next += 1.0;
        }
    }
    let end = record.final_truth;
    let _ = write!(path, "{:.3} {:.3}", end.x, end.y);
    Ok(NavTrial { index, row, path })
}

/// A start pose within the study's radius of the scenario's start, clear of walls, heading
/// uniform; `None` after many tries.
fn draw_start(study: &NavStudy, map: &WorldMap, rng: &mut SimRng) -> Option<Pose2> {
    let centre = study.conditions[0].scenario.world.start;
    for _ in 0..10_000 {
        let r = study.start_radius_m * rng.random::<f64>().sqrt();
        let a = std::f64::consts::TAU * rng.random::<f64>();
        let heading = std::f64::consts::TAU * rng.random::<f64>() - std::f64::consts::PI;
        let (x, y) = (centre.x + r * a.cos(), centre.y + r * a.sin());
        if map.clearance([x, y]) >= study.clearance_m {
            return Some(Pose2::new(x, y, heading));
        }
    }
    None
}

/// What a navigation run did: its summary is the table.
pub type NavReport = super::RunReport<String>;

/// Runs (or resumes) `study` into `dir`. `progress(done, total)` is called as trials finish.
pub fn run_study(
    study: &NavStudy,
    dir: &Path,
    options: &RunOptions,
    mut progress: impl FnMut(u64, u64),
) -> Result<NavReport, StudyError> {
    let progress_dir = dir.join("progress");
    std::fs::create_dir_all(&progress_dir).map_err(io_error(&progress_dir))?;
    claim(dir, (&study.text, &study.path), options.shard)?;
    let total = study.total_trials();
    let (mut log, done) = NavLog::open(&progress_dir, total)?;
    let shard = options.shard;
    let (owned, resumed, missing, pool) = super::plan(options, total, &done)?;
    let mut missing = missing.peekable();
    let map = WorldMap::new(&study.conditions[0].scenario.world);
    let chunk = 2 * pool.current_num_threads();
    let started = Instant::now();
    let (mut finished, mut ran) = (resumed, 0);
    progress(finished, owned);
    while missing.peek().is_some() {
        let indices: Vec<u64> = missing.by_ref().take(chunk).collect();
        let results: Vec<Result<NavTrial, StudyError>> = pool.install(|| {
            indices
                .par_iter()
                .map(|&i| run_trial(study, &map, i))
                .collect()
        });
        let results: Vec<NavTrial> = results.into_iter().collect::<Result<_, _>>()?;
        log.append(&results)?;
        finished += results.len() as u64;
        ran += results.len() as u64;
        progress(finished, owned);
    }
    let mut report = NavReport {
        owned,
        resumed,
        ran,
        wall_seconds: started.elapsed().as_secs_f64(),
        summary: None,
        files: Vec::new(),
    };
    if finished == owned {
        let rows = NavLog::read(&progress_dir, total)?
            .into_iter()
            .filter(|(i, _)| shard.owns(*i))
            .collect();
        let (table, files) = write_results(study, dir, &rows)?;
        report.summary = Some(table);
        report.files = files;
    }
    Ok(report)
}

/// The progress log: `trials.log` and `paths.log`, sealed lines; a trial is done when both
/// hold its line.
struct NavLog {
    trials: (std::fs::File, PathBuf),
    paths: (std::fs::File, PathBuf),
}

impl NavLog {
    /// The complete trials on record: number → (row, path).
    fn read(dir: &Path, total: u64) -> Result<BTreeMap<u64, (String, String)>, StudyError> {
        let mut rows = BTreeMap::new();
        for line in read_lines(&dir.join("trials.log"))? {
            if let Some(row) = verified(&line)
                && row.split(',').count() == HEADER.split(',').count()
            {
                let index = trial_of(row);
                if index < total {
                    rows.insert(index, row.to_string());
                }
            }
        }
        let mut paths = BTreeMap::new();
        for line in read_lines(&dir.join("paths.log"))? {
            if let Some(path) = verified(&line) {
                paths.insert(trial_of(path), path.to_string());
            }
        }
        Ok(rows
            .into_iter()
            .filter_map(|(i, row)| paths.remove(&i).map(|path| (i, (row, path))))
            .collect())
    }

    /// Opens the log keeping only complete trials (a torn or half-written one runs again).
    fn open(dir: &Path, total: u64) -> Result<(NavLog, BTreeSet<u64>), StudyError> {
        let kept = Self::read(dir, total)?;
        let trials_path = dir.join("trials.log");
        let paths_path = dir.join("paths.log");
        let rows: String = kept.values().map(|(r, _)| sealed(r)).collect();
        let paths: String = kept.values().map(|(_, p)| sealed(p)).collect();
        write_atomically(&trials_path, rows.as_bytes())?;
        write_atomically(&paths_path, paths.as_bytes())?;
        let append = |path: &Path| {
            std::fs::OpenOptions::new()
                .append(true)
                .open(path)
                .map_err(io_error(path))
        };
        Ok((
            NavLog {
                trials: (append(&trials_path)?, trials_path),
                paths: (append(&paths_path)?, paths_path),
            },
            kept.keys().copied().collect(),
        ))
    }

    /// Appends finished trials: paths first, so a row is never on record without its path.
    fn append(&mut self, trials: &[NavTrial]) -> Result<(), StudyError> {
        let paths: String = trials.iter().map(|t| sealed(&t.path)).collect();
        let rows: String = trials.iter().map(|t| sealed(&t.row)).collect();
        for ((file, path), text) in [(&mut self.paths, paths), (&mut self.trials, rows)] {
            file.write_all(text.as_bytes())
                .and_then(|()| file.sync_data())
                .map_err(io_error(path))?;
        }
        Ok(())
    }
}

/// One row of `trials.csv`, read back.
#[derive(Clone, Debug)]
struct Row {
    condition: String,
    goals: u64,
    reached: u64,
    first_failure: String,
    collisions: u64,
    min_clearance_m: f64,
    sim_s: f64,
}

fn parse_row(path: &Path, line: usize, text: &str) -> Result<Row, StudyError> {
    let bad = |message: String| StudyError::BadRow {
        path: path.to_path_buf(),
        line,
        message,
    };
    let f: Vec<&str> = text.split(',').collect();
    if f.len() != HEADER.split(',').count() {
        return Err(bad(format!(
            "expected {} fields ({HEADER}), found {}",
            HEADER.split(',').count(),
            f.len()
        )));
    }
    let int = |k: usize| {
        f[k].parse::<u64>()
            .map_err(|_| bad(format!("field {k} `{}` is not a count", f[k])))
    };
    let num = |k: usize| {
        f[k].parse::<f64>()
            .map_err(|_| bad(format!("field {k} `{}` is not a number", f[k])))
    };
    Ok(Row {
        condition: f[1].to_string(),
        goals: int(6)?,
        reached: int(7)?,
        first_failure: f[9].to_string(),
        collisions: int(10)?,
        min_clearance_m: num(11)?,
        sim_s: num(12)?,
    })
}

/// Writes `trials.csv`, `paths.csv`, `summary.json`, `table.md` and `trajectories.svg` from
/// the trials' rows and paths; returns the table and the files.
fn write_results(
    study: &NavStudy,
    dir: &Path,
    trials: &BTreeMap<u64, (String, String)>,
) -> Result<(String, Vec<PathBuf>), StudyError> {
    let trials_path = dir.join("trials.csv");
    let mut text = format!("{HEADER}\n");
    let mut paths = format!("{PATHS_HEADER}\n");
    for (row, path) in trials.values() {
        text.push_str(row);
        text.push('\n');
        paths.push_str(path);
        paths.push('\n');
    }
    write_atomically(&trials_path, text.as_bytes())?;
    let paths_path = dir.join("paths.csv");
    write_atomically(&paths_path, paths.as_bytes())?;
    let rows: Vec<(u64, Row)> = text
        .lines()
        .enumerate()
        .skip(1)
        .map(|(n, l)| Ok((trial_of(l), parse_row(&trials_path, n + 1, l)?)))
        .collect::<Result<_, StudyError>>()?;
    let summary = summarise(study, &rows);
    let summary_path = dir.join("summary.json");
    let json = serde_json::to_string_pretty(&summary).map_err(|e| StudyError::Io {
        path: summary_path.clone(),
        source: e.into(),
    })? + "\n";
    write_atomically(&summary_path, json.as_bytes())?;
    let table = table(study, &summary);
    let table_path = dir.join("table.md");
    write_atomically(&table_path, table.as_bytes())?;
    let svg_path = dir.join("trajectories.svg");
    let svg = trajectories_svg(study, &rows, trials);
    write_atomically(&svg_path, svg.as_bytes())?;
    Ok((
        table,
        vec![trials_path, paths_path, summary_path, table_path, svg_path],
    ))
}

/// One condition's figures.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ConditionSummary {
    /// The condition.
    pub condition: String,
    /// Trials run.
    pub trials: u64,
    /// Goals asked, over all trials.
    pub goals: u64,
    /// Share of the goals reached (the controller said so and the truth agrees).
    pub goal_share: f64,
    /// Share of the trials that reached every goal.
    pub all_goals_share: f64,
    /// Share of the trials with a collision.
    pub collision_share: f64,
    /// Trials whose controller stopped short, by the first reason.
    pub stopped_short: BTreeMap<String, u64>,
    /// Median simulated time of a trial, seconds.
    pub median_s: f64,
    /// 95th percentile of that time, seconds.
    pub p95_s: f64,
    /// Median of the trials' smallest clearance, metres.
    pub median_clearance_m: f64,
    /// The smallest clearance of any trial, metres.
    pub worst_clearance_m: f64,
}

fn quantile(values: &mut [f64], q: f64) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    values[((values.len() - 1) as f64 * q).round() as usize]
}

fn summarise(study: &NavStudy, rows: &[(u64, Row)]) -> Vec<ConditionSummary> {
    study
        .conditions
        .iter()
        .map(|c| {
            let mine: Vec<&Row> = rows
                .iter()
                .map(|(_, r)| r)
                .filter(|r| r.condition == c.name)
                .collect();
            let n = mine.len().max(1) as f64;
            let goals: u64 = mine.iter().map(|r| r.goals).sum();
            let reached: u64 = mine.iter().map(|r| r.reached).sum();
            let mut stopped_short = BTreeMap::new();
            for r in &mine {
                if !r.first_failure.is_empty() {
                    *stopped_short.entry(r.first_failure.clone()).or_insert(0) += 1;
                }
            }
            let mut times: Vec<f64> = mine.iter().map(|r| r.sim_s).collect();
            let mut clearances: Vec<f64> = mine.iter().map(|r| r.min_clearance_m).collect();
            ConditionSummary {
                condition: c.name.clone(),
                trials: mine.len() as u64,
                goals,
                goal_share: reached as f64 / goals.max(1) as f64,
                all_goals_share: mine.iter().filter(|r| r.reached == r.goals).count() as f64 / n,
                collision_share: mine.iter().filter(|r| r.collisions > 0).count() as f64 / n,
                stopped_short,
                median_s: quantile(&mut times, 0.5),
                p95_s: quantile(&mut times, 0.95),
                median_clearance_m: quantile(&mut clearances, 0.5),
                worst_clearance_m: quantile(&mut clearances, 0.0),
            }
        })
        .collect()
}

fn table(study: &NavStudy, summary: &[ConditionSummary]) -> String {
    let mut t = format!(
        "# {}: goals reached over {} trials per condition\n\n{}\n\n| condition | trials | goals reached | runs reaching every goal | runs with a collision | stopped short (first reason) | median time, s | 95 % time, s | clearance, median / worst, m |\n|---|---|---|---|---|---|---|---|---|\n",
        study.name, study.trials_per_condition, study.description
    );
    for c in summary {
        let stopped = if c.stopped_short.is_empty() {
            "none".to_string()
        } else {
            c.stopped_short
                .iter()
                .map(|(k, v)| format!("{k} {v}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let _ = writeln!(
            t,
            "| {} | {} | {:.3} ({} goals) | {:.3} | {:.3} | {stopped} | {:.0} | {:.0} | {:.3} / {:.3} |",
            c.condition,
            c.trials,
            c.goal_share,
            c.goals,
            c.all_goals_share,
            c.collision_share,
            c.median_s,
            c.p95_s,
            c.median_clearance_m,
            c.worst_clearance_m
        );
    }
    t
}

/// Colours of the conditions' paths, in order.
const PALETTE: [&str; 6] = [
    "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b",
];

/// Every trial's true path over the world, a colour per condition, the goals and the starts.
fn trajectories_svg(
    study: &NavStudy,
    rows: &[(u64, Row)],
    trials: &BTreeMap<u64, (String, String)>,
) -> String {
    let scenario = &study.conditions[0].scenario;
    let map = WorldMap::new(&scenario.world);
    let (min, max) = scenario.world.bounds();
    let (min, max) = ([min[0] - 0.3, min[1] - 0.3], [max[0] + 0.3, max[1] + 0.3]);
    let scale = (900.0 / (max[0] - min[0])).min(600.0 / (max[1] - min[1]));
    let plan = Plan {
        min,
        max,
        origin: [Plan::LEFT + 10.0, Plan::ABOVE + 34.0],
        scale,
    };
    let mut layers = Layers::default();
    let mut walls = String::new();
    for f in map.faces() {
        let _ = write!(
            walls,
            "M{:.1} {:.1}L{:.1} {:.1}",
            plan.x(f.a[0]),
            plan.y(f.a[1]),
            plan.x(f.b[0]),
            plan.y(f.b[1])
        );
    }
    layers.add(
        "walls",
        "walls and boxes",
        Swatch::Line("#9a9a9a", 3.0, None),
        &format!(r##"<path d="{walls}" stroke="#9a9a9a" stroke-width="3" fill="none"/>"##),
    );
    let condition_of: BTreeMap<u64, &str> = rows
        .iter()
        .map(|(i, r)| (*i, r.condition.as_str()))
        .collect();
    let crashed: BTreeSet<u64> = rows
        .iter()
        .filter(|(_, r)| r.collisions > 0)
        .map(|(i, _)| *i)
        .collect();
    let mut ends = String::new();
    for (k, c) in study.conditions.iter().enumerate() {
        let colour = PALETTE[k % PALETTE.len()];
        let mut d = String::new();
        for (i, (_, path)) in trials {
            if condition_of.get(i) != Some(&c.name.as_str()) {
                continue;
            }
            let coords: Vec<f64> = path
                .split_once(',')
                .map_or("", |(_, p)| p)
                .split_whitespace()
                .filter_map(|v| v.parse().ok())
                .collect();
            for (j, p) in coords.chunks_exact(2).enumerate() {
                let (x, y) = plan.clamped(p[0], p[1]);
                let _ = write!(d, "{}{x:.1} {y:.1}", if j == 0 { "M" } else { "L" });
            }
            if crashed.contains(i)
                && let Some(p) = coords.rchunks_exact(2).next()
            {
                let (x, y) = plan.clamped(p[0], p[1]);
                let _ = write!(ends, r#"<circle cx="{x:.1}" cy="{y:.1}" r="3.5"/>"#);
            }
        }
        layers.add(
            &format!("condition-{k}"),
            format!("true paths: {}", c.name),
            Swatch::Line(colour, 1.5, None),
            &format!(
                r#"<path d="{d}" stroke="{colour}" stroke-width="1" stroke-opacity="0.45" fill="none"/>"#
            ),
        );
    }
    if !ends.is_empty() {
        layers.add(
            "collisions",
            "end of a run with a collision",
            Swatch::Dots("#000000"),
            &format!(r##"<g fill="#000000">{ends}</g>"##),
        );
    }
    let mut goals = String::new();
    for step in &scenario.steps {
        if let robot::control::Step::Goto { x, y } = *step {
            let (px, py) = plan.clamped(x, y);
            let _ = write!(
                goals,
                r#"<rect x="{:.1}" y="{:.1}" width="10" height="10"/>"#,
                px - 5.0,
                py - 5.0
            );
        }
    }
    layers.add(
        "goals",
        "goals (goto steps)",
        Swatch::Square("#e377c2"),
        &format!(r##"<g fill="#e377c2" stroke="black">{goals}</g>"##),
    );
    let s = scenario.world.start;
    let (sx, sy) = plan.clamped(s.x, s.y);
    layers.add(
        "start-area",
        format!(
            "starts: within {} m of ({:.1}, {:.1}), any heading",
            study.start_radius_m, s.x, s.y
        ),
        Swatch::Area("#cccccc", "#555555"),
        &format!(
            r##"<circle cx="{sx:.1}" cy="{sy:.1}" r="{:.1}" fill="#cccccc" fill-opacity="0.5" stroke="#555555"/>"##,
            (study.start_radius_m * scale).max(3.0)
        ),
    );
    let columns = 2;
    // Room for the longest label at 8 pixels a character (the legend's own estimate is 7).
    let longest = study
        .conditions
        .iter()
        .map(|c| c.name.chars().count() + "true paths: ".len())
        .max()
        .unwrap_or(0);
    let column_width = layers.column_width(300.0).max(36.0 + 8.0 * longest as f64);
    let legend_top = plan.origin[1] + plan.height() + Plan::BELOW + 10.0;
    let rows_n = layers.rows(columns) as f64;
    let width = (plan.origin[0] + plan.width() + 20.0)
        .max(plan.origin[0] + column_width * columns as f64 + 20.0);
    let height = legend_top + rows_n * 18.0 + 40.0;
    let mut svg = open_svg(width, height, 13);
    let _ = writeln!(
        svg,
        r#"<text x="{:.1}" y="20" font-size="15">{}: every trial's true path ({} per condition)</text>"#,
        plan.origin[0],
        xml_escape(&study.name),
        study.trials_per_condition
    );
    svg.push_str(&plan.grid());
    svg.push_str(layers.body());
    svg.push_str(&layers.legend(plan.origin[0], legend_top, columns, column_width));
    svg.push_str(&plan.scale_bar(width - 20.0, height - 15.0));
    svg.push_str("</svg>\n");
    svg
}

/// Combines finished shard folders of a navigation study into `out`.
pub fn merge(
    dirs: &[PathBuf],
    out: &Path,
    text: &str,
) -> Result<(String, Vec<PathBuf>), StudyError> {
    let first = &dirs[0];
    let origin_path = first.join("study-path");
    let origin = std::fs::read_to_string(&origin_path).map_err(io_error(&origin_path))?;
    let mut study = NavStudy::load(origin.trim()).map_err(|e| StudyError::Merge(e.to_string()))?;
    // Shards of a smaller study (`--trials N`) carry the rewritten count.
    if let Some(n) = super::count_in(text, "trials_per_condition")
        && n != study.trials_per_condition
    {
        study = study.with_trials_per_condition(n);
    }
    if study.text != text {
        return Err(StudyError::Merge(format!(
            "{} has changed since the shards ran",
            origin.trim()
        )));
    }
    let mut trials = BTreeMap::new();
    for (dir, rows) in read_shards(dirs, text, "trials.csv", HEADER)? {
        let mut paths: BTreeMap<u64, String> = read_lines(&dir.join("paths.csv"))?
            .into_iter()
            .skip(1)
            .map(|l| (trial_of(&l), l))
            .collect();
        for row in rows {
            let index = trial_of(&row);
            let path = paths.remove(&index).ok_or_else(|| {
                StudyError::Merge(format!("{}: no path for trial {index}", dir.display()))
            })?;
            trials.insert(index, (row, path));
        }
    }
    if trials.len() as u64 != study.total_trials() {
        return Err(StudyError::Merge(format!(
            "the shards hold {} trials, the study has {}",
            trials.len(),
            study.total_trials()
        )));
    }
    std::fs::create_dir_all(out).map_err(io_error(out))?;
    robot::logs::write_file(out.join("study.toml"), text).map_err(io_error(out))?;
    write_results(&study, out, &trials)
}
