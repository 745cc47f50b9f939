//! Localisation over recorded data: `twin map` (a log through the map builder) and `twin match`
//! (scan pairs as JSON Lines through one matcher).

use crate::config::values::show;
use crate::output::logmap::{Panel, occupied_cells, write_log_map_svg};
use crate::output::write_tum;
use robot::Pose2;
use robot::localization::{MapBuilder, MapConfig, MatchStats, MatcherKind, RangeScan, ScanMatcher};
use robot::logs::{LogEvent, RecordedLog};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What the map builder made of a log.
#[derive(Clone, Debug)]
pub struct Replay {
    /// The matcher used.
    pub matcher: MatcherKind,
    /// Each scan: stamp, estimate and odometry (odometry re-based so the first scan is at the
    /// origin, like the estimate).
    pub placed: Vec<robot::localization::Placed>,
    /// The estimate's point map.
    pub map: Vec<[f64; 2]>,
    /// The same scans placed by odometry alone.
    pub odometry_map: Vec<[f64; 2]>,
    /// Each placed scan's ranges (`None` for a log of points).
    pub scans: Vec<Option<RangeScan>>,
    /// The laser's pose on the base.
    pub mount: Pose2,
    /// Wall-clock seconds spent in the map builder.
    pub wall_seconds: f64,
}

/// Runs the map builder over a log; `progress(done, total)` is called as events are consumed.
pub fn replay_log(
    log: &RecordedLog,
    matcher: MatcherKind,
    config: MapConfig,
    mut progress: impl FnMut(usize, usize),
) -> Replay {
    let config = MapConfig {
        mount: log.mount,
        ..config
    };
    let mut builder = MapBuilder::new(matcher.build(), config);
    let mut wall = 0.0;
    let total = log.events.len();
    let mut scans: Vec<robot::localization::ScanPoints> = Vec::new();
    let mut ranges: Vec<Option<RangeScan>> = Vec::new();
    for (i, event) in log.events.iter().enumerate() {
        let clock = Instant::now();
        match event {
            LogEvent::Odometry { stamp, pose } => builder.push_odometry(*stamp, *pose),
            LogEvent::Scan(scan) => {
                let points = scan.points();
                builder.push_points(scan.stamp, points.clone());
                scans.push(points);
                ranges.push(Some(scan.clone()));
            }
            LogEvent::Points { stamp, points } => {
                scans.push(points.clone());
                ranges.push(None);
                builder.push_points(*stamp, points.clone());
            }
        }
        wall += clock.elapsed().as_secs_f64();
        if i % 64 == 0 {
            progress(i, total);
        }
    }
    let clock = Instant::now();
    builder.finish();
    wall += clock.elapsed().as_secs_f64();
    progress(total, total);
    // Odometry re-based on the first scan, and the scans placed by it.
    let placed: Vec<_> = builder.placed().to_vec();
    let origin = placed.first().map_or(Pose2::IDENTITY, |p| p.odometry);
    let placed: Vec<_> = placed
        .into_iter()
        .map(|mut p| {
            p.odometry = origin.relative(&p.odometry);
            p
        })
        .collect();
    let mut odometry_map = Vec::new();
    for (p, points) in placed.iter().zip(&scans) {
        let laser = p.odometry.compose(&log.mount);
        odometry_map.extend(points.xy.iter().map(|q| {
            let (x, y) = laser.transform_point(q[0], q[1]);
            [x, y]
        }));
    }
    Replay {
        matcher,
        placed,
        map: builder.map_points().to_vec(),
        odometry_map,
        scans: ranges,
        mount: log.mount,
        wall_seconds: wall,
    }
}

/// The figures `twin map` reports in `summary.json`.
#[derive(Clone, Debug, Serialize)]
pub struct ReplaySummary {
    /// The log file.
    pub log: String,
    /// The matcher.
    pub matcher: String,
    /// Scans placed.
    pub scans: usize,
    /// Matches made, trusted and converged, and the mean iterations.
    #[serde(flatten)]
    pub stats: MatchStats,
    /// Lines of the log skipped, by kind.
    pub skipped: std::collections::BTreeMap<String, usize>,
    /// Wall-clock seconds in the map builder (machine-dependent).
    pub wall_seconds: f64,
    /// Wall-clock milliseconds per scan (machine-dependent).
    pub ms_per_scan: f64,
    /// 5 cm cells occupied by the map placed by odometry.
    pub odometry_cells: usize,
    /// 5 cm cells occupied by the map placed by the estimate (fewer: sharper).
    pub estimate_cells: usize,
}

impl Replay {
    /// The summary of the replay of `log` from file `name`.
    pub fn summary(&self, name: &str, log: &RecordedLog) -> ReplaySummary {
        ReplaySummary {
            log: name.to_string(),
            matcher: self.matcher.to_string(),
            scans: self.placed.len(),
            stats: MatchStats::of(&self.placed),
            skipped: log.skipped.clone(),
            wall_seconds: self.wall_seconds,
            ms_per_scan: self.wall_seconds * 1e3 / self.placed.len().max(1) as f64,
            odometry_cells: occupied_cells(&self.odometry_map).len(),
            estimate_cells: occupied_cells(&self.map).len(),
        }
    }

    /// Writes `estimate.tum`, `odometry.tum`, `map.svg` and `summary.json` into `dir`.
    pub fn write(&self, dir: &Path, summary: &ReplaySummary) -> std::io::Result<Vec<PathBuf>> {
        std::fs::create_dir_all(dir)?;
        let files =
            ["estimate.tum", "odometry.tum", "map.svg", "summary.json"].map(|f| dir.join(f));
        write_tum(&files[0], self.placed.iter().map(|p| (p.stamp, p.estimate)))?;
        write_tum(&files[1], self.placed.iter().map(|p| (p.stamp, p.odometry)))?;
        let odometry_path: Vec<Pose2> = self.placed.iter().map(|p| p.odometry).collect();
        let estimate_path: Vec<Pose2> = self.placed.iter().map(|p| p.estimate).collect();
        write_log_map_svg(
            &files[2],
            &[
                Panel {
                    title: "odometry".into(),
                    points: &self.odometry_map,
                    path: &odometry_path,
                },
                Panel {
                    title: format!("scan matching ({})", self.matcher),
                    points: &self.map,
                    path: &estimate_path,
                },
            ],
        )?;
        let mut text = serde_json::to_string_pretty(summary)?;
        text.push('\n');
        robot::logs::write_file(&files[3], text)?;
        let placed = self
            .placed
            .iter()
            .zip(&self.scans)
            .filter_map(|(p, scan)| Some((p.estimate.compose(&self.mount), scan.as_ref()?)));
        let mut files = files.to_vec();
        files.extend(crate::output::write_grid(dir, placed)?);
        Ok(files)
    }
}

/// One input line of `twin match`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MatchRequest {
    #[serde(rename = "ref")]
    reference: RangeScan,
    cur: RangeScan,
    guess: [f64; 3],
}

/// One output line of `twin match`.
#[derive(Serialize)]
struct MatchReply {
    x: f64,
    y: f64,
    theta: f64,
    iterations: u32,
    converged: bool,
    settled: bool,
    correspondences: usize,
    /// The figures `converged` is judged by (an infinite σ is written as null).
    quality: robot::localization::MatchQuality,
    micros: f64,
}

/// Answers input line `number` (from 1) of `twin match` with one output line (without the
/// newline): the match, or `{"error": "line N: …"}` naming what is wrong. Every line is
/// answered, an empty one too.
pub fn match_line(number: usize, line: &str, matcher: &dyn ScanMatcher) -> String {
    let error = |message: String| error_line(&format!("line {number}: {message}"));
    if line.trim().is_empty() {
        return error("empty line, expected a scan pair".into());
    }
    let request: MatchRequest = match serde_json::from_str(line) {
        Ok(r) => r,
        // serde_json counts within the line: its "line 1" is this line.
        Err(e) => {
            return error(format!(
                "not a scan pair: {} at column {}",
                strip_position(&e.to_string()),
                e.column()
            ));
        }
    };
    let turn = std::f64::consts::TAU;
    for (name, scan) in [("ref", &request.reference), ("cur", &request.cur)] {
        if !(scan.angle_min.is_finite() && scan.angle_min.abs() <= turn) {
            return error(format!(
                "{name}.angle_min: expected radians within ±2π, found {}",
                show(scan.angle_min)
            ));
        }
        let increment = scan.angle_increment.abs();
        if !(increment > 1e-9 && increment <= turn) {
            return error(format!(
                "{name}.angle_increment: expected radians, non-zero and within ±2π, found {}",
                show(scan.angle_increment)
            ));
        }
        if !robot::localization::fan_within_a_turn(increment, scan.ranges.len()) {
            let span = increment * scan.ranges.len().saturating_sub(1) as f64;
            return error(format!(
                "{name}: expected beams within a turn, found {} beams {} rad apart ({:.1} turns)",
                scan.ranges.len(),
                show(scan.angle_increment),
                span / turn
            ));
        }
        if !(scan.range_max > 0.0 && scan.range_max.is_finite()) {
            return error(format!(
                "{name}.range_max: expected a positive number of metres, found {}",
                show(scan.range_max)
            ));
        }
        if let Some((i, r)) = scan.ranges.iter().enumerate().find(|(_, r)| r.is_nan()) {
            return error(format!("{name}.ranges[{i}]: expected metres, found {r}"));
        }
    }
    let limit = robot::localization::MAX_COORDINATE_M;
    let [x, y, theta] = request.guess;
    if !(x.abs() <= limit && y.abs() <= limit && theta.abs() <= limit) {
        return error(format!(
            "guess: expected [x, y, theta] with x and y within ±{limit} m and theta within ±{limit} rad, found [{}, {}, {}]",
            show(x),
            show(y),
            show(theta)
        ));
    }
    let guess = Pose2::new(request.guess[0], request.guess[1], request.guess[2]);
    let clock = Instant::now();
    let result = matcher.match_scans(&request.reference, &request.cur, guess);
    let micros = clock.elapsed().as_secs_f64() * 1e6;
    let reply = MatchReply {
        x: result.pose.x,
        y: result.pose.y,
        theta: result.pose.theta,
        iterations: result.iterations,
        converged: result.converged,
        settled: result.settled,
        correspondences: result.correspondences,
        quality: result.quality,
        micros,
    };
    serde_json::to_string(&reply).unwrap_or_else(|e| error_line(&e.to_string()))
}

fn error_line(message: &str) -> String {
    serde_json::json!({ "error": message }).to_string()
}

/// A serde_json message without its " at line L column C" (the caller says where).
fn strip_position(message: &str) -> &str {
    message
        .rfind(" at line ")
        .map_or(message, |at| &message[..at])
}

/// `twin map`: build a 2D map from a recorded log (CARMEN .clf, .script, RobotLogger .log) by
/// chaining scan matches seeded by its odometry; write the estimate, the odometry, a picture of
/// both maps and a summary with timings.
#[derive(Clone, Debug, clap::Args)]
pub struct MapArgs {
    /// The log: a CARMEN `.clf`, a `.script`, a RobotLogger `.log` (each possibly `.gz`) or an
    /// MCAP bag of ROS 2 messages (`.mcap`).
    pub log: PathBuf,
    /// The matcher: ls, lorentz, lorentz-lines, mbicp or pl-icp.
    #[arg(long, default_value = "lorentz")]
    pub matcher: MatcherKind,
    /// Output folder [default: out/map-LOGNAME].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Match each scan to the last one the robot moved this far from, metres (0: to the
    /// previous scan).
    #[arg(long, default_value_t = 0.0)]
    pub keyframe_m: f64,
    /// Print nothing but errors.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Runs `twin map`.
pub fn map_main(args: MapArgs) -> Result<(), super::CommandError> {
    use super::CommandError;
    if !(args.keyframe_m >= 0.0 && args.keyframe_m.is_finite()) {
        return Err(CommandError::option(
            "--keyframe-m",
            "must be a distance >= 0",
            args.keyframe_m,
        ));
    }
    let log = robot::logs::read_log(&args.log)?;
    let name = args.log.display().to_string();
    let bar = super::bar(
        args.quiet,
        log.events.len() as u64,
        "{prefix} [{bar:30}] {pos}/{len} records ETA {eta}",
    );
    bar.set_prefix(format!("map ({})", args.matcher));
    let config = MapConfig {
        keyframe_distance_m: args.keyframe_m,
        ..MapConfig::default()
    };
    let replay = replay_log(&log, args.matcher, config, |done, _| {
        bar.set_position(done as u64)
    });
    bar.finish_and_clear();
    let summary = replay.summary(&name, &log);
    let stem = args
        .log
        .file_stem()
        .map_or("log".into(), |s| s.to_string_lossy());
    let dir = args
        .out
        .unwrap_or_else(|| PathBuf::from("out").join(format!("map-{stem}")));
    let files = replay
        .write(&dir, &summary)
        .map_err(|source| CommandError::Write {
            dir: dir.clone(),
            source,
        })?;
    if !args.quiet {
        say!(
            "{name}: {} scans matched with {} in {:.2} s ({:.2} ms per scan, {:.1} iterations per match); {} records of other kinds skipped",
            summary.scans,
            args.matcher,
            summary.wall_seconds,
            summary.ms_per_scan,
            summary.stats.mean_iterations,
            log.skipped_lines()
        );
        say!(
            "map sharpness: {} cells of 5 cm occupied by the estimate's map, {} by odometry's",
            summary.estimate_cells,
            summary.odometry_cells
        );
        say!("wrote {}", dir.display());
        for f in &files {
            say!("  {}", f.display());
        }
    }
    Ok(())
}

/// `twin match`: match scan pairs read as JSON Lines from stdin, one result line per pair on
/// stdout.
///
/// Input: {"ref": {"angle_min", "angle_increment", "range_max", "ranges": [...]}, "cur": {...},
/// "guess": [x, y, theta]}; output: {"x", "y", "theta", "iterations", "converged" (the answer can
/// be trusted), "settled" (the iterations stopped on a tiny step), "correspondences", "quality":
/// {"inliers", "inlier_share", "rms_m", "sigma": [x, y, theta], "sparse", "step": [m, rad]},
/// "micros"}, or {"error": "..."} for a malformed line.
#[derive(Clone, Debug, clap::Args)]
pub struct MatchArgs {
    /// The matcher: ls, lorentz, lorentz-lines, mbicp or pl-icp.
    #[arg(long, default_value = "lorentz")]
    pub matcher: MatcherKind,
}

/// Runs `twin match` on standard input and output.
pub fn match_main(args: MatchArgs) -> Result<(), super::CommandError> {
    use super::CommandError;
    use std::io::{BufRead, Write};
    let matcher = args.matcher.build();
    let stdin = std::io::stdin();
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    let io = |what| move |source| CommandError::Io { what, source };
    for (k, line) in stdin.lock().split(b'\n').enumerate() {
        let line = line.map_err(io("reading stdin"))?;
        let reply = match std::str::from_utf8(&line) {
            Ok(line) => match_line(k + 1, line.trim_end_matches('\r'), matcher.as_ref()),
            Err(e) => error_line(&format!("line {}: not UTF-8: {e}", k + 1)),
        };
        writeln!(out, "{reply}").map_err(io("writing stdout"))?;
        out.flush().map_err(io("writing stdout"))?;
    }
    Ok(())
}

/// One line of a run's `scans.jsonl`, as far as `twin pairs` reads it.
#[derive(Deserialize)]
struct RunScan {
    angle_min: f64,
    angle_increment: f64,
    range_max: f64,
    ranges: Vec<f64>,
    odometry: [f64; 3],
    laser_mount: [f64; 3],
    #[serde(default)]
    laser_tilt: f64,
}

/// One output line of `twin pairs` (the input of `twin match`; `twin matchers --show` writes
/// one too).
#[derive(Serialize)]
pub(crate) struct PairLine<'a> {
    #[serde(rename = "ref")]
    pub reference: &'a RangeScan,
    pub cur: &'a RangeScan,
    pub guess: [f64; 3],
}

/// `twin pairs`: scan pairs as `twin match` reads them — each level scan with the next, the guess
/// from odometry (the current laser pose in the reference laser's frame). From a finished run's
/// RUN_DIR/scans.jsonl, or from a recorded log (`twin map`'s formats: CARMEN, 002's `.script` and
/// RobotLogger `.log`, MCAP), whose odometry is interpolated to each scan's stamp as the map
/// builder does and composed with the log's laser offset.
#[derive(Clone, Debug, clap::Args)]
pub struct PairsArgs {
    /// A run's output folder (`twin run` or `twin drive`), with its scans.jsonl, or a log file.
    pub source: PathBuf,
    /// Write at most this many pairs.
    #[arg(long)]
    pub max: Option<usize>,
}

/// Runs `twin pairs`, writing JSON Lines to stdout.
pub fn pairs_main(args: PairsArgs) -> Result<(), super::CommandError> {
    use super::CommandError;
    use std::io::Write;
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    let mut pairs = Pairs {
        out: &mut out,
        previous: None,
        written: 0,
        max: args.max.unwrap_or(usize::MAX),
    };
    if args.source.is_dir() {
        pairs_of_run(&args.source.join("scans.jsonl"), &mut pairs)?;
    } else {
        pairs_of_log(&args.source, &mut pairs)?;
    }
    out.flush().map_err(|source| CommandError::Io {
        what: "writing stdout",
        source,
    })
}

/// Writes each scan given with the one before it, as `twin match`'s input lines.
struct Pairs<'a, W: std::io::Write> {
    out: &'a mut W,
    /// The scan before, and its laser's pose in the odometry frame.
    previous: Option<(RangeScan, Pose2)>,
    written: usize,
    max: usize,
}

impl<W: std::io::Write> Pairs<'_, W> {
    /// Whether `--max` pairs have been written.
    fn full(&self) -> bool {
        self.written >= self.max
    }

    /// Pairs `next` (a scan and the laser's pose when it was taken) with the scan before, if
    /// any, and keeps it for the one after; `None` breaks the chain (a tilted scan, a scan
    /// without odometry).
    fn push(&mut self, next: Option<(RangeScan, Pose2)>) -> Result<(), super::CommandError> {
        if let (Some((reference, at)), Some((current, laser))) = (&self.previous, &next) {
            let g = at.relative(laser);
            let pair = PairLine {
                reference,
                cur: current,
                guess: [g.x, g.y, g.theta],
            };
            let text = serde_json::to_string(&pair).map_err(|e| super::CommandError::Io {
                what: "writing stdout",
                source: e.into(),
            })?;
            writeln!(self.out, "{text}").map_err(|source| super::CommandError::Io {
                what: "writing stdout",
                source,
            })?;
            self.written += 1;
        }
        self.previous = next;
        Ok(())
    }
}

/// The pairs of a run's scans.jsonl.
fn pairs_of_run(
    path: &Path,
    pairs: &mut Pairs<'_, impl std::io::Write>,
) -> Result<(), super::CommandError> {
    use super::CommandError;
    use std::io::BufRead;
    let file = std::fs::File::open(path).map_err(|source| CommandError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    for (k, line) in std::io::BufReader::new(file).lines().enumerate() {
        if pairs.full() {
            break;
        }
        let line = line.map_err(|source| CommandError::Io {
            what: "reading scans.jsonl",
            source,
        })?;
        if line.trim().is_empty() {
            continue;
        }
        let scan: RunScan = serde_json::from_str(&line).map_err(|e| CommandError::Parse {
            path: path.to_path_buf(),
            line: k + 1,
            message: e.to_string(),
        })?;
        // Tilted scans do not lie in the plane of the next: leave them out.
        if scan.laser_tilt.abs() > 1e-9 {
            pairs.push(None)?;
            continue;
        }
        let [x, y, theta] = scan.odometry;
        let [mx, my, mt] = scan.laser_mount;
        let laser = Pose2::new(x, y, theta).compose(&Pose2::new(mx, my, mt));
        let range = RangeScan {
            stamp: robot::Stamp::ZERO,
            angle_min: scan.angle_min,
            angle_increment: scan.angle_increment,
            range_max: scan.range_max,
            ranges: scan.ranges,
        };
        pairs.push(Some((range, laser)))?;
    }
    Ok(())
}

/// The pairs of a recorded log's range scans: the odometry interpolated to each scan's stamp
/// (a scan outside the odometry's span breaks the chain), composed with the log's laser offset.
fn pairs_of_log(
    path: &Path,
    pairs: &mut Pairs<'_, impl std::io::Write>,
) -> Result<(), super::CommandError> {
    let log = robot::logs::read_log(path)?;
    let mut odometry = robot::odometry::PoseHistory::unbounded();
    for event in &log.events {
        if let LogEvent::Odometry { stamp, pose } = event {
            odometry.push(*stamp, *pose);
        }
    }
    for event in &log.events {
        if pairs.full() {
            break;
        }
        if let LogEvent::Scan(scan) = event {
            let laser = odometry.at(scan.stamp).map(|pose| pose.compose(&log.mount));
            pairs.push(laser.map(|laser| (scan.clone(), laser)))?;
        }
    }
    Ok(())
}
