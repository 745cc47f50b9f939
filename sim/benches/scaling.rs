//! How the twin's cost grows with work: wall-clock seconds per simulated second of the lab tour
//! with every scan cast (`pacing = "polling"`, no localisation, no files), against the laser's
//! scan rate (its serial rate: 38,400, 73,200 and 500,000 bps, about 5, 10 and 37 scans a second —
//! the 26.7 ms sweep caps it below 40) and the world's size (the lab's 8 boxes, then 80 and 800:
//! 1×, 10× and 100×, `sim::world::clutter`).
//!
//! Beside each figure, its ratio to a reference measured in the same run: one level scan of the
//! lab cast by brute force (every beam against every face, no index), so the table travels
//! between machines.
//!
//! `cargo bench --bench scaling`

use robot::control::tour::TourConfig;
use sim::commands::run::{RunOptions, run_scenario};
use sim::config::{Scenario, WorldDescription};
use sim::world::WorldMap;
use std::path::Path;
use std::time::{Duration, Instant};

const RUNS: usize = 5;

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let lab_text = std::fs::read_to_string(root.join("worlds/lab.toml")).unwrap();
    let base = Scenario::load(root.join("scenarios/lab-tour.toml")).unwrap();
    let reference = brute_force_scan_seconds(&base.world);
    println!(
        "reference: one level scan of the lab by brute force (361 beams x {} faces): {:.1} µs",
        WorldMap::new(&base.world).faces().len(),
        reference * 1e6
    );
    println!();
    println!(
        "| world | laser | scans/s simulated | wall s per simulated s | ratio to the reference |"
    );
    println!("|---|---|---|---|---|");
    for extra in [0usize, 72, 792] {
        let world = WorldDescription::parse(
            &sim::world::clutter::lab_with_boxes(&lab_text, extra),
            root.join("worlds/lab-cluttered.toml"),
        )
        .unwrap();
        for baud in [38_400u32, 73_200, 500_000] {
            let mut scenario = base.clone();
            scenario.world = world.clone();
            scenario.robot.laser.baud = baud;
            scenario.localisation = None;
            let options = RunOptions {
                tour: Some(TourConfig::polling(Duration::from_millis(50))),
                ..RunOptions::default()
            };
            // One run to warm the caches and the allocator, then the timed ones.
            run_scenario(&scenario, &options, |_, _| {}).expect("the tour runs");
            let mut per_second = Vec::with_capacity(RUNS);
            let mut rate = 0.0;
            for _ in 0..RUNS {
                let t = Instant::now();
                let record = run_scenario(&scenario, &options, |_, _| {}).expect("the tour runs");
                let wall = t.elapsed().as_secs_f64();
                per_second.push(wall / record.sim_seconds());
                rate = record.scans.len() as f64 / record.sim_seconds();
            }
            per_second.sort_by(f64::total_cmp);
            let median = per_second[RUNS / 2];
            println!(
                "| lab + {extra} boxes ({} in all) | {baud} bps | {rate:.1} | {median:.5} | {:.0} |",
                extra + 8,
                median / reference
            );
        }
    }
}

/// Seconds per level scan of `world` cast by brute force: 361 beams over 180° from the lab's
/// start, each against every face, the nearest crossing kept (median of 201 scans).
fn brute_force_scan_seconds(world: &WorldDescription) -> f64 {
    let map = WorldMap::new(world);
    let faces: Vec<([f64; 2], [f64; 2])> = map.faces().iter().map(|f| (f.a, f.b)).collect();
    let origin = [world.start.x, world.start.y];
    let mut times = Vec::new();
    let mut sink = 0.0;
    for _ in 0..201 {
        let t = Instant::now();
        for k in 0..361 {
            let angle = world.start.theta + (f64::from(k) * 0.5 - 90.0).to_radians();
            let d = [angle.cos(), angle.sin()];
            let mut best = 32.0f64;
            for (a, b) in &faces {
                let e = [b[0] - a[0], b[1] - a[1]];
                let denom = d[0] * e[1] - d[1] * e[0];
                if denom.abs() < 1e-12 {
                    continue;
                }
                let w = [a[0] - origin[0], a[1] - origin[1]];
                let t_ray = (w[0] * e[1] - w[1] * e[0]) / denom;
                let u = (w[0] * d[1] - w[1] * d[0]) / denom;
                if t_ray > 0.0 && (0.0..=1.0).contains(&u) && t_ray < best {
                    best = t_ray;
                }
            }
            sink += best;
        }
        times.push(t.elapsed().as_secs_f64());
    }
    std::hint::black_box(sink);
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}
