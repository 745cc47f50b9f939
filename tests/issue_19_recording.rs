//! Issue 19, recording: every `twin run` writes `run.mcap`, ROS 2 messages in CDR with `ros2msg`
//! schemas. Decoded here by the MCAP project's own Python reader (`mcap-ros2-support`, which
//! `.ci/run` installs: independent of the Rust writer) and held against the run's other files —
//! `/scan` against `scans.jsonl` (same stamps, same ranges, no return as +inf), `/odom`,
//! `/ground_truth` and `/estimate` against the TUM files, `map` → `odom` → `base_link` against
//! the truth, the pan-tilt's transforms against the laser pose `scans.jsonl` gives, the sonar
//! ring against `sonar.json`, the 3D model's cloud against `model.ply`. Then `twin map` maps a
//! recording as it maps a CARMEN log, and the same seed writes the same bytes.

use crate::common::repo;
use std::path::{Path, PathBuf};
use std::process::Command;

/// `twin ARGS --out DIR` into a fresh folder named after `name`.
fn twin_into(name: &str, args: &[&str]) -> PathBuf {
    crate::common::twin_into(&format!("issue-19-rec-{name}"), args)
}

/// The Python reader's report on a run folder.
pub fn python_reads(dir: &Path) -> serde_json::Value {
    let out = Command::new("python3")
        .arg(repo().join("tests/python/read_run_mcap.py"))
        .arg(dir)
        .output()
        .expect("python3 (and `pip install mcap-ros2-support`, as .ci/run does)");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "the Python MCAP reader refused {}: {stderr}\n(it needs `pip install mcap-ros2-support`)",
        dir.display()
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn count(report: &serde_json::Value, topic: &str) -> u64 {
    report["topics"][topic]["count"].as_u64().unwrap_or(0)
}

fn scans_in(dir: &Path) -> u64 {
    std::fs::read_to_string(dir.join("scans.jsonl"))
        .unwrap()
        .lines()
        .count() as u64
}

#[test]
fn a_localising_run_reads_back_in_the_python_reader() {
    let dir = twin_into("tour", &["run", "scenarios/lab-tour.toml", "--quiet"]);
    let report = python_reads(&dir);
    let scans = scans_in(&dir);
    assert!(scans > 20);
    for topic in [
        "/scan",
        "/odom",
        "/tf",
        "/ground_truth",
        "/clock",
        "/estimate",
    ] {
        assert_eq!(count(&report, topic), scans, "{topic}: {report}");
    }
    assert_eq!(
        report["topics"]["/scan"]["type"],
        "sensor_msgs/msg/LaserScan"
    );
    assert_eq!(count(&report, "/tf_static"), 1);
}

#[test]
fn the_pan_tilt_the_sonar_ring_and_the_3d_model_read_back() {
    let scene = twin_into("scene", &["run", "scenarios/scene-lab.toml", "--quiet"]);
    let report = python_reads(&scene);
    assert_eq!(
        report["head_transforms_checked"].as_u64(),
        Some(scans_in(&scene)),
        "every scan's head transforms checked: {report}"
    );
    assert_eq!(count(&report, "/points"), 1, "{report}");
    let ring = twin_into("ring", &["run", "scenarios/sonar-ring.toml", "--quiet"]);
    let report = python_reads(&ring);
    assert_eq!(report["sonar_checked"].as_u64(), Some(16), "{report}");
    assert_eq!(
        report["topics"]["/sonar/0"]["type"],
        "sensor_msgs/msg/Range"
    );
}

#[test]
fn twin_map_maps_a_recording_and_the_same_seed_writes_the_same_bytes() {
    let a = twin_into("seed-a", &["run", "scenarios/lab-tour.toml", "--quiet"]);
    let b = twin_into("seed-b", &["run", "scenarios/lab-tour.toml", "--quiet"]);
    let bytes = std::fs::read(a.join("run.mcap")).unwrap();
    assert!(
        bytes == std::fs::read(b.join("run.mcap")).unwrap(),
        "run.mcap differs between two runs of one seed"
    );
    let log = robot::logs::read_log(&a.join("run.mcap")).unwrap();
    assert_eq!(log.format, robot::logs::LogFormat::Mcap);
    assert_eq!(log.scans() as u64, scans_in(&a));
    assert_eq!(log.odometry_samples() as u64, scans_in(&a));
    // The laser's mount came from /tf_static: the Pioneer's laser is ahead of the axle.
    let pioneer = crate::common::robot("pioneer-3dx");
    assert!(
        (log.mount.x - pioneer.laser.x_m.get()).abs() < 1e-9,
        "{:?}",
        log.mount
    );
    let map_dir = twin_into(
        "map",
        &[
            "map",
            a.join("run.mcap").to_str().unwrap(),
            "--matcher",
            "lorentz",
            "--quiet",
        ],
    );
    for file in ["map.pgm", "map.yaml", "estimate.tum", "summary.json"] {
        assert!(map_dir.join(file).exists(), "twin map wrote no {file}");
    }
    // A cut recording is refused with the file's name, not read in part.
    let cut = a.join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let err = robot::logs::read_log(&cut).unwrap_err().to_string();
    assert!(err.contains("cut.mcap"), "{err}");
}

/// `twin` with `args` from the repository, given at most a minute: a reader that loops on a
/// broken file fails the test rather than hanging it.
fn twin_within_a_minute(args: &[&str]) -> std::process::Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_twin"))
        .args(args)
        .current_dir(repo())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    while child.try_wait().unwrap().is_none() {
        if std::time::Instant::now() > deadline {
            let _ = child.kill();
            panic!("twin {args:?} did not finish in a minute");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

#[test]
fn compressed_bags_map_and_replay_like_the_plain_one() {
    let dir = twin_into(
        "compressed-source",
        &["run", "scenarios/lab-tour.toml", "--quiet"],
    );
    let plain = dir.join("run.mcap");
    let mapped = twin_into("compressed-plain", &["map", plain.to_str().unwrap()]);
    for kind in ["zstd", "lz4"] {
        // Recompressed by the MCAP project's own Python writer, as other tools write bags.
        let bag = dir.join(format!("run-{kind}.mcap"));
        let out = Command::new("python3")
            .arg(repo().join("tests/python/recompress_mcap.py"))
            .args([&plain, &bag])
            .arg(kind)
            .output()
            .expect("python3 with mcap, zstandard and lz4 (.ci/run installs them)");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(
            std::fs::metadata(&bag).unwrap().len() < std::fs::metadata(&plain).unwrap().len(),
            "{kind}: the copy is compressed"
        );
        let again = twin_into(
            &format!("compressed-{kind}"),
            &["map", bag.to_str().unwrap()],
        );
        for file in ["estimate.tum", "odometry.tum", "map.pgm"] {
            let (a, b) = (
                std::fs::read(mapped.join(file)).unwrap(),
                std::fs::read(again.join(file)).unwrap(),
            );
            assert!(a == b, "{kind}: {file} differs from the plain bag's");
        }
        let replayed = twin_into(
            &format!("compressed-replay-{kind}"),
            &[
                "run",
                "scenarios/lab-tour.toml",
                "--replay",
                bag.to_str().unwrap(),
                "--quiet",
            ],
        );
        assert_eq!(
            std::fs::read(replayed.join("estimate.tum")).unwrap(),
            std::fs::read(dir.join("estimate.tum")).unwrap(),
            "{kind}: the replay of the compressed tape"
        );
    }
    // Cut short anywhere, compressed or not: a clear error naming the file, never a hang.
    for kind in ["zstd", "lz4", "plain"] {
        let bag = match kind {
            "plain" => plain.clone(),
            _ => dir.join(format!("run-{kind}.mcap")),
        };
        let bytes = std::fs::read(&bag).unwrap();
        for cut in [100, bytes.len() / 3, bytes.len() - 10] {
            let short = dir.join(format!("short-{kind}-{cut}.mcap"));
            std::fs::write(&short, &bytes[..cut]).unwrap();
            let out = twin_within_a_minute(&[
                "map",
                short.to_str().unwrap(),
                "--out",
                dir.join("short-out").to_str().unwrap(),
            ]);
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert!(!out.status.success(), "{kind} cut at {cut}: accepted");
            assert!(
                stderr.contains(short.file_name().unwrap().to_str().unwrap()),
                "{stderr}"
            );
        }
    }
}

/// `run.mcap` holds the run's events in the order they happened, as the run writes it while it
/// goes on: `/tf_static` first, then the tape's exchanges in their order with each kept scan's
/// topics after the exchange that brought the scan back — so a reader going through the file
/// meets each scan within a second of simulated time of the exchanges around it — and the file
/// is the one the run's record gives afterwards.
#[test]
fn the_recording_holds_the_runs_events_in_the_order_they_happened() {
    use sim::commands::run::{RunOptions, run_scenario};
    let scenario = crate::common::scenario("lab-tour");
    for seed in [4, 9] {
        let options = RunOptions {
            seed: Some(seed),
            stream: true,
            ..RunOptions::default()
        };
        let record = run_scenario(&scenario, &options, |_, _| {}).expect("the run");
        let dir =
            std::env::temp_dir().join(format!("twin-issue-19-order-{}-{seed}", std::process::id()));
        sim::output::write_all(&record, &scenario, &dir).unwrap();
        let bytes = std::fs::read(dir.join("run.mcap")).unwrap();
        let messages: Vec<(String, u64, Vec<u8>)> = mcap::MessageStream::new(&bytes)
            .expect("an MCAP file")
            .map(|m| {
                let m = m.expect("a message");
                (m.channel.topic.clone(), m.log_time, m.data.to_vec())
            })
            .collect();
        assert_eq!(
            messages[0].0, "/tf_static",
            "seed {seed}: the static frames first"
        );
        // The stamp of the scan each exchange brought back, if any (CDR: a 4-byte header, the
        // string's length, the JSON).
        let tape: Vec<(usize, u64, Option<u64>)> = messages
            .iter()
            .enumerate()
            .filter(|(_, m)| m.0 == "/hardware/tape")
            .map(|(k, m)| {
                let json: serde_json::Value =
                    serde_json::from_slice(&m.2[8..m.2.len() - 1]).expect("JSON");
                (k, m.1, json["scan"]["stamp"].as_u64())
            })
            .collect();
        assert_eq!(tape.len(), record.tape.len(), "seed {seed}: every exchange");
        let scans: Vec<(usize, u64)> = messages
            .iter()
            .enumerate()
            .filter(|(_, m)| m.0 == "/clock")
            .map(|(k, m)| (k, m.1))
            .collect();
        assert_eq!(
            scans.len(),
            record.scans.len(),
            "seed {seed}: every kept scan"
        );
        for &(k, t) in &scans {
            let brought = tape
                .iter()
                .position(|e| e.2 == Some(t))
                .unwrap_or_else(|| panic!("seed {seed}: no exchange brought the scan at {t} ns"));
            assert!(
                tape[brought].0 < k,
                "seed {seed}: the scan at {t} ns comes before the exchange that brought it"
            );
            let before = tape.iter().rev().find(|e| e.0 < k).expect("an exchange");
            assert!(
                before.1.abs_diff(t) < 1_000_000_000,
                "seed {seed}: the scan at {t} ns is {} ns from the exchange before it",
                before.1.abs_diff(t)
            );
        }
        let mut after = record.clone();
        after.streamed = None;
        let again = dir.join("after");
        sim::output::write_all(&after, &scenario, &again).unwrap();
        assert!(
            std::fs::read(again.join("run.mcap")).unwrap() == bytes,
            "seed {seed}: the recording written afterwards is another file"
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
