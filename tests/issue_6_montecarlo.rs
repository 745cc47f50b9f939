//! Issue 6: the Monte Carlo study is deterministic whatever the thread count, shards merge into
//! exactly the files a single run writes, and a run killed midway resumes without repeating or
//! losing a trial. A small study (2 rates × 9 trials, two matchers) keeps these quick; the full
//! Table 5.1 study is `twin montecarlo studies/table-5-1.toml` (README, benchmark).

use sim::commands::montecarlo::{RunOptions, Shard, StudyError, merge, run_study};
use sim::config::Study;
use std::path::{Path, PathBuf};

/// The files that must be byte-identical (`timings.csv` holds wall-clock times).
const DETERMINISTIC: [&str; 4] = ["trials.csv", "summary.json", "table.md", "errors.svg"];

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("twin-mc-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A small study file in `dir`.
fn small_study(dir: &Path, seed: u64) -> Study {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join("small.toml");
    std::fs::write(
        &path,
        format!(
            r#"name = "small"
world = "{root}/worlds/orthogonal.toml"
robot = "{root}/scenarios/robots/pioneer-3dx.toml"
matchers = ["ls", "lorentz"]
outlier_rates = [0.02, 0.20]
trials_per_rate = 9
seed = {seed}
"#
        ),
    )
    .unwrap();
    Study::load(&path).unwrap()
}

fn run(study: &Study, dir: &Path, options: RunOptions) {
    run_study(study, dir, &options, |_, _| {}).unwrap();
}

fn assert_same_files(a: &Path, b: &Path) {
    for f in DETERMINISTIC {
        let (x, y) = (
            std::fs::read(a.join(f)).unwrap_or_else(|e| panic!("{}: {e}", a.join(f).display())),
            std::fs::read(b.join(f)).unwrap_or_else(|e| panic!("{}: {e}", b.join(f).display())),
        );
        assert!(
            x == y,
            "{f} differs between {} and {}",
            a.display(),
            b.display()
        );
    }
}

fn threads(n: usize) -> RunOptions {
    RunOptions {
        threads: n,
        ..RunOptions::default()
    }
}

#[test]
fn one_and_two_threads_write_identical_results() {
    let base = scratch("threads");
    let study = small_study(&base, 11);
    run(&study, &base.join("one"), threads(1));
    run(&study, &base.join("two"), threads(2));
    assert_same_files(&base.join("one"), &base.join("two"));
    let csv = std::fs::read_to_string(base.join("one/trials.csv")).unwrap();
    assert_eq!(
        csv.lines().count(),
        1 + 18 * 2,
        "one row per trial and matcher"
    );
    // Not a constant: another seed gives other trials.
    let other = small_study(&base.join("seed-12"), 12);
    run(&other, &base.join("other"), threads(2));
    let csv2 = std::fs::read_to_string(base.join("other/trials.csv")).unwrap();
    assert_ne!(csv, csv2);
}

#[test]
fn shards_merge_into_the_files_of_a_single_run() {
    let base = scratch("shards");
    let study = small_study(&base, 21);
    run(&study, &base.join("single"), threads(2));
    let mut dirs = Vec::new();
    for k in 0..3 {
        let dir = base.join(format!("shard-{k}"));
        let options = RunOptions {
            threads: 1,
            shard: Shard { index: k, count: 3 },
            max_trials: None,
        };
        run(&study, &dir, options);
        dirs.push(dir);
    }
    // Any order of the folders.
    dirs.reverse();
    merge(&dirs, &base.join("merged")).unwrap();
    assert_same_files(&base.join("single"), &base.join("merged"));
    // A missing shard is refused, naming it.
    let err = merge(&dirs[1..], &base.join("incomplete")).unwrap_err();
    assert!(err.to_string().contains("shards missing: 2/3"), "{err}");
    let err = merge(&[dirs[0].clone(), dirs[0].clone()], &base.join("twice")).unwrap_err();
    assert!(err.to_string().contains("given twice"), "{err}");
}

#[test]
fn shards_of_a_smaller_study_merge_too() {
    // `--trials N` rewrites the study's count in the folders' copy; the merge reads the study
    // from its file and must apply the same count (it refused, "has changed", before).
    let base = scratch("smaller-shards");
    let study = small_study(&base, 22).with_trials_per_rate(3);
    run(&study, &base.join("single"), threads(1));
    let dirs: Vec<PathBuf> = (0..2)
        .map(|k| {
            let dir = base.join(format!("shard-{k}"));
            let options = RunOptions {
                threads: 1,
                shard: Shard { index: k, count: 2 },
                max_trials: None,
            };
            run(&study, &dir, options);
            dir
        })
        .collect();
    merge(&dirs, &base.join("merged")).unwrap();
    assert_same_files(&base.join("single"), &base.join("merged"));
}

#[test]
fn a_killed_run_resumes_without_repeating_or_losing_trials() {
    let base = scratch("resume");
    let study = small_study(&base, 31);
    run(&study, &base.join("single"), threads(2));
    let dir = base.join("killed");
    // The first sitting stops after 7 trials...
    let first = run_study(
        &study,
        &dir,
        &RunOptions {
            threads: 2,
            max_trials: Some(7),
            ..RunOptions::default()
        },
        |_, _| {},
    )
    .unwrap();
    assert_eq!((first.ran, first.summary.is_none()), (7, true));
    // ...and was killed while writing: half a trial (one matcher's row of trial 15) and a torn
    // line are on the log.
    let log = dir.join("progress/trials.log");
    let single = std::fs::read_to_string(base.join("single/trials.csv")).unwrap();
    let row_of_15 = single.lines().find(|l| l.starts_with("15,")).unwrap();
    let mut text = std::fs::read_to_string(&log).unwrap();
    text.push_str(row_of_15);
    text.push('\n');
    text.push_str("16,123,0.2,lor");
    std::fs::write(&log, text).unwrap();
    let second = run_study(&study, &dir, &threads(2), |_, _| {}).unwrap();
    assert_eq!(second.resumed, 7, "the complete trials are kept");
    assert_eq!(second.ran, 18 - 7, "the rest, trial 15 included, are run");
    assert_same_files(&base.join("single"), &dir);
    // A second start on a finished folder runs nothing and writes the same files.
    let third = run_study(&study, &dir, &threads(2), |_, _| {}).unwrap();
    assert_eq!(third.ran, 0);
    assert_same_files(&base.join("single"), &dir);
}

#[test]
fn a_folder_of_another_study_is_refused() {
    let base = scratch("other-study");
    let study = small_study(&base, 41);
    run(
        &study,
        &base.join("out"),
        RunOptions {
            max_trials: Some(1),
            ..threads(1)
        },
    );
    let other = small_study(&base.join("x"), 42);
    let err = run_study(&other, &base.join("out"), &threads(1), |_, _| {}).unwrap_err();
    assert!(matches!(err, StudyError::OtherStudy { .. }), "{err}");
}
