//! The same scenario and seed give bit-identical trajectories and scans; another seed does not.
//! A failure names the file and the first line that differs.

use crate::common::*;
use sim::commands::run::{RunOptions, run_scenario};
use sim::output::write_all;
use std::path::{Path, PathBuf};

const DETERMINISTIC: [&str; 3] = ["truth.tum", "odometry.tum", "scans.jsonl"];

fn run_into(dir: &Path, seed: Option<u64>) {
    run_scenario_into("lab-tour", dir, seed);
}

fn run_scenario_into(name: &str, dir: &Path, seed: Option<u64>) {
    let scenario = scenario(name);
    let options = RunOptions {
        seed,
        ..RunOptions::default()
    };
    let record = run_scenario(&scenario, &options, |_, _| {}).unwrap();
    write_all(&record, &scenario, dir).unwrap();
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("twin-determinism-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// `None` when equal, else the first differing line.
fn first_difference(a: &str, b: &str) -> Option<String> {
    for (i, (x, y)) in a.lines().zip(b.lines()).enumerate() {
        if x != y {
            let cut = |s: &str| s.chars().take(120).collect::<String>();
            return Some(format!("line {}:\n  {}\n  {}", i + 1, cut(x), cut(y)));
        }
    }
    (a.lines().count() != b.lines().count())
        .then(|| format!("{} lines vs {} lines", a.lines().count(), b.lines().count()))
}

#[test]
fn same_seed_gives_identical_bytes() {
    same_seed_same_bytes("lab-tour", &DETERMINISTIC);
}

#[test]
fn same_seed_gives_identical_bytes_with_sonar_and_pan_tilt_running() {
    same_seed_same_bytes(
        "lab-tour-thesis",
        &["truth.tum", "odometry.tum", "scans.jsonl", "sonar.json"],
    );
}

fn same_seed_same_bytes(scenario: &str, files: &[&str]) {
    let (a, b) = (
        temp_dir(&format!("{scenario}-a")),
        temp_dir(&format!("{scenario}-b")),
    );
    run_scenario_into(scenario, &a, None);
    run_scenario_into(scenario, &b, None);
    for &name in files {
        let x = std::fs::read_to_string(a.join(name)).unwrap();
        let y = std::fs::read_to_string(b.join(name)).unwrap();
        assert!(!x.is_empty(), "{name} is empty");
        if let Some(diff) = first_difference(&x, &y) {
            panic!("{name} differs between two runs with the same seed, {diff}");
        }
        assert_eq!(x.as_bytes(), y.as_bytes(), "{name}");
    }
    let _ = std::fs::remove_dir_all(a);
    let _ = std::fs::remove_dir_all(b);
}

#[test]
fn another_seed_gives_other_scans_and_true_paths() {
    let (a, b) = (temp_dir("seed-a"), temp_dir("seed-b"));
    run_into(&a, Some(1));
    run_into(&b, Some(2));
    let same =
        |name: &str| std::fs::read(a.join(name)).unwrap() == std::fs::read(b.join(name)).unwrap();
    // The seed draws the wheels' slip (the body moves differently) and the laser's noise.
    assert!(!same("truth.tum"), "truth.tum did not change with the seed");
    assert!(
        !same("scans.jsonl"),
        "scans.jsonl did not change with the seed"
    );
    // Slip moves the body, not the wheels: the encoders, hence odometry, do not see it.
    assert!(same("odometry.tum"), "odometry.tum changed with the seed");
    let _ = std::fs::remove_dir_all(a);
    let _ = std::fs::remove_dir_all(b);
}
