//! Issue 7: every scenario under `scenarios/` is a regression test, found by listing the folder
//! (a new file needs no Rust), run with its own seed and a spread of others (issue 15: a check
//! holds for any seed); a failure names the scenario, the seed and the check out of bounds.
//! Golden digests pin the deterministic
//! outputs (poses and scans) of a few short runs, naming the first scan that differs; and a
//! deliberately tightened bound in a scratch scenario must fail with a readable report.
//!
//! To add a scenario: write `scenarios/NAME.toml` with its `[[check]]`s. To accept a deliberate
//! change of a golden run: `UPDATE_GOLDEN=1 cargo test --release --test suite golden`, and commit
//! `tests/golden/`.

use sim::commands::check::evaluate;
use sim::commands::run::{RunOptions, run_scenario};
use sim::config::Scenario;
use sim::record::RunRecord;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

fn scenarios_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios")
}

fn run(path: &Path) -> (Scenario, RunRecord) {
    let scenario =
        Scenario::load(path).unwrap_or_else(|e| panic!("{}: does not load: {e}", path.display()));
    let record = run_scenario(&scenario, &RunOptions::default(), |_, _| {})
        .unwrap_or_else(|e| panic!("{}: the run failed: {e}", path.display()));
    (scenario, record)
}

/// Seeds each scenario runs with besides its own: `TWIN_SEEDS=N` runs 1..=N (default 5). A
/// check is a claim about the scenario, not about one draw: it must hold for every seed.
fn spread() -> Vec<u64> {
    let n = std::env::var("TWIN_SEEDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(5u64);
    (1..=n).collect()
}

/// Every scenario file under `scenarios/` — found, not listed: a new file is a new case — runs
/// with its own seed and a spread of others, and every check holds for each.
#[test]
fn every_scenario_passes_its_checks_for_every_seed_of_a_spread() {
    use rayon::prelude::*;
    let files = sim::commands::check::scenario_files(&scenarios_dir()).unwrap();
    assert!(
        files.len() >= 15,
        "the shipped scenarios are found: {files:?}"
    );
    let seeds: Vec<Option<u64>> = std::iter::once(None)
        .chain(spread().into_iter().map(Some))
        .collect();
    let runs: Vec<(&PathBuf, Option<u64>)> = files
        .iter()
        .flat_map(|f| seeds.iter().map(move |&s| (f, s)))
        .collect();
    let failures: Vec<String> = runs
        .par_iter()
        .filter_map(|&(file, seed)| {
            let seed_text = seed.map_or("its own seed".to_string(), |s| format!("--seed {s}"));
            match sim::commands::check::check_file(file, seed) {
                Ok((report, _)) if report.outcomes.is_empty() => Some(format!(
                    "{}: a shipped scenario must have at least one [[check]]",
                    file.display()
                )),
                Ok((report, _)) if report.passed() => None,
                Ok((report, _)) => Some(format!("{} with {seed_text}:\n{report}", file.display())),
                Err(e) => Some(format!("{} with {seed_text}: {e}", file.display())),
            }
        })
        .collect();
    assert!(
        failures.is_empty(),
        "{} of {} runs failed their checks:\n{}",
        failures.len(),
        runs.len(),
        failures.join("\n")
    );
}

#[test]
fn a_tightened_bound_fails_with_a_report_naming_the_scenario_and_the_check() {
    let dir = std::env::temp_dir().join(format!("twin-broken-check-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let original = std::fs::read_to_string(scenarios_dir().join("tilted-scan.toml")).unwrap();
    // Paths in the scratch copy point back at the repository's worlds and robots.
    let root = scenarios_dir();
    let text = original
        .replace("\"../worlds/", &format!("\"{}/../worlds/", root.display()))
        .replace("\"robots/", &format!("\"{}/robots/", root.display()))
        .replace("min = 4\nmax = 4", "min = 5\nmax = 6");
    assert_ne!(text, original, "the bound was tightened");
    let path = dir.join("tilted-scan-broken.toml");
    std::fs::write(&path, text).unwrap();
    let (scenario, record) = run(&path);
    let report = evaluate(&scenario, &record);
    assert!(!report.passed());
    let text = report.to_string();
    assert!(text.contains("tilted-scan: 2 check(s), 1 FAILED"), "{text}");
    assert!(
        text.contains("FAIL check[0] scans: measured 4, expected in [5, 6]"),
        "{text}"
    );
    // And `twin run` exits non-zero with that report.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_twin"))
        .args(["run", path.to_str().unwrap(), "-q", "--out"])
        .arg(dir.join("out"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stdout.contains("FAIL check[0] scans"), "{stdout}");
    assert!(stderr.contains("1 of 2 check(s) failed"), "{stderr}");
}

/// One line per kept scan: its stamp, the true and odometry poses, and a hash of its ranges.
fn digest(record: &RunRecord) -> String {
    let mut out =
        String::from("# scan t truth_x truth_y truth_theta odo_x odo_y odo_theta ranges_fnv1a\n");
    for (i, r) in record.scans.iter().enumerate() {
        let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
        for &mm in &r.scan.ranges_mm {
            for b in mm.to_le_bytes() {
                hash = (hash ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3);
            }
        }
        let _ = writeln!(
            out,
            "{i} {} {:.9} {:.9} {:.9} {:.9} {:.9} {:.9} {hash:016x}",
            r.scan.stamp,
            r.truth.x,
            r.truth.y,
            r.truth.theta,
            r.odometry.x,
            r.odometry.y,
            r.odometry.theta
        );
    }
    out
}

/// Compares a run's digest with `tests/golden/NAME.digest`, naming the first scan that differs.
fn golden(file: &str) {
    let (scenario, record) = run(&scenarios_dir().join(file));
    let got = digest(&record);
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/golden")
        .join(format!("{}.digest", scenario.name));
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, &got).unwrap();
        return;
    }
    let expected = std::fs::read_to_string(&path).unwrap_or_else(|e| {
        panic!(
            "{}: {e}; create it with UPDATE_GOLDEN=1 cargo test --release --test suite golden",
            path.display()
        )
    });
    for (k, (e, g)) in expected.lines().zip(got.lines()).enumerate().skip(1) {
        if e != g {
            panic!(
                "{}: scan {} differs first from the golden run\n  golden: {e}\n  now:    {g}\n\
                 (fields: scan t truth_x truth_y truth_theta odo_x odo_y odo_theta ranges_fnv1a;\n\
                 if the change is deliberate, UPDATE_GOLDEN=1 cargo test --release --test suite golden)",
                scenario.name,
                k - 1
            );
        }
    }
    assert_eq!(
        expected.lines().count(),
        got.lines().count(),
        "{}: {} scans in the golden run, {} now",
        scenario.name,
        expected.lines().count() - 1,
        got.lines().count() - 1
    );
}

#[test]
fn golden_orthogonal_doors() {
    golden("orthogonal-doors.toml");
}

#[test]
fn golden_pan_tilt_sweep() {
    golden("pan-tilt-sweep.toml");
}

#[test]
fn golden_wall_collision() {
    golden("wall-collision.toml");
}

#[test]
fn the_digest_names_the_first_differing_scan() {
    // A digest compared with itself, one range changed: the message names that scan.
    let (_, mut record) = run(&scenarios_dir().join("wall-collision.toml"));
    let before = digest(&record);
    let last = record.scans.len() - 1;
    record.scans[last].scan.ranges_mm[100] += 1;
    let after = digest(&record);
    let first = before
        .lines()
        .zip(after.lines())
        .position(|(a, b)| a != b)
        .unwrap();
    assert_eq!(first - 1, last, "the changed scan is the first difference");
}

#[test]
fn malformed_checks_and_steps_are_refused_naming_the_field() {
    let dir = std::env::temp_dir().join(format!("twin-bad-checks-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let root = scenarios_dir();
    let head = format!(
        "name = \"bad\"\nworld = \"{0}/../worlds/orthogonal.toml\"\nrobot = \"{0}/robots/pioneer-3dx.toml\"\nseed = 1\n[script]\nsteps = [\"move 0.5\"]\n",
        root.display()
    );
    let cases = [
        (
            "[[check]]\nkind = \"colisions\"\nmax = 0\n",
            "check[0].kind",
            "unknown check \"colisions\"",
        ),
        (
            "[[check]]\nkind = \"collisions\"\n",
            "check[0].kind",
            "needs a bound: min / max",
        ),
        (
            "[[check]]\nkind = \"scans\"\nmax_m = 3\n",
            "check[0].max_m",
            "takes no min_m / max_m",
        ),
        (
            "[[check]]\nkind = \"map_quality\"\nmin_share = 0.5\n",
            "check[0].kind",
            "needs a [localisation] table",
        ),
        (
            "[[check]]\nkind = \"scans\"\nmin = -1\n",
            "check[0].min",
            "expected a bound from 0 to 1e9, found -1",
        ),
        (
            "[[check]]\nkind = \"scans\"\nmin = 5\nmax = 2\n",
            "check[0].min",
            "could never pass",
        ),
        (
            "[[check]]\nkind = \"scans\"\nmin = 1\ncolour = 3\n",
            "",
            "unknown field `colour`",
        ),
    ];
    for (i, (extra, field, message)) in cases.iter().enumerate() {
        let path = dir.join(format!("bad-{i}.toml"));
        std::fs::write(&path, format!("{head}{extra}")).unwrap();
        let e = Scenario::load(&path).unwrap_err();
        let text = e.to_string();
        assert!(text.contains(message), "case {i}: {text}");
        if !field.is_empty() {
            assert_eq!(e.field.as_deref(), Some(*field), "case {i}: {text}");
        }
        assert!(e.line.is_some(), "case {i}: the line is named: {text}");
    }
    // A head step on a robot without a pan-tilt.
    let path = dir.join("bad-head.toml");
    std::fs::write(&path, head.replace("\"move 0.5\"", "\"sweep 0 10 50 10\"")).unwrap();
    let e = Scenario::load(&path).unwrap_err().to_string();
    assert!(
        e.contains("script.steps[0]") && e.contains("has no pan-tilt unit"),
        "{e}"
    );
}
