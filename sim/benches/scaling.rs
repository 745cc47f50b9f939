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

#[path = "common/reference.rs"]
mod reference;
use reference::brute_force_scan_seconds;

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
