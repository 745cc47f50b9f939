//! Real-time factor of the default lab tour: simulated seconds per wall-clock second, on one
//! core, for the whole run (twin, firmware, physics, laser, and the robot crate's tour driving it
//! through the hardware contract), without writing files. Also reported: the same with the five
//! output files written.
//!
//! `cargo bench --bench realtime`

use sim::config::Scenario;
use sim::run::{RunOptions, run_scenario};
use std::path::Path;
use std::time::Instant;

const RUNS: usize = 15;

fn main() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/lab-tour.toml");
    let scenario = Scenario::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let options = RunOptions::default();
    let warm = run_scenario(&scenario, &options, |_, _| {}).expect("the lab tour runs");
    let sim_seconds = warm.sim_seconds();

    let mut factors = Vec::with_capacity(RUNS);
    for _ in 0..RUNS {
        let t = Instant::now();
        let record = run_scenario(&scenario, &options, |_, _| {}).unwrap();
        factors.push(record.sim_seconds() / t.elapsed().as_secs_f64());
    }
    factors.sort_by(f64::total_cmp);

    let out = std::env::temp_dir().join("twin-bench-realtime");
    let mut with_files = Vec::with_capacity(RUNS);
    for _ in 0..RUNS {
        let t = Instant::now();
        let record = run_scenario(&scenario, &options, |_, _| {}).unwrap();
        sim::output::write_all(&record, &scenario, &out).unwrap();
        with_files.push(record.sim_seconds() / t.elapsed().as_secs_f64());
    }
    with_files.sort_by(f64::total_cmp);
    let _ = std::fs::remove_dir_all(out);

    let laser = scenario.robot.laser.baud;
    println!(
        "lab tour: {sim_seconds:.1} s simulated, {} scans kept, laser at {laser} bps ({:.2} Hz)",
        warm.scans.len(),
        1.0 / robot_laser_period(&scenario)
    );
    println!(
        "real-time factor, simulation only:  median {:.0}x  (min {:.0}x, max {:.0}x, {RUNS} runs)",
        factors[RUNS / 2],
        factors[0],
        factors[RUNS - 1]
    );
    println!(
        "real-time factor, with output files: median {:.0}x  (min {:.0}x, max {:.0}x, {RUNS} runs)",
        with_files[RUNS / 2],
        with_files[0],
        with_files[RUNS - 1]
    );
}

fn robot_laser_period(scenario: &Scenario) -> f64 {
    let l = &scenario.robot.laser;
    let transfer = robot::protocol::serial_time(l.telegram_bytes as usize, l.baud).as_secs_f64();
    transfer.max(l.sweep_s.get())
}
