//! `twin run`: the README's main job writes trajectories in TUM format, scans as JSON Lines, a
//! summary and a map; every shipped scenario runs to its end without hitting a wall.

use crate::common::*;
use sim::commands::run::{RunOptions, run_scenario};
use sim::output::ScanLine;
use std::process::Command;

#[test]
fn the_main_job_writes_its_five_files() {
    let out = std::env::temp_dir().join(format!("twin-run-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let status = Command::new(env!("CARGO_BIN_EXE_twin"))
        .args(["run", "scenarios/lab-tour.toml", "--quiet", "--out"])
        .arg(&out)
        .current_dir(repo())
        .status()
        .unwrap();
    assert!(status.success());

    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    for key in [
        "sim_seconds",
        "wall_seconds",
        "real_time_factor",
        "distance_m",
        "final_odometry_error_m",
        "final_odometry_error_deg",
        "scans",
        "seed",
    ] {
        assert!(
            summary.get(key).is_some_and(|v| v.is_number()),
            "summary lacks {key}"
        );
    }
    let scans = summary["scans"].as_u64().unwrap() as usize;
    assert!(scans > 40, "{summary}");
    assert_eq!(summary["seed"], 2007);
    assert!(summary["sim_seconds"].as_f64().unwrap() > 60.0);
    assert!(summary["real_time_factor"].as_f64().unwrap() > 1.0);

    for name in ["truth.tum", "odometry.tum"] {
        let text = std::fs::read_to_string(out.join(name)).unwrap();
        let lines: Vec<&str> = text.lines().filter(|l| !l.starts_with('#')).collect();
        assert_eq!(lines.len(), scans, "{name}: one line per scan");
        for line in lines {
            let fields: Vec<f64> = line.split(' ').map(|f| f.parse().unwrap()).collect();
            assert_eq!(fields.len(), 8, "{name}: {line}");
            let norm = fields[4..].iter().map(|q| q * q).sum::<f64>();
            assert!((norm - 1.0).abs() < 1e-6, "{name}: quaternion {line}");
        }
    }

    let text = std::fs::read_to_string(out.join("scans.jsonl")).unwrap();
    let lines: Vec<ScanLine> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), scans);
    for l in &lines {
        assert_eq!(l.ranges.len(), 361);
        assert!((l.angle_min + std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert!((l.angle_increment - 0.5f64.to_radians()).abs() < 1e-12);
        assert_eq!(l.range_max, 32.0);
        assert!(l.ranges.iter().all(|&r| (0.0..=32.0).contains(&r)));
    }
    assert!(
        lines.windows(2).all(|w| w[0].t < w[1].t),
        "scans in time order"
    );

    let svg = std::fs::read_to_string(out.join("map.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    assert!(svg.contains("true path") && svg.contains("odometry"));
    let _ = std::fs::remove_dir_all(out);
}

/// Every scenario runs all its steps and keeps scans. Whether it may touch a wall or must drive
/// is each scenario's own `[[check]]` now (issue 7: `wall-collision` must collide,
/// `pan-tilt-sweep` stands still).
#[test]
fn every_shipped_scenario_runs_to_its_end() {
    let mut names: Vec<String> = std::fs::read_dir(repo().join("scenarios"))
        .unwrap()
        .filter_map(|e| {
            let path = e.ok()?.path();
            (path.extension()? == "toml").then(|| path.file_stem()?.to_str().map(String::from))?
        })
        .collect();
    names.sort();
    assert!(names.len() >= 3, "{names:?}");
    for name in names {
        let s = scenario(&name);
        let record = run_scenario(&s, &RunOptions::default(), |_, _| {})
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(record.steps, s.steps.len(), "{name}");
        assert!(!record.scans.is_empty(), "{name} kept no scan");
        let collision_expected = s.checks.iter().any(|c| {
            c.kind == sim::config::checks::CheckKind::Collisions
                && c.bounds.min.is_some_and(|m| m >= 1.0)
        });
        if !collision_expected {
            assert_eq!(record.collisions, 0, "{name} hit a wall");
        }
    }
}
