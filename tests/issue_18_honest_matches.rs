//! Issue 18: `converged` means "this answer can be trusted", judged by one rule for every matcher
//! from a quality measure reported with each match; the map builder and the Monte Carlo study
//! fall back to odometry when it is not, and count it; `twin matchers` prints the comparison.

use crate::common::repo;
use robot::localization::{
    MapBuilder, MapConfig, MatcherKind, RangeScan, Reference, ScanMatcher, TrustRule,
};
use robot::{Pose2, Stamp};
use sim::commands::matchers::{self, CaseSet, Matched, Row, reach};
use std::collections::BTreeMap;
use std::process::Command;

/// The standard sets, small: every row of the README's table, `n` pairs each, seed `seed`.
fn sets(n: usize, seed: u64) -> Vec<CaseSet> {
    matchers::standard_sets(&repo(), n, seed).expect("the bundled worlds and logs load")
}

fn rows(sets: &[CaseSet], kinds: &[MatcherKind]) -> Vec<Row> {
    sets.iter()
        .flat_map(|s| matchers::evaluate(s, kinds, &mut |_| {}))
        .collect()
}

/// On every row — synthetic at 0 % and 20 % outliers, each real log, the large guess — a match
/// the robust matchers flag as converged is right nearly always (from a large guess, mostly),
/// and most right ones are flagged; over two seeds. 120 pairs a row: with 60, one or two
/// answers a few millimetres either side of the 10 cm line move a precision near 0.95 by 0.03.
#[test]
fn the_flag_predicts_success_on_every_row() {
    for seed in [11, 12] {
        let sets = sets(120, seed);
        for row in rows(&sets, &[MatcherKind::Lorentz, MatcherKind::LorentzLines]) {
            // From 20 cm and 10° off, a real scan can fit a repeated structure a metre away as
            // well as the right place: the flag cannot see that, and says so less surely.
            let least = if row.set.contains("20 cm") { 0.75 } else { 0.9 };
            assert!(
                row.flag_precision >= least,
                "seed {seed}, {} {}: a trusted answer is wrong too often: {row:?}",
                row.set,
                row.matcher
            );
            if row.set.starts_with("synthetic") || row.set.contains("belgioioso") {
                assert!(
                    row.flag_recall >= 0.7,
                    "seed {seed}, {} {}: right answers not trusted: {row:?}",
                    row.set,
                    row.matcher
                );
            }
        }
    }
}

/// Least squares lands in wrong minima and used to say converged on nearly every pair: now a
/// flagged answer of it is right more often than its answers are, and among outliers (where
/// it is nearly always wrong) it is hardly ever flagged.
#[test]
fn least_squares_no_longer_claims_its_wrong_answers() {
    let sets = sets(40, 5);
    for row in rows(&sets, &[MatcherKind::LeastSquares]) {
        assert!(row.success < 0.9, "ls is not that good: {row:?}");
        assert!(row.flagged <= 0.7, "{row:?}");
        if row.flagged * row.pairs as f64 >= 5.0 {
            assert!(
                row.flag_precision >= row.success,
                "the flag tells nothing: {row:?}"
            );
        }
        if row.set == "synthetic, 20 %" {
            assert!(row.flagged <= 0.1, "{row:?}");
        }
    }
}

/// A scan of 181 beams over 180°, beam `a` (radians from straight ahead) reading `range(a)`.
fn scan_of(mut range: impl FnMut(f64) -> f64) -> RangeScan {
    let ranges = (0..181)
        .map(|i| range((f64::from(i) - 90.0).to_radians()))
        .collect();
    RangeScan::new(
        -std::f64::consts::FRAC_PI_2,
        1f64.to_radians(),
        30.0,
        ranges,
    )
}

/// A wall seen straight ahead from `distance`.
fn wall(distance: f64) -> RangeScan {
    scan_of(|a| (distance / a.cos().max(0.05)).min(30.0))
}

/// A room's corner: a wall ahead at 3 − `dx` metres and one to the left at 2.
fn corner(dx: f64) -> RangeScan {
    scan_of(|a| {
        let ahead = if a.cos() > 1e-9 {
            (3.0 - dx) / a.cos()
        } else {
            f64::MAX
        };
        let left = if a.sin() > 1e-9 {
            2.0 / a.sin()
        } else {
            f64::MAX
        };
        ahead.min(left).min(29.0)
    })
}

/// A match's quality comes with it: the corner matched is trusted when the answer is right (least
/// squares may stop a few centimetres off, and is then not trusted); a lone wall leaves its
/// length free, so its match is not, whatever the matcher's iterations did.
#[test]
fn every_match_reports_its_quality() {
    for kind in MatcherKind::ALL {
        let matcher = kind.build();
        let good = matcher.match_scans(&corner(0.0), &corner(0.2), Pose2::new(0.18, 0.01, 0.0));
        let off = Pose2::new(0.2, 0.0, 0.0).relative(&good.pose);
        let right = off.x.hypot(off.y) < 0.01 && off.theta.abs() < 0.2f64.to_radians();
        assert_eq!(good.converged, right, "{kind}: {good:?}");
        if kind != MatcherKind::LeastSquares {
            assert!(good.converged, "{kind}: {good:?}");
            assert!(
                good.quality.inlier_share > 0.8 && good.quality.sigma[0] < 0.01,
                "{good:?}"
            );
        }
        let free = matcher.match_scans(&wall(3.0), &wall(2.8), Pose2::new(0.2, 0.0, 0.0));
        assert!(!free.converged, "{kind}: a lone wall was trusted: {free:?}");
        assert!(
            free.quality.sigma[1] > TrustRule::default().max_sigma_m,
            "{free:?}"
        );
    }
}

/// Ranges that are no room at all: what a laser blinded by clutter or a passing crowd reads.
fn clutter() -> RangeScan {
    let mut state = 12345u64;
    scan_of(|_| {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        0.5 + 9.5 * ((state >> 11) as f64 / (1u64 << 53) as f64)
    })
}

/// A match that cannot be trusted is not used: the scan is placed by odometry, and counted.
#[test]
fn the_map_builder_falls_back_to_odometry_and_counts_it() {
    let mut map = MapBuilder::in_odometry_frame(MatcherKind::Lorentz.build(), MapConfig::default());
    let odometry = [
        Pose2::IDENTITY,
        Pose2::new(0.2, 0.0, 0.0),
        Pose2::new(0.45, 0.0, 0.0),
    ];
    // The corner, then clutter that matches nothing, then the corner again (matched against
    // the clutter, the scan before it: not trusted either).
    let scans = [corner(0.0), clutter(), corner(0.45)];
    for (k, (pose, scan)) in odometry.iter().zip(scans).enumerate() {
        let t = Stamp::from_millis(100 * k as u64);
        map.push_odometry(t, *pose);
        map.push_scan(scan.stamped(t));
    }
    map.finish();
    let placed = map.placed();
    assert_eq!(placed.len(), 3);
    for (p, odometry) in placed.iter().zip(odometry).skip(1) {
        assert!(!p.trusted, "{p:?}");
        let off = odometry.relative(&p.estimate);
        assert!(off.x.hypot(off.y) < 1e-12, "placed by odometry: {p:?}");
    }
    let stats = robot::localization::MatchStats::of(placed);
    assert_eq!(stats.fallbacks, 2, "{stats:?}");
    assert_eq!(stats.trusted + stats.fallbacks, stats.matches);
}

/// The corrected logs read straight from their gzip files, with their glitches handled: one
/// `ODOM` stamped −2.88 s in Freiburg 101 (skipped and counted), the Edmonton logger's 10 m
/// declared range (its readings beyond kept, its 51.15 m no-returns not points).
#[test]
fn the_corrected_logs_read_gzipped_with_their_glitches() {
    let dir = repo().join("tests/data/corrected");
    let freiburg = robot::logs::read_log(&dir.join("freiburg-101-corrected.log.gz")).unwrap();
    assert_eq!(freiburg.scans(), 292);
    assert_eq!(freiburg.skipped.get("ODOM with a negative stamp"), Some(&1));
    let edmonton = robot::logs::read_log(&dir.join("edmonton-corrected.log.gz")).unwrap();
    assert_eq!(edmonton.scans(), 340);
    // Its readings beyond the declared 10 m are kept, its 51.09–51.16 m no-returns are not.
    let (mut points, mut far) = (0, 0);
    for event in &edmonton.events {
        if let robot::logs::LogEvent::Scan(scan) = event {
            assert!((scan.range_max - 51.05).abs() < 1e-9, "{}", scan.range_max);
            let returned: Vec<f64> = (0..scan.ranges.len())
                .filter(|&i| scan.returned(i))
                .map(|i| scan.ranges[i])
                .collect();
            assert_eq!(returned.len(), scan.points().len());
            points += returned.len();
            far += returned.iter().filter(|&&r| r >= 10.0).count();
        }
    }
    // Of its 61,200 readings: 3,367 no-returns at 51.09–51.16 m, none at zero.
    assert_eq!((points, far), (57_833, 17_844));
}

/// An `FLASER` does not state its beam step: CARMEN's reader takes it from the count of readings,
/// 1° for 180 and 0.5° for 360 (a SICK's 181 or 361 with the last dropped). The corrected logs'
/// own poses agree: consecutive scans placed by them fit each other best with that step, worse
/// with the readings spread over the whole 180° (the step this reader took before) or narrowed
/// as much the other way.
#[test]
fn the_corrected_logs_fit_their_poses_best_at_carmens_beam_step() {
    let dir = repo().join("tests/data/corrected");
    for (log, beams, step_deg) in [("edmonton", 180, 1.0), ("freiburg-101", 360, 0.5)] {
        let scans = robot::logs::read_log(&dir.join(format!("{log}-corrected.log.gz")))
            .unwrap()
            .scans_with_logged_pose();
        for (scan, _) in &scans {
            assert_eq!(scan.ranges.len(), beams, "{log}");
            assert!((scan.angle_increment - f64::to_radians(step_deg)).abs() < 1e-12);
            assert_eq!(scan.angle_min, -std::f64::consts::FRAC_PI_2);
        }
        // The mean share of each pair's current points on the reference's surfaces at the
        // log's relative pose, with every bearing stretched by `scale`.
        let fit = |scale: f64| {
            let stretched = |scan: &RangeScan| {
                let mut scan = scan.clone();
                scan.angle_increment *= scale;
                scan
            };
            let shares: Vec<f64> = scans
                .windows(2)
                .map(|w| {
                    let reference = Reference::new(stretched(&w[0].0).points());
                    let truth = w[0].1.relative(&w[1].1);
                    let current = stretched(&w[1].0).points();
                    TrustRule::default()
                        .assess(&reference, &current.xy, &truth)
                        .inlier_share
                })
                .collect();
            shares.iter().sum::<f64>() / shares.len() as f64
        };
        let over_180 = beams as f64 / (beams - 1) as f64;
        let (carmen, spread, narrowed) = (fit(1.0), fit(over_180), fit(2.0 - over_180));
        assert!(
            carmen > spread && carmen > narrowed,
            "{log}: {carmen:.4} at CARMEN's step, {spread:.4} over 180°, {narrowed:.4} narrowed"
        );
    }
}

/// A corrected log's poses are its laser's, not its base's: Freiburg 101 declares
/// `PARAM robot_frontlaser_offset -0.04` (the laser 4 cm behind the base's centre), yet its
/// consecutive scans, like Belgioioso's and Edmonton's (offset 0), fit each other best placed
/// by the poses as they stand, worse with the laser moved 4 cm either way along the heading. So
/// the pairs' truth is the poses' own relation, with no offset applied.
#[test]
fn the_corrected_logs_poses_are_their_lasers() {
    let dir = repo().join("tests/data/corrected");
    for log in ["belgioioso", "freiburg-101", "edmonton"] {
        let scans = robot::logs::read_log(&dir.join(format!("{log}-corrected.log.gz")))
            .unwrap()
            .scans_with_logged_pose();
        let references: Vec<Reference> = scans
            .iter()
            .map(|(scan, _)| Reference::new(scan.points()))
            .collect();
        // The mean share of each pair's current points on the reference's surfaces, each scan
        // taken `forward_m` ahead of its logged pose.
        let fit = |forward_m: f64| {
            let laser = Pose2::new(forward_m, 0.0, 0.0);
            let shares: Vec<f64> = scans
                .windows(2)
                .zip(&references)
                .map(|(w, reference)| {
                    let truth = w[0].1.compose(&laser).relative(&w[1].1.compose(&laser));
                    TrustRule::default()
                        .assess(reference, &w[1].0.points().xy, &truth)
                        .inlier_share
                })
                .collect();
            shares.iter().sum::<f64>() / shares.len() as f64
        };
        let (behind, as_logged, ahead) = (fit(-0.04), fit(0.0), fit(0.04));
        assert!(
            as_logged > behind && as_logged > ahead,
            "{log}: {as_logged:.4} as logged, {behind:.4} 4 cm behind, {ahead:.4} 4 cm ahead"
        );
    }
}

/// The quality is the same rule whichever matcher answered: judging a pose directly gives what
/// the match reported.
#[test]
fn the_quality_is_judged_after_the_match_by_one_rule() {
    let (reference, current) = (corner(0.0), corner(0.3));
    let prepared = Reference::new(reference.points());
    for kind in MatcherKind::ALL {
        let result = kind
            .build()
            .align(&prepared, &current.points(), Pose2::new(0.25, 0.0, 0.02));
        let judged = TrustRule::default().assess(&prepared, &current.points().xy, &result.pose);
        assert_eq!(result.quality, judged, "{kind}");
        assert_eq!(result.converged, TrustRule::default().trusts(&judged));
    }
}

/// `twin matchers` prints the table and writes every match's figures.
#[test]
fn twin_matchers_prints_the_table() {
    let out = tempfile_dir("twin-matchers");
    let run = Command::new(env!("CARGO_BIN_EXE_twin"))
        .args([
            "matchers",
            "--pairs",
            "4",
            "--quiet",
            "--matchers",
            "ls,lorentz",
            "--out",
        ])
        .arg(&out)
        .current_dir(repo())
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let table = String::from_utf8(run.stdout).unwrap();
    assert!(table.contains("flag precision / recall"), "{table}");
    assert_eq!(
        table.lines().filter(|l| l.contains("| lorentz |")).count(),
        8
    );
    let csv = std::fs::read_to_string(out.join("pairs.csv")).unwrap();
    // 4 pairs in each of seven rows and 2 from each log in the pooled large-guess row, two
    // matchers.
    assert_eq!(csv.lines().count(), 1 + 2 * (7 * 4 + 6), "{csv}");
    // The closure: a figure on each log's row, none on the synthetic ones; one line a matcher
    // for each triangle of three scans in a row (3 of each log's 4 pairs, 1 of each log's 2
    // in the pooled row).
    for line in table.lines().filter(|l| l.contains("| lorentz |")) {
        let closure = line.rsplit('|').nth(1).unwrap().trim();
        if line.contains("synthetic") {
            assert_eq!(closure, "—", "{line}");
        } else {
            assert!(
                closure.ends_with('°') && closure.contains(" mm, "),
                "{line}"
            );
        }
    }
    let closures = std::fs::read_to_string(out.join("closures.csv")).unwrap();
    assert_eq!(closures.lines().count(), 1 + 2 * (3 * 3 + 3), "{closures}");
    assert!(closures.starts_with(matchers::CLOSURES_HEADER));
    let bad = Command::new(env!("CARGO_BIN_EXE_twin"))
        .args(["matchers", "--pairs", "0"])
        .output()
        .unwrap();
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--pairs"));
    // Run from elsewhere, the command says where it looks for its worlds and logs.
    let elsewhere = Command::new(env!("CARGO_BIN_EXE_twin"))
        .args(["matchers", "--pairs", "2"])
        .current_dir(std::env::temp_dir())
        .output()
        .unwrap();
    assert!(!elsewhere.status.success());
    let stderr = String::from_utf8_lossy(&elsewhere.stderr);
    assert!(
        stderr.contains("--root must be the repository's folder"),
        "{stderr}"
    );
}

/// `twin matchers --seeds 2` pools two seeds into each row: its `pairs.csv` and `closures.csv`
/// are the two single-seed runs' one after the other (each line names its seed), a row's
/// pairs and successes are the two runs' summed, and its seed-by-seed median errors are the two
/// runs' medians (printed under the table). `--seeds 0` is refused by name.
#[test]
fn twin_matchers_pools_seeds_into_its_rows() {
    let out = tempfile_dir("twin-matchers-seeds");
    let run = |args: &[&str], dir: &str| {
        let run = Command::new(env!("CARGO_BIN_EXE_twin"))
            .args(["matchers", "--pairs", "3", "--quiet", "--matchers"])
            .args(["lorentz-lines,pl-icp", "--out"])
            .arg(out.join(dir))
            .args(args)
            .current_dir(repo())
            .output()
            .unwrap();
        let read =
            |file: &str| std::fs::read_to_string(out.join(dir).join(file)).unwrap_or_default();
        let rows: Vec<serde_json::Value> =
            serde_json::from_str(&read("matchers.json")).unwrap_or_default();
        (run, read("pairs.csv"), read("closures.csv"), rows)
    };
    let (_, one_pairs, one_closures, one_rows) = run(&["--seed", "1"], "one");
    let (_, two_pairs, two_closures, two_rows) = run(&["--seed", "2"], "two");
    let (both, pairs, closures, rows) = run(&["--seed", "1", "--seeds", "2"], "both");
    assert!(
        both.status.success(),
        "{}",
        String::from_utf8_lossy(&both.stderr)
    );
    let body = |csv: &str| csv.lines().skip(1).map(str::to_string).collect::<Vec<_>>();
    assert_eq!(body(&pairs), [body(&one_pairs), body(&two_pairs)].concat());
    assert_eq!(
        body(&closures),
        [body(&one_closures), body(&two_closures)].concat()
    );
    assert!(pairs.starts_with("seed,set,pair,") && body(&pairs)[0].starts_with("1,"));
    assert!(body(&pairs).last().unwrap().starts_with("2,"));
    assert_eq!(rows.len(), 16);
    for ((row, one), two) in rows.iter().zip(&one_rows).zip(&two_rows) {
        let pairs = |r: &serde_json::Value| r["pairs"].as_u64().unwrap();
        let right = |r: &serde_json::Value| r["success"].as_f64().unwrap() * pairs(r) as f64;
        assert_eq!(row["set"], one["set"]);
        assert_eq!(pairs(row), pairs(one) + pairs(two), "{row}");
        assert!((right(row) - right(one) - right(two)).abs() < 1e-9, "{row}");
        let triangles = |r: &serde_json::Value| r["closure"]["triangles"].as_u64().unwrap_or(0);
        assert_eq!(triangles(row), triangles(one) + triangles(two), "{row}");
        // The seeds' own medians, lowest and highest: each single run's median.
        let median = |r: &serde_json::Value| r["error_m"][0].as_f64().unwrap();
        let (low, high) = (median(one).min(median(two)), median(one).max(median(two)));
        assert_eq!(
            row["error_by_seed_m"],
            serde_json::json!([low, high]),
            "{row}"
        );
        assert!(one["error_by_seed_m"].is_null() && two["error_by_seed_m"].is_null());
    }
    // Printed under the table with several seeds, not with one.
    let header = "median error of one seed's pairs: lowest – highest";
    assert!(String::from_utf8_lossy(&both.stdout).contains(header));
    let (one, ..) = run(&["--seed", "1"], "one-again");
    assert!(one.status.success() && !String::from_utf8_lossy(&one.stdout).contains(header));
    let (bad, ..) = run(&["--seeds", "0"], "bad");
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--seeds must be between 1 and 1000"));
    let (past, ..) = run(&["--seed", "18446744073709551615", "--seeds", "2"], "past");
    assert!(!past.status.success());
    assert!(String::from_utf8_lossy(&past.stderr).contains("--seed + --seeds within 2^64"));
    let _ = std::fs::remove_dir_all(&out);
}

/// A log row's triangles are three scans in a row: the log's own poses chain exactly (the
/// skip pair's truth is its two pairs' truths composed), in every log row and in the pooled
/// large-guess row, whose triangles never span two logs; a matcher's closure is measured
/// against that chain, and for `lorentz-lines` it is millimetres on most of Belgioioso's
/// triangles.
#[test]
fn a_logs_triangles_chain_its_own_poses() {
    let sets = sets(30, 4);
    for set in &sets {
        if set.name.starts_with("synthetic") {
            assert!(set.triangles.is_empty(), "{}", set.name);
            continue;
        }
        // 29 for each log; 9 for each log's 10 pairs in the pooled row.
        let expected = if set.name.contains("20 cm") { 27 } else { 29 };
        assert_eq!(set.triangles.len(), expected, "{}", set.name);
        for t in &set.triangles {
            let (a, b) = (&set.cases[t.first].truth, &set.cases[t.second].truth);
            let (m, rad) = matchers::closure(a, b, &t.skip.truth);
            assert!(m < 1e-9 && rad < 1e-9, "{} {t:?}: {m} m", set.name);
            // Its scans are the pairs': the skip starts where the first does and ends where
            // the second does.
            assert_eq!(t.skip.reference.ranges, set.cases[t.first].reference.ranges);
            assert_eq!(t.skip.current.ranges, set.cases[t.second].current.ranges);
        }
    }
    let belgioioso = sets.iter().find(|s| s.name.contains("belgioioso")).unwrap();
    let row = &matchers::evaluate(belgioioso, &[MatcherKind::LorentzLines], &mut |_| {})[0];
    let closure = row.closure.expect("a log row has a closure");
    assert_eq!(closure.triangles, 29);
    assert!(
        closure.m[0] < 0.01 && closure.rad[0] < 0.5f64.to_radians(),
        "{closure:?}"
    );
}

/// `twin matchers --log PATH` adds two rows from a corrected log of one's own (here the first
/// 40 scans of Belgioioso's, unzipped and renamed): its pairs from small and large guesses,
/// judged against the log's stated poses, while the standard rows stay as they were to the bit.
/// A log cut inside a line is refused with the file and line named.
#[test]
fn a_corrected_log_of_ones_own_adds_two_rows() {
    use std::io::Read;
    let out = tempfile_dir("twin-matchers-log");
    std::fs::create_dir_all(&out).unwrap();
    let bundled = repo().join("tests/data/corrected/belgioioso-corrected.log.gz");
    let mut text = String::new();
    flate2::read::GzDecoder::new(std::fs::File::open(&bundled).unwrap())
        .read_to_string(&mut text)
        .unwrap();
    let mut kept = Vec::new();
    let mut scans = 0;
    for line in text.lines() {
        scans += usize::from(line.starts_with("FLASER "));
        if scans > 40 {
            break;
        }
        kept.push(line);
    }
    let log = out.join("castle-corrected.clf");
    std::fs::write(&log, kept.join("\n") + "\n").unwrap();

    // The rows' truth is the log's: the same relative poses as the bundled log's first pairs.
    let [small, large] = matchers::extra_log_sets(&log, 100, 3).unwrap();
    assert_eq!(small.name, "real, castle");
    assert_eq!(large.name, "real, castle, guess σ 20 cm / 10°");
    assert_eq!((small.cases.len(), large.cases.len()), (39, 39));
    let exact = matchers::GuessError {
        sigma_m: 0.0,
        sigma_rad: 0.0,
    };
    let standard = matchers::log_set("x", &bundled, 39, exact, 3).unwrap();
    for (own, bundled) in small.cases.iter().zip(&standard.cases) {
        assert_eq!(own.truth, bundled.truth);
    }

    let run = twin_matchers;
    let (ok, table, stderr) = run(&["--log", log.to_str().unwrap()], &out.join("with"));
    assert!(ok, "{stderr}");
    assert!(
        table.contains("| real, castle (6) | lorentz-lines |"),
        "{table}"
    );
    assert!(
        table.contains("| real, castle, guess σ 20 cm / 10° (6) | lorentz-lines |"),
        "{table}"
    );
    let (ok, _, stderr) = run(&[], &out.join("without"));
    assert!(ok, "{stderr}");
    let csv = |dir: &str| std::fs::read_to_string(out.join(dir).join("pairs.csv")).unwrap();
    let (with, without) = (csv("with"), csv("without"));
    assert!(with.starts_with(&without), "the standard rows changed");
    assert_eq!(with.lines().count(), without.lines().count() + 12);

    let cut = out.join("cut.log");
    let whole = kept.join("\n");
    std::fs::write(&cut, &whole[..whole.len() - 300]).unwrap();
    let (ok, _, stderr) = run(&["--log", cut.to_str().unwrap()], &out.join("cut"));
    assert!(!ok);
    assert!(
        stderr.contains("cut.log:") && stderr.contains("line ends early"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// `twin matchers --pairs 6 --quiet --matchers lorentz-lines` with `args`, writing into `dir`:
/// whether it succeeded, its standard output and its standard error.
fn twin_matchers(args: &[&str], dir: &std::path::Path) -> (bool, String, String) {
    let run = Command::new(env!("CARGO_BIN_EXE_twin"))
        .args([
            "matchers",
            "--pairs",
            "6",
            "--quiet",
            "--matchers",
            "lorentz-lines",
        ])
        .args(args)
        .arg("--out")
        .arg(dir)
        .current_dir(repo())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr).into_owned();
    (
        run.status.success(),
        String::from_utf8(run.stdout).unwrap(),
        stderr,
    )
}

/// `twin matchers --world PATH` adds four synthetic rows in that world alone (the LMS at 0.5°
/// and 1°, each at 0 % and 20 % outliers), named after the file, from pairs a short drive
/// apart; here the L-corridor of Aparicio 2011, whose ends are open. The standard rows' pairs
/// stay as they were, and a world file that is not there is refused by name.
#[test]
fn a_world_of_ones_own_adds_four_synthetic_rows() {
    let sets =
        matchers::extra_world_sets(&repo(), &repo().join("worlds/l-corridor.toml"), 20, 3).unwrap();
    let names: Vec<&str> = sets.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "synthetic, l-corridor, 0 %",
            "synthetic, l-corridor, 20 %",
            "synthetic 1°, l-corridor, 0 %",
            "synthetic 1°, l-corridor, 20 %",
        ]
    );
    for set in &sets {
        assert_eq!(set.cases.len(), 20);
        for case in &set.cases {
            // A short drive: at most 30 cm and 20° (the laser sits ahead of the base's centre).
            assert!(case.truth.x.hypot(case.truth.y) < 0.45, "{:?}", case.truth);
            assert!(case.truth.theta.abs() <= 20f64.to_radians() + 1e-9);
            // Both scans see the corridor's walls.
            assert!(case.reference.points().len() > 50 && case.current.points().len() > 50);
        }
    }
    let out = tempfile_dir("twin-matchers-world");
    let run = twin_matchers;
    let (ok, table, stderr) = run(&["--world", "worlds/l-corridor.toml"], &out.join("with"));
    assert!(ok, "{stderr}");
    for row in [
        "synthetic, l-corridor, 20 %",
        "synthetic 1°, l-corridor, 0 %",
    ] {
        assert!(
            table.contains(&format!("| {row} (6) | lorentz-lines |")),
            "{table}"
        );
    }
    let (ok, _, stderr) = run(&[], &out.join("without"));
    assert!(ok, "{stderr}");
    let csv = |dir: &str| std::fs::read_to_string(out.join(dir).join("pairs.csv")).unwrap();
    let (with, without) = (csv("with"), csv("without"));
    assert!(with.starts_with(&without), "the standard rows changed");
    assert_eq!(with.lines().count(), without.lines().count() + 24);
    let (ok, _, stderr) = run(&["--world", "worlds/no-such-world.toml"], &out.join("none"));
    assert!(!ok);
    assert!(stderr.contains("no-such-world.toml"), "{stderr}");
    let _ = std::fs::remove_dir_all(&out);
}

/// Pair 19 of the L-corridor's row (seed 1, `twin matchers --world worlds/l-corridor.toml
/// --show "l-corridor, 0 %/19"`): the current scan sees one wall of the corridor, and the
/// scans fit a pose 13 cm along it as well as the truth (`cargo run --example reach -- 0.02
/// 0.05 worlds/l-corridor.toml`: undecided). `lorentz-lines` answers 10 cm along the wall
/// fitting every point, and the rule as it stood trusted it, its σ along the wall a few
/// millimetres from the chords' noisy normals. Moved 10 cm either way along the wall the answer
/// fits as many points: not held, not trusted. The same holds at the truth: nothing in these
/// scans says where along the wall the robot was.
#[test]
fn an_answer_along_a_corridor_the_scans_leave_free_is_not_trusted() {
    use robot::localization::{Lorentz, MatchQuality, Reference, ScanMatcher, TrustRule};
    let sets =
        matchers::extra_world_sets(&repo(), &repo().join("worlds/l-corridor.toml"), 20, 1).unwrap();
    let case = &sets[0].cases[19];
    let reference = Reference::new(case.reference.points());
    let current = case.current.points();
    let answer = Lorentz::with_lines().align(&reference, &current, case.guess);
    let off = case.truth.relative(&answer.pose);
    assert!(off.x.hypot(off.y) > 0.05, "{off:?}");
    let rule = TrustRule::default();
    let q = answer.quality;
    assert!(q.spread < rule.hold_below_spread, "{q:?}");
    assert!(q.sigma[0].max(q.sigma[1]) < rule.max_sigma_m, "{q:?}");
    assert!(rule.trusts(&MatchQuality { held: true, ..q }), "{q:?}");
    assert!(!q.held && !answer.converged, "{q:?}");
    let at_truth = rule.assess(&reference, &current.xy, &case.truth);
    assert!(!rule.holds(&reference, &current.xy, &case.truth, &at_truth));
}

/// `twin matchers --raw-log PATH` adds a row of a log without a reference (here the MIT log's
/// first 30 scans, whose poses are raw odometry) in a table of its own, with what needs no
/// truth: the flagged share, the time and the closure, which for `lorentz-lines` and `pl-icp`
/// is centimetres at most on the median triangle. No success is claimed for it, and the
/// standard rows' pairs stay as they were. A log too short for a triangle is refused by name.
#[test]
fn a_log_without_a_reference_gets_a_row_of_closures() {
    let out = tempfile_dir("twin-matchers-raw");
    std::fs::create_dir_all(&out).unwrap();
    let text = std::fs::read_to_string(repo().join("tests/data/mit-csail.clf")).unwrap();
    let head = |scans_wanted: usize| {
        let mut kept = Vec::new();
        let mut scans = 0;
        for line in text.lines() {
            scans += usize::from(line.starts_with("FLASER "));
            if scans > scans_wanted {
                break;
            }
            kept.push(line);
        }
        kept.join("\n") + "\n"
    };
    let log = out.join("mit-start.clf");
    std::fs::write(&log, head(30)).unwrap();
    let run = |log: &std::path::Path, dir: &std::path::Path| {
        Command::new(env!("CARGO_BIN_EXE_twin"))
            .args(["matchers", "--pairs", "6", "--quiet"])
            .args(["--matchers", "lorentz-lines,pl-icp", "--raw-log"])
            .arg(log)
            .arg("--out")
            .arg(dir)
            .current_dir(repo())
            .output()
            .unwrap()
    };
    let done = run(&log, &out.join("raw"));
    assert!(
        done.status.success(),
        "{}",
        String::from_utf8_lossy(&done.stderr)
    );
    let stdout = String::from_utf8(done.stdout).unwrap();
    let (judged, raw) = stdout
        .split_once("| pairs without a reference |")
        .expect("a second table");
    assert!(!judged.contains("raw, "), "{judged}");
    assert!(
        raw.contains("| raw, mit-start (6) | lorentz-lines |"),
        "{raw}"
    );
    let rows: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("raw/raw-logs.json")).unwrap())
            .unwrap();
    let rows = rows.as_array().unwrap();
    assert_eq!(rows.len(), 2);
    for row in rows {
        assert!(row.get("success").is_none(), "{row}");
        let closure = &row["closure"];
        assert_eq!(closure["triangles"], 5, "{row}");
        assert!(closure["m"][0].as_f64().unwrap() < 0.02, "{row}");
    }
    let dir = out.join("raw");
    let pairs = std::fs::read_to_string(dir.join("pairs.csv")).unwrap();
    assert!(
        !pairs.contains("\"raw, "),
        "a raw row's pairs are not judged"
    );
    let closures = std::fs::read_to_string(dir.join("closures.csv")).unwrap();
    assert_eq!(
        closures
            .lines()
            .filter(|l| l.starts_with("0,\"raw, mit-start\","))
            .count(),
        2 * 5
    );

    let short = out.join("two-scans.clf");
    std::fs::write(&short, head(2)).unwrap();
    let refused = run(&short, &out.join("short"));
    assert!(!refused.status.success());
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(
        stderr.contains("--raw-log") && stderr.contains("at least three scans"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&out);
}

fn tempfile_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// How many of `set`'s pairs `matcher` answers within the set's tolerance.
fn right_answers(set: &CaseSet, matcher: &robot::localization::Lorentz) -> usize {
    set.cases
        .iter()
        .filter(|c| {
            is_right(
                set,
                c,
                &matcher.match_scans(&c.reference, &c.current, c.guess),
            )
        })
        .count()
}

/// Whether `result` answers `case` of `set` within the set's tolerance.
fn is_right(
    set: &CaseSet,
    case: &matchers::Case,
    result: &robot::localization::MatchResult,
) -> bool {
    let off = case.truth.relative(&result.pose);
    off.x.hypot(off.y) <= set.tolerance_m && off.theta.abs() <= set.tolerance_rad
}

/// From a guess 20 cm and 10° off, a line-assisted Lorentzian that is not trusted starts again
/// around the guess: it is right more often than the same matcher started once, over two seeds.
#[test]
fn restarts_rescue_large_guesses() {
    use robot::localization::Lorentz;
    let once = Lorentz {
        restarts: Vec::new(),
        ..Lorentz::with_lines()
    };
    let again = Lorentz::with_lines();
    for seed in [3, 4] {
        let sets = sets(45, seed);
        let large = sets.last().expect("the large-guess row");
        assert!(large.name.contains("20 cm"), "{}", large.name);
        let (a, b) = (right_answers(large, &once), right_answers(large, &again));
        let n = large.cases.len();
        assert!(
            b >= a,
            "seed {seed}: restarts lost answers: {b} against {a} of {n}"
        );
        assert!(
            b as f64 >= 0.85 * n as f64,
            "seed {seed}: {b} of {n} right with restarts"
        );
    }
}

/// From guesses 20 cm and 10° off, Freiburg 101's corridor lets a match slide a metre or more
/// along it and still be trusted. A line-assisted Lorentzian that checks a trusted answer more
/// than `FAR_SLIDE_M` from the guess against the coarse search's best start trusts fewer such
/// answers, loses no right one, and changes no answer that stayed near its guess; over four
/// seeds (each has the slide on the corridor's pair 8 without the check). Trusted as the rule
/// stood when the check came: without asking whether the scans hold the answer along the
/// corridor (`TrustRule::holds`, which refuses most such slides on its own), and both matchers
/// without the walk of such a refused answer toward the guess (`GuessAlongFree`), which came
/// after.
#[test]
fn a_trusted_answer_far_from_the_guess_is_checked() {
    use robot::localization::{FAR_SLIDE_M, Lorentz};
    let checked = Lorentz {
        guess_along_free: None,
        ..Lorentz::with_lines()
    };
    let unchecked = Lorentz {
        far_slide_m: None,
        ..checked.clone()
    };
    assert_eq!(checked.far_slide_m, Some(FAR_SLIDE_M));
    let (mut slid_before, mut slid_after) = (0, 0);
    for seed in [1, 4, 7, 8] {
        let sets = sets(150, seed);
        let large = sets.last().expect("the large-guess row");
        assert!(large.name.contains("20 cm"), "{}", large.name);
        // The pooled row holds 50 pairs of each log in turn: Freiburg 101's are the second 50.
        for (k, case) in large.cases.iter().enumerate().skip(50).take(50) {
            let before = unchecked.match_scans(&case.reference, &case.current, case.guess);
            let after = checked.match_scans(&case.reference, &case.current, case.guess);
            let slid = |r: &robot::localization::MatchResult| {
                let off = case.truth.relative(&r.pose);
                let unheld = robot::localization::MatchQuality {
                    held: true,
                    ..r.quality
                };
                robot::localization::TrustRule::default().trusts(&unheld)
                    && off.x.hypot(off.y) > 0.3
            };
            slid_before += usize::from(slid(&before));
            slid_after += usize::from(slid(&after));
            assert!(
                !is_right(large, case, &before) || is_right(large, case, &after),
                "seed {seed}, pair {k}: a right answer lost"
            );
            let went = case.guess.relative(&before.pose);
            if went.x.hypot(went.y) <= FAR_SLIDE_M {
                assert_eq!(before.pose, after.pose, "seed {seed}, pair {k}");
            }
        }
    }
    assert!(
        slid_before >= 4,
        "the slide is gone without the check: {slid_before}"
    );
    assert!(
        slid_after < slid_before,
        "trusted slides {slid_after} with the check, {slid_before} without"
    );
}

/// A trusted answer far from its guess whose surfaces face every way is not checked against
/// the coarse search (`FAR_SLIDE_SPREAD`): a slide runs along a direction the surfaces leave
/// free. On the large guesses' row of four seeds, no right answer is lost and no pair takes
/// more searches than with every far answer checked, and checks are left out. (The answers
/// that stay checked, along Freiburg 101's corridor, are
/// `a_trusted_answer_far_from_the_guess_is_checked`'s.)
#[test]
fn a_far_answer_whose_surfaces_face_every_way_is_not_checked() {
    use robot::localization::{FAR_SLIDE_SPREAD, Lorentz};
    let gated = Lorentz::with_lines();
    assert_eq!(gated.far_slide_spread, Some(FAR_SLIDE_SPREAD));
    let every = Lorentz {
        far_slide_spread: None,
        ..Lorentz::with_lines()
    };
    let mut left_out = 0;
    for seed in [1, 4, 7, 8] {
        let sets = sets(150, seed);
        let large = sets.last().expect("the large-guess row");
        assert!(large.name.contains("20 cm"), "{}", large.name);
        for (k, case) in large.cases.iter().enumerate() {
            let a = gated.match_scans(&case.reference, &case.current, case.guess);
            let b = every.match_scans(&case.reference, &case.current, case.guess);
            let at = format!("seed {seed}, pair {k}");
            assert!(
                !is_right(large, case, &b) || is_right(large, case, &a),
                "{at}: lost"
            );
            assert!(a.iterations <= b.iterations, "{at}: {a:?} against {b:?}");
            left_out += usize::from(a.iterations < b.iterations);
        }
    }
    assert!(left_out >= 10, "{left_out} checks left out");
}

/// From a guess 20 cm and 10° off, a line-assisted Lorentzian that tries its wide second
/// schedule (σ 20 cm first) when its answer is untrusted, or fits loosely after going far, is
/// right at least as often as without it on each of two seeds and more often over both; on the
/// synthetic rows, where the guesses are near, it loses at most one pair of the 300 a row over
/// both seeds (since the reference's surfaces are fitted, one pair of seed 7's 20 % row).
#[test]
fn a_wide_second_schedule_rescues_large_guesses() {
    use robot::localization::Lorentz;
    let narrow = Lorentz {
        wide_sigmas_m: Vec::new(),
        ..Lorentz::with_lines()
    };
    let both = Lorentz::with_lines();
    assert!(!both.wide_sigmas_m.is_empty());
    let (mut without, mut with) = (0, 0);
    // Right answers on each synthetic row, without and with, summed over the seeds.
    let mut synthetic: Vec<(String, usize, usize)> = Vec::new();
    for seed in [7, 8] {
        let sets = sets(150, seed);
        let large = sets.last().expect("the large-guess row");
        assert!(large.name.contains("20 cm"), "{}", large.name);
        let (a, b) = (right_answers(large, &narrow), right_answers(large, &both));
        assert!(b >= a, "seed {seed}, large guesses: {b} against {a}");
        (without, with) = (without + a, with + b);
        for set in sets.iter().filter(|s| s.name.starts_with("synthetic")) {
            let (a, b) = (right_answers(set, &narrow), right_answers(set, &both));
            tally(&mut synthetic, &set.name, a, b);
        }
    }
    assert!(!synthetic.is_empty());
    for (name, a, b) in &synthetic {
        assert!(b + 1 >= *a, "{name}: {b} against {a}");
    }
    assert!(
        with > without,
        "the wide schedule rescued nothing: {with} against {without}"
    );
}

/// On sparse scans the line-assisted Lorentzian leaves the wide schedule to untrusted answers
/// (`sparse_loose_wide`): from guesses 20 cm and 10° off Edmonton's 1° scans, where nearly every
/// trusted answer fits loosely after going far, it keeps those answers as they are, in fewer
/// iterations on many pairs and never more, right on all but at most two pairs fewer than
/// with the wide schedule over two seeds; the dense logs' pairs of the row answer the same to
/// the bit.
#[test]
fn sparse_trusted_answers_skip_the_wide_schedule() {
    use robot::localization::Lorentz;
    let kept = Lorentz::with_lines();
    assert!(!kept.sparse_loose_wide);
    let widened = Lorentz {
        sparse_loose_wide: true,
        ..Lorentz::with_lines()
    };
    let (mut right, mut fewer, mut sparse) = ([0usize; 2], 0, 0);
    for seed in [7, 8] {
        let sets = sets(150, seed);
        let large = sets.last().expect("the large-guess row");
        assert!(large.name.contains("20 cm"), "{}", large.name);
        for case in &large.cases {
            let a = kept.match_scans(&case.reference, &case.current, case.guess);
            let b = widened.match_scans(&case.reference, &case.current, case.guess);
            let is_sparse = robot::localization::beam_step_below(
                &case.current.points(),
                robot::localization::SPARSE_BEAM_STEP_RAD,
            ) != Some(true);
            if !is_sparse {
                assert_eq!(a.pose, b.pose, "a dense pair moved");
                continue;
            }
            sparse += 1;
            assert!(a.iterations <= b.iterations, "{a:?} against {b:?}");
            fewer += usize::from(a.iterations < b.iterations);
            right[0] += usize::from(is_right(large, case, &a));
            right[1] += usize::from(is_right(large, case, &b));
        }
    }
    assert!(sparse >= 90, "{sparse} sparse pairs");
    assert!(
        fewer * 4 >= sparse,
        "the wide schedule ran on {fewer} of {sparse}"
    );
    assert!(
        right[0] + 2 >= right[1],
        "right {} against {}",
        right[0],
        right[1]
    );
}

/// The line-assisted Lorentzian also polishes its answer from before the last σ pass and keeps
/// it when it fits clearly more points (`before_last_margin`), but only in the wide schedule:
/// a sparse scan's first schedule ends with the point-to-line finish, which places the answer
/// (it had run there too, for Edmonton's 1° scans, until the finish came). On seeds held out
/// from those it was measured on (37 and 38, 150 pairs a row), with and without it: the sparse
/// rows give the same answer on at least nine pairs in ten (the others ran the wide schedule)
/// and are right on as many pairs, give or take one.
#[test]
fn the_second_polish_is_left_to_the_wide_schedule() {
    use robot::localization::Lorentz;
    let without = Lorentz {
        before_last_margin: None,
        ..Lorentz::with_lines()
    };
    let with = Lorentz::with_lines();
    assert!(with.before_last_margin.is_some());
    // Per sparse row: right answers without and with, pairs matched, answers the same.
    let mut rows: BTreeMap<String, ([usize; 2], usize, usize)> = BTreeMap::new();
    for seed in [37, 38] {
        for set in sets(150, seed) {
            if !sparse_row(&set.name) {
                continue;
            }
            let (right, pairs, same) = rows.entry(set.name.clone()).or_default();
            for c in &set.cases {
                let a = without.match_scans(&c.reference, &c.current, c.guess);
                let b = with.match_scans(&c.reference, &c.current, c.guess);
                right[0] += usize::from(is_right(&set, c, &a));
                right[1] += usize::from(is_right(&set, c, &b));
                *pairs += 1;
                *same += usize::from(a.pose == b.pose);
            }
        }
    }
    assert_eq!(rows.len(), 3, "Edmonton and the two 1° rows: {rows:?}");
    for (name, (right, pairs, same)) in &rows {
        println!("{name}: right {right:?}, the same answer on {same} of {pairs}");
        assert!(10 * same >= 9 * pairs, "{name}: {same} of {pairs} the same");
        assert!(right[1] + 1 >= right[0], "{name}: {right:?}");
        assert!(right[0] + 1 >= right[1], "{name}: {right:?}");
    }
}

/// On sparse scans the σ passes stop when a search moves the estimate by under 0.3 mm and
/// 0.003° (`SPARSE_EARLY_CONVERGENCE`), not 0.1 mm and 0.001° (the passes before the last) and
/// 0.01 mm and 0.0001° (the last): the finish takes the answer on. On seeds held out from
/// those it was chosen on (35 and 36, 150 pairs a row): fewer correspondence searches on every
/// sparse row, a twentieth fewer on the twin's 1° pairs without outliers, and at most one
/// right answer fewer on any; the dense scans do not change.
#[test]
fn sparse_passes_stop_sooner() {
    use robot::localization::{Lorentz, SPARSE_EARLY_CONVERGENCE};
    let sooner = Lorentz::with_lines();
    assert_eq!(
        sooner.sparse_early_convergence,
        Some(SPARSE_EARLY_CONVERGENCE)
    );
    let longer = Lorentz {
        sparse_early_convergence: None,
        ..Lorentz::with_lines()
    };
    let rows = sparse_rows_side_by_side([&longer, &sooner], [35, 36]);
    assert_fewer_searches(&rows, 1, (20, 19));
}

/// Adds a row's right answers without (`a`) and with (`b`) to its running totals.
fn tally(totals: &mut Vec<(String, usize, usize)>, row: &str, a: usize, b: usize) {
    match totals.iter_mut().find(|(name, _, _)| name == row) {
        Some(total) => (total.1, total.2) = (total.1 + a, total.2 + b),
        None => totals.push((row.to_string(), a, b)),
    }
}

/// On dense scans (beams 0.5° apart) the line-assisted Lorentzian narrows its σ from 5 cm
/// (`DENSE_SIGMAS`) instead of the thesis's 2 → 5 → 0.5 cm, whose widening middle pass lets
/// the points that see what the reference did not pull the answer aside. Started at the truth
/// of two synthetic pairs the thesis's schedule leaves for places 92 and 57 mm away (found
/// over seeds 5 and 11), it ends 4 and 32 mm from it, within the row's 5 cm (of the four such
/// pairs found, the other two still leave it); and over four other seeds of 300 pairs a row it
/// is right at least as often on the synthetic rows and Belgioioso. (Before the first match
/// took one NLM step a search it was right more often over them all on those seeds; since,
/// the four seeds give the same counts, and over seeds 1–12 the narrowing schedule is right on
/// 3595, 3590 and 3599 pairs of 3,600 where the thesis's is on 3594, 3585 and 3597, with half
/// the searches.) Edmonton's 1° scans keep the thesis's schedule, with the same answers to the
/// last bit. Both without the crowd rule, which comes with the dense schedule (`CROWD_RATIO`,
/// tested on its own below), and without the sparse scans' finish (`SPARSE_FINISH`) and quick
/// finish (`SPARSE_QUICK`), which
/// the thesis's schedule would otherwise run on dense scans too, so that the schedule alone is
/// compared (and so with the thesis's last pass, which the finish replaces on sparse scans),
/// and without the walk of an answer refused along a corridor toward the guess
/// (`GuessAlongFree`), which would bring an untrusted answer back toward the truth here.
#[test]
fn dense_scans_narrow_their_sigma_throughout() {
    use robot::localization::{Lorentz, beam_step};
    // Without the finish, sparse scans keep the thesis's last pass too (`SPARSE_SIGMAS`
    // leaves it to the finish).
    let narrowing = Lorentz {
        crowd_ratio: None,
        sparse_finish: None,
        sparse_quick: None,
        guess_along_free: None,
        sigmas_m: thesis_sigmas(),
        ..Lorentz::with_lines()
    };
    let thesis = Lorentz {
        dense_sigmas_m: Vec::new(),
        ..narrowing.clone()
    };
    let from_truth = |case: &matchers::Case, m: &Lorentz| {
        let reference = Reference::new(case.reference.points());
        let answer = m.align(&reference, &case.current.points(), case.truth);
        let off = case.truth.relative(&answer.pose);
        off.x.hypot(off.y)
    };
    for (seed, pair) in [(5, 291), (11, 231)] {
        let sets = sets(300, seed);
        let set = sets
            .iter()
            .find(|s| s.name.starts_with("synthetic, 0"))
            .expect("a row");
        let case = &set.cases[pair];
        let (away, stays) = (from_truth(case, &thesis), from_truth(case, &narrowing));
        assert!(
            away > set.tolerance_m && stays < set.tolerance_m,
            "seed {seed} pair {pair}: {:.1} mm from the truth with the thesis's schedule, {:.1} \
             mm narrowing (a success within {} mm)",
            away * 1e3,
            stays * 1e3,
            set.tolerance_m * 1e3
        );
    }
    let mut counts = Vec::new();
    for seed in [7, 8, 9, 10] {
        for set in sets(300, seed) {
            let dense = beam_step(&set.cases[0].current.points())
                .is_some_and(|step| step < 0.75f64.to_radians());
            let sparse = sparse_row(&set.name);
            assert_eq!(dense, !sparse, "{}", set.name);
            let looked_at = set.name.starts_with("synthetic,")
                || set.name.contains("belgioioso")
                || set.name.contains("edmonton");
            if looked_at {
                let (a, b) = (
                    right_answers(&set, &thesis),
                    right_answers(&set, &narrowing),
                );
                if set.name.contains("edmonton") {
                    assert_eq!(a, b, "seed {seed}: Edmonton keeps the thesis's schedule");
                }
                tally(&mut counts, &set.name, a, b);
            }
        }
    }
    assert_eq!(counts.len(), 4, "{counts:?}");
    for (name, a, b) in &counts {
        assert!(b >= a, "{name}: {b} right answers narrowing against {a}");
    }
    let (a, b) = counts.iter().fold((0, 0), |(a, b), c| (a + c.1, b + c.2));
    assert!(b >= a, "the rows lost pairs: {counts:?}");
}

/// When no start gives a trusted answer (the guess, the wide schedule, the restarts), the
/// line-assisted Lorentzian starts again from the best poses of a coarse correlative search
/// 60 cm and 30° around the guess (`COARSE`), and keeps a trusted answer that fits clearly more
/// points than its first. From guesses 20 cm and 10° off, two pairs the restarts leave beyond
/// the row's 10 cm (seeds 6 and 8) end within it: six over seeds 1–12, and none the other way,
/// since Edmonton's readings beyond its declared 10 m are read and its sparse scans asked a
/// smaller share (seed 2's pairs 200 and 245, which this test held before, are found without
/// it now). Those two pairs are compared without the sparse finish, which also rescues seed
/// 6's. Over four other seeds of 300 pairs it is right more often on the large guesses, and
/// Edmonton's sparse scans, whose corridors offer look-alike places within the window, lose no
/// pair.
#[test]
fn a_coarse_search_finds_what_the_restarts_miss() {
    use robot::localization::{COARSE, Lorentz};
    let without = Lorentz {
        coarse: None,
        ..Lorentz::with_lines()
    };
    let with = Lorentz::with_lines();
    assert_eq!(with.coarse, Some(COARSE));
    let large = |sets: &[CaseSet]| -> CaseSet {
        sets.iter()
            .find(|s| s.name.starts_with("real, guess"))
            .expect("the large guesses' row")
            .clone()
    };
    // The two pairs without the sparse finish (`SPARSE_FINISH`), which rescues seed 6's pair on
    // its own: the coarse search alone is compared.
    let [unfinished_without, unfinished_with] = [&without, &with].map(|m| Lorentz {
        sparse_finish: None,
        ..m.clone()
    });
    for (seed, pair) in [(6, 261), (8, 181)] {
        let set = large(&sets(300, seed));
        let one = CaseSet {
            cases: vec![set.cases[pair].clone()],
            ..set
        };
        assert_eq!(
            (
                right_answers(&one, &unfinished_without),
                right_answers(&one, &unfinished_with)
            ),
            (0, 1),
            "seed {seed} pair {pair}"
        );
    }
    let mut counts = Vec::new();
    for seed in [13, 14, 15, 16] {
        for set in sets(300, seed) {
            if set.name.starts_with("real, guess") || set.name.contains("edmonton") {
                let (a, b) = (right_answers(&set, &without), right_answers(&set, &with));
                tally(&mut counts, &set.name, a, b);
            }
        }
    }
    assert_eq!(counts.len(), 2, "{counts:?}");
    for (name, a, b) in &counts {
        if name.contains("edmonton") {
            assert!(
                b >= a,
                "{name}: {b} right answers with the coarse search against {a}"
            );
        } else {
            assert!(
                b > a,
                "{name}: {b} right answers with the coarse search against {a}"
            );
        }
    }
}

/// The pairs `range` of the corrected log named `log` (its row of `twin matchers`), with the
/// guesses of `seed`; pair numbers in the outcomes then count from the range's start.
fn log_pairs(log: &str, range: std::ops::Range<usize>, seed: u64) -> CaseSet {
    let mut set = matchers::standard_sets(&repo(), range.end, seed)
        .expect("the bundled logs load")
        .into_iter()
        .find(|s| s.name.contains(log))
        .expect("the log's row");
    set.cases.drain(..range.start);
    set.triangles.retain(|t| t.first >= range.start);
    for t in &mut set.triangles {
        t.first -= range.start;
        t.second -= range.start;
    }
    set
}

/// A corrected log's pose can be wrong where the scans are not: on Freiburg 101's pairs 248–250,
/// on every seed, point-to-line ICP and `lorentz-lines` agree within a centimetre on an answer
/// 11–14 cm from the log's pose, which leaves under a third of the current points on the
/// reference's surfaces where the answers fit over four in five. Such failures are counted as
/// disputed (and stay failures); on synthetic pairs, whose truth is exact, none is.
#[test]
fn the_scans_dispute_a_corrected_pose_where_it_is_wrong() {
    let kinds = [MatcherKind::LorentzLines, MatcherKind::PointToLine];
    for seed in [1, 7] {
        let set = log_pairs("freiburg", 246..252, seed);
        let mut outcomes = Vec::new();
        let rows = matchers::evaluate(&set, &kinds, &mut |m| {
            if let Matched::Pair(o) = m {
                outcomes.push(o)
            }
        });
        for o in &outcomes {
            // Pairs 248, 249 and 250 are the third to fifth kept.
            let pair = o.pair + 246;
            if (248..=250).contains(&pair) {
                assert!(
                    !o.success && o.disputed && o.truth_share < 0.3,
                    "seed {seed}, pair {pair}, {}: {:?}",
                    o.matcher,
                    (o.error, o.truth_share, o.result.quality.inlier_share)
                );
            } else {
                assert!(!o.disputed, "seed {seed}, pair {pair}: {:?}", o.error);
            }
        }
        assert!(rows.iter().all(|r| r.disputed == 3), "{rows:?}");
        // Both matchers land within a centimetre of each other on the disputed pairs.
        for pair in 2..=4 {
            let [a, b] = [0, 1].map(|m| &outcomes[m * set.cases.len() + pair].result.pose);
            let apart = a.relative(b);
            assert!(apart.x.hypot(apart.y) < 0.01, "seed {seed}, pair {pair}");
        }
    }
    for set in sets(40, 3).iter().filter(|s| s.name.contains("synthetic")) {
        for row in matchers::evaluate(set, &kinds, &mut |_| {}) {
            assert_eq!(row.disputed, 0, "{row:?}");
        }
    }
}

/// Edmonton's corrected poses are off by about a decimetre on some pairs too, where the scans
/// do not dispute them twice over: on pair 288 `lorentz-lines` and `pl-icp`, started from the
/// same guess, land within 2 cm and 0.2° of each other, 12–13 cm from the log's pose, and both
/// fit 10 points in 100 more of the current points than it (0.38 and 0.37 against 0.26), on
/// every seed of 1–20. Such failures are counted as agreed (and stay failures); on synthetic
/// pairs, whose truth is exact, none is. (Pair 153, which this test held too, is no longer
/// one: finished by point-to-line ICP (`SPARSE_FINISH`), `lorentz-lines` lands on `pl-icp`'s
/// answer there, 8.5 cm from the log's pose, inside the row's 10 cm.)
#[test]
fn two_matchers_agree_against_a_corrected_pose_where_it_is_off() {
    let kinds = [MatcherKind::LorentzLines, MatcherKind::PointToLine];
    for seed in [1, 7] {
        let (pairs, pair) = (286..291, 288);
        let start = pairs.start;
        let set = log_pairs("edmonton", pairs, seed);
        let mut outcomes = Vec::new();
        let mut rows = matchers::evaluate(&set, &kinds, &mut |m| {
            if let Matched::Pair(o) = m {
                outcomes.push(o)
            }
        });
        matchers::mark_agreed(&mut outcomes, &mut rows);
        for o in outcomes
            .iter()
            .filter(|o| o.matcher == MatcherKind::LorentzLines)
        {
            if o.pair + start == pair {
                assert!(
                    !o.success && o.agreed && !o.disputed,
                    "seed {seed}, pair {pair}: {:?}",
                    (o.error, o.truth_share, o.result.quality.inlier_share)
                );
            }
            if o.agreed {
                assert!(!o.success, "seed {seed}, pair {}", o.pair + start);
            }
        }
        let agreed = |kind| rows.iter().find(|r| r.matcher == kind).unwrap().agreed;
        assert!(agreed(MatcherKind::LorentzLines) >= 1, "{rows:?}");
    }
    for set in sets(40, 3).iter().filter(|s| s.name.contains("synthetic")) {
        let mut outcomes = Vec::new();
        let mut rows = matchers::evaluate(set, &kinds, &mut |m| {
            if let Matched::Pair(o) = m {
                outcomes.push(o)
            }
        });
        matchers::mark_agreed(&mut outcomes, &mut rows);
        assert!(rows.iter().all(|r| r.agreed == 0), "{rows:?}");
    }
}

/// `twin matchers --show SET/PAIR` draws the pair: the reference scan, the current scan at the
/// true pose and at each matcher's answer, all inside the picture and in its legend, with a
/// detail view where the scans share only a corner of it, and writes the pair beside it as
/// `twin match` reads it; a bad request is refused by name.
#[test]
fn twin_matchers_shows_a_pair() {
    let out = tempfile_dir("twin-matchers-show");
    let show = |spec: &str, with_out: bool| {
        let mut command = Command::new(env!("CARGO_BIN_EXE_twin"));
        command
            .args([
                "matchers",
                "--matchers",
                "lorentz-lines,pl-icp",
                "--show",
                spec,
            ])
            .current_dir(repo());
        if with_out {
            command.arg("--out").arg(&out);
        }
        command.output().unwrap()
    };
    // The picture of `spec`, written as `file`: drawn, and every element inside its canvas.
    let drawn = |spec: &str, file: &str| {
        let run = show(spec, true);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let svg = std::fs::read_to_string(out.join(file)).unwrap();
        assert_eq!(crate::common::svg::problems(&svg), Vec::<String>::new());
        svg
    };
    let svg = drawn("freiburg-101/248", "pair-real-freiburg-101-248.svg");
    for label in [
        "reference scan",
        "the pose given as truth",
        "lorentz-lines",
        "pl-icp",
    ] {
        assert!(svg.contains(label), "{label} missing");
    }
    // Beside the picture, the pair as `twin match` reads it: matched again, the same answer's
    // share as the legend's.
    let pair = std::fs::read(out.join("pair-real-freiburg-101-248.jsonl")).unwrap();
    let mut matcher = Command::new(env!("CARGO_BIN_EXE_twin"))
        .args(["match", "--matcher", "lorentz-lines"])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::io::Write::write_all(&mut matcher.stdin.take().unwrap(), &pair).unwrap();
    let reply = matcher.wait_with_output().unwrap();
    let reply: serde_json::Value = serde_json::from_slice(&reply.stdout).unwrap();
    assert_eq!(reply["converged"], true, "{reply}");
    let share = reply["quality"]["inlier_share"].as_f64().unwrap();
    let legend = format!("answer of lorentz-lines: {:.0} %", 100.0 * share);
    assert!(svg.contains(&legend), "{legend} not in the legend");
    // Freiburg's scans share surfaces across the whole view: one view, no detail.
    assert!(
        !svg.contains("detail-area"),
        "a detail view of Freiburg 101's pair 248"
    );
    // A synthetic pair with 20 % outliers out to 32 m, the robot facing one wall: a detail
    // view beside the overview, its grid finer, its area drawn on the overview and listed.
    let svg = drawn("20 %/35", "pair-synthetic-20-35.svg");
    assert!(
        svg.contains(r#"data-layer="detail-area""#),
        "no detail view"
    );
    let grids: Vec<f64> = svg
        .split("grid ")
        .skip(1)
        .filter_map(|rest| rest.split(' ').next()?.parse().ok())
        .collect();
    assert_eq!(grids.len(), 2, "two views, each with its grid: {grids:?}");
    assert!(grids[1] < grids[0], "the detail's grid is finer: {grids:?}");
    for (spec, with_out, expected) in [
        ("freiburg-101", true, "SET/PAIR"),
        ("nowhere/3", true, "row's name"),
        ("freiburg-101/x", true, "pair number"),
        ("freiburg-101/900", true, "291 pairs"),
        ("freiburg-101/248", false, "--out"),
    ] {
        let run = show(spec, with_out);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success(), "{spec} was accepted");
        assert!(
            stderr.contains("--show") && stderr.contains(expected),
            "{spec}: {stderr}"
        );
    }
}

/// Two line-assisted Lorentzians side by side on every pair of `sets(150, seed)` for each of
/// `seeds`, each pair's two answers handed to `visit`. Edmonton's sparse scans take neither
/// matcher's dense-scan rules, so there the two must give the same answers; the twin's 1°
/// rows, as sparse, are left out.
fn each_pair_side_by_side(
    matchers: [&robot::localization::Lorentz; 2],
    seeds: &[u64],
    visit: impl FnMut(&CaseSet, &matchers::Case, [&robot::localization::MatchResult; 2]),
) {
    let taking = |name: &str| {
        (!name.contains("1°")).then(|| Taking {
            pairs: usize::MAX,
            unchanged: name.contains("edmonton"),
        })
    };
    each_pair_taken_side_by_side(matchers, (seeds, 150), taking, visit);
}

/// How a row takes part in [`each_pair_taken_side_by_side`]: its first `pairs` matched by both,
/// and with `unchanged`, the two answers required to be the same.
struct Taking {
    pairs: usize,
    unchanged: bool,
}

/// Two line-assisted Lorentzians side by side on the rows of `sets(n, seed)` that `taking`
/// picks by name, for each of `seeds`: each pair's two answers handed to `visit`.
fn each_pair_taken_side_by_side(
    matchers: [&robot::localization::Lorentz; 2],
    (seeds, n): (&[u64], usize),
    taking: impl Fn(&str) -> Option<Taking>,
    mut visit: impl FnMut(&CaseSet, &matchers::Case, [&robot::localization::MatchResult; 2]),
) {
    for &seed in seeds {
        for set in sets(n, seed) {
            let Some(Taking { pairs, unchanged }) = taking(&set.name) else {
                continue;
            };
            for (k, c) in set.cases.iter().enumerate().take(pairs) {
                let [a, b] = matchers.map(|m| m.match_scans(&c.reference, &c.current, c.guess));
                if unchanged {
                    assert_eq!(a, b, "seed {seed}, {} pair {k}: as before", set.name);
                }
                visit(&set, c, [&a, &b]);
            }
        }
    }
}

/// [`each_pair_side_by_side`], per row: each matcher's right answers and median
/// correspondence searches a pair.
fn rows_side_by_side(
    matchers: [&robot::localization::Lorentz; 2],
    seeds: [u64; 2],
) -> BTreeMap<String, ([usize; 2], [u32; 2])> {
    let mut rows: BTreeMap<String, ([usize; 2], [Vec<u32>; 2])> = BTreeMap::new();
    each_pair_side_by_side(matchers, &seeds, |set, c, answers| {
        let (right, searches) = rows.entry(set.name.clone()).or_default();
        for (k, r) in answers.into_iter().enumerate() {
            right[k] += usize::from(is_right(set, c, r));
            searches[k].push(r.iterations);
        }
    });
    assert_eq!(rows.len(), 6, "every row of the table but the 1° ones");
    rows.into_iter()
        .map(|(name, (right, mut searches))| {
            let medians = searches.each_mut().map(|v| {
                v.sort_unstable();
                v[v.len() / 2]
            });
            println!("{name}: right {right:?}, median searches {medians:?}");
            (name, (right, medians))
        })
        .collect()
}

/// On dense scans, in a search whose line normals spread (`LINE_RESIDUALS_SPREAD`), the
/// line-assisted Lorentzian counts a point projected inside a reference line by its distance
/// to that line alone, so the estimate no longer crawls along walls by what the projections
/// move in one search. Over two seeds held out from the twelve it was chosen on (13 and 14, 150
/// pairs a row): on every dense row it is right as often (a pair either way allowed; none moved
/// over seeds 1–12) for fewer correspondence searches, a quarter fewer or more on the synthetic
/// pairs without outliers and Belgioioso; Edmonton's sparse 1° scans, which ask a share of
/// their own (`SPARSE_LINE_RESIDUALS_SPREAD`), the same answers to the last bit.
#[test]
fn point_to_line_residuals_take_fewer_searches() {
    use robot::localization::Lorentz;
    let product = Lorentz {
        line_residuals_spread: None,
        ..Lorentz::with_lines()
    };
    let to_lines = Lorentz::with_lines();
    for (name, (right, [a, b])) in &rows_side_by_side([&product, &to_lines], [13, 14]) {
        assert!(right[1] + 1 >= right[0], "{name}: right {right:?}");
        if !name.contains("edmonton") {
            assert!(b < a, "{name}: {a} -> {b} searches");
        }
        if name.starts_with("synthetic, 0") || name.contains("belgioioso") {
            assert!(4 * b <= 3 * a, "{name}: {a} -> {b} searches");
        }
    }
}

/// A pair saved under `tests/data/` as JSON: its reference and current scans, the guess and
/// the true pose.
fn saved_pair(name: &str) -> (RangeScan, RangeScan, Pose2, Pose2) {
    let text = std::fs::read_to_string(repo().join("tests/data").join(name)).unwrap();
    let pair: serde_json::Value = serde_json::from_str(&text).unwrap();
    let scan = |k: &str| -> RangeScan { serde_json::from_value(pair[k].clone()).unwrap() };
    let pose = |k: &str| {
        let v: Vec<f64> = serde_json::from_value(pair[k].clone()).unwrap();
        Pose2::new(v[0], v[1], v[2])
    };
    (scan("ref"), scan("cur"), pose("guess"), pose("truth"))
}

/// How far an answer lies from `truth`: metres and degrees.
fn off_truth(truth: &Pose2, r: &robot::localization::MatchResult) -> (f64, f64) {
    let d = truth.relative(&r.pose);
    (d.x.hypot(d.y), d.theta.abs().to_degrees())
}

/// A pair of the goto-lab study (`tests/data/pair-restart-slides.json`: a 0.6 m advance past
/// black and glass, where the current scan sees a table 0.3 m away that the reference saw
/// through): no start near the guess is trusted, and point-to-line residuals let a restart
/// 8–16° or 15 cm away slide to a look-alike place 9 cm and 2.8° off that fits 75 % of the
/// points and passed the trust rule, so the map builder drifted 62 cm over the run. Restarts
/// and the coarse search keep the product form: a trusted answer must be right. Since the
/// crowd rule (`CROWD_RATIO`: the table's points the reference saw through no longer crowd
/// onto one of its points) the first match from the guess finds the truth, 3 mm off, and
/// trusts it, with point-to-line residuals or without; before, nothing was trusted and the map
/// builder placed that scan by odometry.
#[test]
fn a_restart_is_not_free_to_slide() {
    use robot::localization::{Lorentz, MatchResult};
    let (reference, current, guess, truth) = saved_pair("pair-restart-slides.json");
    let off = |r: &MatchResult| off_truth(&truth, r);
    let answer = Lorentz::with_lines().match_scans(&reference, &current, guess);
    let (metres, degrees) = off(&answer);
    assert!(
        !answer.converged || (metres < 0.05 && degrees < 1.0),
        "trusted {:.0} mm and {degrees:.1}° off",
        metres * 1e3
    );
    assert!(
        answer.converged,
        "the right answer, {:.0} mm off, is trusted",
        metres * 1e3
    );
    // Without point-to-line residuals anywhere, the same.
    let product = Lorentz {
        line_residuals_spread: None,
        ..Lorentz::with_lines()
    };
    let (metres, degrees) = off(&product.match_scans(&reference, &current, guess));
    assert!(
        metres < 0.05 && degrees < 1.0,
        "{:.0} mm, {degrees:.1}° off",
        metres * 1e3
    );
    // Crowded pairs kept (the matcher before), nothing is trusted.
    let crowded = Lorentz {
        crowd_ratio: None,
        ..Lorentz::with_lines()
    };
    assert!(!crowded.match_scans(&reference, &current, guess).converged);
}

/// Another pair of the goto-lab scenario (`tests/data/pair-restart-shortfall.json`, seed 77):
/// a 0.6 m advance along the LSC's two long walls, where a box and the far wall are all that
/// hold the advance. The first match from the guess finds the truth and fits 72 % of the
/// points, but is not trusted (its Gauss–Newton step is 2.1 cm, over the rule's 2 cm); one
/// restart of eight slides back along the walls to where the robot stood (0.59 m short) and
/// fits 52 %, and the trust rule passed it: the robot steered by it and ended its goal 0.58 m
/// off. A restart's answer must now fit nearly as many points as the first
/// (`RESTART_SHORTFALL`): the first stays, untrusted, and the map builder places the scan by
/// odometry, which is right here.
#[test]
fn a_restart_that_fits_fewer_points_does_not_replace_the_first() {
    use robot::localization::{Lorentz, MatchResult};
    let (reference, current, guess, truth) = saved_pair("pair-restart-shortfall.json");
    let off = |r: &MatchResult| off_truth(&truth, r);
    let answer = Lorentz::with_lines().match_scans(&reference, &current, guess);
    let (metres, degrees) = off(&answer);
    assert!(
        !answer.converged || (metres < 0.05 && degrees < 1.0),
        "trusted {:.0} mm and {degrees:.1}° off",
        metres * 1e3
    );
    assert!(
        metres < 0.05 && degrees < 1.0,
        "the first answer, {:.0} mm and {degrees:.1}° off, is kept",
        metres * 1e3
    );
    // Any trusted answer that fits most, however little (the matcher before): the look-alike.
    // Without the walk along the corridor toward the guess (`GuessAlongFree`), which came
    // after and would move that untrusted answer.
    let before = Lorentz {
        restart_shortfall: None,
        guess_along_free: None,
        ..Lorentz::with_lines()
    };
    let slid = before.match_scans(&reference, &current, guess);
    let (metres, _) = off(&slid);
    // Trusted then by the rule as it stood (`held` was not asked before 2026-12-06); the scans'
    // hold along the walls now refuses it too.
    let rule = robot::localization::TrustRule::default();
    let without_hold = robot::localization::MatchQuality {
        held: true,
        ..slid.quality
    };
    assert!(
        rule.trusts(&without_hold) && metres > 0.3,
        "before: {:.0} mm off, trusted without the hold {}",
        metres * 1e3,
        rule.trusts(&without_hold)
    );
    assert!(!slid.converged && !slid.quality.held, "{:?}", slid.quality);
    assert!(slid.quality.inlier_share + 0.1 < answer.quality.inlier_share);
    // The map builder falls back to odometry for it, and counts it.
    let mut builder = MapBuilder::new(Box::new(Lorentz::with_lines()), MapConfig::default());
    builder.push_odometry(Stamp::from_secs_f64(0.0), Pose2::IDENTITY);
    builder.push_odometry(Stamp::from_secs_f64(1.0), guess);
    builder.push_odometry(Stamp::from_secs_f64(2.0), guess);
    builder.push_scan(reference.clone().stamped(Stamp::from_secs_f64(0.0)));
    builder.push_scan(current.clone().stamped(Stamp::from_secs_f64(1.0)));
    builder.finish();
    let placed = builder.placed();
    assert_eq!(placed.len(), 2);
    assert!(!placed[1].trusted);
    let d = truth.relative(&placed[1].estimate);
    assert!(d.x.hypot(d.y) < 0.05, "placed {:?}", placed[1].estimate);
}

/// The first match of a dense scan from the guess counts the line pairs' distances to their
/// lines alone wherever their normals spread a little (`FIRST_SPREAD`, a tenth), not only where
/// they spread by half, so its points slide along the walls of a room seen mostly one way
/// instead of crawling along them search by search; a loose answer (under 70 % of the points
/// inliers) is matched again with the half. Belgioioso's pair 125, whose scans share little
/// more than one wall: with the tenth and no second match the answer slides along that wall
/// beyond the row's 10 cm from most guesses (found on eight seeds of twelve); the second match
/// keeps it within 10 cm from every guess. Over two other seeds of 150 pairs a row, against
/// the half in every search: no row loses more than a pair, all rows together lose none, the
/// median correspondence searches a pair fall by at least a fifth on the synthetic pairs
/// without outliers and on Freiburg 101, and Edmonton's sparse scans keep the same answers.
/// All without the crowd rule (`CROWD_RATIO`). With it, the σ passes end 14 cm from the log's
/// pose on most seeds (there the points past the reference's view that crowded onto the end
/// of its wall held the answer near the log's pose), fitting as many current points as the
/// answer without it; the slide check (`SLIDE_CHECK`), where two points across the wall vote,
/// brings it back within the row's 10 cm, fitting at least as many, and both more than the
/// log's pose does.
#[test]
fn the_first_match_slides_along_its_lines_and_a_loose_answer_is_checked() {
    use robot::localization::{FIRST_SPREAD, Lorentz};
    let unchecked = Lorentz {
        line_residuals_spread: Some(FIRST_SPREAD),
        first_spread: None,
        crowd_ratio: None,
        ..Lorentz::with_lines()
    };
    let gated = Lorentz {
        first_spread: None,
        crowd_ratio: None,
        ..Lorentz::with_lines()
    };
    let first = Lorentz {
        crowd_ratio: None,
        ..Lorentz::with_lines()
    };
    let uncrowded = Lorentz::with_lines();
    let log = repo().join("tests/data/corrected/belgioioso-corrected.log.gz");
    let error = matchers::GuessError {
        sigma_m: 0.05,
        sigma_rad: 2f64.to_radians(),
    };
    let mut slid = 0;
    for seed in 1..=12 {
        let set = matchers::log_set("belgioioso", &log, 126, error, seed).expect("the log reads");
        let case = &set.cases[125];
        let off = |m: &Lorentz| {
            let answer = m.match_scans(&case.reference, &case.current, case.guess);
            let off = case.truth.relative(&answer.pose);
            off.x.hypot(off.y)
        };
        let (free, checked) = (off(&unchecked), off(&first));
        slid += usize::from(free > set.tolerance_m);
        let share = |m: &Lorentz| {
            let answer = m.match_scans(&case.reference, &case.current, case.guess);
            assert!(answer.converged, "seed {seed}: {} trusted", m.name());
            answer.quality.inlier_share
        };
        let reference = Reference::new(case.reference.points());
        let at_log = TrustRule::default()
            .assess(&reference, &case.current.points().xy, &case.truth)
            .inlier_share;
        let (near, crowded) = (share(&first), share(&uncrowded));
        assert!(
            crowded + 0.01 >= near && near.min(crowded) > at_log + 0.1,
            "seed {seed}: inliers {near:.3} without the crowd rule, {crowded:.3} with it, \
             {at_log:.3} at the log's pose"
        );
        let with_crowd_rule = off(&uncrowded);
        assert!(
            with_crowd_rule <= set.tolerance_m,
            "seed {seed}: with the crowd rule {:.1} mm from the log's pose",
            with_crowd_rule * 1e3
        );
        assert!(
            checked <= set.tolerance_m,
            "seed {seed}: {:.1} mm from the truth (without the second match: {:.1} mm)",
            checked * 1e3,
            free * 1e3
        );
    }
    assert!(
        slid >= 6,
        "without the second match it slid on {slid} seeds of 12"
    );
    let rows = rows_side_by_side([&gated, &first], [21, 22]);
    let (mut all_a, mut all_b) = (0, 0);
    for (name, (right, [a, b])) in &rows {
        assert!(right[1] + 1 >= right[0], "{name}: right {right:?}");
        (all_a, all_b) = (all_a + right[0], all_b + right[1]);
        if name.starts_with("synthetic, 0") || name.contains("freiburg") {
            assert!(5 * b <= 4 * a, "{name}: {a} -> {b} searches");
        }
    }
    assert!(all_b >= all_a, "{all_a} -> {all_b} right answers: {rows:?}");
}

/// Current points that see what the reference did not — past the end of its view after a 25°
/// turn — pile onto the last reference points of the wall they lie on, tens on one point
/// (`CROWD_RATIO`). In the Table 5.1 study the two trials with the worst translation errors of
/// the line-assisted Lorentzian, one at each outlier rate, were such pairs: leaving out the
/// pairs crowded onto one reference point far beyond its nearest, they end within a few
/// millimetres; keeping them (the matcher before), 28–34 mm off, with the answer trusted: past
/// the study's 10 mm line. (Trial 13357 ended 3.9 mm off until a dense first pass started on
/// every second point, `FIRST_PASS_THINNING`, and 5.5 mm since; keeping the crowded pairs,
/// 27.6 mm. Since the polish both ways went 2 cm wide, `BOTH_WAYS_WIDTH_M`, its scan with 20 %
/// outliers ends 3.7 mm off, and 17.0 mm keeping the crowded pairs: the polish pulls that
/// answer part of the way back.)
#[test]
fn points_past_the_references_view_do_not_crowd_onto_its_edge() {
    use robot::localization::{CROWD_RATIO, Lorentz, ScanMatcher};
    use sim::commands::montecarlo::{Trials, errors};
    use sim::config::Study;
    let study = Study::load(repo().join("studies/table-5-1.toml")).expect("the study");
    let trials = Trials::new(&study);
    let now = Lorentz::with_lines();
    assert_eq!(now.crowd_ratio, Some(CROWD_RATIO));
    let crowded = Lorentz {
        crowd_ratio: None,
        ..Lorentz::with_lines()
    };
    // Trial 3734 at 2 % outliers (a turn right), trial 13357 at 20 % (a turn left).
    for index in [3734, 13357] {
        let (_, motion, pair, guess) = trials.pair(index).expect("the trial's pair");
        let mm = |m: &Lorentz| {
            let answer = m.match_scans(&pair.reference, &pair.current, guess);
            (errors(&pair.truth, &answer.pose).1, answer.converged)
        };
        let ((kept, _), (dropped, trusted)) = (mm(&crowded), mm(&now));
        assert!(
            kept > 10.0 && dropped < 8.0 && trusted,
            "trial {index} ({motion:?}): {kept:.1} mm off with the crowded pairs, {dropped:.1} mm \
             without (trusted: {trusted})"
        );
    }
}

/// Where, after the first σ pass of a dense scan, enough current points already lie within
/// 2 cm of their targets (`FIRST_PASS_ENOUGH`: seven in ten when this test was written, 65 in
/// 100 since 2026-11-30), the narrower passes are left out and the polish finishes the answer. Over two seeds held out from the twenty it was chosen on (23 and 24, 150
/// pairs a row): every row right as often (a pair either way allowed), none taking more
/// searches, the synthetic pairs without outliers a third fewer or better (22 → 12 a pair over
/// seeds 1–20, measured before `FIRST_PASS_SURFACE_POINTS`) and Belgioioso fewer; Edmonton's
/// 1° scans are not dense, with the same answers to the last bit. Both without the slide check
/// (`SLIDE_CHECK`), a later step that matches some dense answers again, whose searches would
/// count for both. Both also without `CLEAN_PASS_ENOUGH` (below), which asks clean scans 4 cm
/// since 2026-12-06.
#[test]
fn clean_first_passes_skip_the_narrow_ones() {
    use robot::localization::{FIRST_PASS_ENOUGH, Lorentz};
    let now = Lorentz {
        slide_check: None,
        clean_pass_enough: None,
        ..Lorentz::with_lines()
    };
    assert_eq!(now.first_pass_enough, Some(FIRST_PASS_ENOUGH));
    let every_pass = Lorentz {
        first_pass_enough: None,
        ..now.clone()
    };
    let rows = as_right_in_fewer_searches([&every_pass, &now], [23, 24], (2, 3));
    let (_, [a, b]) = rows["real, belgioioso"];
    assert!(b < a, "Belgioioso: {a} -> {b} searches");
}

/// Belgioioso's real scans, where a median pair fits four of its points in five, seldom had
/// seven in ten within 2 cm after the first pass and ran every pass; since 2026-11-30 65 in
/// 100 are enough (`FIRST_PASS_ENOUGH`). Over two seeds no threshold was chosen on
/// (37 and 38, 150 pairs a row), against the seven in ten before: every row right as often (a
/// pair either way allowed), none taking more searches, Belgioioso fewer. Without the slide
/// check and `CLEAN_PASS_ENOUGH`, as above.
#[test]
fn real_first_passes_skip_the_narrow_ones_too() {
    use robot::localization::{FIRST_PASS_ENOUGH, Lorentz};
    let now = Lorentz {
        slide_check: None,
        clean_pass_enough: None,
        ..Lorentz::with_lines()
    };
    assert_eq!(FIRST_PASS_ENOUGH, (0.02, 0.65));
    let seven_in_ten = Lorentz {
        first_pass_enough: Some((0.02, 0.7)),
        ..now.clone()
    };
    let rows = as_right_in_fewer_searches([&seven_in_ten, &now], [37, 38], (1, 1));
    let (_, [a, b]) = rows["real, belgioioso"];
    assert!(b < a, "Belgioioso: {a} -> {b} searches");
}

/// A real log's dense scans seldom had 65 in 100 of their points within 2 cm after the first
/// pass, and ran the narrower passes on pairs `pl-icp` settles at once; since 2026-12-06 a
/// dense scan that looks clean (few points far from both neighbours: a real log's, the twin's
/// without outliers) leaves them out with 65 in 100 within 4 cm (`CLEAN_PASS_ENOUGH`). Over two
/// seeds no distance was chosen on (61 and 62, 150 pairs a row), against 2 cm for every scan:
/// every row right as often (a pair either way allowed), none taking more searches, Freiburg
/// 101 a quarter fewer or better; the twin's pairs with 20 % outliers, which do not look
/// clean, and Edmonton's 1° scans, which are not dense, give the same answers to the last bit.
/// Without the slide check, as above.
#[test]
fn clean_scans_leave_the_narrow_passes_sooner() {
    use robot::localization::{CLEAN_PASS_ENOUGH, Lorentz};
    let now = Lorentz {
        slide_check: None,
        ..Lorentz::with_lines()
    };
    assert_eq!(CLEAN_PASS_ENOUGH, (0.04, 0.65));
    let two_cm = Lorentz {
        clean_pass_enough: None,
        ..now.clone()
    };
    let rows = as_right_in_fewer_searches([&two_cm, &now], [61, 62], (1, 1));
    let (_, [a, b]) = rows["real, freiburg-101"];
    assert!(4 * b <= 3 * a, "Freiburg 101: {a} -> {b} searches");
    // The rows whose scans are not clean, or not dense, answer as before to the bit (`Taking`
    // requires it).
    let mut compared = 0;
    let taking = |name: &str| {
        (name == "synthetic, 20 %" || name == "real, edmonton").then_some(Taking {
            pairs: usize::MAX,
            unchanged: true,
        })
    };
    each_pair_taken_side_by_side([&two_cm, &now], (&[61], 150), taking, |_, _, _| {
        compared += 1
    });
    assert_eq!(compared, 300, "both rows, 150 pairs each");
}

/// With 20 % outliers about a fifth of a dense scan's points are lonely (1 m or more from both
/// neighbours), and a pair on one is never within 2 cm of its target: counted over every point,
/// `FIRST_PASS_ENOUGH`'s 65 in 100 asked about four in five of the others, and the narrower
/// passes ran on most such pairs. Since 2026-12-07 a dense scan that does not look clean counts
/// them over the points that are not lonely, where the line normals spread by a quarter, and a
/// match the count lets off takes two more polish rounds (`LONELY_PASS_ENOUGH`). Over two seeds
/// held out from the eighty it was measured on (81 and 82, 150 pairs a row), against the count
/// over every point: every row right as often (a pair either way allowed), none taking more
/// searches, the twin's pairs with 20 % outliers a fifth fewer or better, their median error
/// within 0.1 mm; the real logs' scans all look clean, with the same answers to the last bit.
/// Without the slide check, as above.
#[test]
fn scans_with_outliers_count_the_points_not_lonely() {
    use robot::localization::{LONELY_PASS_ENOUGH, Lorentz};
    use sim::commands::montecarlo::errors;
    let now = Lorentz {
        slide_check: None,
        ..Lorentz::with_lines()
    };
    assert_eq!(now.lonely_pass_enough, Some(LONELY_PASS_ENOUGH));
    let every_point = Lorentz {
        lonely_pass_enough: None,
        ..now.clone()
    };
    let rows = as_right_in_fewer_searches([&every_point, &now], [81, 82], (1, 1));
    let (_, [a, b]) = rows["synthetic, 20 %"];
    assert!(5 * b <= 4 * a, "synthetic, 20 %: {a} -> {b} searches");
    // The real logs answer as before to the bit (`Taking` requires it); the twin's pairs with
    // 20 % outliers as precisely.
    let mut errors_mm: [Vec<f64>; 2] = [Vec::new(), Vec::new()];
    let taking = |name: &str| {
        let real = name.starts_with("real");
        (real || name == "synthetic, 20 %").then_some(Taking {
            pairs: usize::MAX,
            unchanged: real,
        })
    };
    each_pair_taken_side_by_side(
        [&every_point, &now],
        (&[81], 150),
        taking,
        |set, c, answers| {
            if set.name == "synthetic, 20 %" {
                for (k, answer) in answers.iter().enumerate() {
                    errors_mm[k].push(errors(&c.truth, &answer.pose).1);
                }
            }
        },
    );
    let [before, after] = errors_mm.map(|mut e| {
        assert_eq!(e.len(), 150);
        e.sort_by(f64::total_cmp);
        e[e.len() / 2]
    });
    assert!(
        (after - before).abs() < 0.1,
        "median error {before:.2} -> {after:.2} mm"
    );
}

/// Per row, for each of two matchers: the summed errors (mm) of the pairs both get right, their
/// right answers, and their trusted wrong ones.
type Side = ([f64; 2], [usize; 2], [usize; 2]);

/// The polish both ways ([`BOTH_WAYS`]) on a scan that does not look clean: over held-out seed
/// 83 (150 pairs a row), on the pairs both answer right the twin's pairs with 20 % outliers lie
/// nearer the truth on average, at 1° by a twelfth at least, with as many of them right and
/// no more trusted and wrong (a pair either way allowed); Edmonton's 1° scans, some of which do
/// not look clean, right as often; the other real logs' scans all look clean, with the same
/// answers to the last bit. Without the slide check, as above. Checked on the first 150 pairs
/// of each of seeds 1–80 (`twin matchers` with and without it, the slide check on): the mean
/// error's ratio was 0.87–0.98 at 0.5° and 0.73–0.89 at 1°, right answers at most one fewer and
/// trusted wrong ones at most one more on every seed. (The ratio of the median errors on 150
/// pairs is no claim about the rows: it ranged 0.83–1.05.)
#[test]
fn scans_with_outliers_are_polished_both_ways() {
    use robot::localization::{BOTH_WAYS, Lorentz};
    use sim::commands::montecarlo::errors;
    let now = Lorentz {
        slide_check: None,
        ..Lorentz::with_lines()
    };
    assert_eq!(now.both_ways, Some(BOTH_WAYS));
    let left_as_is = Lorentz {
        both_ways: None,
        ..now.clone()
    };
    let taking = |name: &str| {
        let real = name.starts_with("real");
        let clean = name.contains("belgioioso") || name.contains("freiburg");
        (real || name.ends_with("20 %")).then_some(Taking {
            pairs: usize::MAX,
            unchanged: clean,
        })
    };
    let mut rows: BTreeMap<String, Side> = BTreeMap::new();
    each_pair_taken_side_by_side(
        [&left_as_is, &now],
        (&[83], 150),
        taking,
        |set, c, answers| {
            let (errors_mm, right, trusted_wrong) = rows.entry(set.name.clone()).or_default();
            let is = answers.map(|answer| is_right(set, c, answer));
            for (k, answer) in answers.iter().enumerate() {
                if is == [true, true] {
                    errors_mm[k] += errors(&c.truth, &answer.pose).1;
                }
                right[k] += usize::from(is[k]);
                trusted_wrong[k] += usize::from(answer.converged && !is[k]);
            }
        },
    );
    assert_eq!(
        rows.len(),
        6,
        "the two synthetic rows with outliers and four real ones"
    );
    for (name, ([before, after], right, trusted_wrong)) in rows {
        println!(
            "{name}: errors summed over the pairs right both ways {before:.1} -> {after:.1} mm, right {right:?}, trusted and wrong {trusted_wrong:?}"
        );
        assert!(right[1] + 1 >= right[0], "{name}: right {right:?}");
        assert!(
            trusted_wrong[1] <= trusted_wrong[0] + 1,
            "{name}: trusted and wrong {trusted_wrong:?}"
        );
        let most = match name.as_str() {
            "synthetic, 20 %" => 1.0,
            "synthetic 1°, 20 %" => 11.0 / 12.0,
            _ => continue,
        };
        assert!(
            after < most * before,
            "{name}: errors summed over the pairs right both ways {before:.1} -> {after:.1} mm"
        );
    }
}

/// [`rows_side_by_side`] of a line-assisted Lorentzian without a step (`before`) and with it
/// (`now`): every row right as often (a pair either way allowed) in no more searches, the
/// synthetic pairs without outliers in at most `fraction` of them.
fn as_right_in_fewer_searches(
    [before, now]: [&robot::localization::Lorentz; 2],
    seeds: [u64; 2],
    (num, den): (u32, u32),
) -> BTreeMap<String, ([usize; 2], [u32; 2])> {
    let rows = rows_side_by_side([before, now], seeds);
    for (name, (right, [a, b])) in &rows {
        assert!(right[1] + 1 >= right[0], "{name}: right {right:?}");
        assert!(b <= a, "{name}: {a} -> {b} searches");
        if name.starts_with("synthetic, 0") {
            assert!(den * b <= num * a, "{name}: {a} -> {b} searches");
        }
    }
    rows
}

/// A σ pass whose searches alternate between two sets of pairs, the estimate between two poses,
/// never settles: it ran to its cap of 30 searches and stopped on one of the two. With
/// `stop_on_cycles` it stops as soon as a search brings the estimate back to where it was two
/// searches before. Over one held-out seed (25, 150 pairs a row): every row right as often (a
/// pair either way allowed), each taking no more searches and the rows together fewer, and
/// nearly every answer within a millimetre and a hundredth of a degree of the one the uncapped
/// cycle gave. (The synthetic pairs without outliers stopped cycling on this seed once a dense
/// first pass stopped at `FIRST_PASS_CONVERGENCE`: their searches are the same both ways.)
#[test]
fn a_pass_that_alternates_stops() {
    use robot::localization::Lorentz;
    let now = Lorentz::with_lines();
    assert!(now.stop_on_cycles);
    let to_the_cap = Lorentz {
        stop_on_cycles: false,
        ..Lorentz::with_lines()
    };
    let mut all = [0, 0];
    for set in sets(150, 25) {
        let (mut right, mut searches, mut near) = ([0, 0], [0, 0], 0);
        for c in &set.cases {
            let [a, b] =
                [&to_the_cap, &now].map(|m| m.match_scans(&c.reference, &c.current, c.guess));
            for (k, r) in [&a, &b].iter().enumerate() {
                right[k] += usize::from(is_right(&set, c, r));
                searches[k] += r.iterations;
            }
            let apart = a.pose.relative(&b.pose);
            near += usize::from(
                apart.x.hypot(apart.y) < 1e-3 && apart.theta.abs() < 1e-2f64.to_radians(),
            );
        }
        let name = &set.name;
        println!("{name}: right {right:?}, searches {searches:?}, near {near}");
        assert!(right[1] + 1 >= right[0], "{name}: right {right:?}");
        assert!(searches[1] <= searches[0], "{name}: searches {searches:?}");
        assert!(
            100 * near >= 98 * set.cases.len(),
            "{name}: {near} answers near"
        );
        for k in 0..2 {
            all[k] += searches[k];
        }
    }
    assert!(all[1] < all[0], "searches in all {all:?}");
}

/// In the first σ pass of a dense scan, a pair that no reference line holds (a corner, a short
/// face, a point past a line's end) is held to the reference's surface at its nearest point when
/// that surface is straight over all seven points it was fitted to
/// (`FIRST_PASS_SURFACE_POINTS`), instead of pulling point to point toward that point. Over two
/// held-out seeds (26 and 27, 150 pairs a row): every row right as often (a pair either way
/// allowed), the synthetic pairs without outliers in a quarter fewer searches or better (12 → 7
/// a pair over seeds 1–20), none of the dense rows in more; Edmonton's 1° scans are not dense,
/// with the same answers to the last bit.
#[test]
fn first_passes_hold_lone_pairs_to_straight_surfaces() {
    use robot::localization::{FIRST_PASS_SURFACE_POINTS, Lorentz};
    let now = Lorentz::with_lines();
    assert_eq!(now.first_pass_surfaces, Some(FIRST_PASS_SURFACE_POINTS));
    let nearest_points = Lorentz {
        first_pass_surfaces: None,
        ..Lorentz::with_lines()
    };
    as_right_in_fewer_searches([&nearest_points, &now], [26, 27], (3, 4));
}

/// Where the σ passes of a dense scan end a degree or two off in heading, the point-to-line
/// polish, whose Cauchy weights make little of the farther points that would say so, creeps
/// toward the minimum a tenth of a degree a round; with `polish_more` it goes on while its
/// last round still turns the estimate by more than 0.02° (`POLISH_MORE`). Over four held-out
/// seeds (32 to 35, 150 pairs a row): every row right as often (a pair either way allowed),
/// the synthetic pairs with 20 % outliers nearer the truth in heading in all (on 18 of seeds
/// 1–20, 300 pairs a seed; the gain sits in the few pairs whose polish creeps, so a single
/// seed of 150 pairs can miss it: seed 36 summed 0.01° more); Edmonton's 1° scans are not
/// dense, with the same answers to the last bit.
#[test]
fn a_polish_that_still_turns_goes_on() {
    use robot::localization::{Lorentz, POLISH_MORE};
    let now = Lorentz::with_lines();
    assert_eq!(now.polish_more, Some(POLISH_MORE));
    let five_rounds = Lorentz {
        polish_more: None,
        ..Lorentz::with_lines()
    };
    let mut rows: BTreeMap<String, ([usize; 2], [f64; 2], usize)> = BTreeMap::new();
    each_pair_side_by_side([&five_rounds, &now], &[32, 33, 34, 35], |set, c, [a, b]| {
        let (right, heading, changed) = rows.entry(set.name.clone()).or_default();
        *changed += usize::from(a.pose != b.pose);
        for (k, r) in [a, b].into_iter().enumerate() {
            right[k] += usize::from(is_right(set, c, r));
            heading[k] += c.truth.relative(&r.pose).theta.abs().to_degrees();
        }
    });
    assert_eq!(rows.len(), 6, "every row of the table but the 1° ones");
    for (name, (right, heading, changed)) in &rows {
        println!("{name}: right {right:?}, heading errors summed {heading:?}°, {changed} changed");
        assert!(right[1] + 1 >= right[0], "{name}: right {right:?}");
    }
    let (_, heading, changed) = &rows["synthetic, 20 %"];
    assert!(*changed > 0, "some polish went on");
    assert!(
        heading[1] < heading[0],
        "heading errors summed {heading:?}°"
    );
}

/// The first σ pass of a dense scan stops at a step of 0.9 mm and 0.009°
/// ([`FIRST_PASS_CONVERGENCE`](robot::localization::FIRST_PASS_CONVERGENCE)), nine times the
/// other early passes' test: the polish or the narrower passes take the answer on from there.
/// Over two held-out seeds (38–39, 150 pairs a row): every row right as often (a pair either
/// way allowed), each dense row in fewer searches in all, the synthetic answers' translation
/// errors summed within 1 % of before; Edmonton's 1° scans are not dense, with the same
/// answers to the last bit.
#[test]
fn a_dense_first_pass_stops_sooner() {
    use robot::localization::{FIRST_PASS_CONVERGENCE, Lorentz};
    let now = Lorentz::with_lines();
    assert_eq!(now.first_pass_convergence, Some(FIRST_PASS_CONVERGENCE));
    // Both with the old test in the first match too (`a_first_match_stops_sooner`, below).
    let now = Lorentz {
        first_match_convergence: None,
        ..now
    };
    let before = Lorentz {
        first_pass_convergence: None,
        ..now.clone()
    };
    let rows = dense_rows_side_by_side([&before, &now], &[38, 39]);
    for (name, (right, searches, errors)) in &rows {
        let errors = errors.each_ref().map(|e| e.iter().sum::<f64>());
        println!("{name}: right {right:?}, searches {searches:?}, errors summed {errors:?} m");
        if name.starts_with("synthetic") {
            assert!(errors[1] < 1.01 * errors[0], "{name}: errors {errors:?}");
        }
    }
}

/// Two matchers' right answers, searches in all and translation errors (metres), one row's.
type RowTotals = ([usize; 2], [u32; 2], [Vec<f64>; 2]);

/// Per row but the 1° ones, two matchers' right answers, searches in all and translation
/// errors (metres) side by side over `seeds` ([`each_pair_side_by_side`]), with what every
/// cheaper dense schedule must show asserted: every row right as often (a pair either way
/// allowed) and each dense row in fewer searches.
fn dense_rows_side_by_side(
    matchers: [&robot::localization::Lorentz; 2],
    seeds: &[u64],
) -> BTreeMap<String, RowTotals> {
    let (rows, _) = rows_right_as_often(matchers, seeds);
    for (name, (_, searches, _)) in &rows {
        if !name.contains("edmonton") {
            assert!(searches[1] < searches[0], "{name}: searches {searches:?}");
        }
    }
    rows
}

/// Two matchers' totals on every row but the 1° ones ([`each_pair_side_by_side`]), each row
/// right as often (a pair either way allowed), and how many answers differ on each row.
fn rows_right_as_often(
    matchers: [&robot::localization::Lorentz; 2],
    seeds: &[u64],
) -> (BTreeMap<String, RowTotals>, BTreeMap<String, usize>) {
    let mut rows: BTreeMap<String, RowTotals> = BTreeMap::new();
    let mut moved = BTreeMap::new();
    each_pair_side_by_side(matchers, seeds, |set, c, [a, b]| {
        let (right, searches, errors) = rows.entry(set.name.clone()).or_default();
        *moved.entry(set.name.clone()).or_default() += usize::from(a.pose != b.pose);
        for (k, r) in [a, b].into_iter().enumerate() {
            right[k] += usize::from(is_right(set, c, r));
            searches[k] += r.iterations;
            let off = c.truth.relative(&r.pose);
            errors[k].push(off.x.hypot(off.y));
        }
    });
    assert_eq!(rows.len(), 6, "every row of the table but the 1° ones");
    for (name, (right, _, _)) in &rows {
        assert!(right[1] + 1 >= right[0], "{name}: right {right:?}");
    }
    (rows, moved)
}

/// Each row's median translation errors, the two matchers'; on the synthetic rows within a
/// twentieth of a millimetre of each other, and the second's under the issue's 2 mm without
/// outliers.
fn medians_hold(rows: &mut BTreeMap<String, RowTotals>) {
    for (name, (right, searches, errors)) in rows {
        let medians = errors.each_mut().map(|e| {
            e.sort_by(f64::total_cmp);
            e[e.len() / 2]
        });
        println!("{name}: right {right:?}, searches {searches:?}, median errors {medians:?} m");
        if name.starts_with("synthetic") {
            assert!(
                (medians[1] - medians[0]).abs() < 5e-5,
                "{name}: median errors {medians:?}"
            );
        }
        if name == "synthetic, 0 %" {
            assert!(medians[1] <= 0.002, "{name}: median error {} m", medians[1]);
        }
    }
}

/// The first σ pass of a dense scan's first match from the guess stops at a step of 0.9 mm
/// and 0.009° ([`FIRST_MATCH_CONVERGENCE`](robot::localization::FIRST_MATCH_CONVERGENCE)),
/// three times [`FIRST_PASS_CONVERGENCE`](robot::localization::FIRST_PASS_CONVERGENCE), which
/// the restarts keep. Over two seeds outside those it was chosen and checked on (97–98, 150
/// pairs a row): every row right as often (a pair either way allowed), each dense row in fewer
/// searches in all, the synthetic rows' median translation errors within a twentieth of a
/// millimetre of before and under the issue's 2 mm without outliers; Edmonton's 1° scans are
/// not dense, with the same answers to the last bit.
#[test]
fn a_first_match_stops_sooner() {
    use robot::localization::{FIRST_MATCH_CONVERGENCE, Lorentz};
    let now = Lorentz::with_lines();
    assert_eq!(now.first_match_convergence, Some(FIRST_MATCH_CONVERGENCE));
    let before = Lorentz {
        first_match_convergence: None,
        ..Lorentz::with_lines()
    };
    let mut rows = dense_rows_side_by_side([&before, &now], &[97, 98]);
    medians_hold(&mut rows);
}

/// The first searches of a dense scan's first σ pass pair every second current point
/// ([`FIRST_PASS_THINNING`](robot::localization::FIRST_PASS_THINNING): two searches at most,
/// fewer once one moves the estimate by under 1 mm and 0.001 rad), and a search of every
/// point follows before the pass may end; only on scans that look clean, so those with 20 %
/// outliers are matched as before, to the last bit. Over two seeds outside those it was chosen
/// on (104–105, 150 pairs a row): every row right as often (a pair either way allowed), in as
/// many searches within 6 % (half of them cost half), the synthetic rows' median translation
/// errors within a twentieth of a millimetre of before and under the issue's 2 mm without
/// outliers; some answers moved on the rows without outliers; Edmonton's 1° scans are not
/// dense, with the same answers to the last bit. What it saves is time, which `cargo bench
/// --bench matcher_race` measures. Both without `LONELY_PASS_ENOUGH` and `BOTH_WAYS`, which
/// tell a scan that does not look clean by the thinning's test (without the thinning,
/// `BOTH_WAYS` polishes every dense scan both ways) and so move the answers.
#[test]
fn a_dense_first_pass_starts_on_every_second_point() {
    use robot::localization::{FIRST_PASS_THINNING, Lorentz};
    let now = Lorentz {
        lonely_pass_enough: None,
        both_ways: None,
        ..Lorentz::with_lines()
    };
    assert_eq!(now.first_pass_thinning, Some(FIRST_PASS_THINNING));
    let every_point = Lorentz {
        first_pass_thinning: None,
        ..now.clone()
    };
    let (mut rows, moved) = rows_right_as_often([&every_point, &now], &[104, 105]);
    println!("answers moved: {moved:?}");
    assert!(
        moved["synthetic, 0 %"] > 0,
        "thinned searches moved no answer"
    );
    assert_eq!(
        moved["synthetic, 20 %"], 0,
        "a scan with outliers was thinned"
    );
    // Since a sparse scan's trusted answers no longer run the wide schedule
    // (`sparse_loose_wide`), the large guesses' Edmonton third, the same for both, dilutes the
    // dense pairs' count less: 1.051 there on these seeds, 1.05 being the bound before.
    for (name, (_, searches, _)) in &rows {
        assert!(
            f64::from(searches[1]) <= 1.06 * f64::from(searches[0]),
            "{name}: searches {searches:?}"
        );
    }
    medians_hold(&mut rows);
}

/// The MIT log has no ground truth, but now and then its odometry lags a scan: the robot drives a
/// steady 0.2–0.26 m a scan down a corridor and one pair's odometry says 8–13 cm less. Every such
/// pair of the log (the odometry of its eight neighbours within 3 cm of their median, its own
/// more than 8 cm from it) is answered with the steady motion, and trusted: a corridor leaves the
/// answer free along it only as far as its doors and ends allow, and `lorentz-lines` follows the
/// scans there rather than the guess.
#[test]
fn an_odometry_glitch_does_not_hold_the_answer() {
    let log =
        robot::logs::read_log(&repo().join("tests/data/mit-csail.clf")).expect("the MIT log reads");
    // Each scan with the pose its FLASER line states, in this log the odometry.
    let scans = log.scans_with_logged_pose();
    assert_eq!(scans.len(), log.scans(), "odometry before every scan");
    let guesses: Vec<Pose2> = scans.windows(2).map(|w| w[0].1.relative(&w[1].1)).collect();
    let matcher = MatcherKind::LorentzLines.build();
    let mut glitches = 0;
    for k in 4..guesses.len() - 4 {
        let mut around: Vec<f64> = (k - 4..=k + 4)
            .filter(|&j| j != k)
            .map(|j| guesses[j].x)
            .collect();
        around.sort_by(f64::total_cmp);
        let steady = 0.5 * (around[3] + around[4]);
        let calm = around.iter().all(|x| (x - steady).abs() < 0.03);
        if !calm || (guesses[k].x - steady).abs() <= 0.08 {
            continue;
        }
        glitches += 1;
        let reference = Reference::new(scans[k].0.points());
        let result = matcher.align(&reference, &scans[k + 1].0.points(), guesses[k]);
        println!(
            "pair {k}: odometry {:.3} m, its neighbours {steady:.3} m, answer {:.3} m",
            guesses[k].x, result.pose.x
        );
        assert!(result.converged, "pair {k}: not trusted: {result:?}");
        assert!(
            (result.pose.x - steady).abs() < 0.03,
            "pair {k}: the answer {:.3} m stays near the odometry {:.3} m, not the steady {steady:.3} m",
            result.pose.x,
            guesses[k].x
        );
    }
    assert!(
        glitches >= 5,
        "the log's odometry glitches {glitches} times"
    );
}

/// On sparse 1° scans the line-assisted Lorentzian finishes its answer with point-to-line ICP
/// (`SPARSE_FINISH`), and its answers depend less on the guess. Over seeds held out from the
/// twenty it was chosen on (21–24: Edmonton's 300 pairs, each seed with guesses of its own),
/// fewer pairs have an answer more than a centimetre from the median of their four, and no
/// fewer are right; the dense scans do not run it, with the same answers to the last bit.
/// The finish stops when its pairings come round in a cycle (`stop_on_cycles`): the same right
/// answers for under half the finish's iterations (without, a quarter of the finishes ran to
/// the cap of 100), counted against a finish of no iterations (a matcher without the finish
/// also runs its passes otherwise: `sparse_early_convergence`, `before_last_margin`). Without
/// the finish the matcher is the thesis's on these scans: its three passes from the guess
/// (σ 2, 5 and 0.5 cm), where `SPARSE_SIGMAS` leaves the last to the finish and the first to
/// a point-to-line round (`SPARSE_START`; with that round and the thesis's passes, no finish,
/// 56 unsteady pairs against the finished matcher's 60 when the round came in: the narrow
/// pass, stopped at the tight test, steadies the answer as well).
#[test]
fn a_point_to_line_finish_steadies_sparse_answers() {
    use robot::localization::{Convergence, Lorentz, PointToLine, SPARSE_FINISH};
    // Without the slide check, a later step whose second match (finished too) would count
    // among the finish's iterations.
    let base = Lorentz {
        sparse_slide_check: None,
        ..Lorentz::with_lines()
    };
    let without = Lorentz {
        sparse_finish: None,
        sparse_start: None,
        sigmas_m: thesis_sigmas(),
        ..base.clone()
    };
    let with = base.clone();
    assert_eq!(with.sparse_finish, Some(SPARSE_FINISH));
    let cycling = Lorentz {
        sparse_finish: Some(PointToLine {
            stop_on_cycles: None,
            ..SPARSE_FINISH
        }),
        ..base.clone()
    };
    // A finish of no iterations: the σ passes of `with` (which, followed by a finish, differ
    // from `without`'s), whose iterations the others' less are their finishes'.
    let idle = Lorentz {
        sparse_finish: Some(PointToLine {
            convergence: Convergence {
                max_iterations: 0,
                ..SPARSE_FINISH.convergence
            },
            ..SPARSE_FINISH
        }),
        ..base
    };
    let matchers = [&without, &with, &cycling, &idle];
    // Each Edmonton pair's answers from every seed, without and with.
    let mut answers: BTreeMap<usize, [Vec<Pose2>; 2]> = BTreeMap::new();
    let mut right = [0usize; 3];
    // The finish's iterations, summed: with and without stopping on cycles.
    let mut finishing = [0u64; 2];
    for seed in [21, 22, 23, 24] {
        for set in sets(300, seed) {
            if set.name.contains("edmonton") {
                for (k, c) in set.cases.iter().enumerate() {
                    let results =
                        matchers.map(|m| m.match_scans(&c.reference, &c.current, c.guess));
                    for (m, r) in results.iter().take(3).enumerate() {
                        right[m] += usize::from(is_right(&set, c, r));
                    }
                    let [unfinished, finished, cycled, passes] = &results;
                    let entry = answers.entry(k).or_default();
                    entry[0].push(unfinished.pose);
                    entry[1].push(finished.pose);
                    let [a, b] = [finished, cycled].map(|r| {
                        let more = r.iterations.checked_sub(passes.iterations);
                        u64::from(more.expect("a finish adds iterations to the passes'"))
                    });
                    finishing[0] += a;
                    finishing[1] += b;
                }
            } else if seed == 21 && !set.name.starts_with("real, guess") && !set.name.contains("1°")
            {
                for c in set.cases.iter().take(50) {
                    let [a, b] =
                        [&without, &with].map(|m| m.match_scans(&c.reference, &c.current, c.guess));
                    assert_eq!(a, b, "{}: dense scans are not finished", set.name);
                }
            }
        }
    }
    assert_eq!(answers.len(), 300, "Edmonton's pairs");
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        0.5 * (v[(v.len() - 1) / 2] + v[v.len() / 2])
    };
    let mut unsteady = [0usize; 2];
    for poses in answers.values() {
        for (m, poses) in poses.iter().enumerate() {
            let mx = median(&mut poses.iter().map(|p| p.x).collect());
            let my = median(&mut poses.iter().map(|p| p.y).collect());
            let far = poses.iter().any(|p| (p.x - mx).hypot(p.y - my) > 0.01);
            unsteady[m] += usize::from(far);
        }
    }
    println!(
        "unsteady pairs {unsteady:?}, right answers {right:?} (without, with the finish, \
         without its cycle stop), the finish's iterations {finishing:?}"
    );
    assert!(
        unsteady[1] < unsteady[0],
        "answers over a centimetre from their median: {} finished against {}",
        unsteady[1],
        unsteady[0]
    );
    assert!(right[1] >= right[0], "right answers: {right:?}");
    assert_eq!(right[1], right[2], "the cycle stop changed right answers");
    assert!(
        2 * finishing[0] < finishing[1],
        "the finish's iterations: {finishing:?}"
    );
}

/// On sparse scans the line-assisted Lorentzian leaves out the thesis's last σ pass, at 5 mm
/// (`SPARSE_SIGMAS`): the point-to-line finish places the answer where that pass did (its
/// first pass, at 2 cm, gave way to a point-to-line round since, `SPARSE_START`; both
/// matchers here start with it). On seeds held out from the twenty it was measured on (33 and
/// 34: Edmonton's pairs, the twin's 1° pairs with and without outliers, 150 each): at least a
/// twentieth fewer correspondence searches, at most one right answer fewer on any row; the
/// dense scans do not change.
#[test]
fn sparse_scans_leave_the_narrow_pass_to_the_finish() {
    use robot::localization::{Lorentz, SPARSE_SIGMAS};
    let two = Lorentz::with_lines();
    assert_eq!(two.sigmas_m, SPARSE_SIGMAS.to_vec());
    let three = Lorentz {
        sigmas_m: thesis_sigmas(),
        ..Lorentz::with_lines()
    };
    let rows = sparse_rows_side_by_side([&three, &two], [33, 34]);
    assert_fewer_searches(&rows, 1, (20, 19));
}

/// A sparse match starts with one round of point-to-line ICP from the guess
/// (`SPARSE_START`), and its σ passes at 5 cm (`SPARSE_SIGMAS`): the thesis's 2 cm pass, which
/// crept along the walls a search at a time from a guess centimetres off, is gone. On seeds
/// held out from those it was chosen and checked on (35 and 36, 150 pairs a row): fewer
/// correspondence searches on every sparse row, at least a fifth fewer on the twin's 1° pairs
/// without outliers, at most one right answer fewer on any row; the dense scans do not change.
#[test]
fn sparse_matches_start_with_a_point_to_line_round() {
    use robot::localization::{Lorentz, SPARSE_SIGMAS, SPARSE_START};
    let started = Lorentz::with_lines();
    assert_eq!(started.sparse_start, Some(SPARSE_START));
    assert_eq!(started.sigmas_m, SPARSE_SIGMAS.to_vec());
    let crept = Lorentz {
        sparse_start: None,
        sigmas_m: vec![0.02, 0.05],
        ..Lorentz::with_lines()
    };
    let rows = sparse_rows_side_by_side([&crept, &started], [35, 36]);
    assert_fewer_searches(&rows, 1, (5, 4));
}

/// A start round that carries the estimate beyond its reach (`StartRounds::reach_m`, here 0)
/// leaves the match at the guess: the same answers to the last bit as a matcher without the
/// round, one search more each (the round's searches warmed the nearest-point cache, which
/// answers exactly as the tree does); on dense scans the round never runs.
#[test]
fn a_start_round_out_of_reach_leaves_the_guess() {
    use robot::localization::{Lorentz, SPARSE_START, StartRounds};
    // Without the quick finish, whose answers do not depend on the start.
    let unreachable = Lorentz {
        sparse_start: Some(StartRounds {
            reach_m: 0.0,
            ..SPARSE_START
        }),
        sparse_quick: None,
        ..Lorentz::with_lines()
    };
    let without = Lorentz {
        sparse_start: None,
        sparse_quick: None,
        ..Lorentz::with_lines()
    };
    let mut sparse = 0;
    for set in sets(150, 37) {
        let is_sparse = sparse_row(&set.name);
        // The large guesses' row draws from several logs, sparse and dense.
        if !is_sparse && !dense_row(&set.name) {
            continue;
        }
        for c in set.cases.iter().take(25) {
            let [a, b] =
                [&without, &unreachable].map(|m| m.match_scans(&c.reference, &c.current, c.guess));
            assert_eq!(a.pose, b.pose, "{}: the same answer", set.name);
            assert_eq!(a.quality, b.quality, "{}: the same quality", set.name);
            let more = u32::from(is_sparse);
            assert_eq!(b.iterations, a.iterations + more, "{}: searches", set.name);
            sparse += usize::from(is_sparse);
        }
    }
    assert_eq!(sparse, 75, "Edmonton's and the two 1° rows' pairs");
}

/// A sparse match that point-to-line ICP alone settles ends there (`SPARSE_QUICK`): its answer
/// fits 85 % of the points and is pinned to 2.5 mm along its weakest direction and 0.1° in
/// heading, and is checked for a slide; otherwise the match goes on from that ICP's first
/// round, as if it had not run. On seeds held out from the seventy it was chosen and checked
/// on (95 and 96, 150 pairs a row): every sparse row right on at least as many pairs; most of the
/// twin's 1° pairs without outliers end early, in a tenth fewer searches over the row (and
/// without the σ passes' minimisations, the polish and the lines: a third of the time); a
/// pair turned away gets the whole match's answer to the bit (Edmonton's, whose fits are
/// looser, nearly all); the dense scans never run it.
#[test]
fn a_sparse_pair_that_icp_settles_ends_early() {
    use robot::localization::{Lorentz, SPARSE_QUICK};
    let quick = Lorentz::with_lines();
    assert_eq!(quick.sparse_quick, Some(SPARSE_QUICK));
    let whole = Lorentz {
        sparse_quick: None,
        ..Lorentz::with_lines()
    };
    let mut rows: BTreeMap<String, ([usize; 2], [u64; 2], usize, usize)> = BTreeMap::new();
    for seed in [95, 96] {
        for set in sets(150, seed) {
            let sparse = sparse_row(&set.name);
            if !sparse && !dense_row(&set.name) {
                continue;
            }
            for c in set.cases.iter().take(if sparse { 150 } else { 15 }) {
                let [a, b] =
                    [&whole, &quick].map(|m| m.match_scans(&c.reference, &c.current, c.guess));
                if !sparse {
                    assert_eq!(a, b, "{}: dense scans as before", set.name);
                    continue;
                }
                let (right, searches, ended, same) = rows.entry(set.name.clone()).or_default();
                right[0] += usize::from(is_right(&set, c, &a));
                right[1] += usize::from(is_right(&set, c, &b));
                searches[0] += u64::from(a.iterations);
                searches[1] += u64::from(b.iterations);
                *ended += usize::from(b.iterations < a.iterations);
                *same += usize::from(a.pose == b.pose && a.quality == b.quality);
            }
        }
    }
    assert_eq!(rows.len(), 3, "Edmonton and the two 1° rows: {rows:?}");
    for (name, (right, searches, ended, same)) in &rows {
        println!(
            "{name}: right {right:?}, searches {searches:?}, ended early {ended}, same {same}"
        );
        assert!(right[1] >= right[0], "{name}: right {right:?}");
        if name.contains("1°, 0") {
            assert!(*ended >= 150, "{name}: {ended} of 300 ended early");
            assert!(20 * searches[1] <= 19 * searches[0], "{name}: {searches:?}");
        }
        if name.contains("edmonton") {
            assert!(*same >= 290, "{name}: {same} of 300 the same");
        }
    }
}

/// The thesis's σ schedule, 2 → 5 → 0.5 cm, in metres: what a matcher without the sparse
/// finish runs on sparse scans (`SPARSE_SIGMAS` leaves the last pass to the finish).
fn thesis_sigmas() -> Vec<f64> {
    robot::localization::THESIS_SIGMAS
        .iter()
        .map(|s| s * 0.01)
        .collect()
}

/// Two sparse-scan matchers side by side on `seeds` (150 pairs a row), each without its quick
/// finish (`SPARSE_QUICK`): for Edmonton and the
/// twin's two 1° rows, each matcher's right answers and correspondence searches; on the dense
/// rows (the synthetic ones at 0.5°, Belgioioso; their first 20 pairs) the two must give the
/// same answers, as they differ only in what sparse scans do.
fn sparse_rows_side_by_side(
    matchers: [&robot::localization::Lorentz; 2],
    seeds: [u64; 2],
) -> BTreeMap<String, ([usize; 2], [u64; 2])> {
    // The whole match, which the features compared here are part of: without the quick
    // finish, which would end most of the 1° pairs before them alike.
    let whole = matchers.map(|m| robot::localization::Lorentz {
        sparse_quick: None,
        ..m.clone()
    });
    let matchers = [&whole[0], &whole[1]];
    let mut rows: BTreeMap<String, ([usize; 2], [u64; 2])> = BTreeMap::new();
    for seed in seeds {
        for set in sets(150, seed) {
            let sparse = sparse_row(&set.name);
            let dense = dense_row(&set.name);
            for c in set.cases.iter().take(if sparse { 150 } else { 20 }) {
                let answers = matchers.map(|m| m.match_scans(&c.reference, &c.current, c.guess));
                if dense {
                    assert_eq!(
                        answers[0], answers[1],
                        "{}: dense scans as before",
                        set.name
                    );
                } else if sparse {
                    let (right, searches) = rows.entry(set.name.clone()).or_default();
                    for (m, r) in answers.iter().enumerate() {
                        right[m] += usize::from(is_right(&set, c, r));
                        searches[m] += u64::from(r.iterations);
                    }
                }
            }
        }
    }
    assert_eq!(rows.len(), 3, "Edmonton and the two 1° rows: {rows:?}");
    rows
}

/// On sparse scans too, a search whose line normals spread (a tenth,
/// `SPARSE_LINE_RESIDUALS_SPREAD`; a fifth when this test was written) counts a point projected
/// inside a reference line by its distance to that line alone: the first σ pass no longer crawls
/// along the walls a search at a time. On seeds held out from the twenty it was chosen on (33 and
/// 34, 150 pairs a row): the twin's 1° pairs without outliers take at least a third fewer
/// correspondence searches, Edmonton's fewer; no sparse row is right on more than two fewer pairs;
/// the dense scans do not change.
#[test]
fn sparse_scans_slide_along_their_lines_too() {
    use robot::localization::{Lorentz, SPARSE_LINE_RESIDUALS_SPREAD};
    let to_lines = Lorentz::with_lines();
    assert_eq!(
        to_lines.sparse_line_residuals_spread,
        Some(SPARSE_LINE_RESIDUALS_SPREAD)
    );
    let product = Lorentz {
        sparse_line_residuals_spread: None,
        ..Lorentz::with_lines()
    };
    let rows = sparse_rows_side_by_side([&product, &to_lines], [33, 34]);
    assert_fewer_searches(&rows, 2, (3, 2));
}

/// Since the finish took the place of the 5 mm pass (`SPARSE_SIGMAS`), sparse scans count
/// distances to lines where their normals spread by a tenth (`SPARSE_LINE_RESIDUALS_SPREAD`),
/// not a fifth: on seeds held out from those it was chosen on (39 and 40, 150 pairs a row),
/// fewer correspondence searches on every sparse row and a twentieth fewer on the twin's 1°
/// pairs without outliers, at most one right answer fewer on any; the dense scans do not
/// change.
#[test]
fn sparse_scans_take_lines_from_a_tenth_of_the_spread() {
    use robot::localization::{Lorentz, SPARSE_LINE_RESIDUALS_SPREAD};
    let tenth = Lorentz::with_lines();
    assert_eq!(tenth.sparse_line_residuals_spread, Some(0.1));
    assert_eq!(SPARSE_LINE_RESIDUALS_SPREAD, 0.1);
    let fifth = Lorentz {
        sparse_line_residuals_spread: Some(0.2),
        ..Lorentz::with_lines()
    };
    let rows = sparse_rows_side_by_side([&fifth, &tenth], [39, 40]);
    assert_fewer_searches(&rows, 1, (20, 19));
}

/// Of `sparse_rows_side_by_side`'s rows, the second matcher's: right on at most `slack` pairs
/// fewer than the first's on each row, fewer searches on each, and on the twin's 1° pairs
/// without outliers at most `den / num` of the first's searches.
fn assert_fewer_searches(
    rows: &BTreeMap<String, ([usize; 2], [u64; 2])>,
    slack: usize,
    (num, den): (u64, u64),
) {
    for (name, (right, searches)) in rows {
        println!("{name}: right {right:?}, searches {searches:?}");
        assert!(right[1] + slack >= right[0], "{name}: right {right:?}");
        assert!(searches[1] < searches[0], "{name}: searches {searches:?}");
        if name.contains("1°, 0") {
            assert!(
                num * searches[1] <= den * searches[0],
                "{name}: {searches:?}"
            );
        }
    }
}

/// Whether the row named `name` holds sparse scans only (beams 1° apart: the twin's 1° rows
/// and Edmonton's).
fn sparse_row(name: &str) -> bool {
    name.contains("1°") || name.contains("edmonton")
}

/// Whether the row named `name` holds dense scans only (beams 0.5° apart: the twin's standard
/// rows and Belgioioso's; Freiburg 101's too, left out where a test names only these).
fn dense_row(name: &str) -> bool {
    name.starts_with("synthetic,") || name.contains("belgioioso")
}

/// Every pair (300) of the rows `rows` picks by name, for [`side_by_side_held_out`], their
/// answers free to change.
fn every_pair_of(rows: impl Fn(&str) -> bool) -> impl Fn(&str) -> Option<Taking> {
    move |name| {
        rows(name).then_some(Taking {
            pairs: 300,
            unchanged: false,
        })
    }
}

/// `old` and `new` side by side on `seeds` (held out from those the slide check was chosen on,
/// 300 pairs a row), on the rows `taking` picks by name: no right answer of `old` lost, the
/// answers the same on the rows marked `unchanged`. The right answers of both.
fn side_by_side_held_out(
    [old, new]: [&robot::localization::Lorentz; 2],
    seeds: &[u64],
    taking: impl Fn(&str) -> Option<Taking>,
) -> (usize, usize) {
    let (mut before, mut after) = (0, 0);
    each_pair_taken_side_by_side([old, new], (seeds, 300), taking, |set, c, [a, b]| {
        let (was, is) = (is_right(set, c, a), is_right(set, c, b));
        assert!(!was || is, "{}: a right answer lost", set.name);
        before += usize::from(was);
        after += usize::from(is);
    });
    (before, after)
}

/// The slide check asks only two points across the wall to agree on a shift
/// (`SLIDE_CHECK.min_gain`), since the trust rule's judgement at that shift and the margin
/// weigh it before an answer changes: against the same check asking five, on the dense rows
/// of two seeds held out from those the setting was chosen on (24 and 25, 300 pairs a row,
/// the twin's and Belgioioso's), every right answer stays right and at least two more are
/// (Belgioioso's pair 125, 14 cm along its corridor from both seeds' guesses with five).
#[test]
fn two_points_across_a_wall_can_undo_a_slide() {
    use robot::localization::{Lorentz, SLIDE_CHECK, SlideCheck};
    assert_eq!(SLIDE_CHECK.min_gain, 2);
    let five = Lorentz {
        slide_check: Some(SlideCheck {
            min_gain: 5,
            ..SLIDE_CHECK
        }),
        ..Lorentz::with_lines()
    };
    let new = Lorentz::with_lines();
    let (before, after) = side_by_side_held_out([&five, &new], &[24, 25], every_pair_of(dense_row));
    assert!(
        after >= before + 2,
        "right answers {after} asking two points, {before} asking five"
    );
}

/// A trusted dense answer is checked along the direction its inliers hold it least
/// (`SLIDE_CHECK`): where the few points on the surfaces across that direction lie centimetres
/// off theirs, the σ passes run again from where they would have it. On the twin's dense rows of
/// two seeds held out from those the check's settings were chosen on (24 and 25, 300 pairs a
/// row; the check was chosen on seeds 1–10 and 51–60): every pair the unchecked matcher gets
/// right stays right, and at least two more are (seed 24's pair 108 with 20 % outliers and
/// seed 25's pair 180 without, answers 6–9 cm along a wall before); sparse scans run their own
/// (`sparse_slide_check`, below), and their answers do not change.
#[test]
fn a_trusted_answer_slid_along_a_wall_is_checked() {
    use robot::localization::{Lorentz, SLIDE_CHECK};
    let checked = Lorentz::with_lines();
    assert_eq!(checked.slide_check, Some(SLIDE_CHECK));
    let unchecked = Lorentz {
        slide_check: None,
        ..Lorentz::with_lines()
    };
    let (before, after) = side_by_side_held_out([&unchecked, &checked], &[24, 25], |name| {
        if name.starts_with("synthetic,") {
            Some(Taking {
                pairs: 300,
                unchanged: false,
            })
        } else if sparse_row(name) {
            Some(Taking {
                pairs: 20,
                unchanged: true,
            })
        } else {
            None
        }
    });
    assert!(
        after >= before + 2,
        "right answers {after} with the check, {before} without"
    );
}

/// A trusted sparse answer is checked as a dense one is (`sparse_slide_check`, with
/// `SLIDE_CHECK`'s settings), on the answer the point-to-line finish has finished, the second
/// match a sparse one, finished too. On the twin's 1° scans and Edmonton's of two seeds held
/// out from those the check was chosen on (24 and 28, 300 pairs a row; chosen on 1–10 and
/// 51–60): every pair the unchecked matcher gets right stays right, and at least two more are
/// (seed 24's pair 220 without outliers and seed 28's pair 135 with 20 %, 11 and 18 cm along a
/// wall before).
#[test]
fn a_trusted_sparse_answer_slid_along_a_wall_is_checked() {
    use robot::localization::{Lorentz, SLIDE_CHECK};
    let checked = Lorentz::with_lines();
    assert_eq!(checked.sparse_slide_check, Some(SLIDE_CHECK));
    let unchecked = Lorentz {
        sparse_slide_check: None,
        ..Lorentz::with_lines()
    };
    let rows = every_pair_of(sparse_row);
    let (before, after) = side_by_side_held_out([&unchecked, &checked], &[24, 28], rows);
    assert!(
        after >= before + 2,
        "right answers {after} with the check, {before} without"
    );
}

/// The rescue of an untrusted answer is cheaper two ways, and right as often. A restart that
/// comes to where an earlier one ended a σ pass takes that one's answer (`merge_reach`); and
/// when an answer's only fault is its overlap and the first two restarts come back to it, the
/// other restarts and the coarse search are left out (`restarts_agree`). On the real rows of
/// two seeds (150 pairs a row), against the same matcher without either and with the first
/// alone: each row right on as many pairs, give or take one, no more wrong answers trusted,
/// and fewer searches on every row, by a tenth on Belgioioso's (where, over seeds 1–40 of
/// `twin matchers`, a quarter went).
#[test]
fn restarts_that_come_back_end_the_rescue() {
    use robot::localization::{Lorentz, MERGE_REACH, RESTARTS_AGREE};
    let both = Lorentz::with_lines();
    assert_eq!(both.merge_reach, Some(MERGE_REACH));
    assert_eq!(both.restarts_agree, Some(RESTARTS_AGREE));
    let merged = Lorentz {
        restarts_agree: None,
        ..Lorentz::with_lines()
    };
    let neither = Lorentz {
        merge_reach: None,
        ..merged.clone()
    };
    let matchers = [&neither, &merged, &both];
    // Per real row: right answers, wrong answers trusted and searches, for each matcher.
    let mut totals: Vec<(String, [[usize; 3]; 3])> = Vec::new();
    for seed in [43, 44] {
        for set in sets(150, seed)
            .iter()
            .filter(|s| s.name.starts_with("real"))
        {
            let at = match totals.iter().position(|(name, _)| *name == set.name) {
                Some(at) => at,
                None => {
                    totals.push((set.name.clone(), [[0; 3]; 3]));
                    totals.len() - 1
                }
            };
            for case in &set.cases {
                for (k, matcher) in matchers.iter().enumerate() {
                    let result = matcher.match_scans(&case.reference, &case.current, case.guess);
                    let right = is_right(set, case, &result);
                    let tally = &mut totals[at].1[k];
                    tally[0] += usize::from(right);
                    tally[1] += usize::from(result.converged && !right);
                    tally[2] += result.iterations as usize;
                }
            }
        }
    }
    assert_eq!(totals.len(), 4, "{totals:?}");
    for (row, [neither, merged, both]) in &totals {
        for (name, t) in [("merged", merged), ("both", both)] {
            assert!(
                t[0] + 1 >= neither[0],
                "{row}, {name}: right {t:?} against {neither:?}"
            );
            assert!(
                t[1] <= neither[1],
                "{row}, {name}: trusted wrong {t:?} against {neither:?}"
            );
            assert!(
                t[2] < neither[2],
                "{row}, {name}: searches {t:?} against {neither:?}"
            );
        }
        assert!(
            both[2] <= merged[2],
            "{row}: searches {both:?} against {merged:?}"
        );
        if row.contains("belgioioso") {
            assert!(
                both[2] * 10 <= neither[2] * 9,
                "{row}: searches {both:?} against {neither:?}"
            );
        }
    }
}

/// The scans alone, with no matcher, say where a corrected log's pose cannot be reached: on
/// Freiburg 101's pairs 233 and 249 every pose within 10 cm and 2° of the log's fits at least 5
/// in 100 of the current points fewer (within 2 cm of the reference's surfaces, the laser's
/// accuracy) than a pose 13–18 cm from it, while the log's own pose fits under a tenth of them.
/// On an ordinary Belgioioso pair every pose that fits best lies within the tolerance, and no
/// synthetic pair, whose truth is exact, is out of reach.
#[test]
fn the_scans_alone_say_where_a_corrected_pose_is_out_of_reach() {
    let judge = reach::Judge::LASER;
    let log = |name: &str, n: usize| {
        let path = repo().join(format!("tests/data/corrected/{name}-corrected.log.gz"));
        let error = matchers::GuessError {
            sigma_m: 0.05,
            sigma_rad: 2f64.to_radians(),
        };
        matchers::log_set(name, &path, n, error, 1).expect("the bundled log loads")
    };
    let freiburg = log("freiburg-101", 250);
    for pair in [233, 249] {
        let j = judge.judge(&freiburg.cases[pair]);
        assert_eq!(j.reach, reach::Reach::Out, "pair {pair}: {j:?}");
        assert!(j.at_truth * 10 < j.points, "pair {pair}: {j:?}");
        let off = freiburg.cases[pair].truth.relative(&j.outside.pose);
        assert!(off.x.hypot(off.y) > 0.12, "pair {pair}: {j:?}");
    }
    let belgioioso = log("belgioioso", 11);
    let j = judge.judge(&belgioioso.cases[10]);
    assert_eq!(j.reach, reach::Reach::Decided, "{j:?}");
    assert!(j.inside.points >= j.at_truth, "{j:?}");
    for set in sets(12, 3).iter().filter(|s| s.name.contains("synthetic")) {
        for (k, case) in set.cases.iter().enumerate() {
            let j = judge.judge(case);
            assert_ne!(j.reach, reach::Reach::Out, "{} pair {k}: {j:?}", set.name);
        }
    }
}

/// The closed loop where the look-alike above was found: `goto-lab` on seed 77 trusted a match
/// 0.59 m short and ended 0.58 m from its goal. Now no match the localiser relies on lies
/// (`wrong_trusted_matches`, 5 cm or 1° from the true motion), and the goals are reached
/// within the run's usual error.
#[test]
fn goto_lab_seed_77_relies_on_no_wrong_match() {
    use sim::commands::run::{RunOptions, run_scenario};
    use sim::record::WRONG_MATCH;
    let options = RunOptions {
        seed: Some(77),
        ..RunOptions::default()
    };
    let record = run_scenario(&crate::common::scenario("goto-lab"), &options, |_, _| {})
        .unwrap_or_else(|e| panic!("goto-lab: {e}"));
    let loc = record.localisation.as_ref().expect("goto-lab localises");
    let errors: Vec<(f64, f64)> = loc.trusted_match_errors(&record.scans).collect();
    assert!(errors.len() > 50, "{} trusted matches", errors.len());
    assert_eq!(
        loc.wrong_trusted(&record.scans, WRONG_MATCH),
        0,
        "the worst: {:?}",
        errors
            .iter()
            .copied()
            .fold((0.0f64, 0.0f64), |a, e| (a.0.max(e.0), a.1.max(e.1)))
    );
    let worst_goal = record
        .navigation_results()
        .iter()
        .filter_map(|r| r.true_distance_m)
        .fold(0.0f64, f64::max);
    assert!(worst_goal < 0.3, "{worst_goal:.3} m from a goal");
}

/// Belgioioso's pair 89 from guesses σ 20 cm / 10° off (the large guesses' row, seeds 1–5):
/// the robot 0.55 m from a wall, the scans sharing a third of their points, so no answer can
/// be trusted. From most of these guesses the first match slides away and fits a sixth of the
/// points; the rescue's coarse search finds the log's pose, fitting a third, untrusted too.
/// The match answers that one (`untrusted_best`), still untrusted; before, the first.
#[test]
fn with_nothing_trusted_the_answer_is_where_the_scans_fit_best() {
    use robot::localization::Lorentz;
    let log = repo().join("tests/data/corrected/belgioioso-corrected.log.gz");
    let large = matchers::GuessError {
        sigma_m: 0.20,
        sigma_rad: 10f64.to_radians(),
    };
    let first_only = Lorentz {
        untrusted_best: false,
        ..Lorentz::with_lines()
    };
    let (mut right, mut right_before) = (0, 0);
    for seed in 1..=5 {
        let set = matchers::log_set("large/belgioioso", &log, 90, large, seed).expect("the log");
        let case = &set.cases[89];
        let ok = |r: &robot::localization::MatchResult| {
            let off = case.truth.relative(&r.pose);
            off.x.hypot(off.y) <= set.tolerance_m && off.theta.abs() <= set.tolerance_rad
        };
        let matched = |m: &Lorentz| m.match_scans(&case.reference, &case.current, case.guess);
        let (answer, before) = (matched(&Lorentz::with_lines()), matched(&first_only));
        assert!(!answer.converged && !before.converged, "seed {seed}");
        assert!(
            answer.quality.inlier_share + 1e-9 >= before.quality.inlier_share,
            "seed {seed}: {} of the points fit, {} before",
            answer.quality.inlier_share,
            before.quality.inlier_share
        );
        right += usize::from(ok(&answer));
        right_before += usize::from(ok(&before));
    }
    assert!(
        right == 5 && right_before <= 2,
        "right on {right} seeds of 5 ({right_before} answering the first)"
    );
}

/// An untrusted answer whose only fault is σ (the scans' geometry, which no start changes)
/// ends its rescue when the first restarts come back to it, as one whose only fault is its
/// overlap does (`RestartsAgree::sigma`): on the twin's 1° pairs without outliers and
/// Edmonton's 1° scans, seeds 1–4, every answer and flag is the same to the bit as with the
/// rescue run through, no pair takes more searches, and some take fewer.
#[test]
fn an_answer_loose_only_in_sigma_ends_its_rescue_when_the_restarts_come_back() {
    use robot::localization::{Lorentz, RESTARTS_AGREE, RestartsAgree};
    const { assert!(RESTARTS_AGREE.sigma) };
    let agreeing = Lorentz::with_lines();
    let running = Lorentz {
        restarts_agree: Some(RestartsAgree {
            sigma: false,
            ..RESTARTS_AGREE
        }),
        ..Lorentz::with_lines()
    };
    let (mut pairs, mut fewer, mut saved) = (0, 0, 0);
    for seed in 1..=4 {
        for set in sets(300, seed)
            .iter()
            .filter(|s| s.name.contains("1°, 0") || s.name.contains("edmonton"))
        {
            for (pair, case) in set.cases.iter().enumerate() {
                let a = agreeing.match_scans(&case.reference, &case.current, case.guess);
                let b = running.match_scans(&case.reference, &case.current, case.guess);
                let at = format!("seed {seed}, {} pair {pair}", set.name);
                assert_eq!(a.pose, b.pose, "{at}");
                assert_eq!(a.converged, b.converged, "{at}");
                assert!(a.iterations <= b.iterations, "{at}: {a:?} against {b:?}");
                fewer += usize::from(a.iterations < b.iterations);
                saved += b.iterations - a.iterations;
                pairs += 1;
            }
        }
    }
    assert_eq!(pairs, 4 * 600);
    assert!(
        fewer >= 1 && saved >= 100,
        "{fewer} pairs, {saved} searches saved"
    );
}

/// Any two restarts that come back to an answer whose only fault is its overlap (or σ) end
/// its rescue, not only the first two in their order (`RestartsAgree::in_turn` false): where
/// one of the first restarts slides off to a place that fits little, Belgioioso's pair 89
/// (the robot beside a wall) ran all eight and the coarse search's starts too. On the real rows
/// of seeds 5–6: no pair takes more searches, none right with the first two in turn is wrong,
/// no more wrong answers are trusted, and every row but Freiburg 101's (whose rescues find
/// trusted answers) spares searches.
#[test]
fn any_two_restarts_that_come_back_end_the_rescue() {
    use robot::localization::{Lorentz, RESTARTS_AGREE, RestartsAgree};
    const { assert!(!RESTARTS_AGREE.in_turn) };
    let any = Lorentz::with_lines();
    let in_turn = Lorentz {
        restarts_agree: Some(RestartsAgree {
            in_turn: true,
            ..RESTARTS_AGREE
        }),
        ..Lorentz::with_lines()
    };
    let mut rows: Vec<(String, usize, usize)> = Vec::new();
    for seed in 5..=6 {
        // Per real row: wrong answers trusted (either matcher) and searches saved.
        let mut tally: BTreeMap<String, ([usize; 2], usize)> = BTreeMap::new();
        let real = every_pair_of(|name| name.starts_with("real"));
        each_pair_taken_side_by_side([&any, &in_turn], (&[seed], 300), real, |set, c, [a, b]| {
            let at = format!("seed {seed}, {}", set.name);
            assert!(a.iterations <= b.iterations, "{at}: {a:?} against {b:?}");
            let (right_a, right_b) = (is_right(set, c, a), is_right(set, c, b));
            assert!(right_a || !right_b, "{at}: {a:?} against {b:?}");
            let (trusted_wrong, saved) = tally.entry(set.name.clone()).or_default();
            trusted_wrong[0] += usize::from(a.converged && !right_a);
            trusted_wrong[1] += usize::from(b.converged && !right_b);
            *saved += (b.iterations - a.iterations) as usize;
        });
        for (row, (trusted_wrong, saved)) in tally {
            assert!(
                trusted_wrong[0] <= trusted_wrong[1],
                "seed {seed}, {row}: wrong answers trusted {trusted_wrong:?}"
            );
            rows.push((row, seed as usize, saved));
        }
    }
    assert_eq!(rows.len(), 8, "{rows:?}");
    for (row, seed, saved) in &rows {
        if !row.contains("freiburg") {
            assert!(*saved >= 100, "seed {seed}, {row}: {saved} searches saved");
        }
    }
}

/// A loose first answer's second match is left out when every search of the first would have
/// counted its line pairs' residuals the same way with the second's share
/// (`Lorentz::rematch_alike` false): on every standard row, seeds 1–2, every answer and flag is
/// the same to the bit as with the second match run, no pair takes more searches, and many
/// take fewer.
#[test]
fn a_second_match_that_would_repeat_the_first_is_left_out() {
    use robot::localization::Lorentz;
    let leaving = Lorentz::with_lines();
    assert!(!leaving.rematch_alike);
    let running = Lorentz {
        rematch_alike: true,
        ..Lorentz::with_lines()
    };
    let (mut pairs, mut fewer, mut saved) = (0, 0, 0);
    for seed in 1..=2 {
        for set in sets(300, seed) {
            for (pair, case) in set.cases.iter().enumerate() {
                let a = leaving.match_scans(&case.reference, &case.current, case.guess);
                let b = running.match_scans(&case.reference, &case.current, case.guess);
                let at = format!("seed {seed}, {} pair {pair}", set.name);
                assert_eq!(a.pose, b.pose, "{at}");
                assert_eq!(a.quality, b.quality, "{at}");
                assert_eq!(a.converged, b.converged, "{at}");
                assert!(a.iterations <= b.iterations, "{at}: {a:?} against {b:?}");
                fewer += usize::from(a.iterations < b.iterations);
                saved += b.iterations - a.iterations;
                pairs += 1;
            }
        }
    }
    // Freiburg 101's rows hold fewer pairs than 300 (its scans with poses).
    assert!(pairs > 2 * 2300, "{pairs} pairs");
    assert!(
        fewer >= 50 && saved >= 1500,
        "{fewer} pairs, {saved} searches saved"
    );
}

/// Two matchers side by side on the first 100 pairs of the corrected log `log`
/// (`tests/data/corrected/LOG-corrected.log.gz`) from guesses σ 20 cm / 10° off, for each of
/// `seeds`: each pair's place ("seed S, pair P"), its two answers and whether each is right
/// handed to `visit`.
fn each_large_guess_pair_side_by_side(
    log: &str,
    seeds: &[u64],
    matchers: [&robot::localization::Lorentz; 2],
    mut visit: impl FnMut(&str, [&robot::localization::MatchResult; 2], [bool; 2]),
) {
    let path = repo().join(format!("tests/data/corrected/{log}-corrected.log.gz"));
    let large = matchers::GuessError {
        sigma_m: 0.20,
        sigma_rad: 10f64.to_radians(),
    };
    for &seed in seeds {
        let set =
            matchers::log_set(&format!("large/{log}"), &path, 100, large, seed).expect("the log");
        for (pair, case) in set.cases.iter().enumerate() {
            let [a, b] =
                matchers.map(|m| m.match_scans(&case.reference, &case.current, case.guess));
            let right = [&a, &b].map(|r| is_right(&set, case, r));
            visit(&format!("seed {seed}, pair {pair}"), [&a, &b], right);
        }
    }
}

/// What [`rescue_side_by_side`] counts of two matchers' answers: each one's right answers and
/// wrong trusted ones, and the pairs the first matched in 300 searches or more fewer (and the
/// searches it saved there).
struct RescueTally {
    right: [usize; 2],
    wrong_trusted: [usize; 2],
    spared: u32,
    saved: u32,
}

/// [`each_large_guess_pair_side_by_side`] for a rescue changed in the first matcher: it
/// asserts that no pair right with the second is wrong with the first (and, with
/// `no_more_searches`, that none takes the first more searches), and tallies the rest.
fn rescue_side_by_side(
    log: &str,
    seeds: &[u64],
    matchers: [&robot::localization::Lorentz; 2],
    no_more_searches: bool,
) -> RescueTally {
    let mut tally = RescueTally {
        right: [0; 2],
        wrong_trusted: [0; 2],
        spared: 0,
        saved: 0,
    };
    each_large_guess_pair_side_by_side(log, seeds, matchers, |at, [a, b], ok| {
        let at = format!("{at}: {a:?} against {b:?}");
        assert!(ok[0] || !ok[1], "{at}");
        if no_more_searches {
            assert!(a.iterations <= b.iterations, "{at}");
        }
        for (k, r) in [a, b].into_iter().enumerate() {
            tally.right[k] += usize::from(ok[k]);
            tally.wrong_trusted[k] += usize::from(r.converged && !ok[k]);
        }
        if b.iterations >= a.iterations + 300 {
            tally.spared += 1;
            tally.saved += b.iterations - a.iterations;
        }
    });
    tally
}

/// A dense first answer that fits under a quarter of the current points says the guess is far
/// off, often in heading beyond the restarts' ±16°: the coarse search's starts run before the
/// restarts, and a trusted answer of theirs ends the rescue (`Lorentz::coarse_first_below`).
/// On Freiburg 101's first 100 pairs from guesses σ 20 cm / 10° off, seeds 13 and 18 (where
/// the twin's race found such pairs, 0.7–1.1 thousand searches each): no pair right with the
/// restarts first is wrong, no more wrong answers are trusted, at least as many are right,
/// and at least two pairs are matched in hundreds of searches fewer.
#[test]
fn a_first_answer_that_fits_little_tries_the_coarse_starts_first() {
    use robot::localization::{COARSE_FIRST_BELOW, Lorentz};
    assert_eq!(
        Lorentz::with_lines().coarse_first_below,
        Some(COARSE_FIRST_BELOW)
    );
    // Without the other reason to try the coarse starts first (`coarse_first_slid`), asked
    // of Freiburg 101's corridor on its own below.
    let coarse_first = Lorentz {
        coarse_first_slid: false,
        ..Lorentz::with_lines()
    };
    let restarts_first = Lorentz {
        coarse_first_below: None,
        ..coarse_first.clone()
    };
    let matchers = [&coarse_first, &restarts_first];
    let RescueTally {
        right: [right, right_before],
        wrong_trusted: [wrong_trusted, wrong_trusted_before],
        spared,
        saved,
    } = rescue_side_by_side("freiburg-101", &[13, 18], matchers, false);
    assert!(
        right >= right_before && wrong_trusted <= wrong_trusted_before,
        "right {right} ({right_before} with the restarts first), wrong and trusted \
         {wrong_trusted} ({wrong_trusted_before})"
    );
    assert!(spared >= 2, "{spared} pairs spared, {saved} searches");
}

/// An untrusted first answer that slid far from the guess along the one direction its
/// surfaces leave free (a corridor) has the coarse search's starts tried before the restarts,
/// which slide along the corridor as it did (`Lorentz::coarse_first_slid`). On Freiburg 101's
/// first 100 pairs from guesses σ 20 cm / 10° off, seeds 6 and 28 (its pair 44 among them,
/// 1.8 m along its corridor, 730–840 searches with the restarts first): no pair right with the
/// restarts first is wrong, no more wrong answers are trusted, no pair takes more searches,
/// and at least two take hundreds fewer.
#[test]
fn a_first_answer_slid_along_a_corridor_tries_the_coarse_starts_first() {
    use robot::localization::Lorentz;
    let coarse_first = Lorentz::with_lines();
    assert!(coarse_first.coarse_first_slid);
    let restarts_first = Lorentz {
        coarse_first_slid: false,
        ..Lorentz::with_lines()
    };
    let matchers = [&coarse_first, &restarts_first];
    let RescueTally {
        wrong_trusted: [wrong_trusted, wrong_trusted_before],
        spared,
        saved,
        ..
    } = rescue_side_by_side("freiburg-101", &[6, 28], matchers, true);
    assert!(
        wrong_trusted <= wrong_trusted_before,
        "wrong and trusted {wrong_trusted} ({wrong_trusted_before} with the restarts first)"
    );
    assert!(spared >= 2, "{spared} pairs spared, {saved} searches");
}

/// When the coarse starts, tried first after a first answer that fits little, find nothing
/// trusted but all come to one place, the rescue ends there (`Lorentz::coarse_agreement_ends`):
/// on Belgioioso's first 100 pairs from guesses σ 20 cm / 10° off, seeds 1–5 (its pair 89,
/// where the log's pose fits a third of the points, among them), every answer, quality figure
/// and flag is the same to the bit as with the restarts run, no pair takes more searches, and
/// some take hundreds fewer.
#[test]
fn coarse_starts_that_agree_on_an_untrusted_place_end_the_rescue() {
    use robot::localization::Lorentz;
    let ending = Lorentz::with_lines();
    assert!(ending.coarse_agreement_ends);
    let running = Lorentz {
        coarse_agreement_ends: false,
        ..Lorentz::with_lines()
    };
    let (mut spared, mut saved) = (0, 0);
    let seeds = [1, 2, 3, 4, 5];
    each_large_guess_pair_side_by_side(
        "belgioioso",
        &seeds,
        [&ending, &running],
        |at, [a, b], _| {
            assert_eq!(a.pose, b.pose, "{at}");
            assert_eq!(a.quality, b.quality, "{at}");
            assert_eq!(a.converged, b.converged, "{at}");
            assert!(a.iterations <= b.iterations, "{at}: {a:?} against {b:?}");
            if a.iterations < b.iterations {
                spared += 1;
                saved += b.iterations - a.iterations;
            }
        },
    );
    assert!(
        spared >= 3 && saved >= 1000,
        "{spared} pairs, {saved} searches spared"
    );
}
