//! Issue 17: many robots stepping together. Each robot of a fleet is a whole twin (firmware,
//! motors, physics, laser); the fleet steps them over the threads of a rayon pool, and gives the
//! same bits on one thread or two, and each robot the same bits it gives alone with its seed.

use robot::{Pose2, Stamp};
use sim::Twin;
use sim::config::NoiseSettings;
use sim::twin::fleet::Fleet;
use std::sync::Mutex;

/// Free starting places in the lab, 1.2 m apart.
fn lab_starts(n: usize) -> Vec<Pose2> {
    let world = crate::common::world("lab");
    let starts = sim::twin::fleet::grid_starts(&world, n, 1.2, 0.3);
    assert_eq!(starts.len(), n, "room for {n} robots");
    starts
}

/// Robot `k`'s command: an arc of its own (wheel speeds `v` around the firmware's 100 = still).
fn command(k: usize) -> Vec<u8> {
    format!("v{} {}\n", 150 + 5 * (k % 7), 130 + 5 * (k % 5)).into_bytes()
}

/// A robot's scans: each one's stamp and ranges.
type Scans = Vec<(Stamp, Vec<u16>)>;

/// What a robot did: its scans and its pose at the end.
type Trace = (Scans, Pose2);

fn run_fleet(threads: usize, n: usize, steps: usize) -> Vec<Trace> {
    let world = crate::common::world("lab");
    let robot = crate::common::robot("pioneer-3dx");
    let noise = NoiseSettings::defaults_for(&robot);
    let mut fleet = Fleet::new(&world, &robot, &noise, 7, &lab_starts(n)).unwrap();
    for (k, twin) in fleet.robots_mut().iter_mut().enumerate() {
        twin.board_mut().deliver(Stamp::ZERO, command(k));
    }
    let scans: Vec<Mutex<Scans>> = (0..n).map(|_| Mutex::new(Vec::new())).collect();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        for _ in 0..steps {
            fleet.step(|k, twin| {
                while let Some((_, scan)) = twin.pop_scan() {
                    scans[k].lock().unwrap().push((scan.stamp, scan.ranges_mm));
                }
            });
        }
    });
    scans
        .into_iter()
        .zip(fleet.robots())
        .map(|(s, twin)| (s.into_inner().unwrap(), twin.true_pose()))
        .collect()
}

#[test]
fn a_fleet_gives_the_same_bits_on_one_thread_or_two() {
    let one = run_fleet(1, 6, 400);
    let two = run_fleet(2, 6, 400);
    assert_eq!(one, two);
    // The robots moved, each its own way, and scanned all along.
    for (k, (scans, end)) in one.iter().enumerate() {
        assert!(
            scans.len() >= 15,
            "robot {k}: {} scans in 3.3 s",
            scans.len()
        );
        let start = lab_starts(6)[k];
        assert!(
            end.distance(&start) > 0.05,
            "robot {k} moved: {start:?} -> {end:?}"
        );
    }
    assert_ne!(one[0].1, one[1].1);
}

#[test]
fn each_robot_of_a_fleet_runs_as_it_would_alone() {
    let fleet = run_fleet(2, 3, 200);
    let world = crate::common::world("lab");
    let robot = crate::common::robot("pioneer-3dx");
    let noise = NoiseSettings::defaults_for(&robot);
    for (k, start) in lab_starts(3).into_iter().enumerate() {
        let mut alone_world = world.clone();
        alone_world.start = start;
        let mut twin = Twin::new(&alone_world, &robot, &noise, Fleet::robot_seed(7, k)).unwrap();
        twin.board_mut().deliver(Stamp::ZERO, command(k));
        let mut scans = Vec::new();
        for _ in 0..200 {
            twin.step();
            while let Some((_, scan)) = twin.pop_scan() {
                scans.push((scan.stamp, scan.ranges_mm));
            }
        }
        assert_eq!((scans, twin.true_pose()), fleet[k], "robot {k}");
    }
}

#[test]
fn a_robot_on_a_wall_is_named() {
    let world = crate::common::world("lab");
    let robot = crate::common::robot("pioneer-3dx");
    let starts = [Pose2::new(2.0, 2.0, 0.0), Pose2::new(0.05, 2.0, 0.0)];
    let err = Fleet::new(&world, &robot, &NoiseSettings::NONE, 1, &starts)
        .err()
        .expect("robot 1 overlaps the west wall");
    assert!(err.to_string().contains("robot 1 at (0.05, 2.00)"), "{err}");
}
