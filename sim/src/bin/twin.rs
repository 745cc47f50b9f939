//! `twin` — the digital twin of a laser-equipped indoor mobile robot.
//!
//! ```text
//! twin run scenarios/lab-tour.toml [--out DIR] [--seed N]
//! twin check scenarios/ [--seeds N]
//! twin map tests/data/mit-csail.clf [--matcher NAME] [--out DIR]
//! twin match --matcher lorentz < tests/data/pairs.jsonl > results.jsonl
//! twin pairs out/lab-tour > pairs.jsonl
//! twin matchers [--pairs 300] [--matchers lorentz,mbicp] [--out DIR]
//! twin view out/survey-lab [--port P]
//! twin serve scenarios/lab-tour.toml --base tcp:127.0.0.1:4001 --laser tcp:127.0.0.1:4003
//! twin drive scenarios/lab-tour.toml --base /dev/ttyUSB0 --laser /dev/ttyUSB2 [--out DIR]
//! twin montecarlo studies/table-5-1.toml [--out DIR] [--threads N] [--shard K/N] [--trials N]
//! twin montecarlo merge DIR... --out DIR
//! twin reconstruct out/survey-lab [--world worlds/lab.toml] [--rule incidence]
//! ```
//!
//! This file only parses the arguments; each command lives in `sim::commands`.

use clap::{Parser, Subcommand};
use sim::commands::{self, CommandError};
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
    Run(commands::run::RunArgs),
    /// Run every scenario of a folder and evaluate its checks; print a table, exit non-zero if
    /// any check fails.
    Check(commands::check::CheckArgs),
    /// Build a 2D map from a recorded log (CARMEN .clf, .script, RobotLogger .log) by chaining
    /// scan matches seeded by its odometry; write the estimate, the odometry, a picture of both
    /// maps and a summary with timings.
    Map(commands::map::MapArgs),
    /// Run the twin in (scaled) real time and offer its devices byte for byte, as the robot's
    /// serial ports would: the base and pan-tilt firmware and the SICK LMS's telegrams, on TCP
    /// ports or pseudo-terminals. Runs until killed (or for --duration).
    Serve(commands::serve::ServeArgs),
    /// Drive a scenario's script on the real robot (or on `twin serve`) through the serial
    /// backend, with the same controller and localisation as `twin run`; write the odometry and
    /// estimate trajectories, the scans, a map picture and a summary.
    Drive(commands::drive::DriveArgs),
    /// Run a Monte Carlo study of the scan matchers (the thesis's Table 5.1 by default): every
    /// matcher on the same twin scan pairs at each outlier rate; resumable, shardable, and
    /// bit-identical whatever the thread count. `twin montecarlo merge DIR... --out DIR` combines
    /// shards.
    Montecarlo(commands::montecarlo::MontecarloArgs),
    /// Rebuild the 3D model of a finished run from its output folder (scans.jsonl and the
    /// poses) — a twin run's or a real robot's drive — and write it as PLY with its figures and
    /// picture; with --world, score it against the true surfaces.
    Reconstruct(commands::reconstruct::ReconstructArgs),
    /// Match scan pairs read as JSON Lines from stdin, one result line per pair on stdout.
    ///
    /// Input: {"ref": {"angle_min", "angle_increment", "range_max", "ranges": [...]}, "cur": {...},
    /// "guess": [x, y, theta]}; output: {"x", "y", "theta", "iterations", "converged" (the answer
    /// can be trusted), "settled", "correspondences", "quality": {"inliers", "inlier_share",
    /// "rms_m", "sigma": [x, y, theta], "sparse", "step": [m, rad]}, "micros"}, or {"error": "..."}
    /// for a malformed line.
    Match(commands::map::MatchArgs),
    /// Compare the scan matchers on the same pairs — the twin's in four worlds at 0 % and 20 %
    /// outliers, its SICK's beams 0.5° and 1° apart, and the SLAM-corrected real logs — and
    /// print success, errors, time and how well each answer's `converged` flag predicts success.
    Matchers(commands::matchers::MatchersArgs),
    /// Write a finished run's consecutive level scans as the pairs `twin match` reads (JSON
    /// Lines on stdout, the guess from odometry): `twin pairs out/lab-tour > pairs.jsonl`.
    Pairs(commands::map::PairsArgs),
    /// Look around a finished run in the browser: the world, the paths, the robot replayed
    /// scan by scan, the 3D model; navigate it with the thesis's keys or a gamepad. Serves the
    /// folder on 127.0.0.1 and prints the address.
    View(commands::view::ViewArgs),
}

fn main() -> ExitCode {
    let outcome: Result<(), CommandError> = match Cli::parse().command {
        Command::Run(args) => commands::run::main(args),
        Command::Check(args) => commands::check::main(args),
        Command::Map(args) => commands::map::map_main(args),
        Command::Serve(args) => commands::serve::main(args),
        Command::Drive(args) => commands::drive::main(args),
        Command::Montecarlo(args) => commands::montecarlo::main(args),
        Command::Reconstruct(args) => commands::reconstruct::main(args),
        Command::Match(args) => commands::map::match_main(args),
        Command::Pairs(args) => commands::map::pairs_main(args),
        Command::Matchers(args) => commands::matchers::main(args),
        Command::View(args) => commands::view::main(args),
    };
    match outcome {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // Every error's message already names its cause (file, line, field, device).
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
