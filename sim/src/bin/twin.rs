//! `twin` — the digital twin of a laser-equipped indoor mobile robot.
//!
//! ```text
//! twin run scenarios/lab-tour.toml [--out DIR] [--seed N]
//! twin map tests/data/mit-csail.clf [--matcher NAME] [--out DIR]
//! twin match --matcher lorentz < pairs.jsonl > results.jsonl
//! ```

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use robot::localization::{MapConfig, MatcherKind};
use sim::config::Scenario;
use sim::run::{RunOptions, run_scenario};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "twin",
    version,
    about = "The digital twin of a laser-equipped indoor mobile robot"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scenario headless, as fast as possible, and write trajectories, scans, a summary
    /// and a map picture.
    Run {
        /// The scenario file (e.g. scenarios/lab-tour.toml).
        scenario: PathBuf,
        /// Output folder [default: out/SCENARIO-NAME].
        #[arg(long)]
        out: Option<PathBuf>,
        /// Seed replacing the scenario's.
        #[arg(long)]
        seed: Option<u64>,
        /// Print nothing but errors.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Build a 2D map from a recorded log (CARMEN .clf, .script, RobotLogger .log) by chaining
    /// scan matches seeded by its odometry; write the estimate, the odometry, a picture of both
    /// maps and a summary with timings.
    Map {
        /// The log file.
        log: PathBuf,
        /// The matcher: ls, lorentz, lorentz-lines or mbicp.
        #[arg(long, default_value = "lorentz")]
        matcher: MatcherKind,
        /// Output folder [default: out/map-LOGNAME].
        #[arg(long)]
        out: Option<PathBuf>,
        /// Match each scan to the last one the robot moved this far from, metres (0: to the
        /// previous scan).
        #[arg(long, default_value_t = 0.0)]
        keyframe_m: f64,
        /// Print nothing but errors.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Match scan pairs read as JSON Lines from stdin, one result line per pair on stdout.
    ///
    /// Input: {"ref": {"angle_min", "angle_increment", "range_max", "ranges": [...]}, "cur": {...},
    /// "guess": [x, y, theta]}; output: {"x", "y", "theta", "iterations", "converged",
    /// "correspondences", "micros"}, or {"error": "..."} for a malformed line.
    Match {
        /// The matcher: ls, lorentz, lorentz-lines or mbicp.
        #[arg(long, default_value = "lorentz")]
        matcher: MatcherKind,
    },
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Run {
            scenario,
            out,
            seed,
            quiet,
        } => run_command(scenario, out, seed, quiet),
        Command::Map {
            log,
            matcher,
            out,
            keyframe_m,
            quiet,
        } => map_command(log, matcher, out, keyframe_m, quiet),
        Command::Match { matcher } => match_command(matcher),
    }
}

fn map_command(
    path: PathBuf,
    matcher: MatcherKind,
    out: Option<PathBuf>,
    keyframe_m: f64,
    quiet: bool,
) -> Result<()> {
    if !(keyframe_m >= 0.0 && keyframe_m.is_finite()) {
        anyhow::bail!("--keyframe-m must be a distance >= 0, found {keyframe_m}");
    }
    let log = robot::logs::read_log(&path)?;
    let name = path.display().to_string();
    let bar = if quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(log.events.len() as u64).with_style(
            ProgressStyle::with_template("{prefix} [{bar:30}] {pos}/{len} records ETA {eta}")
                .expect("valid template")
                .progress_chars("=> "),
        )
    };
    bar.set_prefix(format!("map ({matcher})"));
    let config = MapConfig {
        keyframe_distance_m: keyframe_m,
        ..MapConfig::default()
    };
    let replay = sim::replay::replay_log(&log, matcher, config, |done, _| {
        bar.set_position(done as u64)
    });
    bar.finish_and_clear();
    let summary = replay.summary(&name, &log);
    let stem = path
        .file_stem()
        .map_or("log".into(), |s| s.to_string_lossy());
    let dir = out.unwrap_or_else(|| PathBuf::from("out").join(format!("map-{stem}")));
    let files = replay
        .write(&dir, &summary)
        .with_context(|| format!("writing the outputs into {}", dir.display()))?;
    if !quiet {
        println!(
            "{name}: {} scans matched with {matcher} in {:.2} s ({:.2} ms per scan, {:.1} iterations per match); {} lines skipped",
            summary.scans,
            summary.wall_seconds,
            summary.ms_per_scan,
            summary.stats.mean_iterations,
            log.skipped_lines()
        );
        println!(
            "map sharpness: {} cells of 5 cm occupied by the estimate's map, {} by odometry's",
            summary.estimate_cells, summary.odometry_cells
        );
        println!("wrote {}", dir.display());
        for f in &files {
            println!("  {}", f.display());
        }
    }
    Ok(())
}

fn match_command(matcher: MatcherKind) -> Result<()> {
    use std::io::{BufRead, Write};
    let matcher = matcher.build();
    let stdin = std::io::stdin();
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    for line in stdin.lock().lines() {
        let line = line.context("reading stdin")?;
        if line.trim().is_empty() {
            continue;
        }
        writeln!(out, "{}", sim::replay::match_line(&line, matcher.as_ref()))?;
        out.flush()?;
    }
    Ok(())
}

fn run_command(path: PathBuf, out: Option<PathBuf>, seed: Option<u64>, quiet: bool) -> Result<()> {
    let scenario = Scenario::load(&path)?;
    let bar = if quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(scenario.steps.len() as u64).with_style(
            ProgressStyle::with_template(
                "{prefix} [{bar:30}] step {pos}/{len} {elapsed_precise} ETA {eta}",
            )
            .expect("valid template")
            .progress_chars("=> "),
        )
    };
    bar.set_prefix(scenario.name.clone());
    let options = RunOptions {
        seed,
        ..RunOptions::default()
    };
    let record = run_scenario(&scenario, &options, |done, _| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    let dir = out.unwrap_or_else(|| PathBuf::from("out").join(&scenario.name));
    let written = sim::output::write_all(&record, &scenario, &dir)
        .with_context(|| format!("writing the outputs into {}", dir.display()))?;
    if !quiet {
        println!(
            "{}: {:.1} s simulated in {:.3} s ({:.0}x real time), {} scans, {:.2} m driven",
            record.scenario,
            record.sim_seconds(),
            record.wall_seconds,
            record.real_time_factor(),
            record.scans.len(),
            record.distance_m
        );
        println!(
            "final odometry error {:.3} m, {:.2} deg; {} collision(s); seed {}",
            record.final_odometry_error_m(),
            record.final_odometry_error_deg(),
            record.collisions,
            record.seed
        );
        if let Some(loc) = &record.localisation {
            let (final_m, final_deg, rms_m, rms_deg) = sim::output::estimate_errors(&record, loc);
            println!(
                "estimate ({}): final error {final_m:.3} m, {final_deg:.2} deg; RMS {rms_m:.3} m, {rms_deg:.2} deg",
                loc.matcher
            );
        }
        println!("wrote {}", written.dir.display());
        for f in &written.files {
            println!("  {}", f.display());
        }
    }
    Ok(())
}
