//! One module per thing a user runs; the `twin` binary parses the arguments and calls them.
//!
//! - [`run`]: `twin run`, a scenario's script through the hardware contract on the twin;
//! - [`check`]: `twin check`, and the evaluation of a scenario's `[[check]]` bounds;
//! - [`map`]: `twin map` and `twin match`, localisation over recorded logs and scan pairs;
//! - [`serve`]: `twin serve`, the twin's devices byte for byte on TCP ports or pseudo-terminals;
//! - [`drive`]: `twin drive`, a scenario's script through any backend (the real robot);
//! - [`reconstruct`]: the 3D model of a run's scenes, and `twin reconstruct` from a run's folder;
//! - [`matchers`]: `twin matchers`, every scan matcher on the same synthetic and real pairs;
//! - [`montecarlo`]: `twin montecarlo`, the thesis's Table 5.1 study, parallel, resumable and
//!   shardable.

/// `println!` for a command's report on standard output, ending the program quietly when the
/// reader has gone (`twin run … | head -1`) instead of panicking on the closed pipe.
macro_rules! say {
    () => {
        $crate::commands::say_line(format_args!(""))
    };
    ($($arg:tt)*) => {
        $crate::commands::say_line(format_args!($($arg)*))
    };
}

pub mod check;
pub mod drive;
pub mod live;
pub mod map;
pub mod matchers;
pub mod montecarlo;
pub mod reconstruct;
pub mod replay;
pub mod run;
pub mod serve;
pub mod view;

use crate::config::ConfigError;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;

/// Writes one line to standard output (see `say!`); a closed pipe ends the program with
/// status 0, as the reader wanted no more.
pub fn say_line(args: std::fmt::Arguments<'_>) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    let written = out
        .write_fmt(args)
        .and_then(|()| out.write_all(b"\n"))
        .and_then(|()| out.flush());
    if let Err(e) = written {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(0);
        }
        eprintln!("error: writing standard output: {e}");
        std::process::exit(1);
    }
}

/// Why a command failed: what the `twin` binary prints after `error:`.
#[derive(Debug, thiserror::Error)]
pub enum CommandError {
    /// A file the command reads is malformed or unreadable.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// An option's value is out of its range.
    #[error("{option} {expected}, found {found}")]
    Option {
        /// The option, as typed (`--speed`).
        option: &'static str,
        /// What it must be.
        expected: &'static str,
        /// What was given.
        found: String,
    },
    /// An option the command needs for this input was not given.
    #[error("{option} is needed: {why}")]
    MissingOption {
        /// The option, as typed (`--pantilt`).
        option: &'static str,
        /// Why this input needs it.
        why: String,
    },
    /// `twin view` cannot serve.
    #[error(transparent)]
    View(#[from] view::ViewError),
    /// The live view cannot start.
    #[error(transparent)]
    Live(#[from] live::LiveError),
    /// A replay failed.
    #[error(transparent)]
    Replay(#[from] replay::ReplayRunError),
    /// A file cannot be opened or read.
    #[error("{}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// What failed.
        #[source]
        source: std::io::Error,
    },
    /// A line of a file is not what was expected.
    #[error("{}:{line}: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong and what was expected.
        message: String,
    },
    /// A scenario's run failed on the twin.
    #[error(transparent)]
    Run(#[from] run::RunError),
    /// The output files cannot be written.
    #[error("writing the outputs into {}: {source}", dir.display())]
    Write {
        /// The output folder.
        dir: PathBuf,
        /// What failed.
        #[source]
        source: std::io::Error,
    },
    /// A folder cannot be read.
    #[error("reading {}: {source}", dir.display())]
    Folder {
        /// The folder.
        dir: PathBuf,
        /// What failed.
        #[source]
        source: std::io::Error,
    },
    /// Standard input or output failed.
    #[error("{what}: {source}")]
    Io {
        /// What was being done.
        what: &'static str,
        /// What failed.
        #[source]
        source: std::io::Error,
    },
    /// A scenario's checks did not hold.
    #[error("{}: {failed} of {total} check(s) failed", path.display())]
    ChecksFailed {
        /// The scenario file.
        path: PathBuf,
        /// Checks failed.
        failed: usize,
        /// Checks evaluated.
        total: usize,
    },
    /// Some scenarios of a folder failed or could not run.
    #[error("{failed} of {total} scenario(s) failed")]
    ScenariosFailed {
        /// Scenarios that failed or could not run.
        failed: usize,
        /// Scenarios found.
        total: usize,
    },
    /// A folder holds no scenario file.
    #[error("{}: no scenario files (*.toml) in this folder", .0.display())]
    NoScenarios(PathBuf),
    /// A recorded log cannot be read.
    #[error(transparent)]
    Log(#[from] robot::logs::LogError),
    /// A Monte Carlo study cannot run or merge.
    #[error(transparent)]
    Study(#[from] montecarlo::StudyError),
    /// The twin's devices cannot be served.
    #[error(transparent)]
    Serve(#[from] serve::ServeError),
    /// The real robot's devices cannot be opened.
    #[error("opening the robot's devices: {0}")]
    Open(#[source] robot::serial::SerialError),
    /// A run's folder cannot be reconstructed.
    #[error(transparent)]
    RunFolder(#[from] reconstruct::FolderError),
    /// Scan pairs for comparing the matchers cannot be made.
    #[error("making scan pairs: {0}")]
    Pairs(String),
    /// A drive through the serial backend failed.
    #[error(transparent)]
    Drive(#[from] drive::DriveError<robot::serial::SerialError>),
}

impl CommandError {
    /// Writing the outputs into `dir` failed.
    pub(crate) fn write(dir: &std::path::Path) -> impl FnOnce(std::io::Error) -> CommandError + '_ {
        move |source| CommandError::Write {
            dir: dir.to_path_buf(),
            source,
        }
    }

    /// An option out of range.
    pub(crate) fn option(
        option: &'static str,
        expected: &'static str,
        found: impl ToString,
    ) -> Self {
        CommandError::Option {
            option,
            expected,
            found: found.to_string(),
        }
    }
}

/// A progress bar of `len` items drawn with `template`, hidden when `quiet`.
pub(crate) fn bar(quiet: bool, len: u64, template: &str) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    ProgressBar::new(len).with_style(
        ProgressStyle::with_template(template)
            .expect("valid template")
            .with_key(
                "rate",
                |state: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
                    let _ = write!(w, "{:.0}/s", state.per_sec());
                },
            )
            .progress_chars("=> "),
    )
}

/// The progress bar of a scripted run: steps done, elapsed time and ETA (hidden when quiet).
pub(crate) fn step_bar(quiet: bool, steps: usize) -> ProgressBar {
    bar(
        quiet,
        steps as u64,
        "{prefix} [{bar:30}] step {pos}/{len} {elapsed_precise} ETA {eta}",
    )
}
