//! Issue 17: many robots stepping together. Each robot of a fleet is a whole twin (firmware,
//! motors, physics, laser); the fleet steps them over the threads of a rayon pool, and gives the
//! same bits on one thread or two; a fleet of one is the robot alone; each robot's laser sees
//! the others, and robots that drive into each other stop each other.

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
fn a_fleet_of_one_runs_as_the_robot_alone() {
    let fleet = run_fleet(2, 1, 300);
    let world = crate::common::world("lab");
    let robot = crate::common::robot("pioneer-3dx");
    let noise = NoiseSettings::defaults_for(&robot);
    let mut alone_world = world.clone();
    alone_world.start = lab_starts(1)[0];
    let mut twin = Twin::new(&alone_world, &robot, &noise, Fleet::robot_seed(7, 0)).unwrap();
    twin.board_mut().deliver(Stamp::ZERO, command(0));
    let mut scans = Vec::new();
    for _ in 0..300 {
        twin.step();
        while let Some((_, scan)) = twin.pop_scan() {
            scans.push((scan.stamp, scan.ranges_mm));
        }
    }
    assert_eq!((scans, twin.true_pose()), fleet[0]);
}

#[test]
fn robots_of_a_fleet_see_each_other() {
    // Two robots face each other 3 m apart in a 20 m room: each one's middle beam meets the
    // other's body, not the wall 10 m away.
    let world = crate::common::big_room();
    let robot = crate::common::robot("pioneer-3dx");
    let starts = [
        Pose2::new(0.0, 0.0, 0.0),
        Pose2::new(3.0, 0.0, std::f64::consts::PI),
    ];
    let mut fleet = Fleet::new(&world, &robot, &NoiseSettings::NONE, 1, &starts).unwrap();
    // One map of the world, built once, shared by every robot.
    let robots = fleet.robots();
    assert!(std::sync::Arc::ptr_eq(robots[0].map(), robots[1].map()));
    let middle: Vec<Mutex<Vec<u16>>> = (0..2).map(|_| Mutex::new(Vec::new())).collect();
    for _ in 0..60 {
        fleet.step(|k, twin| {
            while let Some((_, scan)) = twin.pop_scan() {
                middle[k]
                    .lock()
                    .unwrap()
                    .push(scan.ranges_mm[scan.len() / 2]);
            }
        });
    }
    let mount = robot.laser_mount();
    let body = fleet.robots()[1].body_disc();
    // Robot 0's laser sits `mount.x` ahead of its axle; robot 1's body is a disc.
    let expected = (body.center[0] - mount.x - body.radius) * 1000.0;
    for (k, readings) in middle.iter().enumerate() {
        let readings = readings.lock().unwrap();
        assert!(!readings.is_empty(), "robot {k} scanned");
        for &r in readings.iter() {
            assert!(
                (f64::from(r) - expected).abs() <= 2.0,
                "robot {k} reads {r} mm ahead, the other robot's body is at {expected:.0} mm"
            );
        }
    }
    // Alone, the same robot sees the wall.
    let mut alone = Fleet::new(&world, &robot, &NoiseSettings::NONE, 1, &starts[..1]).unwrap();
    let far = Mutex::new(Vec::new());
    for _ in 0..60 {
        alone.step(|_, twin| {
            while let Some((_, scan)) = twin.pop_scan() {
                far.lock().unwrap().push(scan.ranges_mm[scan.len() / 2]);
            }
        });
    }
    assert!(far.into_inner().unwrap().iter().all(|&r| r > 9_000));
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

#[test]
fn robots_of_a_fleet_bump_into_each_other() {
    // Two robots 1.6 m apart drive straight at each other: they meet and stop each other, as a
    // wall would, instead of passing through; both count the collision.
    let world = crate::common::big_room();
    let robot = crate::common::robot("pioneer-3dx");
    let starts = [
        Pose2::new(-0.8, 0.0, 0.0),
        Pose2::new(0.8, 0.0, std::f64::consts::PI),
    ];
    let mut fleet = Fleet::new(&world, &robot, &NoiseSettings::NONE, 1, &starts).unwrap();
    for twin in fleet.robots_mut() {
        twin.board_mut()
            .deliver(Stamp::ZERO, b"v160 160\n".to_vec());
    }
    let mut closest = f64::INFINITY;
    for _ in 0..1000 {
        fleet.step(|_, _| {});
        let [a, b] = [0, 1].map(|k| fleet.robots()[k].body_disc());
        closest = closest.min((a.center[0] - b.center[0]).hypot(a.center[1] - b.center[1]));
    }
    let radius = fleet.robots()[0].body_disc().radius;
    assert!(
        closest > 2.0 * radius - 0.03,
        "the bodies ({radius} m) came within {closest:.3} m of each other"
    );
    for (k, twin) in fleet.robots().iter().enumerate() {
        assert!(twin.collisions() >= 1, "robot {k} counted the collision");
        assert!(
            twin.true_pose().x.abs() < 0.8,
            "robot {k} moved towards the other"
        );
    }
    // Alone, a robot drives on through where the other stood.
    let mut alone = Fleet::new(&world, &robot, &NoiseSettings::NONE, 1, &starts[..1]).unwrap();
    alone.robots_mut()[0]
        .board_mut()
        .deliver(Stamp::ZERO, b"v160 160\n".to_vec());
    for _ in 0..1000 {
        alone.step(|_, _| {});
    }
    let free = alone.robots()[0].true_pose().x;
    let stopped = fleet.robots()[0].true_pose().x;
    assert!(
        free > stopped + 0.2,
        "alone it reached x = {free:.2} m, stopped at {stopped:.2} m"
    );
}

/// A robot alone glides where it is clear of every wall (rapier's solver skipped); a fleet's
/// robots do not, for their neighbours' discs come and go in each other's physics and a rapier
/// that saw that late would order its contacts otherwise (tried: the scans differed). Thirty
/// robots on arcs that cross in the lab give the same scans and poses, to the bit, with the
/// glide allowed as with rapier stepped at every step.
#[test]
fn a_gliding_fleet_is_the_fleet_stepped_by_rapier_throughout() {
    let run = |gliding: bool| {
        let world = crate::common::world("lab");
        let robot = crate::common::robot("pioneer-3dx");
        let noise = NoiseSettings::defaults_for(&robot);
        let n = 30;
        let mut fleet = Fleet::new(&world, &robot, &noise, 7, &lab_starts(n)).unwrap();
        for (k, twin) in fleet.robots_mut().iter_mut().enumerate() {
            twin.set_gliding(gliding);
            twin.board_mut().deliver(Stamp::ZERO, command(k));
        }
        let scans: Vec<Mutex<Scans>> = (0..n).map(|_| Mutex::new(Vec::new())).collect();
        for _ in 0..1500 {
            fleet.step(|k, twin| {
                while let Some((_, scan)) = twin.pop_scan() {
                    scans[k].lock().unwrap().push((scan.stamp, scan.ranges_mm));
                }
            });
        }
        let collisions: u32 = fleet.robots().iter().map(Twin::collisions).sum();
        let traces: Vec<Trace> = scans
            .into_iter()
            .zip(fleet.robots())
            .map(|(s, twin)| (s.into_inner().unwrap(), twin.true_pose()))
            .collect();
        (traces, collisions)
    };
    let (glided, collisions) = run(true);
    let (stepped, reference_collisions) = run(false);
    assert!(
        reference_collisions > 0,
        "some robots meet a wall or each other"
    );
    assert_eq!(collisions, reference_collisions);
    for (k, (a, b)) in glided.iter().zip(&stepped).enumerate() {
        assert_eq!(a.1, b.1, "robot {k}'s pose");
        assert!(a.0 == b.0, "robot {k}'s scans");
    }
}
