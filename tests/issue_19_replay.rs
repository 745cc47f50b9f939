//! Issue 19, replay: `ReplayRobot`, the third backend of the hardware contract, answers every
//! call from the tape a run recorded in `run.mcap`. `twin run SCENARIO --replay run.mcap` runs
//! the scenario's controller and localiser on it and writes the same estimate, odometry and scans,
//! byte for byte; a controller that decides differently is stopped and named.

use crate::common::repo;
use std::path::PathBuf;
use std::process::Command;

/// Runs `twin ARGS --out DIR`; returns the folder, or the error text when `ok` is false.
fn twin(name: &str, args: &[&str], ok: bool) -> (PathBuf, String) {
    let dir = std::env::temp_dir().join(format!(
        "twin-issue-19-replay-{name}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    let out = Command::new(env!("CARGO_BIN_EXE_twin"))
        .args(args)
        .arg("--quiet")
        .arg("--out")
        .arg(&dir)
        .current_dir(repo())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.success(), ok, "twin {args:?}: {stderr}");
    (dir, stderr)
}

fn same_files(a: &std::path::Path, b: &std::path::Path, files: &[&str]) {
    for file in files {
        let (x, y) = (
            std::fs::read(a.join(file)).unwrap_or_else(|e| panic!("{file}: {e}")),
            std::fs::read(b.join(file)).unwrap_or_else(|e| panic!("{file}: {e}")),
        );
        assert!(x == y, "{file} differs between the run and its replay");
    }
}

#[test]
fn a_replay_gives_the_runs_estimate_byte_for_byte() {
    // The lab tour (localising) and the thesis's robot with its pan-tilt and sonar ring running.
    for scenario in ["lab-tour", "lab-tour-thesis"] {
        let path = format!("scenarios/{scenario}.toml");
        let (run, _) = twin(&format!("{scenario}-run"), &["run", &path], true);
        let recording = run.join("run.mcap");
        let (replay, _) = twin(
            &format!("{scenario}-replay"),
            &["run", &path, "--replay", recording.to_str().unwrap()],
            true,
        );
        let mut files = vec!["odometry.tum", "scans.jsonl"];
        if run.join("estimate.tum").exists() {
            files.push("estimate.tum");
        }
        same_files(&run, &replay, &files);
        // The replay recorded its tape again: a replay of the replay gives the same again.
        let (again, _) = twin(
            &format!("{scenario}-again"),
            &[
                "run",
                &path,
                "--replay",
                replay.join("run.mcap").to_str().unwrap(),
            ],
            true,
        );
        same_files(&replay, &again, &files);
    }
}

#[test]
fn a_controller_that_decides_differently_is_stopped_and_named() {
    let (run, _) = twin("differ-run", &["run", "scenarios/lab-tour.toml"], true);
    // Another script on the lab tour's recording: its first different call stops it.
    let (_, stderr) = twin(
        "differ-replay",
        &[
            "run",
            "scenarios/wall-collision.toml",
            "--replay",
            run.join("run.mcap").to_str().unwrap(),
        ],
        false,
    );
    assert!(
        stderr.contains("decided differently") && stderr.contains("exchange "),
        "{stderr}"
    );
    // A file with no tape says what a replay needs.
    let log = repo().join("tests/data/corrected/README.md");
    let (_, stderr) = twin(
        "no-tape",
        &[
            "run",
            "scenarios/lab-tour.toml",
            "--replay",
            log.to_str().unwrap(),
        ],
        false,
    );
    assert!(stderr.contains("README.md"), "{stderr}");
}

/// The real robot's path: a drive through `SerialRobot` (against `twin serve`, as `twin drive`
/// tapes it) with the sonar ring firing and the pan-tilt homed, replayed through `ReplayRobot`:
/// the same calls, the same estimate.
#[test]
fn a_served_drive_replays_with_its_sonar_and_head() {
    // The tilted-scan tour (thesis robot, head positioned first) with the ring firing too.
    let mut scenario = crate::common::scenario("tilted-scan");
    scenario.sonar = crate::common::scenario("lab-tour-thesis").sonar;
    assert!(scenario.sonar.is_some());
    let (drive, events) = crate::common::drive_served(&scenario, 20.0);
    let drive = drive.unwrap_or_else(|e| panic!("{e}; events: {events:#?}"));
    assert!(
        drive
            .tape
            .iter()
            .any(|x| matches!(x.call, robot::replay::Call::Sonar { .. })),
        "the drive fired the ring"
    );
    let replayed = sim::commands::replay::replay_scenario(&scenario, drive.tape.clone(), |_, _| {})
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(replayed.scans, drive.scans);
    assert_eq!(replayed.final_odometry, drive.final_odometry);
    assert_eq!(
        replayed.localisation.as_ref().map(|l| &l.1),
        drive.localisation.as_ref().map(|l| &l.1)
    );
}
