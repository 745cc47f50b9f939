//! The first laser model through the hardware contract: ranges against hand-computed distances,
//! the no-return value, noise, and timing set by the serial line.

use crate::common;

use crate::common::*;
use robot::hardware::{Laser, LaserScan};
use sim::config::NoiseSettings;
use std::time::Duration;

/// Distance from `origin` along `dir` to the axis-aligned rectangle [x0, x1] × [y0, y1] seen from
/// inside, by hand.
fn distance_inside_rectangle(
    origin: (f64, f64),
    dir: (f64, f64),
    x: (f64, f64),
    y: (f64, f64),
) -> f64 {
    let tx = if dir.0 > 0.0 {
        (x.1 - origin.0) / dir.0
    } else if dir.0 < 0.0 {
        (x.0 - origin.0) / dir.0
    } else {
        f64::INFINITY
    };
    let ty = if dir.1 > 0.0 {
        (y.1 - origin.1) / dir.1
    } else if dir.1 < 0.0 {
        (y.0 - origin.1) / dir.1
    } else {
        f64::INFINITY
    };
    tx.min(ty)
}

fn first_scan(robot: &mut sim::SimRobot) -> LaserScan {
    robot
        .read_scan(Duration::from_secs(2))
        .unwrap()
        .expect("the laser sends scans")
}

#[test]
fn noiseless_ranges_equal_the_analytic_distances() {
    let room = world_from(
        r#"
name = "room"
[start]
x = 1.3
y = 0.7
heading_deg = 30
[[wall]]
points = [[-2.0, -1.5], [4.5, -1.5], [4.5, 3.0], [-2.0, 3.0]]
closed = true
"#,
    );
    let mut robot = pioneer_in(&room, NoiseSettings::NONE, 3);
    let scan = first_scan(&mut robot);
    assert_eq!(scan.len(), 361);
    let mount = common::robot("pioneer-3dx").laser_mount();
    let laser = room.start.compose(&mount);
    for i in 0..scan.len() {
        let a = laser.theta + scan.angle(i);
        let expected = distance_inside_rectangle(
            (laser.x, laser.y),
            (a.cos(), a.sin()),
            (-2.0, 4.5),
            (-1.5, 3.0),
        );
        let got = scan.range_m(i).expect("every beam hits a wall");
        // Millimetre readings, single-precision ray casts.
        assert!(
            (got - expected).abs() <= 0.0006,
            "beam {i}: {got} vs {expected}"
        );
    }
}

#[test]
fn beyond_32_metres_the_reading_is_the_maximum() {
    let corridor = world_from(
        r#"
name = "long corridor"
[start]
x = 0
y = 0
[[wall]]
points = [[-1, 1.5], [60, 1.5]]
[[wall]]
points = [[-1, -1.5], [60, -1.5]]
"#,
    );
    let mut robot = pioneer_in(&corridor, NoiseSettings::NONE, 3);
    let scan = first_scan(&mut robot);
    assert_eq!(scan.ranges_mm[180], 32_000, "straight down a 60 m corridor");
    assert_eq!(scan.range_m(180), None);
    assert_eq!(scan.range_max_mm, 32_000);
    // Sideways the walls are 1.5 m away.
    assert_eq!(scan.ranges_mm[0], 1500);
    assert_eq!(scan.ranges_mm[360], 1500);
}

#[test]
fn range_noise_is_gaussian_with_the_configured_sigma_and_per_seed() {
    let noise = NoiseSettings {
        laser_sigma_m: 0.02,
        ..NoiseSettings::NONE
    };
    let mut robot = pioneer_in(&big_room(), noise, 11);
    let mut errors = Vec::new();
    let laser = big_room()
        .start
        .compose(&common::robot("pioneer-3dx").laser_mount());
    for _ in 0..30 {
        let scan = first_scan(&mut robot);
        for i in (0..361).step_by(4) {
            let a = laser.theta + scan.angle(i);
            let truth = distance_inside_rectangle(
                (laser.x, laser.y),
                (a.cos(), a.sin()),
                (-10.0, 10.0),
                (-10.0, 10.0),
            );
            errors.push(scan.range_m(i).unwrap() - truth);
        }
    }
    let n = errors.len() as f64;
    let mean = errors.iter().sum::<f64>() / n;
    let sd = (errors.iter().map(|e| (e - mean) * (e - mean)).sum::<f64>() / n).sqrt();
    assert!(mean.abs() < 0.002, "mean error {mean}");
    assert!((sd - 0.02).abs() < 0.0015, "sd {sd} over {n} readings");
    let seed_11 = first_scan(&mut pioneer_in(&big_room(), noise, 11));
    let seed_12 = first_scan(&mut pioneer_in(&big_room(), noise, 12));
    assert_ne!(
        seed_11.ranges_mm, seed_12.ranges_mm,
        "each seed draws its own noise"
    );
}

#[test]
fn scans_come_at_the_rate_the_serial_line_allows() {
    // 732-byte telegrams at 38400 bps take 190.625 ms, longer than the 26.67 ms sweep: each
    // telegram carries the latest sweep complete when the line frees, so stamps fall on sweep
    // starts 7 or 8 sweeps apart and average the transfer time.
    let sweep = 26_670_000u64;
    let transfer = 190_625_000u64;
    let mut robot = pioneer_in(&big_room(), NoiseSettings::NONE, 1);
    let stamps: Vec<u64> = (0..41)
        .map(|_| first_scan(&mut robot).stamp.nanos())
        .collect();
    for pair in stamps.windows(2) {
        let gap = pair[1] - pair[0];
        assert_eq!(gap % sweep, 0, "stamps on sweep starts");
        assert!(gap == 7 * sweep || gap == 8 * sweep, "{gap} ns apart");
    }
    let mean = (stamps[40] - stamps[0]) as f64 / 40.0;
    assert!(
        (mean - transfer as f64).abs() < sweep as f64 / 40.0 + 1.0,
        "{mean}"
    );
    // A scan reaches the host a sweep plus a transfer after it began, or later if the line
    // was still busy with the previous telegram.
    let before = robot.host_time();
    let scan = first_scan(&mut robot);
    assert!(robot.host_time() >= before);
    let age = robot.host_time().nanos() - scan.stamp.nanos();
    assert!(
        (sweep + transfer..2 * sweep + transfer).contains(&age),
        "{age}"
    );
    // The thesis's robot sends at 9600 bps: 762.5 ms per telegram, 28 or 29 sweeps apart.
    let mut slow = common::thesis_in(&big_room(), NoiseSettings::NONE, 1);
    let a = first_scan(&mut slow).stamp.nanos();
    let b = first_scan(&mut slow).stamp.nanos();
    assert!(b - a == 28 * sweep || b - a == 29 * sweep, "{}", b - a);
}

#[test]
fn a_silent_wait_times_out_after_the_timeout_of_robot_time() {
    let mut robot = pioneer_in(&big_room(), NoiseSettings::NONE, 1);
    first_scan(&mut robot);
    let before = robot.host_time();
    assert!(
        robot
            .read_scan(Duration::from_millis(20))
            .unwrap()
            .is_none(),
        "the next scan is ~190 ms away"
    );
    assert_eq!(robot.host_time().nanos() - before.nanos(), 20_000_000);
}
