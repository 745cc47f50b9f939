//! Issue 4: localisation that runs unchanged on the twin and the real robot.
//!
//! Every matcher on twin scan pairs with known truth (small motions, 2 % and 20 % uniform
//! outliers, 25° turns), the L-corridor of 002 App. E built from its wall equations, the map
//! builder on a twin run and on the real MIT CSAIL log, and the `twin map` / `twin match`
//! interfaces with their bad-input behaviour.

use crate::common;

use rand::{RngExt, SeedableRng};
use robot::Pose2;
use robot::geometry::wrap_angle;
use robot::localization::{MatcherKind, RangeScan, ScanMatcher};
use sim::commands::montecarlo::pairs::{PairMaker, ScanPair};
use sim::config::Outliers;
use std::io::Write;
use std::process::{Command, Stdio};

/// `(translation error m, heading error rad)` of a match against the truth.
fn error(matcher: &dyn ScanMatcher, pair: &ScanPair, guess: Pose2) -> (f64, f64) {
    let r = matcher.match_scans(&pair.reference, &pair.current, guess);
    (
        r.pose.distance(&pair.truth),
        wrap_angle(r.pose.theta - pair.truth.theta).abs(),
    )
}

fn maker(outliers: &str) -> PairMaker {
    PairMaker::new(
        &common::world("orthogonal"),
        &common::robot("pioneer-3dx"),
        Outliers::preset(outliers).unwrap(),
    )
}

/// Pairs 0.5 m / 25° apart at most (the thesis's motions), with a guess a few cm and degrees off.
fn thesis_pairs(maker: &PairMaker, n: usize, seed: u64) -> Vec<(Pose2, ScanPair)> {
    let mut rng = sim::rng::SimRng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let a = maker.free_pose(0.6, &mut rng).unwrap();
            let u = |rng: &mut sim::rng::SimRng| rng.random::<f64>() - 0.5;
            let motion = Pose2::new(u(&mut rng), 0.1 * u(&mut rng), 0.8 * u(&mut rng));
            let pair = maker.pair(a, a.compose(&motion), &mut rng);
            let off = Pose2::new(0.06 * u(&mut rng), 0.06 * u(&mut rng), 0.05 * u(&mut rng));
            (pair.truth.compose(&off), pair)
        })
        .collect()
}

fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    s / n.max(1) as f64
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[test]
fn every_matcher_recovers_small_motions_without_outliers() {
    let maker = maker("none");
    let mut rng = sim::rng::SimRng::seed_from_u64(4);
    let pairs: Vec<_> = (0..25)
        .map(|_| {
            let a = maker.free_pose(0.6, &mut rng).unwrap();
            let motion = Pose2::new(
                0.1 * (rng.random::<f64>() - 0.5),
                0.04 * (rng.random::<f64>() - 0.5),
                0.06 * (rng.random::<f64>() - 0.5),
            );
            maker.pair(a, a.compose(&motion), &mut rng)
        })
        .collect();
    for kind in MatcherKind::ALL {
        let m = kind.build();
        let errors: Vec<_> = pairs
            .iter()
            .map(|p| error(m.as_ref(), p, Pose2::IDENTITY))
            .collect();
        let t = median(errors.iter().map(|e| e.0).collect());
        let r = median(errors.iter().map(|e| e.1).collect());
        assert!(t < 0.01, "{kind}: median translation error {t} m");
        assert!(
            r < 0.2f64.to_radians(),
            "{kind}: median heading error {r} rad"
        );
    }
}

#[test]
fn lorentzian_matchers_beat_least_squares_by_far_under_uniform_outliers() {
    for (preset, seed) in [("thesis-2pct", 2), ("thesis-20pct", 20)] {
        let maker = maker(preset);
        let pairs = thesis_pairs(&maker, 30, seed);
        let mean_error = |kind: MatcherKind| {
            let m = kind.build();
            let errors: Vec<_> = pairs
                .iter()
                .map(|(g, p)| error(m.as_ref(), p, *g))
                .collect();
            (
                mean(errors.iter().map(|e| e.0)),
                mean(errors.iter().map(|e| e.1)),
            )
        };
        let ls = mean_error(MatcherKind::LeastSquares);
        for kind in [MatcherKind::Lorentz, MatcherKind::LorentzLines] {
            let robust = mean_error(kind);
            assert!(
                robust.0 * 5.0 < ls.0 && robust.1 * 5.0 < ls.1,
                "{preset}: {kind} {robust:?} against least squares {ls:?} (mean m, rad)"
            );
            assert!(
                robust.0 < 0.02 && robust.1 < 0.5f64.to_radians(),
                "{preset}: {kind} {robust:?}"
            );
        }
    }
}

#[test]
fn mbicp_recovers_turns_that_point_to_point_icp_misses() {
    let maker = maker("none");
    let mut rng = sim::rng::SimRng::seed_from_u64(25);
    let pairs: Vec<_> = (0..30)
        .map(|k| {
            let a = maker.free_pose(0.6, &mut rng).unwrap();
            let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
            maker.pair(
                a,
                a.compose(&Pose2::new(0.0, 0.0, sign * 25f64.to_radians())),
                &mut rng,
            )
        })
        .collect();
    // The guess knows nothing of the turn.
    let recovered = |kind: MatcherKind| {
        let m = kind.build();
        pairs
            .iter()
            .filter(|p| {
                let (t, r) = error(m.as_ref(), p, Pose2::IDENTITY);
                t < 0.05 && r < 1f64.to_radians()
            })
            .count()
    };
    let (mbicp, icp) = (
        recovered(MatcherKind::Mbicp),
        recovered(MatcherKind::LeastSquares),
    );
    assert!(mbicp >= 27, "MbICP recovered {mbicp} of 30 turns of 25°");
    assert!(
        icp + 8 <= mbicp,
        "point-to-point ICP recovered {icp}, MbICP {mbicp}"
    );
}

/// 002 App. E's L-shaped corridor, its coordinates read as centimetres: walls y = 50
/// (0 ≤ x ≤ 250), y = −50 (0 ≤ x ≤ 350), x = 250 (50 ≤ y ≤ 300), x = 350 (−50 ≤ y ≤ 300).
/// Beams that meet no wall read infinity.
fn l_corridor_scan(pose: Pose2) -> RangeScan {
    let walls = [
        ([0.0, 0.5], [2.5, 0.5]),
        ([0.0, -0.5], [3.5, -0.5]),
        ([2.5, 0.5], [2.5, 3.0]),
        ([3.5, -0.5], [3.5, 3.0]),
    ];
    let ranges = (0..361)
        .map(|i| {
            let a = pose.theta + (i as f64 * 0.5 - 90.0).to_radians();
            let d = [a.cos(), a.sin()];
            walls
                .iter()
                .filter_map(|(p, q)| {
                    let e = [q[0] - p[0], q[1] - p[1]];
                    let den = d[0] * e[1] - d[1] * e[0];
                    if den.abs() < 1e-12 {
                        return None;
                    }
                    let w = [p[0] - pose.x, p[1] - pose.y];
                    let t = (w[0] * e[1] - w[1] * e[0]) / den;
                    let s = (w[0] * d[1] - w[1] * d[0]) / den;
                    (t > 0.0 && (0.0..=1.0).contains(&s)).then_some(t)
                })
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    RangeScan::new(
        -std::f64::consts::FRAC_PI_2,
        0.5f64.to_radians(),
        32.0,
        ranges,
    )
}

#[test]
fn the_l_corridor_of_002_appendix_e() {
    // Down the corridor and round the corner, as the appendix's robot drives.
    let path = [
        Pose2::new(0.3, 0.0, 0.0),
        Pose2::new(0.8, 0.05, 0.05),
        Pose2::new(1.3, 0.0, 0.0),
        Pose2::new(1.8, -0.05, -0.05),
        Pose2::new(2.3, 0.0, 0.2),
        Pose2::new(2.7, 0.0, 0.5),
        Pose2::new(2.95, 0.15, 0.85),
        Pose2::new(3.0, 0.45, 1.2),
        Pose2::new(3.0, 0.8, 1.5),
        Pose2::new(3.0, 1.3, 1.57),
    ];
    let scans: Vec<_> = path.iter().map(|p| l_corridor_scan(*p)).collect();
    assert!(
        scans[9].ranges.iter().any(|r| r.is_infinite()),
        "the open end reads infinity"
    );
    let mut failures = Vec::new();
    // Forward (each scan against the one before) and back (against the one after): after a
    // retreat the current scan sees wall beside the robot that the reference never saw.
    let steps = (1..path.len()).flat_map(|k| [(k - 1, k), (k, k - 1)]);
    for kind in [
        MatcherKind::Lorentz,
        MatcherKind::LorentzLines,
        MatcherKind::Mbicp,
    ] {
        let m = kind.build();
        for (a, b) in steps.clone() {
            let truth = path[a].relative(&path[b]);
            let guess = truth.compose(&Pose2::new(0.04, -0.03, 0.03));
            let r = m.match_scans(&scans[a], &scans[b], guess);
            let (t, e) = (
                r.pose.distance(&truth),
                wrap_angle(r.pose.theta - truth.theta).abs(),
            );
            // Up the second corridor only the far ends of its walls fix the position along it:
            // the point-to-point matchers may slide a few centimetres there.
            let (t_max, e_max) = (0.05, 1.5f64.to_radians());
            if !(t < t_max && e < e_max) {
                failures.push(format!(
                    "{kind}, scan {b} against {a}: {t:.4} m, {e:.5} rad"
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn a_twin_run_localises_better_than_its_odometry() {
    let scenario = common::scenario("lab-tour");
    let record =
        sim::commands::run::run_scenario(&scenario, &Default::default(), |_, _| {}).unwrap();
    let loc = record.localisation.as_ref().expect("lab-tour localises");
    assert_eq!(loc.placed.len(), record.scans.len());
    let summary = sim::output::LocalisationSummary::of(&record, loc);
    assert!(
        summary.rms_error_m < 0.75 * summary.odometry_rms_error_m,
        "estimate RMS {} m against odometry {} m",
        summary.rms_error_m,
        summary.odometry_rms_error_m
    );
    let dir = std::env::temp_dir().join("issue4-lab-tour");
    let written = sim::output::write_all(&record, &scenario, &dir).unwrap();
    let estimate = std::fs::read_to_string(dir.join("estimate.tum")).unwrap();
    assert_eq!(estimate.lines().count(), record.scans.len() + 1);
    let json = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    assert!(json.contains("\"rms_error_m\"") && json.contains("\"lorentz\""));
    assert!(written.files.iter().any(|f| f.ends_with("estimate.tum")));
}

#[test]
fn the_mit_csail_log_gives_a_sharper_map_than_odometry() {
    let log = robot::logs::read_log(&common::repo().join("tests/data/mit-csail.clf")).unwrap();
    assert_eq!(log.scans(), 1988);
    assert_eq!(log.skipped_lines(), 3, "the three comment lines");
    let replay =
        sim::commands::map::replay_log(&log, MatcherKind::Lorentz, Default::default(), |_, _| {});
    let summary = replay.summary("mit-csail.clf", &log);
    assert_eq!(summary.scans, 1988);
    assert!(summary.stats.trusted > 1900, "{summary:?}");
    assert!(
        (summary.estimate_cells as f64) < 0.6 * summary.odometry_cells as f64,
        "{summary:?}"
    );
}

#[test]
fn twin_map_names_bad_logs() {
    let dir = std::env::temp_dir().join("issue4-bad-logs");
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("broken.clf");
    std::fs::write(&bad, "FLASER 3 1.0 2.0 x\n").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_twin"))
        .args(["map", bad.to_str().unwrap(), "--quiet"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("broken.clf:1:") && err.contains("`x`"),
        "{err}"
    );
    let unknown = dir.join("notes.txt");
    std::fs::write(&unknown, "hello\n").unwrap();
    let err = robot::logs::read_log(&unknown).unwrap_err().to_string();
    assert!(
        err.contains("notes.txt") && err.contains("unknown log format"),
        "{err}"
    );
}

#[test]
fn twin_match_answers_every_line_and_survives_garbage() {
    let maker = maker("none");
    let mut rng = sim::rng::SimRng::seed_from_u64(9);
    let a = maker.free_pose(0.6, &mut rng).unwrap();
    let pair = maker.pair(a, a.compose(&Pose2::new(0.2, 0.0, 0.05)), &mut rng);
    let line = serde_json::json!({
        "ref": pair.reference, "cur": pair.current, "guess": [0.17, 0.02, 0.03]
    })
    .to_string();
    let input = format!("{line}\n{{\"ref\": 3}}\nnot json at all\n{line}\n");
    let mut child = Command::new(env!("CARGO_BIN_EXE_twin"))
        .args(["match", "--matcher", "mbicp"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(input.as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
    let lines: Vec<serde_json::Value> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 4);
    for k in [0, 3] {
        let (x, y, t) = (
            lines[k]["x"].as_f64().unwrap(),
            lines[k]["y"].as_f64().unwrap(),
            lines[k]["theta"].as_f64().unwrap(),
        );
        let found = Pose2::new(x, y, t);
        assert!(
            found.distance(&pair.truth) < 0.01,
            "{found:?} vs {:?}",
            pair.truth
        );
        assert!(lines[k]["converged"].as_bool().unwrap());
        assert!(lines[k]["correspondences"].as_u64().unwrap() > 100);
        assert!(lines[k]["micros"].as_f64().unwrap() > 0.0);
    }
    for k in [1, 2] {
        assert!(
            lines[k]["error"].as_str().is_some_and(|e| !e.is_empty()),
            "{}",
            lines[k]
        );
    }
}
