//! Issue 17: a step in which the robot moves clear of every wall is integrated without rapier's
//! solver (`sim::twin::systems::step_physics`), as the solver integrates a body that meets
//! nothing. Every bundled scenario gives the same files to the byte with the glide as with
//! rapier stepped at every step — including the ones that drive into walls, brush door frames
//! and stop against furniture.

use crate::common::*;
use sim::commands::run::{RunOptions, run_scenario};
use sim::output::write_all;

#[test]
fn every_scenario_writes_the_same_bytes_with_rapier_at_every_step() {
    let folder = repo().join("scenarios");
    let mut names: Vec<String> = std::fs::read_dir(&folder)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert!(
        names.len() >= 15,
        "the bundled scenarios are found: {names:?}"
    );
    let root = std::env::temp_dir().join(format!("twin-glide-{}", std::process::id()));
    let mut compared = 0;
    for name in &names {
        let scenario = scenario(name);
        let mut files = Vec::new();
        for every_step in [false, true] {
            let options = RunOptions {
                physics_every_step: every_step,
                ..RunOptions::default()
            };
            let record = run_scenario(&scenario, &options, |_, _| {}).unwrap();
            let dir = root.join(format!("{name}-{every_step}"));
            let _ = std::fs::remove_dir_all(&dir);
            write_all(&record, &scenario, &dir).unwrap();
            files.push(dir);
        }
        for entry in std::fs::read_dir(&files[1]).unwrap() {
            let file = entry.unwrap().file_name();
            let read = |dir: &std::path::Path| {
                let bytes = std::fs::read(dir.join(&file))
                    .unwrap_or_else(|e| panic!("{name}: {file:?} not written: {e}"));
                if file != "summary.json" {
                    return bytes;
                }
                // The summary's lines but those holding the wall-clock time.
                String::from_utf8(bytes)
                    .unwrap()
                    .lines()
                    .filter(|l| !l.contains("\"wall_") && !l.contains("\"real_time_factor\""))
                    .collect::<Vec<_>>()
                    .join("\n")
                    .into_bytes()
            };
            let (glided, reference) = (read(&files[0]), read(&files[1]));
            assert!(
                glided == reference,
                "{name}: {file:?} differs between the glide and rapier at every step"
            );
            compared += 1;
        }
        let _ = std::fs::remove_dir_all(&files[0]);
        let _ = std::fs::remove_dir_all(&files[1]);
    }
    assert!(compared > 100, "{compared} files compared");
}
