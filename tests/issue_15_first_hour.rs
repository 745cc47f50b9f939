//! Issue 15: a newcomer's first hour. Every picture a run writes keeps its drawing inside the
//! canvas and lists in its legend exactly what it draws; the messages a newcomer meets first say
//! what is wrong and what was expected; a study can be run small and still give its table.

use crate::common::svg;

use std::path::{Path, PathBuf};
use std::process::Command;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("twin-issue-15-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn twin(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_twin"))
        .args(args)
        .current_dir(repo())
        .output()
        .expect("twin runs")
}

/// The SVG files in `dir`.
fn pictures(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "svg"))
        .collect();
    files.sort();
    files
}

fn assert_pictures_sound(files: &[PathBuf]) {
    let mut failures = Vec::new();
    for file in files {
        let text = std::fs::read_to_string(file).unwrap();
        for problem in svg::problems(&text) {
            failures.push(format!("{}: {problem}", file.display()));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn the_picture_reader_sees_what_is_outside_and_what_the_legend_misses() {
    // A checker that cannot fail proves nothing: feed it a flawed picture.
    let bad = r#"<svg width="100" height="50" font-size="10"><g data-layer="a"><circle cx="99" cy="20" r="3"/></g><g data-layer="b"><path d="M1 1h0"/></g><g data-legend="a"><text x="5" y="45">a</text></g><g data-legend="c"><text x="50" y="45">c</text></g></svg>"#;
    let problems = svg::problems(bad);
    assert!(
        problems.iter().any(|p| p.contains("outside")),
        "{problems:?}"
    );
    assert!(
        problems
            .iter()
            .any(|p| p == "drawn but not in the legend: b"),
        "{problems:?}"
    );
    assert!(
        problems
            .iter()
            .any(|p| p == "in the legend but not drawn: c"),
        "{problems:?}"
    );
    let nonsense = r#"<svg width="100" height="50" font-size="10"><g data-layer="a"><circle cx="50" cy="20" r="3"/></g><g data-legend="a"><text x="5" y="45">floor at inf m</text></g></svg>"#;
    assert!(
        svg::problems(nonsense)
            .iter()
            .any(|p| p.contains("\"inf\"")),
        "{:?}",
        svg::problems(nonsense)
    );
    let good = r#"<svg width="100" height="50" font-size="10"><g data-layer="a"><circle cx="50" cy="20" r="3"/></g><g data-legend="a"><text x="5" y="45">a</text></g></svg>"#;
    assert_eq!(svg::problems(good), Vec::<String>::new());
}

#[test]
fn every_picture_of_every_scenario_is_inside_its_frame_with_a_matching_legend() {
    let out = scratch("pictures");
    let mut files = Vec::new();
    let scenarios = sim::commands::check::scenario_files(&repo().join("scenarios")).unwrap();
    for path in &scenarios {
        let scenario = sim::config::Scenario::load(path).unwrap();
        let record = sim::commands::run::run_scenario(
            &scenario,
            &sim::commands::run::RunOptions::default(),
            |_, _| {},
        )
        .unwrap();
        let dir = out.join(&scenario.name);
        sim::output::write_all(&record, &scenario, &dir).unwrap();
        files.extend(pictures(&dir));
    }
    assert!(
        files.len() > scenarios.len(),
        "every run writes map.svg, some more: {files:?}"
    );
    assert!(files.iter().any(|f| f.ends_with("tilted-scan.svg")));
    assert_pictures_sound(&files);
}

#[test]
fn the_pictures_of_twin_map_and_of_a_study_are_sound_too() {
    let out = scratch("map-and-study");
    let map_dir = out.join("map");
    let o = twin(&[
        "map",
        "tests/data/mit-csail.clf",
        "--quiet",
        "--out",
        map_dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let study_dir = out.join("study");
    let o = twin(&[
        "montecarlo",
        "studies/table-5-1.toml",
        "--trials",
        "3",
        "--threads",
        "1",
        "--quiet",
        "--out",
        study_dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut files = pictures(&map_dir);
    files.extend(pictures(&study_dir));
    assert!(files.iter().any(|f| f.ends_with("map.svg")), "{files:?}");
    assert!(files.iter().any(|f| f.ends_with("errors.svg")), "{files:?}");
    assert_pictures_sound(&files);
}

#[test]
fn a_small_study_still_writes_its_table() {
    let dir = scratch("small-study");
    let o = twin(&[
        "montecarlo",
        "studies/table-5-1.toml",
        "--trials",
        "4",
        "--threads",
        "2",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let table = std::fs::read_to_string(dir.join("table.md")).expect("table.md written");
    assert!(table.contains("4 trials per rate"), "{table}");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("8 trials run"), "{stdout}");
    // The folder holds the smaller study: its file says so, and the full study is refused there.
    let kept = std::fs::read_to_string(dir.join("study.toml")).unwrap();
    assert!(kept.contains("trials_per_rate = 4"), "{kept}");
    let o = twin(&[
        "montecarlo",
        "studies/table-5-1.toml",
        "--quiet",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    // And zero trials is refused by the option itself.
    let o = twin(&["montecarlo", "studies/table-5-1.toml", "--trials", "0"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--trials"));
}

#[test]
fn a_missing_log_names_the_file_and_the_os_error_once() {
    let o = twin(&["map", "nothere.clf"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("nothere.clf"), "{err}");
    assert_eq!(err.matches("No such file").count(), 1, "{err}");
}

#[test]
fn driving_a_pan_tilt_scenario_without_its_address_names_the_missing_flag() {
    let o = twin(&[
        "drive",
        "scenarios/pan-tilt-sweep.toml",
        "--base",
        "tcp:127.0.0.1:9",
        "--laser",
        "tcp:127.0.0.1:9",
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--pantilt is needed"), "{err}");
    assert!(!err.contains("has no pan-tilt"), "{err}");
}

#[test]
fn a_ramp_argument_out_of_range_gives_the_ramps_range() {
    use robot::protocol::base::parse_command_text;
    let e = parse_command_text("k5 -30 50").unwrap_err().to_string();
    assert!(e.contains("argument 2 (Pf)") && e.contains("0..=90"), "{e}");
    let e = parse_command_text("v300 100").unwrap_err().to_string();
    assert!(e.contains("10..=190"), "{e}");
    let e = parse_command_text("w100 2x 1 0").unwrap_err().to_string();
    assert!(e.contains("(Fi)") && e.contains("0..=1"), "{e}");
    let e = parse_command_text("a-5").unwrap_err().to_string();
    assert!(e.contains("0..=65535"), "{e}");
    // Parsed numbers out of range are named by the same rule.
    let e = parse_command_text("k5 95 50").unwrap_err().to_string();
    assert!(e.contains("Pf") && e.contains("90"), "{e}");
}

#[test]
fn twin_check_with_seeds_reports_each_checks_spread() {
    let o = twin(&[
        "check",
        "scenarios/tilted-scan.toml",
        "--seeds",
        "3",
        "--quiet",
    ]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{out}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(
        out.contains("## tilted-scan — seeds 1..=3: 3 of 3 runs pass every check"),
        "{out}"
    );
    assert!(
        out.contains("| check | bound | min | median | 95 % | max | seeds passing |"),
        "{out}"
    );
    assert!(
        out.contains("| check[0] scans |") && out.contains("| 3/3 |"),
        "{out}"
    );
    // A bound no seed meets fails the command and names each failing seed.
    let dir = scratch("seeds");
    let text = std::fs::read_to_string(repo().join("scenarios/tilted-scan.toml"))
        .unwrap()
        .replace("\"../worlds/", &format!("\"{}/worlds/", repo().display()))
        .replace(
            "\"robots/",
            &format!("\"{}/scenarios/robots/", repo().display()),
        )
        .replace("min = 4\nmax = 4", "min = 5\nmax = 6");
    let path = dir.join("tight.toml");
    std::fs::write(&path, text).unwrap();
    let o = twin(&["check", path.to_str().unwrap(), "--seeds", "2", "--quiet"]);
    assert!(!o.status.success());
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("0 of 2 runs pass"), "{out}");
    assert!(out.contains("--seed 1: FAIL check[0] scans"), "{out}");
    assert!(out.contains("--seed 2: FAIL check[0] scans"), "{out}");
}

#[test]
fn the_world_example_of_formats_md_loads() {
    let text = std::fs::read_to_string(repo().join("FORMATS.md")).unwrap();
    let world = text.split("## World").nth(1).expect("a World section");
    let example = world
        .split("```toml\n")
        .nth(1)
        .and_then(|b| b.split("```").next())
        .expect("a toml example");
    let dir = scratch("formats");
    let path = dir.join("world.toml");
    std::fs::write(&path, example).unwrap();
    let w = sim::config::WorldDescription::load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(!w.walls.is_empty());
}

#[test]
fn twin_pairs_makes_what_twin_match_reads() {
    let dir = scratch("pairs");
    let o = twin(&[
        "run",
        "scenarios/lab-tour.toml",
        "--quiet",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = twin(&["pairs", dir.to_str().unwrap(), "--max", "4"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let pairs = o.stdout;
    assert_eq!(pairs.iter().filter(|&&b| b == b'\n').count(), 4);
    let mut child = Command::new(env!("CARGO_BIN_EXE_twin"))
        .arg("match")
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    use std::io::Write;
    child.stdin.take().unwrap().write_all(&pairs).unwrap();
    let out = child.wait_with_output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(text.lines().count(), 4, "{text}");
    assert!(
        text.lines().all(|l| l.contains("\"converged\":true")),
        "{text}"
    );
    // The first motion of the tour is 0.5 m ahead: the match finds it.
    let first: serde_json::Value = serde_json::from_str(text.lines().next().unwrap()).unwrap();
    assert!((first["x"].as_f64().unwrap() - 0.5).abs() < 0.05, "{first}");
    // The shipped example answers too.
    let shipped = std::fs::read(repo().join("tests/data/pairs.jsonl")).unwrap();
    assert!(shipped.iter().filter(|&&b| b == b'\n').count() >= 3);
}

/// `twin pairs` reads a recorded log too: each scan with the next, the guess the laser's motion
/// by the log's odometry. Checked against the MIT log's first `FLASER` lines read here on their
/// own (in this file `x y theta` are the odometry, and no laser offset is declared).
#[test]
fn twin_pairs_reads_a_log() {
    let log = repo().join("tests/data/mit-csail.clf");
    let o = twin(&["pairs", log.to_str().unwrap(), "--max", "3"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    let pairs: Vec<serde_json::Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).expect("a JSON pair"))
        .collect();
    assert_eq!(pairs.len(), 3, "{text}");
    let lines = std::fs::read_to_string(&log).unwrap();
    let flaser: Vec<(Vec<f64>, [f64; 3])> = lines
        .lines()
        .filter(|l| l.starts_with("FLASER "))
        .take(4)
        .map(|l| {
            let f: Vec<f64> = l
                .split_whitespace()
                .skip(1)
                .filter_map(|w| w.parse().ok())
                .collect();
            let n = f[0] as usize;
            (f[1..=n].to_vec(), [f[n + 1], f[n + 2], f[n + 3]])
        })
        .collect();
    for (k, pair) in pairs.iter().enumerate() {
        let ([ax, ay, at], [bx, by, bt]) = (flaser[k].1, flaser[k + 1].1);
        let (dx, dy) = (bx - ax, by - ay);
        let want = [
            at.cos() * dx + at.sin() * dy,
            -at.sin() * dx + at.cos() * dy,
            (bt - at + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI,
        ];
        let guess: Vec<f64> = pair["guess"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        for i in 0..3 {
            assert!(
                (guess[i] - want[i]).abs() < 1e-9,
                "pair {k}: guess {guess:?}, want {want:?}"
            );
        }
        let ranges = pair["cur"]["ranges"].as_array().unwrap();
        assert_eq!(ranges.len(), flaser[k + 1].0.len(), "pair {k}");
        assert_eq!(ranges[100].as_f64(), Some(flaser[k + 1].0[100]), "pair {k}");
    }
    // A file that is neither a run's folder nor a log is named in the error.
    let o = twin(&["pairs", "no-such-log.clf"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("no-such-log.clf"));
}
