//! How many of the SLAM-corrected logs' pairs any matcher could get right against the logs'
//! poses, judged by the scans alone (`sim::commands::matchers::reach`): for the first 300
//! consecutive pairs of each log, the real rows of `twin matchers`, every pair whose verdict is
//! not *decided*, then a line a log with the pairs out of reach and the share right at most.
//!
//! ```sh
//! cargo run --release --example reach              # band 2 cm (the laser's ±2 cm), margin 0.05
//! cargo run --release --example reach -- 0.05      # the trust rule's 5 cm band
//! cargo run --release --example reach -- 0.02 0.1  # a margin of 10 in 100 points
//! # A world's synthetic pairs instead (the row `twin matchers --world` adds at 0.5° and 0 %,
//! # seed 1, 300 pairs), judged against the twin's exact truth with the synthetic rows'
//! # tolerance of 5 cm and 1°:
//! cargo run --release --example reach -- 0.02 0.05 worlds/l-corridor.toml
//! ```
//!
//! About a minute and a half on two cores.

use rayon::prelude::*;
use sim::commands::matchers::reach::{Judge, Reach};
use sim::commands::matchers::{CaseSet, GuessError, extra_world_sets, log_set};
use std::path::Path;

fn main() {
    // Each argument with what it may be: BAND in metres, above 0 and at most 1; MARGIN a share
    // of the points, 0 to 1.
    let arg = |k: usize, what: &str, default: f64, ok: fn(f64) -> bool| -> f64 {
        let Some(v) = std::env::args().nth(k) else {
            return default;
        };
        match v.parse::<f64>() {
            Ok(x) if ok(x) => x,
            _ => {
                eprintln!("reach: expected {what}, got {v:?}");
                std::process::exit(2)
            }
        }
    };
    let judge = Judge {
        band_m: arg(
            1,
            "BAND in metres, above 0 and at most 1",
            Judge::LASER.band_m,
            |x| x > 0.0 && x <= 1.0,
        ),
        margin: arg(
            2,
            "MARGIN, a share of the points from 0 to 1",
            Judge::LASER.margin,
            |x| (0.0..=1.0).contains(&x),
        ),
        ..Judge::LASER
    };
    // The guesses play no part: only the pairs and their poses are judged.
    let error = GuessError {
        sigma_m: 0.05,
        sigma_rad: 2f64.to_radians(),
    };
    println!(
        "band {:.0} mm, margin {} of the current points",
        judge.band_m * 1e3,
        judge.margin
    );
    // With a world file: its synthetic row at 0.5° and 0 %, judged at its own tolerance.
    let sets: Vec<(String, CaseSet, Judge)> = match std::env::args().nth(3) {
        Some(world) => {
            let [set, ..] = extra_world_sets(Path::new("."), Path::new(&world), 300, 1)
                .unwrap_or_else(|e| {
                    eprintln!("reach: {e}");
                    std::process::exit(2)
                });
            let judge = Judge {
                tolerance_m: set.tolerance_m,
                tolerance_rad: set.tolerance_rad,
                ..judge
            };
            vec![(set.name.clone(), set, judge)]
        }
        None => ["belgioioso", "freiburg-101", "edmonton"]
            .into_iter()
            .map(|name| {
                let log =
                    Path::new("tests/data/corrected").join(format!("{name}-corrected.log.gz"));
                let set = log_set(name, &log, 300, error, 1).expect("the bundled logs load");
                (name.to_string(), set, judge)
            })
            .collect(),
    };
    for (name, set, judge) in sets {
        let judged: Vec<_> = set.cases.par_iter().map(|c| judge.judge(c)).collect();
        let mut out = Vec::new();
        let mut undecided = 0;
        for (k, j) in judged.iter().enumerate() {
            if j.reach == Reach::Decided {
                continue;
            }
            let off = |p: &robot::Pose2| {
                let o = set.cases[k].truth.relative(p);
                (o.x.hypot(o.y) * 1e3, o.theta.to_degrees())
            };
            let (i, o) = (off(&j.inside.pose), off(&j.outside.pose));
            println!(
                "{name} pair {k}: {:?}; of {} points, {} at the pose given as truth, {} inside ({:.0} mm, {:.2}°), {} outside ({:.0} mm, {:.2}°)",
                j.reach,
                j.points,
                j.at_truth,
                j.inside.points,
                i.0,
                i.1,
                j.outside.points,
                o.0,
                o.1,
            );
            match j.reach {
                Reach::Out => out.push(k),
                _ => undecided += 1,
            }
        }
        println!(
            "{name}: {} pairs, {undecided} undecided, out of reach {out:?}: at most {:.4} right",
            judged.len(),
            1.0 - out.len() as f64 / judged.len() as f64
        );
    }
}
