//! Odometry against the twin's ground truth.
//!
//! Without slip or mismatch the twin's kinematics are exact: odometry integrated from the
//! encoders' true edge counts follows the true pose to encoder quantisation. The firmware's
//! reported counters miss only the wheels' coast after each brake (App. A `speed_control` stops
//! counting when the motors switch off). With random slip, odometry drifts, and more with more
//! slip.

use crate::common::*;
use robot::geometry::wrap_angle;
use robot::hardware::{DriveBase, DriveCommand};
use robot::odometry::{Odometer, integrate_arc};
use sim::GroundTruth;
use sim::commands::run::{RunOptions, run_scenario};
use sim::config::NoiseSettings;

#[test]
fn without_slip_or_mismatch_odometry_from_the_encoders_follows_truth() {
    let desc = robot("pioneer-3dx");
    let g = desc.geometry();
    let m = g.metres_per_count();
    let mut r = pioneer_in(&big_room(), NoiseSettings::NONE, 9);
    let mut from_edges = r.true_pose();
    let mut from_firmware = Odometer::new(g, r.true_pose());
    let tour = [
        DriveCommand::Advance(g.tenths_for_distance(1.0).unwrap()),
        DriveCommand::TurnLeft(g.tenths_for_turn(90f64.to_radians()).unwrap()),
        DriveCommand::Advance(g.tenths_for_distance(0.5).unwrap()),
        DriveCommand::TurnRight(g.tenths_for_turn(25f64.to_radians()).unwrap()),
        DriveCommand::Retreat(g.tenths_for_distance(0.7).unwrap()),
        DriveCommand::TurnLeft(g.tenths_for_turn(25f64.to_radians()).unwrap()),
    ];
    let mut last = r.twin().encoder_edges();
    let mut worst = (0.0f64, 0.0f64);
    let mut coast_total = 0;
    for command in tour {
        let at_command = r.twin().encoder_edges();
        r.drive(command).unwrap();
        from_firmware.commanded(&command);
        let signs = match command {
            DriveCommand::Advance(_) => (1.0, 1.0),
            DriveCommand::Retreat(_) => (-1.0, -1.0),
            DriveCommand::TurnLeft(_) => (-1.0, 1.0),
            _ => (1.0, -1.0),
        };
        // Step by step: integrate the wheels' true edge counts and compare with the body.
        let mut settled = 0;
        while settled < 60 {
            r.twin_mut().step();
            let now = r.twin().encoder_edges();
            let (dl, dr) = ((now.0 - last.0) as f64, (now.1 - last.1) as f64);
            last = now;
            from_edges = integrate_arc(from_edges, signs.0 * dl * m, signs.1 * dr * m, g.track_m);
            let truth = r.true_pose();
            worst.0 = worst.0.max(truth.distance(&from_edges));
            worst.1 = worst
                .1
                .max(wrap_angle(truth.theta - from_edges.theta).abs());
            if r.twin().firmware().motors_on() == (false, false) {
                settled += 1;
            }
        }
        // The firmware counted everything but the coast after the brake.
        let reported = r.drive_status().unwrap();
        from_firmware.observe(&reported);
        let turned = (last.0 - at_command.0, last.1 - at_command.1);
        let coast = (
            turned.0 - u64::from(reported.left_counts),
            turned.1 - u64::from(reported.right_counts),
        );
        assert!(
            coast.0 < 250 && coast.1 < 250,
            "{command:?}: coast {coast:?}"
        );
        coast_total += coast.0 + coast.1;
    }
    // Quantisation: one count is 9.35 µm of wheel travel and 0.003° of heading.
    assert!(worst.0 < 5e-5, "worst position gap {} m", worst.0);
    assert!(worst.1 < 2e-4, "worst heading gap {} rad", worst.1);
    assert!(coast_total > 0, "the wheels coast after every brake");
    // The firmware's odometry falls short by the coast alone.
    let short = r.true_pose().distance(&from_firmware.pose());
    assert!(
        short > 1e-4 && short < 0.02,
        "firmware odometry off by {short} m"
    );
}

fn final_error(slip: f64, seed: u64) -> f64 {
    let mut scenario = scenario("lab-tour");
    scenario.noise = NoiseSettings {
        slip_sigma_sqrt_m: slip,
        ..NoiseSettings::NONE
    };
    let options = RunOptions {
        seed: Some(seed),
        ..RunOptions::default()
    };
    let record = run_scenario(&scenario, &options, |_, _| {}).unwrap();
    assert_eq!(record.collisions, 0, "slip {slip}, seed {seed}");
    record.final_odometry_error_m()
}

#[test]
fn slip_makes_odometry_drift() {
    let exact = final_error(0.0, 1);
    let slippery: Vec<f64> = (1..=4).map(|seed| final_error(0.01, seed)).collect();
    let mean = slippery.iter().sum::<f64>() / slippery.len() as f64;
    // Without slip only the coast remains; with 1 cm/√m of slip the error is several times larger.
    assert!(exact < 0.1, "{exact}");
    assert!(
        mean > 3.0 * exact.max(0.01),
        "no slip {exact} m, slip {slippery:?}"
    );
    // Each seed slips its own way.
    assert!(slippery.windows(2).all(|w| w[0] != w[1]), "{slippery:?}");
}

#[test]
fn odometry_starts_where_the_robot_is_put() {
    let scenario = scenario("lab-tour");
    let record = run_scenario(&scenario, &RunOptions::default(), |_, _| {}).unwrap();
    let first = &record.scans[0];
    // The first scan is taken after the first move: both poses are about 0.5 m from the start.
    for pose in [first.truth, first.odometry] {
        let d = pose.distance(&scenario.world.start);
        assert!((d - 0.5).abs() < 0.02, "{pose:?}");
    }
}
