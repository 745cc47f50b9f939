//! Readers of recorded runs: CARMEN logs (`.clf`), the two formats of 002 App. C (`.script` and
//! RobotLogger `.log`) and MCAP files of ROS 2 messages (`.mcap`, which [`mcap::Recorder`] also
//! writes; the messages themselves are in [`ros2`]).
//!
//! Each reader turns a file into a [`RecordedLog`]: odometry samples and scans in file order,
//! in SI units and REP-103 axes, plus the laser's mount and a count of the lines it skipped.
//! A line that claims to be a known record but cannot be read is an error naming the file, the
//! line and what was expected; lines of unknown kinds are skipped and counted.

mod carmen;
pub mod mcap;
mod robotlogger;
pub mod ros2;
mod script;

use crate::geometry::Pose2;
use crate::localization::{RangeScan, ScanPoints};
use crate::time::Stamp;
use std::collections::BTreeMap;
use std::path::Path;

/// A new, empty file at `path`, in place of any file there (a link there is replaced, not
/// followed).
///
/// An old file is removed first rather than truncated. On ext4 (its default `auto_da_alloc`),
/// a file truncated to nothing and written again is pushed to the disk when it is closed, and
/// the next run's truncation then waits for that write: about a millisecond a file, more than
/// most of a run's files take to write. A new file waits for the kernel's usual write-back.
pub fn create_file(path: impl AsRef<Path>) -> std::io::Result<std::fs::File> {
    let path = path.as_ref();
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(e),
        _ => {}
    }
    std::fs::File::create(path)
}

/// Writes `bytes` into a new file at `path` ([`create_file`]), in place of any file there.
pub fn write_file(path: impl AsRef<Path>, bytes: impl AsRef<[u8]>) -> std::io::Result<()> {
    use std::io::Write;
    create_file(path)?.write_all(bytes.as_ref())
}

/// One record of a log.
#[derive(Clone, Debug, PartialEq)]
pub enum LogEvent {
    /// The base's odometry pose at a time.
    Odometry {
        /// When.
        stamp: Stamp,
        /// The pose in the odometry frame.
        pose: Pose2,
    },
    /// A range scan.
    Scan(RangeScan),
    /// A scan given as Cartesian points in the laser frame (RobotLogger).
    Points {
        /// When.
        stamp: Stamp,
        /// The points, in scan order.
        points: ScanPoints,
    },
}

/// The formats understood.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum LogFormat {
    /// CARMEN (`FLASER`, `ROBOTLASER1`, `ODOM`).
    Carmen,
    /// 002's `.script` (`POS`, `LASER-RANGE`).
    Script,
    /// 002's RobotLogger `.log` (`odometry:`, `laser-scan:`, `laser-geometry:`).
    RobotLogger,
    /// MCAP of ROS 2 messages (`LaserScan`, `Odometry`, `/tf`).
    Mcap,
}

/// A log read into memory.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordedLog {
    /// Which format it was.
    pub format: LogFormat,
    /// The laser's pose on the base (identity when the log does not say).
    pub mount: Pose2,
    /// The records, in file order.
    pub events: Vec<LogEvent>,
    /// Lines skipped, by their first word.
    pub skipped: BTreeMap<String, usize>,
    /// The pose a scan's own line states, by the scan's index in `events`: a CARMEN `FLASER`'s
    /// `x y theta` and a `ROBOTLASER1`'s laser pose (in a SLAM-corrected log, the corrected
    /// pose, where the odometry fields may keep the raw odometry). Other formats state none.
    pub line_poses: BTreeMap<usize, Pose2>,
}

impl RecordedLog {
    fn new(format: LogFormat) -> Self {
        RecordedLog {
            format,
            mount: Pose2::IDENTITY,
            events: Vec::new(),
            skipped: BTreeMap::new(),
            line_poses: BTreeMap::new(),
        }
    }

    fn skip(&mut self, kind: &str) {
        *self.skipped.entry(kind.to_string()).or_default() += 1;
    }

    /// Number of scans (ranges or points).
    pub fn scans(&self) -> usize {
        self.events
            .iter()
            .filter(|e| !matches!(e, LogEvent::Odometry { .. }))
            .count()
    }

    /// Number of odometry samples.
    pub fn odometry_samples(&self) -> usize {
        self.events.len() - self.scans()
    }

    /// Lines skipped in total.
    pub fn skipped_lines(&self) -> usize {
        self.skipped.values().sum()
    }

    /// Each range scan with the pose its own line states ([`RecordedLog::line_poses`]: in a
    /// corrected CARMEN log, the corrected pose), or else the odometry pose recorded last before
    /// it; scans with neither are left out.
    pub fn scans_with_logged_pose(&self) -> Vec<(RangeScan, Pose2)> {
        let mut pose = None;
        let mut scans = Vec::new();
        for (k, event) in self.events.iter().enumerate() {
            match event {
                LogEvent::Odometry { pose: p, .. } => pose = Some(*p),
                LogEvent::Scan(scan) => {
                    if let Some(p) = self.line_poses.get(&k).copied().or(pose) {
                        scans.push((scan.clone(), p));
                    }
                }
                LogEvent::Points { .. } => {}
            }
        }
        scans
    }
}

/// Why a log cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    /// The file cannot be read.
    #[error("{file}: {source}")]
    Io {
        /// The file.
        file: String,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A line is not what its kind requires.
    #[error("{file}:{line}: {message}")]
    Malformed {
        /// The file.
        file: String,
        /// Line number, from 1.
        line: usize,
        /// What was wrong and what was expected.
        message: String,
    },
    /// The file holds no scan: nothing to map.
    #[error(
        "{file}: no scans in this {format:?} log ({lines} lines, {skipped} skipped): expected laser records"
    )]
    NoScans {
        /// The file.
        file: String,
        /// The format it was read as.
        format: LogFormat,
        /// Lines in the file.
        lines: usize,
        /// Lines skipped as unknown.
        skipped: usize,
    },
    /// Neither the extension nor the content says which format the file is.
    #[error(
        "{file}: unknown log format: expected a CARMEN .clf, a .script (POS/LASER-RANGE), a RobotLogger .log or an MCAP bag of ROS 2 messages"
    )]
    UnknownFormat {
        /// The file.
        file: String,
    },
}

/// The largest magnitude of any number in a log: above every timestamp (seconds since 1970),
/// range and coordinate a robot records.
pub const MAX_LOG_NUMBER: f64 = 1e12;

/// Where a parser is, for error messages.
pub(crate) struct Cursor<'a> {
    file: &'a str,
    line: usize,
}

impl Cursor<'_> {
    fn error(&self, message: impl Into<String>) -> LogError {
        LogError::Malformed {
            file: self.file.to_string(),
            line: self.line,
            message: message.into(),
        }
    }

    /// Parses field `what` as a finite number.
    fn number(&self, text: Option<&str>, what: &str) -> Result<f64, LogError> {
        self.number_named(text, || what.to_string())
    }

    /// [`Cursor::number`] for a field whose name is written only if it is wrong (a scan's
    /// hundreds of readings each have one: naming them all cost more than reading them).
    fn number_named(&self, text: Option<&str>, what: impl Fn() -> String) -> Result<f64, LogError> {
        let Some(text) = text else {
            return Err(self.error(format!("missing {} (line ends early)", what())));
        };
        match text.trim().parse::<f64>() {
            Ok(v) if v.abs() <= MAX_LOG_NUMBER => Ok(v),
            Ok(_) => Err(self.error(format!(
                "{} `{text}` is not plausible: expected a magnitude up to 1e12",
                what()
            ))),
            _ => Err(self.error(format!("{} `{text}` is not a number", what()))),
        }
    }
}

/// Reads a log, choosing the format by extension (`.clf`, `.script`, `.log`) or, failing that,
/// by the first record; a gzipped log (`.gz`) is unpacked first.
pub fn read_log(path: &Path) -> Result<RecordedLog, LogError> {
    let file = path.display().to_string();
    let io = |source| LogError::Io {
        file: file.clone(),
        source,
    };
    /// An MCAP file's first bytes.
    const MCAP_MAGIC: &[u8] = b"\x89MCAP0\r\n";
    let bytes = std::fs::read(path).map_err(io)?;
    if bytes.starts_with(MCAP_MAGIC) || path.extension().is_some_and(|e| e == "mcap") {
        return mcap::read_mcap(&bytes, &file);
    }
    let gzipped = path.extension().is_some_and(|e| e == "gz");
    let text = if gzipped {
        use std::io::Read;
        let mut text = String::new();
        flate2::read::GzDecoder::new(bytes.as_slice())
            .read_to_string(&mut text)
            .map_err(io)?;
        text
    } else {
        String::from_utf8(bytes).map_err(|e| {
            io(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!(
                    "not text (a byte that is not UTF-8 at {})",
                    e.utf8_error().valid_up_to()
                ),
            ))
        })?
    };
    // `name.log.gz` is read as `name.log`.
    let inner = if gzipped {
        Path::new(path.file_stem().unwrap_or_default())
    } else {
        path
    };
    let format = match inner.extension().and_then(|e| e.to_str()) {
        Some("clf") => Some(LogFormat::Carmen),
        Some("script") => Some(LogFormat::Script),
        Some("log") if text.contains("laser-scan:") || text.contains("odometry:") => {
            Some(LogFormat::RobotLogger)
        }
        _ => sniff(&text),
    };
    parse_log(
        &text,
        format.ok_or(LogError::UnknownFormat { file: file.clone() })?,
        &file,
    )
}

/// Parses log text in a known format; `file` names it in errors.
/// A log without a single scan is an error.
pub fn parse_log(text: &str, format: LogFormat, file: &str) -> Result<RecordedLog, LogError> {
    let log = match format {
        LogFormat::Carmen => carmen::parse(text, file),
        LogFormat::Script => script::parse(text, file),
        LogFormat::RobotLogger => robotlogger::parse(text, file),
        LogFormat::Mcap => mcap::read_mcap(text.as_bytes(), file),
    }?;
    if log.scans() == 0 {
        return Err(LogError::NoScans {
            file: file.to_string(),
            format,
            lines: text.lines().count(),
            skipped: log.skipped_lines(),
        });
    }
    Ok(log)
}

fn sniff(text: &str) -> Option<LogFormat> {
    text.lines().find_map(|line| {
        let word = line.split_whitespace().next()?;
        match word {
            "FLASER" | "ROBOTLASER1" | "ODOM" | "PARAM" => Some(LogFormat::Carmen),
            "POS" | "LASER-RANGE" => Some(LogFormat::Script),
            "odometry:" | "laser-scan:" | "laser-geometry:" => Some(LogFormat::RobotLogger),
            _ => None,
        }
    })
}

#[cfg(test)]
mod file_tests {
    use super::*;

    #[test]
    fn a_file_written_again_holds_only_the_new_bytes() {
        let dir = std::env::temp_dir().join(format!("robot-create-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("out.txt");
        write_file(&path, "a longer first version\n").unwrap();
        write_file(&path, "short\n").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "short\n");
        // A folder where the file should go is an error, not a folder removed.
        let err = write_file(&dir, "x").unwrap_err();
        assert_ne!(err.kind(), std::io::ErrorKind::NotFound, "{err}");
        assert!(dir.is_dir());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
