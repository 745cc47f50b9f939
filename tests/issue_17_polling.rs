//! Issue 17: `pacing = "polling"` at every laser rate. Polling `l` while the base moves shifts
//! the firmware's main-loop timing, and at some rates the braking ramp reaches zero speed a few
//! counts short of the target: the firmware then leaves the motors on for ever (App. A). The
//! tour notices the stall and stops the motion with `p`; before, it waited 120 s and failed.

use robot::control::tour::TourConfig;
use sim::commands::run::{RunOptions, run_scenario};
use std::time::Duration;

fn polled_lab_tour(baud: u32) -> (sim::record::RunRecord, usize) {
    let mut scenario = crate::common::scenario("lab-tour");
    scenario.robot.laser.baud = baud;
    // The first 25 steps: the campaign's failures came at steps 1, 14 and 23.
    scenario.steps.truncate(25);
    let options = RunOptions {
        tour: Some(TourConfig::polling(Duration::from_millis(50))),
        ..RunOptions::default()
    };
    let record =
        run_scenario(&scenario, &options, |_, _| {}).unwrap_or_else(|e| panic!("{baud} bps: {e}"));
    let motions = scenario
        .steps
        .iter()
        .filter(|s| s.to_string().starts_with("move") || s.to_string().starts_with("turn"))
        .count();
    (record, motions)
}

#[test]
fn polling_pacing_finishes_the_lab_tour_at_every_laser_rate() {
    use rayon::prelude::*;
    let rates = [38_400u32, 70_000, 73_200, 76_800, 80_000, 115_200, 500_000];
    let results: Vec<(u32, sim::record::RunRecord, usize)> = rates
        .par_iter()
        .map(|&baud| {
            let (record, motions) = polled_lab_tour(baud);
            (baud, record, motions)
        })
        .collect();
    let mut stalled_somewhere = false;
    for (baud, record, motions) in &results {
        assert_eq!(record.steps, 25, "{baud} bps: every step carried out");
        // Polling keeps every scan: many more than one per motion.
        assert!(
            record.scans.len() > 4 * motions,
            "{baud} bps: {} scans",
            record.scans.len()
        );
        // A stall is stopped at once: a few millimetres short, so odometry stays close to the
        // stop-and-go tour's (the drift is that of the slip and the wheel mismatch).
        assert!(
            record.final_odometry_error_m() < 1.0,
            "{baud} bps: odometry off by {} m",
            record.final_odometry_error_m()
        );
        stalled_somewhere |= record.stalled_motions > 0;
    }
    assert!(
        stalled_somewhere,
        "at some of these rates a motion ends short: the case this test is about"
    );
}
