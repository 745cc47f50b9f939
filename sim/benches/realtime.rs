//! Real-time factor of the lab tour: simulated seconds per wall-clock second, on one core, for
//! the whole run (twin, firmware, physics, sensors, and the robot crate's tour driving it through
//! the hardware contract), without writing files, and with the output files written.
//!
//! Two tours: `lab-tour` (the default: a Pioneer with a fixed laser) and `lab-tour-thesis` (the
//! thesis's robot with everything running: the laser on the pan-tilt, homed then levelled, and
//! the 16 sonars firing throughout).
//!
//! `cargo bench --bench realtime`

use sim::commands::run::{RunOptions, run_scenario};
use sim::config::Scenario;
use std::path::Path;
use std::time::Instant;

const RUNS: usize = 15;

fn main() {
    for name in ["lab-tour", "lab-tour-thesis"] {
        measure(name);
    }
}

fn measure(name: &str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenarios")
        .join(format!("{name}.toml"));
    let scenario = Scenario::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let options = RunOptions::default();
    let warm = run_scenario(&scenario, &options, |_, _| {}).expect("the tour runs");
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

    let mut running = vec![format!("laser at {} bps", scenario.robot.laser.baud)];
    if scenario.sonar.is_some() {
        running.push("sonar ring firing".into());
    }
    if scenario.pan_tilt.is_some() {
        running.push("pan-tilt".into());
    }
    println!(
        "{name}: {sim_seconds:.1} s simulated, {} scans kept; {}",
        warm.scans.len(),
        running.join(", ")
    );
    println!(
        "  real-time factor, simulation only:   median {:.0}x  (min {:.0}x, max {:.0}x, {RUNS} runs)",
        factors[RUNS / 2],
        factors[0],
        factors[RUNS - 1]
    );
    println!(
        "  real-time factor, with output files: median {:.0}x  (min {:.0}x, max {:.0}x, {RUNS} runs)",
        with_files[RUNS / 2],
        with_files[0],
        with_files[RUNS - 1]
    );
}
