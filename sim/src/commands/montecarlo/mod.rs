//! `twin montecarlo`: the thesis's scan-matching study (§5.2, Table 5.1) as a parallel,
//! deterministic, resumable and shardable Monte Carlo run.
//!
//! A **trial** is one scan pair: a random start pose in free space, one motion (advance or retreat,
//! or a turn) driven by the twin's drive model — firmware, motors, slip — so the odometry guess
//! carries real slip error, then a scan before and a scan after with uniform outliers at the
//! trial's rate, and every matcher of the study on that pair from the same odometry guess, its
//! answer compared with the twin's ground truth.
//!
//! Trial `i` draws everything from the substream `i` of the study's seed, so a trial's result
//! depends on the study and `i` only: not on the thread that ran it, the order, the shard or an
//! interruption. Trials `0 .. trials_per_rate` use the first rate, the next block the second,
//! and so on.
//!
//! The run keeps a log in `DIR/progress/` (each finished trial's rows, appended and flushed chunk
//! by chunk): started again with the same DIR it keeps the complete trials, drops a torn last
//! line or a half-written trial, and runs only what is missing. `--shard K/N` runs the trials
//! `i` with `i mod N = K`; [`merge`] combines shards into the files one run would have written.
//!
//! `trials.csv`, `summary.json`, `table.md` and `errors.svg` depend on the study only, so they are
//! byte-identical whatever the threads, shards or interruptions; the wall-clock time of each match
//! goes to `timings.csv` beside them, which naturally differs from run to run.

pub mod navigation;
pub mod pairs;
mod report;

pub use report::{CellStats, Summary, write_reports};

use crate::commands::montecarlo::pairs::{PairMaker, ScanPair};
use crate::config::Outliers;
use crate::config::Study;
use crate::rng::{self, SimRng};
use crate::twin::Twin;
use crate::twin::sim_robot::{GroundTruth, SimError, SimRobot};
use rand::RngExt;
use rayon::prelude::*;
use robot::Pose2;
use robot::control::Step;
use robot::geometry::wrap_angle;
use robot::hardware::{DriveBase, DriveCommand, DriveWait};
use robot::localization::MatcherKind;
use robot::odometry::Odometer;
use robot::protocol::base::DriveLine;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The header of `trials.csv`.
pub const TRIALS_HEADER: &str = "trial,seed,rate,matcher,motion,true_x,true_y,true_theta,guess_x,guess_y,guess_theta,est_x,est_y,est_theta,e_theta_deg,e_t_mm,iterations,converged";
/// The header of `timings.csv`.
pub const TIMINGS_HEADER: &str = "trial,matcher,micros";

/// Why a study cannot run or merge.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// Reading or writing the output folder failed.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// What failed.
        #[source]
        source: std::io::Error,
    },
    /// The folder holds another study's results.
    #[error(
        "{dir} holds results of a different study (its study.toml differs from {study}); use another --out"
    )]
    OtherStudy {
        /// The folder.
        dir: PathBuf,
        /// The study given.
        study: PathBuf,
    },
    /// The folder was started with another shard.
    #[error("{dir} holds shard {found} of the study, not {given}")]
    OtherShard {
        /// The folder.
        dir: PathBuf,
        /// Its shard.
        found: String,
        /// The one given.
        given: String,
    },
    /// A trial could not be driven on the twin.
    #[error("trial {trial}: {message}")]
    Trial {
        /// The trial.
        trial: u64,
        /// What went wrong.
        message: String,
    },
    /// The worker threads cannot start.
    #[error("cannot start the worker threads: {0}")]
    Threads(String),
    /// Shards that do not make a whole study.
    #[error("cannot merge: {0}")]
    Merge(String),
    /// A results file that does not read.
    #[error("{path}:{line}: {message}")]
    BadRow {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
}

fn io_error(path: &Path) -> impl FnOnce(std::io::Error) -> StudyError + '_ {
    move |source| StudyError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Which share of the trials a run takes: those `i` with `i mod count = index`.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This shard's number, `0..count`.
    pub index: u64,
    /// How many shards.
    pub count: u64,
}

impl Shard {
    /// The whole study.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// Whether trial `i` is this shard's.
    pub fn owns(&self, i: u64) -> bool {
        i % self.count == self.index
    }

    /// This shard's trials of `0..total`, in order, computed as they are asked for (a study
    /// of 10⁹ trials costs no memory).
    pub fn trials(self, total: u64) -> impl Iterator<Item = u64> + Clone {
        (self.index..total).step_by(self.count.max(1) as usize)
    }

    /// How many of `0..total` are this shard's.
    pub fn count_of(&self, total: u64) -> u64 {
        total.saturating_sub(self.index).div_ceil(self.count.max(1))
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl std::str::FromStr for Shard {
    type Err = String;

    /// ```
    /// use sim::commands::montecarlo::Shard;
    /// assert_eq!("2/8".parse(), Ok(Shard { index: 2, count: 8 }));
    /// assert!("8/8".parse::<Shard>().is_err());
    /// ```
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || format!("`{s}` is not a shard: expected K/N with 0 <= K < N (e.g. 0/4)");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count): (u64, u64) = (
            k.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

/// The motion of a trial.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Motion {
    /// Straight, metres (negative: retreat).
    Straight(f64),
    /// In place, degrees (positive: left).
    Turn(f64),
}

impl Motion {
    fn label(&self) -> String {
        match *self {
            Motion::Straight(m) if m >= 0.0 => format!("advance {m}"),
            Motion::Straight(m) => format!("retreat {}", -m),
            Motion::Turn(d) if d >= 0.0 => format!("left {d}"),
            Motion::Turn(d) => format!("right {}", -d),
        }
    }

    fn step(&self) -> Step {
        match *self {
            Motion::Straight(metres) => Step::Move { metres },
            Motion::Turn(degrees) => Step::Turn { degrees },
        }
    }
}

/// One matcher's answer on a trial's pair.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    /// The matcher.
    pub matcher: MatcherKind,
    /// Its estimate of the current laser frame in the reference frame.
    pub estimate: Pose2,
    /// Iterations.
    pub iterations: u32,
    /// Converged before the cap.
    pub converged: bool,
    /// Wall-clock microseconds of the match (machine-dependent).
    pub micros: f64,
}

/// One trial: the pair's truth, the odometry guess and every matcher's answer.
#[derive(Clone, Debug, PartialEq)]
pub struct Trial {
    /// The trial's number.
    pub index: u64,
    /// The seed of its twin.
    pub seed: u64,
    /// Its outlier rate.
    pub rate: f64,
    /// The motion driven.
    pub motion: Motion,
    /// The true pose of the second laser frame in the first.
    pub truth: Pose2,
    /// The same from odometry: the guess every matcher starts from.
    pub guess: Pose2,
    /// The answers, in the study's matcher order.
    pub outcomes: Vec<Outcome>,
}

impl Trial {
    /// The trial's rows of `trials.csv`, one per matcher.
    pub fn rows(&self) -> String {
        let mut out = String::new();
        for o in &self.outcomes {
            let (e_theta, e_t) = errors(&self.truth, &o.estimate);
            let _ = writeln!(
                out,
                "{},{},{},{},{},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{},{}",
                self.index,
                self.seed,
                self.rate,
                o.matcher,
                self.motion.label(),
                self.truth.x,
                self.truth.y,
                self.truth.theta,
                self.guess.x,
                self.guess.y,
                self.guess.theta,
                o.estimate.x,
                o.estimate.y,
                o.estimate.theta,
                e_theta,
                e_t,
                o.iterations,
                u8::from(o.converged)
            );
        }
        out
    }

    /// The trial's rows of `timings.csv`.
    pub fn timing_rows(&self) -> String {
        let mut out = String::new();
        for o in &self.outcomes {
            let _ = writeln!(out, "{},{},{:.1}", self.index, o.matcher, o.micros);
        }
        out
    }
}

/// Heading error in degrees and translation error in millimetres of `estimate` against `truth`.
pub fn errors(truth: &Pose2, estimate: &Pose2) -> (f64, f64) {
    (
        wrap_angle(estimate.theta - truth.theta).abs().to_degrees(),
        (estimate.x - truth.x).hypot(estimate.y - truth.y) * 1e3,
    )
}

/// What a study needs to run trials: one pair maker per outlier rate.
pub struct Trials<'a> {
    study: &'a Study,
    makers: Vec<PairMaker>,
    stream: u64,
}

impl<'a> Trials<'a> {
    /// Prepares `study`'s trials.
    pub fn new(study: &'a Study) -> Self {
        // The study's laser noise replaces the robot file's.
        let mut robot = study.robot.clone();
        robot.laser.sigma_m = crate::config::values::Sigma(study.noise.laser_sigma_m);
        let makers = study
            .outlier_rates
            .iter()
            .map(|&uniform| {
                PairMaker::new(
                    &study.world,
                    &robot,
                    Outliers {
                        uniform,
                        ..Outliers::NONE
                    },
                )
            })
            .collect();
        Trials {
            study,
            makers,
            stream: rng::stream_seed(study.seed, "montecarlo"),
        }
    }

    /// Trial `index`'s scan pair and the odometry guess its matchers start from, without
    /// matching: its twin's seed, the motion driven, the pair and the guess.
    pub fn pair(&self, index: u64) -> Result<(u64, Motion, ScanPair, Pose2), StudyError> {
        let study = self.study;
        let maker = &self.makers[self.rate_index(index).min(self.makers.len() - 1)];
        let mut rng: SimRng = rng::substream(self.stream, index);
        let seed: u64 = rng.random();
        let fail = |message: String| StudyError::Trial {
            trial: index,
            message,
        };
        let start = maker
            .free_pose(study.clearance_m, &mut rng)
            .map_err(|why| fail(format!("{why}: lower the study's clearance_m")))?;
        let motion = draw_motion(study, &mut rng);
        let (odometry, rest) =
            drive(study, start, motion, seed).map_err(|e| fail(e.to_string()))?;
        let pair = maker.pair(start, rest, &mut rng);
        let mount = study.robot.laser_mount();
        let guess = start.compose(&mount).relative(&odometry.compose(&mount));
        Ok((seed, motion, pair, guess))
    }

    /// Which of the study's outlier rates trial `index` runs at (its trials come rate by rate).
    fn rate_index(&self, index: u64) -> usize {
        (index / self.study.trials_per_rate) as usize
    }

    /// Runs trial `index`.
    pub fn run(&self, index: u64) -> Result<Trial, StudyError> {
        let study = self.study;
        let rate_index = self.rate_index(index);
        let (seed, motion, pair, guess) = self.pair(index)?;
        let outcomes = study
            .matchers
            .iter()
            .map(|&kind| {
                let matcher = kind.build();
                let clock = Instant::now();
                let result = matcher.match_scans(&pair.reference, &pair.current, guess);
                Outcome {
                    matcher: kind,
                    estimate: result.pose,
                    iterations: result.iterations,
                    converged: result.converged,
                    micros: clock.elapsed().as_secs_f64() * 1e6,
                }
            })
            .collect();
        Ok(Trial {
            index,
            seed,
            rate: study.outlier_rates[rate_index.min(study.outlier_rates.len() - 1)],
            motion,
            truth: pair.truth,
            guess,
            outcomes,
        })
    }
}

fn draw_motion(study: &Study, rng: &mut SimRng) -> Motion {
    let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
    let straight = match (study.motion.advance_m > 0.0, study.motion.turn_deg > 0.0) {
        (true, true) => rng.random::<bool>(),
        (straight, _) => straight,
    };
    if straight {
        Motion::Straight(sign * study.motion.advance_m)
    } else {
        Motion::Turn(sign * study.motion.turn_deg)
    }
}

/// Drives `motion` from `start` on a twin seeded `seed`; returns the odometry at rest and the
/// true pose once the wheels have stopped coasting.
fn drive(study: &Study, start: Pose2, motion: Motion, seed: u64) -> Result<(Pose2, Pose2), String> {
    let mut world = study.world.clone();
    world.start = start;
    let twin = Twin::new(&world, &study.robot, &study.noise, seed).map_err(|e| e.to_string())?;
    let mut robot = SimRobot::new(twin, study.robot.drive.serial_baud);
    let geometry = study.robot.geometry();
    let Some(DriveLine::Command(command)) = motion
        .step()
        .to_line(&geometry)
        .map_err(|e| e.to_string())?
    else {
        return Err(format!("{motion:?} is not a motion command"));
    };
    let sim = |e: SimError| e.to_string();
    robot
        .drive(DriveCommand::Ramp(robot::hardware::Ramp::POWER_ON))
        .map_err(sim)?;
    robot.drive(command).map_err(sim)?;
    let mut odometer = Odometer::new(geometry, start);
    odometer.commanded(&command);
    let mut status = robot.drive_status().map_err(sim)?;
    for _ in 0..20 {
        if status.is_idle() {
            break;
        }
        robot.wait_drive(DriveWait::motors(10_000)).map_err(sim)?;
        status = robot.drive_status().map_err(sim)?;
    }
    if !status.is_idle() {
        return Err("the motion did not end in 200 s".into());
    }
    let odometry = odometer.observe(&status);
    robot.wait_drive(DriveWait::sleep(100)).map_err(sim)?;
    Ok((odometry, robot.true_pose()))
}

/// How a run goes.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Worker threads (0: all cores).
    pub threads: usize,
    /// Which trials.
    pub shard: Shard,
    /// Run at most this many trials now, then stop (resumable later).
    pub max_trials: Option<u64>,
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            threads: 0,
            shard: Shard::WHOLE,
            max_trials: None,
        }
    }
}

/// What a run did (`S`: what its finished results are summarised by).
#[derive(Clone, Debug)]
pub struct RunReport<S = Summary> {
    /// Trials of this shard.
    pub owned: u64,
    /// Trials found done in DIR before the run.
    pub resumed: u64,
    /// Trials run now.
    pub ran: u64,
    /// Wall-clock seconds of the trials run now.
    pub wall_seconds: f64,
    /// The summary, once every trial of the shard is done.
    pub summary: Option<S>,
    /// The files written, once done.
    pub files: Vec<PathBuf>,
}

/// Trials run between two flushes of the log, per worker thread.
const CHUNK_PER_THREAD: usize = 16;

/// Runs (or resumes) `study` into `dir`. `progress(done, total)` is called as trials finish.
pub fn run_study(
    study: &Study,
    dir: &Path,
    options: &RunOptions,
    mut progress: impl FnMut(u64, u64),
) -> Result<RunReport, StudyError> {
    let progress_dir = dir.join("progress");
    std::fs::create_dir_all(&progress_dir).map_err(io_error(&progress_dir))?;
    claim(dir, (&study.text, &study.path), options.shard)?;
    let mut log = Log::open(&progress_dir, study)?;
    let done = log.done.clone();
    let shard = options.shard;
    let (owned, resumed, missing, pool) = plan(options, study.total_trials(), &done)?;
    let mut missing = missing.peekable();
    let trials = Trials::new(study);
    let chunk = CHUNK_PER_THREAD * pool.current_num_threads();
    let started = Instant::now();
    let mut finished = resumed;
    let mut ran = 0;
    progress(finished, owned);
    while missing.peek().is_some() {
        let indices: Vec<u64> = missing.by_ref().take(chunk).collect();
        let results: Vec<Result<Trial, StudyError>> =
            pool.install(|| indices.par_iter().map(|&i| trials.run(i)).collect());
        let results: Vec<Trial> = results.into_iter().collect::<Result<_, _>>()?;
        log.append(&results)?;
        finished += results.len() as u64;
        ran += results.len() as u64;
        progress(finished, owned);
    }
    let wall_seconds = started.elapsed().as_secs_f64();
    let mut report = RunReport {
        owned,
        resumed,
        ran,
        wall_seconds,
        summary: None,
        files: Vec::new(),
    };
    if finished == owned {
        let (summary, files) = finish(study, dir, &progress_dir, shard)?;
        report.summary = Some(summary);
        report.files = files;
    }
    Ok(report)
}

/// A shard's plan: the trials of `0..total` it owns, how many of them `done` holds, those
/// missing (at most `max_trials`), and a pool of the options' threads. The trials are never
/// listed: memory follows the trials run, not the study's size.
fn plan<'a>(
    options: &RunOptions,
    total: u64,
    done: &'a BTreeSet<u64>,
) -> Result<(u64, u64, impl Iterator<Item = u64> + 'a, rayon::ThreadPool), StudyError> {
    let shard = options.shard;
    let owned = shard.count_of(total);
    let resumed = done.iter().filter(|&&i| i < total && shard.owns(i)).count() as u64;
    let missing = shard
        .trials(total)
        .filter(move |i| !done.contains(i))
        .take(options.max_trials.map_or(usize::MAX, |m| m as usize));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(options.threads)
        .build()
        .map_err(|e| StudyError::Threads(e.to_string()))?;
    Ok((owned, resumed, missing, pool))
}

/// Records which study (and shard) `dir` holds, or checks it is the same.
fn claim(dir: &Path, (text, path): (&str, &Path), shard: Shard) -> Result<(), StudyError> {
    let study_file = dir.join("study.toml");
    match std::fs::read_to_string(&study_file) {
        Ok(found) if found != text => {
            return Err(StudyError::OtherStudy {
                dir: dir.to_path_buf(),
                study: path.to_path_buf(),
            });
        }
        Ok(_) => {}
        Err(_) => std::fs::write(&study_file, text).map_err(io_error(&study_file))?,
    }
    let origin = dir.join("study-path");
    let path = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    std::fs::write(&origin, format!("{}\n", path.display())).map_err(io_error(&origin))?;
    let shard_file = dir.join("shard");
    match std::fs::read_to_string(&shard_file) {
        Ok(text) if text.trim() != shard.to_string() => Err(StudyError::OtherShard {
            dir: dir.to_path_buf(),
            found: text.trim().to_string(),
            given: shard.to_string(),
        }),
        Ok(_) => Ok(()),
        Err(_) => std::fs::write(&shard_file, format!("{shard}\n")).map_err(io_error(&shard_file)),
    }
}

/// The progress log: `trials.log` (rows of finished trials) and `timings.log`.
struct Log {
    trials: std::fs::File,
    timings: std::fs::File,
    trials_path: PathBuf,
    timings_path: PathBuf,
    done: BTreeSet<u64>,
}

impl Log {
    /// Opens the log, keeping only complete trials (a torn line or a half-written trial from an
    /// interrupted run is dropped, and that trial runs again).
    fn open(dir: &Path, study: &Study) -> Result<Log, StudyError> {
        let trials_path = dir.join("trials.log");
        let timings_path = dir.join("timings.log");
        let rows = read_lines(&trials_path)?;
        let mut by_trial: BTreeMap<u64, Vec<String>> = BTreeMap::new();
        // A row whose checksum does not match was changed after it was written: its trial
        // runs again, like a torn one.
        let mut broken = BTreeSet::new();
        for line in rows {
            match verified(&line) {
                Some(row) => {
                    if let Some(index) = complete_row(row, study) {
                        by_trial.entry(index).or_default().push(line);
                    }
                }
                None => {
                    broken.insert(trial_of(&line));
                }
            }
        }
        by_trial.retain(|index, _| !broken.contains(index));
        let names: Vec<String> = study.matchers.iter().map(ToString::to_string).collect();
        by_trial.retain(|_, lines| {
            lines.len() == names.len()
                && lines
                    .iter()
                    .zip(&names)
                    .all(|(l, n)| l.split(',').nth(3) == Some(n.as_str()))
        });
        let done: BTreeSet<u64> = by_trial.keys().copied().collect();
        let mut timings: BTreeMap<(u64, String), String> = BTreeMap::new();
        for line in read_lines(&timings_path)? {
            let Some(row) = verified(&line) else { continue };
            let fields: Vec<&str> = row.split(',').collect();
            if let [trial, matcher, micros] = fields[..]
                && let Ok(trial) = trial.parse::<u64>()
                && micros.parse::<f64>().is_ok()
                && done.contains(&trial)
            {
                timings.insert((trial, matcher.to_string()), line.clone());
            }
        }
        // Rewrite both logs with what is kept, then append.
        let kept: String = by_trial
            .values()
            .flatten()
            .map(|l| format!("{l}\n"))
            .collect();
        write_atomically(&trials_path, kept.as_bytes())?;
        let kept: String = timings.values().map(|l| format!("{l}\n")).collect();
        write_atomically(&timings_path, kept.as_bytes())?;
        let append = |path: &Path| {
            std::fs::OpenOptions::new()
                .append(true)
                .open(path)
                .map_err(io_error(path))
        };
        Ok(Log {
            trials: append(&trials_path)?,
            timings: append(&timings_path)?,
            trials_path,
            timings_path,
            done,
        })
    }

    /// Appends finished trials: timings first, so a trial's rows are never on record without
    /// them; each file flushed to disk.
    fn append(&mut self, trials: &[Trial]) -> Result<(), StudyError> {
        let timings: String = trials.iter().map(|t| sealed(&t.timing_rows())).collect();
        let rows: String = trials.iter().map(|t| sealed(&t.rows())).collect();
        self.timings
            .write_all(timings.as_bytes())
            .and_then(|()| self.timings.sync_data())
            .map_err(io_error(&self.timings_path))?;
        self.trials
            .write_all(rows.as_bytes())
            .and_then(|()| self.trials.sync_data())
            .map_err(io_error(&self.trials_path))?;
        self.done.extend(trials.iter().map(|t| t.index));
        Ok(())
    }
}

/// Each line of `rows` with its checksum appended: `row;checksum` (16 hex digits).
fn sealed(rows: &str) -> String {
    rows.lines()
        .map(|row| format!("{row};{:016x}\n", checksum(row)))
        .collect()
}

/// The row of a sealed log line, if its checksum matches.
fn verified(line: &str) -> Option<&str> {
    let (row, sum) = line.rsplit_once(';')?;
    (u64::from_str_radix(sum, 16).ok()? == checksum(row) && sum.len() == 16).then_some(row)
}

/// FNV-1a, 64 bits: enough to catch a changed or garbled row.
fn checksum(row: &str) -> u64 {
    row.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// The lines of a file (none if it does not exist); a last line without its newline is torn.
fn read_lines(path: &Path) -> Result<Vec<String>, StudyError> {
    let text = match std::fs::read(path) {
        Ok(bytes) => bytes,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(io_error(path)(e)),
    };
    let complete = text.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
    Ok(String::from_utf8_lossy(&text[..complete])
        .lines()
        .map(str::to_string)
        .collect())
}

/// The trial number a results line starts with (`u64::MAX` when it has none, which no study
/// owns).
fn trial_of(line: &str) -> u64 {
    line.split(',')
        .next()
        .and_then(|f| f.parse().ok())
        .unwrap_or(u64::MAX)
}

/// The trial number of a well-formed row of `study`, or `None`.
fn complete_row(line: &str, study: &Study) -> Option<u64> {
    let fields: Vec<&str> = line.split(',').collect();
    if fields.len() != TRIALS_HEADER.split(',').count() {
        return None;
    }
    let index: u64 = fields[0].parse().ok()?;
    if index >= study.total_trials() || !study.matchers.iter().any(|m| m.name() == fields[3]) {
        return None;
    }
    fields[5..16]
        .iter()
        .all(|f| f.parse::<f64>().is_ok())
        .then_some(index)
}

fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), StudyError> {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, bytes).map_err(io_error(&tmp))?;
    std::fs::rename(&tmp, path).map_err(io_error(path))
}

/// Writes the final files of the trials `owned` from the log.
fn finish(
    study: &Study,
    dir: &Path,
    progress_dir: &Path,
    shard: Shard,
) -> Result<(Summary, Vec<PathBuf>), StudyError> {
    let owned = |index: u64| index < study.total_trials() && shard.owns(index);
    let mut rows: BTreeMap<u64, Vec<String>> = BTreeMap::new();
    for line in read_lines(&progress_dir.join("trials.log"))? {
        let Some(line) = verified(&line) else {
            continue;
        };
        let index = trial_of(line);
        if owned(index) {
            rows.entry(index).or_default().push(line.to_string());
        }
    }
    let mut timings: BTreeMap<u64, Vec<String>> = BTreeMap::new();
    for line in read_lines(&progress_dir.join("timings.log"))? {
        let Some(line) = verified(&line) else {
            continue;
        };
        let index = trial_of(line);
        timings.entry(index).or_default().push(line.to_string());
    }
    write_results(study, dir, rows, timings)
}

/// Writes `trials.csv`, `timings.csv` and the reports from rows grouped by trial.
fn write_results(
    study: &Study,
    dir: &Path,
    rows: BTreeMap<u64, Vec<String>>,
    timings: BTreeMap<u64, Vec<String>>,
) -> Result<(Summary, Vec<PathBuf>), StudyError> {
    let trials_path = dir.join("trials.csv");
    let mut text = format!("{TRIALS_HEADER}\n");
    for lines in rows.values() {
        for l in lines {
            text.push_str(l);
            text.push('\n');
        }
    }
    write_atomically(&trials_path, text.as_bytes())?;
    let timings_path = dir.join("timings.csv");
    let mut t = format!("{TIMINGS_HEADER}\n");
    for (index, lines) in &timings {
        if rows.contains_key(index) {
            for l in lines {
                t.push_str(l);
                t.push('\n');
            }
        }
    }
    write_atomically(&timings_path, t.as_bytes())?;
    let records = report::parse_rows(&trials_path, &text)?;
    let summary = Summary::of(study, &records);
    let mut files = vec![trials_path, timings_path];
    files.extend(write_reports(study, &summary, &records, dir)?);
    Ok((summary, files))
}

/// Combines the shard folders `dirs` (each complete) into `out`, writing the same `trials.csv`,
/// `summary.json`, `table.md` and `errors.svg` a single run would have written.
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<(Summary, Vec<PathBuf>), StudyError> {
    let first = dirs
        .first()
        .ok_or_else(|| StudyError::Merge("name at least one shard folder".into()))?;
    let study_path = first.join("study.toml");
    let text = std::fs::read_to_string(&study_path).map_err(io_error(&study_path))?;
    let mut rows: BTreeMap<u64, Vec<String>> = BTreeMap::new();
    let mut timings: BTreeMap<u64, Vec<String>> = BTreeMap::new();
    for (dir, lines) in read_shards(dirs, &text, "trials.csv", TRIALS_HEADER)? {
        for line in lines {
            rows.entry(trial_of(&line)).or_default().push(line);
        }
        for line in read_lines(&dir.join("timings.csv"))?.into_iter().skip(1) {
            timings.entry(trial_of(&line)).or_default().push(line);
        }
    }
    // The copy's relative paths (world, robot) resolve from the study's own folder: load the
    // study from where the shards' run recorded it, and check it is still the same text.
    let origin_path = first.join("study-path");
    let origin = std::fs::read_to_string(&origin_path).map_err(io_error(&origin_path))?;
    let mut study = Study::load(origin.trim()).map_err(|e| StudyError::Merge(e.to_string()))?;
    // Shards of a smaller study (`--trials N`) carry the rewritten count.
    if let Some(n) = count_in(&text, "trials_per_rate")
        && n != study.trials_per_rate
    {
        study = study.with_trials_per_rate(n);
    }
    if study.text != text {
        return Err(StudyError::Merge(format!(
            "{} has changed since the shards ran",
            origin.trim()
        )));
    }
    std::fs::create_dir_all(out).map_err(io_error(out))?;
    robot::logs::write_file(out.join("study.toml"), &text).map_err(io_error(out))?;
    let expected = study.total_trials();
    if rows.len() as u64 != expected {
        return Err(StudyError::Merge(format!(
            "the shards hold {} trials, the study has {expected}",
            rows.len()
        )));
    }
    write_results(&study, out, rows, timings)
}

/// The finished shard folders `dirs` of the study whose text is `text`: each folder with the
/// rows of its `results` file (after the `header`). Refuses a folder of another study, shards of
/// different counts, a shard given twice, an unfinished shard and a row of another shard's
/// trial, and names the shards missing.
fn read_shards(
    dirs: &[PathBuf],
    text: &str,
    results: &str,
    header: &str,
) -> Result<Vec<(PathBuf, Vec<String>)>, StudyError> {
    let first = dirs
        .first()
        .ok_or_else(|| StudyError::Merge("name at least one shard folder".into()))?;
    let mut shards = BTreeSet::new();
    let mut count = None;
    let mut found = Vec::new();
    for dir in dirs {
        let path = dir.join("study.toml");
        let other = std::fs::read_to_string(&path).map_err(io_error(&path))?;
        if other != text {
            return Err(StudyError::Merge(format!(
                "{} holds another study than {}",
                dir.display(),
                first.display()
            )));
        }
        let path = dir.join("shard");
        let shard: Shard = std::fs::read_to_string(&path)
            .map_err(io_error(&path))?
            .trim()
            .parse()
            .map_err(StudyError::Merge)?;
        if *count.get_or_insert(shard.count) != shard.count {
            return Err(StudyError::Merge(format!(
                "{} is shard {shard}, the others are of {}",
                dir.display(),
                count.unwrap_or(0)
            )));
        }
        if !shards.insert(shard.index) {
            return Err(StudyError::Merge(format!("shard {shard} is given twice")));
        }
        let path = dir.join(results);
        let mut lines = read_lines(&path)?;
        if lines.first().map(String::as_str) != Some(header) {
            return Err(StudyError::Merge(format!(
                "{} is missing or not finished (run the shard to its end first)",
                path.display()
            )));
        }
        lines.remove(0);
        if let Some(index) = lines.iter().map(|l| trial_of(l)).find(|&i| !shard.owns(i)) {
            return Err(StudyError::Merge(format!(
                "{} has trial {index}, which is not shard {shard}'s",
                path.display()
            )));
        }
        found.push((dir.clone(), lines));
    }
    let count = count.unwrap_or(1);
    if shards.len() as u64 != count {
        let missing: Vec<String> = (0..count)
            .filter(|k| !shards.contains(k))
            .map(|k| format!("{k}/{count}"))
            .collect();
        return Err(StudyError::Merge(format!(
            "shards missing: {}",
            missing.join(", ")
        )));
    }
    Ok(found)
}

/// The count a study's text gives `key` (`key = N  # comment`), if it gives one.
fn count_in(text: &str, key: &str) -> Option<u64> {
    text.lines().find_map(|l| {
        let v = l.trim_start().strip_prefix(key)?;
        v.trim_start()
            .strip_prefix('=')?
            .split('#')
            .next()?
            .trim()
            .parse()
            .ok()
    })
}

/// Where a study's outputs go by default.
pub fn default_dir(study: &Study) -> PathBuf {
    PathBuf::from("out").join(format!("montecarlo-{}", study.name))
}

/// `twin montecarlo`: run a Monte Carlo study of the scan matchers (the thesis's Table 5.1 by
/// default): every matcher on the same twin scan pairs at each outlier rate; resumable,
/// shardable, and bit-identical whatever the thread count. `twin montecarlo merge DIR... --out
/// DIR` combines shards.
#[derive(Clone, Debug, clap::Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct MontecarloArgs {
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
    shard: Shard,
    /// Run at most this many trials now and stop (run again to go on).
    #[arg(long)]
    max_trials: Option<u64>,
    /// A smaller study of the same design: N trials per outlier rate instead of the file's, with
    /// its own table (its output folder holds that smaller study).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=100_000_000))]
    trials: Option<u64>,
    /// Print nothing but errors.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Clone, Debug, clap::Subcommand)]
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

/// Runs `twin montecarlo` (or its `merge`).
pub fn main(args: MontecarloArgs) -> Result<(), super::CommandError> {
    if let Some(MontecarloCommand::Merge { dirs, out, quiet }) = args.merge {
        let first = dirs.first().map(|d| d.join("study.toml"));
        let text = first
            .as_ref()
            .and_then(|p| std::fs::read_to_string(p).ok())
            .unwrap_or_default();
        if crate::config::NavStudy::is_navigation(&text) {
            let (table, files) = navigation::merge(&dirs, &out, &text)?;
            if !quiet {
                say!("{}", table.trim_end_matches('\n'));
                say!("merged {} shard folders into {}", dirs.len(), out.display());
                for f in &files {
                    say!("  {}", f.display());
                }
            }
            return Ok(());
        }
        let (summary, files) = merge(&dirs, &out)?;
        if !quiet {
            say!("{}", summary.table().trim_end_matches('\n'));
            say!("merged {} shard folders into {}", dirs.len(), out.display());
            for f in &files {
                say!("  {}", f.display());
            }
        }
        return Ok(());
    }
    let path = args
        .study
        .clone()
        .expect("clap requires the study without a subcommand");
    if std::fs::read_to_string(&path).is_ok_and(|t| crate::config::NavStudy::is_navigation(&t)) {
        return navigation_main(&path, &args);
    }
    let mut study = Study::load(&path)?;
    if let Some(trials) = args.trials {
        study = study.with_trials_per_rate(trials);
    }
    // A smaller study gets a folder of its own: it never meets the full study's trials.
    let dir = args.out.clone().unwrap_or_else(|| match args.trials {
        Some(n) => PathBuf::from("out").join(format!("montecarlo-{}-{n}-per-rate", study.name)),
        None => default_dir(&study),
    });
    let run = |options: &RunOptions, progress: &mut dyn FnMut(u64, u64)| {
        run_study(&study, &dir, options, progress)
    };
    let Some(report) = run_shown(&args, &study.name, study.total_trials(), &dir, run)? else {
        return Ok(());
    };
    let rate = report.ran as f64 / report.wall_seconds.max(1e-9);
    say!(
        "{} trials run in {:.1} s ({rate:.0} trials/s, {} matchers each)",
        report.ran,
        report.wall_seconds,
        study.matchers.len()
    );
    let table = report.summary.as_ref().map(Summary::table);
    say_finished(table, &report, &dir, args.shard);
    Ok(())
}

/// Runs a study's shard with a progress bar; `None` when `--quiet` (nothing more to say), else
/// the report, after saying how many trials were found done.
fn run_shown<S>(
    args: &MontecarloArgs,
    name: &str,
    total: u64,
    dir: &Path,
    run: impl FnOnce(&RunOptions, &mut dyn FnMut(u64, u64)) -> Result<RunReport<S>, StudyError>,
) -> Result<Option<RunReport<S>>, super::CommandError> {
    let bar = super::bar(
        args.quiet,
        args.shard.count_of(total),
        "{prefix} [{bar:30}] {pos}/{len} trials {rate} ETA {eta}",
    );
    bar.set_prefix(format!("{name} (shard {})", args.shard));
    let options = RunOptions {
        threads: args.threads,
        shard: args.shard,
        max_trials: args.max_trials,
    };
    let report = run(&options, &mut |done, total| {
        bar.set_length(total);
        bar.set_position(done);
    })?;
    bar.finish_and_clear();
    if args.quiet {
        return Ok(None);
    }
    if report.resumed > 0 {
        say!(
            "resumed: {} trials were already done in {}",
            report.resumed,
            dir.display()
        );
    }
    Ok(Some(report))
}

/// Prints a finished run's table and files, or how far an unfinished one got.
fn say_finished<S>(table: Option<String>, report: &RunReport<S>, dir: &Path, shard: Shard) {
    match table {
        Some(table) => {
            say!("{}", table.trim_end_matches('\n'));
            say!("wrote {}", dir.display());
            for f in &report.files {
                say!("  {}", f.display());
            }
        }
        None => say!(
            "{} of {} trials of shard {shard} done; run the same command again to go on",
            report.resumed + report.ran,
            report.owned,
        ),
    }
}

/// `twin montecarlo` on a navigation study (a file that names a scenario).
fn navigation_main(path: &Path, args: &MontecarloArgs) -> Result<(), super::CommandError> {
    let mut study = crate::config::NavStudy::load(path)?;
    if let Some(trials) = args.trials {
        study = study.with_trials_per_condition(trials);
    }
    let dir = args.out.clone().unwrap_or_else(|| match args.trials {
        Some(n) => {
            PathBuf::from("out").join(format!("montecarlo-{}-{n}-per-condition", study.name))
        }
        None => PathBuf::from("out").join(format!("montecarlo-{}", study.name)),
    });
    let run = |options: &RunOptions, progress: &mut dyn FnMut(u64, u64)| {
        navigation::run_study(&study, &dir, options, progress)
    };
    let Some(report) = run_shown(args, &study.name, study.total_trials(), &dir, run)? else {
        return Ok(());
    };
    say!(
        "{} closed-loop runs in {:.1} s",
        report.ran,
        report.wall_seconds
    );
    say_finished(report.summary.clone(), &report, &dir, args.shard);
    Ok(())
}
