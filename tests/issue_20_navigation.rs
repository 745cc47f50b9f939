//! Issue 20: controllers that close the loop — `goto X Y` and `explore SECONDS` on the twin,
//! through `twin serve` + `twin drive` (the real backend), and in a replay; the glass door; the
//! closed-loop study over seeds, resumable and shardable.

use crate::common::{drive_served, repo, scenario, svg, twin_into};
use robot::control::{Decision, NavOutcome};
use sim::commands::check::evaluate;
use sim::commands::run::{RunOptions, run_scenario};
use sim::record::RunRecord;
use std::path::Path;

fn run(name: &str, seed: Option<u64>, edit: impl FnOnce(&mut sim::config::Scenario)) -> RunRecord {
    let mut s = scenario(name);
    edit(&mut s);
    let options = RunOptions {
        seed,
        ..RunOptions::default()
    };
    run_scenario(&s, &options, |_, _| {}).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn failed_checks(name: &str, record: &RunRecord) -> Vec<String> {
    evaluate(&scenario(name), record)
        .outcomes
        .into_iter()
        .filter(|o| !o.passed)
        .map(|o| format!("{}: {} (expected {})", o.name, o.measured, o.expected))
        .collect()
}

#[test]
fn goto_reaches_every_goal_round_the_obstacles_on_several_seeds() {
    for seed in [1, 2, 3] {
        let record = run("goto-lab", Some(seed), |_| {});
        let failed = failed_checks("goto-lab", &record);
        assert!(failed.is_empty(), "seed {seed}: {failed:?}");
        let results = record.navigation_results();
        assert_eq!(results.len(), 3, "three goto steps, three outcomes");
        for r in &results {
            assert!(matches!(r.outcome, NavOutcome::Reached { .. }), "{r:?}");
            assert!(r.true_distance_m.unwrap() < 0.5, "{r:?}");
        }
        // It steered by the estimate, which is not the truth: the decisions say where it
        // believed it was, and at least one of those beliefs is off the truth by a centimetre.
        let off = record.decisions.iter().any(|d| {
            let t = record.truth_at(robot::Stamp::from_secs_f64(d.t));
            (d.estimate[0] - t.x).hypot(d.estimate[1] - t.y) > 0.01
        });
        assert!(off, "seed {seed}: the estimate steered, not the truth");
        // The controller's motions are the firmware's own: turns and moves of at most a step.
        for d in &record.decisions {
            if let Decision::Motion {
                turn_rad,
                advance_m,
                ..
            } = d.decision
            {
                assert!(turn_rad.abs() <= 30f64.to_radians() + 1e-9, "{d:?}");
                assert!((0.0..=0.6 + 1e-9).contains(&advance_m), "{d:?}");
            }
        }
    }
}

#[test]
fn the_sonar_keeps_the_robot_out_of_the_glass_door_that_the_laser_sees_through() {
    // With its ring, on these seeds: stops with its reason, touching nothing.
    for seed in [2, 4, 5] {
        let record = run("glass-door-goto", Some(seed), |_| {});
        let failed = failed_checks("glass-door-goto", &record);
        assert!(failed.is_empty(), "seed {seed}: {failed:?}");
        let results = record.navigation_results();
        assert!(
            matches!(
                results[0].outcome,
                NavOutcome::NoWay { .. } | NavOutcome::Blocked { .. }
            ),
            "{results:?}"
        );
    }
    // The same controller ignoring the ring drives into the glass on some of the same seeds:
    // the sonar is what saves it.
    let crashes = [2, 4, 5]
        .into_iter()
        .filter(|&seed| {
            let record = run("glass-door-goto", Some(seed), |s| {
                s.tour.navigation.sonar = None;
            });
            record.collisions > 0
        })
        .count();
    assert!(
        crashes >= 1,
        "laser alone never hit the glass: the test shows nothing"
    );
}

#[test]
fn explore_follows_walls_round_the_room_without_touching_them() {
    let record = run("explore-lab", None, |_| {});
    let failed = failed_checks("explore-lab", &record);
    assert!(failed.is_empty(), "{failed:?}");
    let results = record.navigation_results();
    assert!(
        matches!(results[..], [ref r] if r.outcome == NavOutcome::Explored),
        "{results:?}"
    );
    // Round the room: the path reaches both ends of the LSC.
    let xs: Vec<f64> = record.true_path.iter().map(|(_, p)| p.x).collect();
    let (lo, hi) = xs
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    assert!(lo < 2.0 && hi > 7.0, "explored x {lo:.2}..{hi:.2}");
}

#[test]
fn a_replay_of_a_closed_loop_run_makes_the_same_decisions() {
    let dir = twin_into(
        "goto-replay-source",
        &["run", "scenarios/goto-lab.toml", "--quiet"],
    );
    let tape = dir.join("run.mcap");
    let again = twin_into(
        "goto-replay",
        &[
            "run",
            "scenarios/goto-lab.toml",
            "--replay",
            tape.to_str().unwrap(),
            "--quiet",
        ],
    );
    for file in ["decisions.jsonl", "estimate.tum", "odometry.tum"] {
        let a = std::fs::read(dir.join(file)).unwrap();
        let b = std::fs::read(again.join(file)).unwrap();
        assert!(!a.is_empty(), "{file} is empty");
        assert!(a == b, "{file} differs between the run and its replay");
    }
    let lines = std::fs::read_to_string(dir.join("decisions.jsonl")).unwrap();
    assert!(lines.lines().count() > 10, "{lines}");
    assert_eq!(lines.matches("\"Reached\"").count(), 3);
}

#[test]
fn the_same_goal_through_twin_serve_and_twin_drive_is_reached() {
    let mut s = scenario("goto-lab");
    // One goal, the first, to keep the wall-clock time short at 50x.
    s.steps.truncate(2);
    let (drive, events) = drive_served(&s, 50.0);
    let drive = drive.unwrap_or_else(|e| panic!("{e}; link events {events:?}"));
    let done: Vec<&Decision> = drive
        .decisions
        .iter()
        .map(|d| &d.decision)
        .filter(|d| matches!(d, Decision::Done(_)))
        .collect();
    assert!(
        matches!(done[..], [Decision::Done(NavOutcome::Reached { .. })]),
        "{done:?}"
    );
    assert!(drive.decisions.len() > 3);
}

fn study_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("twin-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn twin(args: &[&str]) -> String {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_twin"))
        .args(args)
        .current_dir(repo())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "twin {args:?}: {stderr}");
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn same_files(a: &Path, b: &Path) {
    for f in [
        "trials.csv",
        "paths.csv",
        "summary.json",
        "table.md",
        "trajectories.svg",
    ] {
        let (x, y) = (
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
        );
        assert!(
            x == y,
            "{f} differs between {} and {}",
            a.display(),
            b.display()
        );
    }
}

#[test]
fn the_closed_loop_study_is_the_same_whole_sharded_or_resumed() {
    let study = "studies/goto-lab.toml";
    let whole = study_dir("nav-whole");
    let w = whole.to_str().unwrap();
    twin(&[
        "montecarlo",
        study,
        "--trials",
        "1",
        "--threads",
        "2",
        "--quiet",
        "--out",
        w,
    ]);
    let table = std::fs::read_to_string(whole.join("table.md")).unwrap();
    assert_eq!(
        table.matches("\n| ").count(),
        5 + 1,
        "a row per condition: {table}"
    );
    let svg_text = std::fs::read_to_string(whole.join("trajectories.svg")).unwrap();
    assert_eq!(svg::problems(&svg_text), Vec::<String>::new());
    // Shards, one of them interrupted and resumed, then merged.
    let (s0, s1) = (study_dir("nav-s0"), study_dir("nav-s1"));
    let (a, b) = (s0.to_str().unwrap(), s1.to_str().unwrap());
    twin(&[
        "montecarlo",
        study,
        "--trials",
        "1",
        "--shard",
        "0/2",
        "--max-trials",
        "1",
        "--quiet",
        "--out",
        a,
    ]);
    assert!(
        !s0.join("trials.csv").exists(),
        "a shard half done writes no results"
    );
    twin(&[
        "montecarlo",
        study,
        "--trials",
        "1",
        "--shard",
        "0/2",
        "--threads",
        "1",
        "--quiet",
        "--out",
        a,
    ]);
    twin(&[
        "montecarlo",
        study,
        "--trials",
        "1",
        "--shard",
        "1/2",
        "--quiet",
        "--out",
        b,
    ]);
    let merged = study_dir("nav-merged");
    twin(&[
        "montecarlo",
        "merge",
        a,
        b,
        "--quiet",
        "--out",
        merged.to_str().unwrap(),
    ]);
    same_files(&whole, &merged);
    // Each row: the trial's goals, how many reached, its collisions and clearance.
    let rows = std::fs::read_to_string(whole.join("trials.csv")).unwrap();
    assert_eq!(rows.lines().count(), 1 + 5);
    for row in rows.lines().skip(1) {
        let f: Vec<&str> = row.split(',').collect();
        assert_eq!(f[6], "3", "three goals: {row}");
        assert!(f[11].parse::<f64>().unwrap().is_finite(), "{row}");
    }
}

#[test]
fn bad_navigation_studies_and_steps_are_named() {
    let dir = study_dir("nav-bad");
    std::fs::create_dir_all(&dir).unwrap();
    let scenario_path = repo().join("scenarios/goto-lab.toml");
    let write = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let base = format!(
        "name = \"x\"\nscenario = \"{}\"\ntrials_per_condition = 2\nseed = 1\n",
        scenario_path.display()
    );
    let cases = [
        (
            format!("{base}[[condition]]\nname = \"a, b\"\n"),
            "condition[0].name",
        ),
        (base.clone(), "condition"),
        (
            format!("{base}[[condition]]\nname = \"a\"\nnoise = {{ outliers = \"lots\" }}\n"),
            "noise.outliers",
        ),
        (
            format!(
                "name = \"x\"\nscenario = \"{}\"\ntrials_per_condition = 2\nseed = 1\n[[condition]]\nname = \"a\"\n",
                repo().join("scenarios/lab-tour.toml").display()
            ),
            "no `goto X Y` step",
        ),
    ];
    for (i, (text, expected)) in cases.iter().enumerate() {
        let path = write(&format!("bad-{i}.toml"), text);
        let e = sim::config::NavStudy::load(&path).unwrap_err().to_string();
        assert!(e.contains(expected), "case {i}: {e}");
        assert!(
            e.contains(&format!("bad-{i}.toml")),
            "the file is named: {e}"
        );
    }
    for bad in ["goto 1", "goto 1 2 3", "goto a b", "explore -5", "explore"] {
        let root = repo().display().to_string();
        let text = std::fs::read_to_string(&scenario_path)
            .unwrap()
            .replace("\"../worlds/", &format!("\"{root}/worlds/"))
            .replace("\"robots/", &format!("\"{root}/scenarios/robots/"))
            .replace("\"goto 7.5 3.3\"", &format!("\"{bad}\""));
        let path = write("bad-step.toml", &text);
        let e = sim::config::Scenario::load(&path).unwrap_err().to_string();
        assert!(e.contains("script.steps[1]"), "{bad}: {e}");
    }
}
