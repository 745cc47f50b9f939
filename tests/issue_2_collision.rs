//! Driving into a wall: rapier stops the base at the wall, whatever the speed, while the wheels
//! keep turning and the odometry believes the whole move happened.

use crate::common::*;
use robot::Pose2;
use robot::hardware::{DriveBase, DriveWait, Ramp};
use robot::odometry::Odometer;
use sim::GroundTruth;
use sim::config::NoiseSettings;

const WALL_X: f64 = 1.5;

fn facing_a_wall() -> sim::config::WorldDescription {
    world_from(
        r#"
name = "wall ahead"
[start]
x = 0
y = 0
[[wall]]
points = [[-3, -3], [1.5, -3], [1.5, 3], [-3, 3]]
closed = true
"#,
    )
}

/// Drives `metres` forward with `ramp` into the wall at x = 1.5 m; returns (true pose,
/// odometry pose, collisions).
fn drive_into_wall(ramp: Ramp, metres: f64) -> (Pose2, Pose2, u32) {
    let desc = robot("pioneer-3dx");
    let mut r = pioneer_in(&facing_a_wall(), NoiseSettings::NONE, 5);
    r.set_ramp(ramp).unwrap();
    let tenths = desc.geometry().tenths_for_distance(metres).unwrap();
    r.advance(tenths).unwrap();
    r.wait_drive(DriveWait::motors(60_000)).unwrap();
    let status = r.drive_status().unwrap();
    assert!(status.is_idle());
    r.wait_drive(DriveWait::sleep(300)).unwrap();
    let mut odo = Odometer::new(desc.geometry(), Pose2::IDENTITY);
    odo.commanded(&robot::hardware::DriveCommand::Advance(tenths));
    (r.true_pose(), odo.observe(&status), r.collisions())
}

#[test]
fn driving_into_a_wall_stops_the_base_at_the_wall() {
    let desc = robot("pioneer-3dx");
    let front = desc.body.center_x_m.get() + desc.body.radius_m.get();
    let (truth, odometry, collisions) = drive_into_wall(Ramp::POWER_ON, 2.5);
    let contact_x = WALL_X - front;
    assert!(
        truth.x <= contact_x + 0.003,
        "the base passed into the wall: {truth:?}"
    );
    assert!(
        truth.x >= contact_x - 0.02,
        "the base stopped short: {truth:?} (contact at {contact_x})"
    );
    assert!(
        truth.y.abs() < 0.05 && truth.theta.abs() < 0.05,
        "{truth:?}"
    );
    assert!(collisions >= 1);
    // The wheels turned the whole way: the odometry believes 2.5 m.
    assert!((odometry.x - 2.5).abs() < 0.01, "{odometry:?}");
}

#[test]
fn at_full_speed_the_base_does_not_tunnel_through() {
    let desc = robot("pioneer-3dx");
    let front = desc.body.center_x_m.get() + desc.body.radius_m.get();
    let (truth, _, collisions) = drive_into_wall(
        Ramp {
            initial: 5,
            top: 90,
            period_ms: 2,
        },
        4.0,
    );
    assert!(truth.x <= WALL_X - front + 0.003, "{truth:?}");
    assert!(collisions >= 1);
}

#[test]
fn a_base_that_stays_clear_of_walls_has_no_collision() {
    let (truth, _, collisions) = drive_into_wall(Ramp::POWER_ON, 0.8);
    assert_eq!(collisions, 0, "{truth:?}");
    assert!(truth.x > 0.79, "{truth:?}");
}
