//! `twin` — the digital twin of a laser-equipped indoor mobile robot.
//!
//! ```text
//! twin run scenarios/lab-tour.toml [--out DIR] [--seed N]
//! ```

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
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
    }
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
        println!("wrote {}", written.dir.display());
        for f in &written.files {
            println!("  {}", f.display());
        }
    }
    Ok(())
}
