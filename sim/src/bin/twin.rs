//! `twin` — the digital twin of a laser-equipped indoor mobile robot.
//!
//! ```text
//! twin run scenarios/lab-tour.toml [--out DIR] [--seed N]
//! twin check scenarios/
//! twin map tests/data/mit-csail.clf [--matcher NAME] [--out DIR]
//! twin match --matcher lorentz < pairs.jsonl > results.jsonl
//! twin serve scenarios/lab-tour.toml --base tcp:127.0.0.1:4001 --laser tcp:127.0.0.1:4003
//! twin drive scenarios/lab-tour.toml --base /dev/ttyUSB0 --laser /dev/ttyUSB2 [--out DIR]
//! twin montecarlo studies/table-5-1.toml [--out DIR] [--threads N] [--shard K/N]
//! twin montecarlo merge DIR... --out DIR
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
    /// and a map picture; evaluate its checks and fail if one is out of bounds.
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
    /// Run every scenario of a folder and evaluate its checks; print a table, exit non-zero if
    /// any check fails.
    Check {
        /// The folder (e.g. scenarios/).
        dir: PathBuf,
        /// Print only the table and failures.
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
    /// Run the twin in (scaled) real time and offer its devices byte for byte, as the robot's
    /// serial ports would: the base and pan-tilt firmware and the SICK LMS's telegrams, on TCP
    /// ports or pseudo-terminals. Runs until killed (or for --duration).
    Serve {
        /// The scenario file: its world, robot, noise and seed (its script is not run).
        scenario: PathBuf,
        /// Where to offer the base microcontroller: tcp:HOST:PORT (port 0: any free) or pty.
        #[arg(long)]
        base: sim::serve::Offer,
        /// Where to offer the pan-tilt microcontroller (robots with a pan-tilt).
        #[arg(long = "pantilt")]
        pan_tilt: Option<sim::serve::Offer>,
        /// Where to offer the laser.
        #[arg(long)]
        laser: Option<sim::serve::Offer>,
        /// Simulated seconds per wall-clock second.
        #[arg(long, default_value_t = 1.0)]
        speed: f64,
        /// Stop after this many simulated seconds.
        #[arg(long)]
        duration: Option<f64>,
        /// Seed replacing the scenario's.
        #[arg(long)]
        seed: Option<u64>,
        /// Print only the addresses and errors.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Drive a scenario's script on the real robot (or on `twin serve`) through the serial
    /// backend, with the same controller and localisation as `twin run`; write the odometry and
    /// estimate trajectories, the scans, a map picture and a summary.
    Drive {
        /// The scenario file: its script, robot description, pacing and matcher (its world is
        /// only used for the start pose).
        script: PathBuf,
        /// The base microcontroller: a serial device (/dev/ttyUSB0) or tcp:HOST:PORT.
        #[arg(long)]
        base: robot::serial::Endpoint,
        /// The pan-tilt microcontroller, if the scenario positions the head.
        #[arg(long = "pantilt")]
        pan_tilt: Option<robot::serial::Endpoint>,
        /// The laser.
        #[arg(long)]
        laser: robot::serial::Endpoint,
        /// The matcher: ls, lorentz, lorentz-lines or mbicp [default: the scenario's, if any].
        #[arg(long)]
        matcher: Option<MatcherKind>,
        /// Output folder [default: out/drive-SCENARIO-NAME].
        #[arg(long)]
        out: Option<PathBuf>,
        /// How much faster than real time the devices run (the --speed of `twin serve`; 1 on the
        /// real robot).
        #[arg(long, default_value_t = 1.0)]
        time_scale: f64,
        /// Print nothing but errors.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Run a Monte Carlo study of the scan matchers (the thesis's Table 5.1 by default): every
    /// matcher on the same twin scan pairs at each outlier rate; resumable, shardable, and
    /// bit-identical whatever the thread count. `twin montecarlo merge DIR... --out DIR` combines
    /// shards.
    Montecarlo(MontecarloArgs),
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

#[derive(clap::Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
struct MontecarloArgs {
    #[command(subcommand)]
    merge: Option<MontecarloCommand>,
    /// The study file (e.g. studies/table-5-1.toml).
    #[arg(required = true)]
    study: Option<PathBuf>,
    /// Output folder [default: out/montecarlo-STUDY-NAME]; started again with the same folder,
    /// the run finishes the missing trials.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Worker threads (0: all cores).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Run only the trials i with i mod N = K (K counts from 0).
    #[arg(long, default_value = "0/1")]
    shard: sim::montecarlo::Shard,
    /// Run at most this many trials now and stop (run again to go on).
    #[arg(long)]
    max_trials: Option<u64>,
    /// Print nothing but errors.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Subcommand)]
enum MontecarloCommand {
    /// Combine finished shard folders into the files a single run would have written.
    Merge {
        /// The shard folders, one per shard.
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
        /// Where to write the merged results.
        #[arg(long)]
        out: PathBuf,
        /// Print nothing but errors.
        #[arg(long, short)]
        quiet: bool,
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
        Command::Check { dir, quiet } => check_command(dir, quiet),
        Command::Montecarlo(args) => montecarlo_command(args),
        Command::Serve {
            scenario,
            base,
            pan_tilt,
            laser,
            speed,
            duration,
            seed,
            quiet,
        } => serve_command(
            scenario,
            sim::serve::ServeOptions {
                speed,
                base,
                pan_tilt,
                laser,
            },
            duration,
            seed,
            quiet,
        ),
        Command::Drive {
            script,
            base,
            pan_tilt,
            laser,
            matcher,
            out,
            time_scale,
            quiet,
        } => drive_command(
            script, base, pan_tilt, laser, matcher, out, time_scale, quiet,
        ),
    }
}

fn serve_command(
    path: PathBuf,
    options: sim::serve::ServeOptions,
    duration: Option<f64>,
    seed: Option<u64>,
    quiet: bool,
) -> Result<()> {
    if !(options.speed > 0.0 && options.speed <= 1000.0) {
        anyhow::bail!(
            "--speed must be above 0 and at most 1000, found {}",
            options.speed
        );
    }
    let duration = match duration {
        Some(d) if d > 0.0 && d.is_finite() => Some(std::time::Duration::from_secs_f64(d)),
        Some(d) => anyhow::bail!("--duration must be a positive number of seconds, found {d}"),
        None => None,
    };
    let scenario = Scenario::load(&path)?;
    let twin = sim::Twin::new(
        &scenario.world,
        &scenario.robot,
        &scenario.noise,
        seed.unwrap_or(scenario.seed),
    )?;
    let mut server = sim::serve::Server::new(twin, &options)?;
    println!(
        "serving {} ({}) at {}x real time",
        scenario.name, scenario.robot.name, options.speed
    );
    for (device, address) in server.addresses() {
        println!("{device:<9} {address}");
    }
    use std::io::Write as _;
    std::io::stdout().flush()?;
    let stop = std::sync::atomic::AtomicBool::new(false);
    server.run(&stop, duration, |t, line| {
        if !quiet {
            eprintln!("[{t}] {line}");
        }
    });
    if !quiet {
        for (device, stats) in server.stats() {
            println!(
                "{device}: {} connection(s), {} bytes in ({} dropped), {} messages, {} bytes out ({} lost)",
                stats.connections,
                stats.bytes_in,
                stats.bytes_dropped_in,
                stats.messages_in,
                stats.bytes_out,
                stats.bytes_dropped_out
            );
        }
    }
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn drive_command(
    path: PathBuf,
    base: robot::serial::Endpoint,
    pan_tilt: Option<robot::serial::Endpoint>,
    laser: robot::serial::Endpoint,
    matcher: Option<MatcherKind>,
    out: Option<PathBuf>,
    time_scale: f64,
    quiet: bool,
) -> Result<()> {
    use robot::serial::{SerialConfig, SerialRobot};
    if !(time_scale > 0.0 && time_scale <= 1000.0) {
        anyhow::bail!("--time-scale must be above 0 and at most 1000, found {time_scale}");
    }
    let scenario = Scenario::load(&path)?;
    let mut config = SerialConfig::new(base);
    config.pan_tilt = pan_tilt;
    config.laser = Some(laser);
    config.base_baud = scenario.robot.drive.serial_baud;
    if let Some(pt) = &scenario.robot.pan_tilt {
        config.pan_tilt_baud = pt.serial_baud;
    }
    config.laser_baud = scenario.robot.laser.baud;
    config.laser_sweep = std::time::Duration::from_secs_f64(scenario.robot.laser.sweep_s.get());
    config.laser_range_max_mm = (scenario.robot.laser.range_max_m.get() * 1000.0).round() as u16;
    let clock: std::sync::Arc<dyn robot::Clock> =
        std::sync::Arc::new(sim::serve::WallClock::new(time_scale));
    let mut robot = SerialRobot::open(config, clock).context("opening the robot's devices")?;
    let bar = step_bar(quiet, scenario.steps.len());
    bar.set_prefix(format!("drive {}", scenario.name));
    let result = sim::drive::drive_scenario(&mut robot, &scenario, matcher, |done, _| {
        bar.set_position(done as u64)
    });
    bar.finish_and_clear();
    let events: Vec<String> = robot
        .take_events()
        .iter()
        .map(ToString::to_string)
        .collect();
    if !quiet {
        for e in &events {
            eprintln!("{e}");
        }
    }
    let record = result?;
    let dir = out.unwrap_or_else(|| PathBuf::from("out").join(format!("drive-{}", scenario.name)));
    let files = sim::drive::write_drive(&record, &scenario, events.clone(), &dir)
        .with_context(|| format!("writing the outputs into {}", dir.display()))?;
    if !quiet {
        let p = record.final_odometry;
        println!(
            "{}: {} steps, {} scans in {:.1} s; final odometry ({:.3} m, {:.3} m, {:.2} deg); {} link event(s)",
            record.scenario,
            record.steps,
            record.scans.len(),
            record.wall_seconds,
            p.x,
            p.y,
            p.theta.to_degrees(),
            events.len()
        );
        if let Some((kind, placed, _)) = &record.localisation
            && let Some(last) = placed.last()
        {
            let e = last.estimate;
            println!(
                "estimate ({kind}): ({:.3} m, {:.3} m, {:.2} deg)",
                e.x,
                e.y,
                e.theta.to_degrees()
            );
        }
        println!("wrote {}", dir.display());
        for f in &files {
            println!("  {}", f.display());
        }
    }
    Ok(())
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
    let bar = step_bar(quiet, scenario.steps.len());
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
    let report = sim::checks::evaluate(&scenario, &record);
    if !report.outcomes.is_empty() && (!quiet || !report.passed()) {
        print!("{report}");
    }
    let failed = report.failures().count();
    if failed > 0 {
        anyhow::bail!(
            "{}: {failed} of {} check(s) failed",
            path.display(),
            report.outcomes.len()
        );
    }
    Ok(())
}

fn check_command(dir: PathBuf, quiet: bool) -> Result<()> {
    use rayon::prelude::*;
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    if files.is_empty() {
        anyhow::bail!(
            "{}: no scenario files (*.toml) in this folder",
            dir.display()
        );
    }
    let bar = if quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(files.len() as u64).with_style(
            ProgressStyle::with_template(
                "check [{bar:30}] {pos}/{len} scenarios {elapsed_precise}",
            )
            .expect("valid template")
            .progress_chars("=> "),
        )
    };
    // Per file: its check report and wall seconds, or why it could not run.
    type Outcome = Result<(sim::checks::CheckReport, f64), String>;
    let results: Vec<(PathBuf, Outcome)> = files
        .par_iter()
        .map(|path| {
            let started = std::time::Instant::now();
            let outcome = Scenario::load(path)
                .map_err(|e| e.to_string())
                .and_then(|scenario| {
                    let record = run_scenario(&scenario, &RunOptions::default(), |_, _| {})
                        .map_err(|e| e.to_string())?;
                    Ok((
                        sim::checks::evaluate(&scenario, &record),
                        started.elapsed().as_secs_f64(),
                    ))
                });
            bar.inc(1);
            (path.clone(), outcome)
        })
        .collect();
    bar.finish_and_clear();
    println!("| scenario | checks | passed | failed | seconds |");
    println!("|---|---|---|---|---|");
    let mut failed = 0;
    for (path, result) in &results {
        let name = path.file_stem().map_or("?".into(), |s| s.to_string_lossy());
        match result {
            Ok((report, seconds)) => {
                let bad = report.failures().count();
                failed += usize::from(bad > 0);
                println!(
                    "| {name} | {} | {} | {bad} | {seconds:.1} |",
                    report.outcomes.len(),
                    report.outcomes.len() - bad
                );
            }
            Err(_) => {
                failed += 1;
                println!("| {name} | - | - | error | - |");
            }
        }
    }
    for (path, result) in &results {
        match result {
            Ok((report, _)) if !report.passed() => {
                println!();
                print!("{report}");
            }
            Err(e) => println!("\n{}: {e}", path.display()),
            _ => {}
        }
    }
    if failed > 0 {
        anyhow::bail!("{failed} of {} scenario(s) failed", results.len());
    }
    Ok(())
}

fn montecarlo_command(args: MontecarloArgs) -> Result<()> {
    use sim::montecarlo::{RunOptions, merge, run_study};
    if let Some(MontecarloCommand::Merge { dirs, out, quiet }) = args.merge {
        let (summary, files) = merge(&dirs, &out)?;
        if !quiet {
            print!("{}", summary.table());
            println!("merged {} shard folders into {}", dirs.len(), out.display());
            for f in &files {
                println!("  {}", f.display());
            }
        }
        return Ok(());
    }
    let path = args
        .study
        .expect("clap requires the study without a subcommand");
    let study = sim::config::Study::load(&path)?;
    let dir = args
        .out
        .unwrap_or_else(|| sim::montecarlo::default_dir(&study));
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(0).with_style(
            ProgressStyle::with_template(
                "{prefix} [{bar:30}] {pos}/{len} trials {per_sec} ETA {eta}",
            )
            .expect("valid template")
            .progress_chars("=> "),
        )
    };
    bar.set_prefix(format!("{} (shard {})", study.name, args.shard));
    let options = RunOptions {
        threads: args.threads,
        shard: args.shard,
        max_trials: args.max_trials,
    };
    let report = run_study(&study, &dir, &options, |done, total| {
        bar.set_length(total);
        bar.set_position(done);
    })?;
    bar.finish_and_clear();
    if args.quiet {
        return Ok(());
    }
    if report.resumed > 0 {
        println!(
            "resumed: {} trials were already done in {}",
            report.resumed,
            dir.display()
        );
    }
    let rate = report.ran as f64 / report.wall_seconds.max(1e-9);
    println!(
        "{} trials run in {:.1} s ({rate:.0} trials/s, {} matchers each)",
        report.ran,
        report.wall_seconds,
        study.matchers.len()
    );
    match &report.summary {
        Some(summary) => {
            print!("{}", summary.table());
            println!("wrote {}", dir.display());
            for f in &report.files {
                println!("  {}", f.display());
            }
        }
        None => println!(
            "{} of {} trials of shard {} done; run the same command again to go on",
            report.resumed + report.ran,
            report.owned,
            args.shard
        ),
    }
    Ok(())
}

/// The progress bar of a scripted run: steps done, elapsed time and ETA (hidden when quiet).
fn step_bar(quiet: bool, steps: usize) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    ProgressBar::new(steps as u64).with_style(
        ProgressStyle::with_template(
            "{prefix} [{bar:30}] step {pos}/{len} {elapsed_precise} ETA {eta}",
        )
        .expect("valid template")
        .progress_chars("=> "),
    )
}
