//! The sonar ring through the hardware contract and the ported firmware: echo times convert to
//! distances, a wall met at 45° sends the burst away, the firmware only listens for its echo
//! window, and the ring fires its sequence one transducer at a time with the firmware's timing;
//! the sonar-ring run writes one full reading and draws it.

use crate::common;

use crate::common::*;
use robot::hardware::{
    DriveBase, DriveWait, ErrorKind, HardwareError, SONAR_NO_ECHO, SPEED_OF_SOUND, SonarCommand,
    SonarEchoes, SonarRing, echo_distance_m,
};
use sim::config::NoiseSettings;

/// The Pioneer at the origin, heading `heading_deg`, with a wall x = 2 in front.
fn before_a_wall(heading_deg: f64) -> sim::SimRobot {
    wall_at(2.0, heading_deg)
}

/// The Pioneer at the origin, heading `heading_deg`, with a wall x = `x`.
fn wall_at(x: f64, heading_deg: f64) -> sim::SimRobot {
    let text = format!(
        "name = \"wall\"\n[start]\nx = 0\ny = 0\nheading_deg = {heading_deg}\n[[wall]]\npoints = [[{x}, -30], [{x}, 30]]\n"
    );
    pioneer_in(&world_from(&text), NoiseSettings::NONE, 3)
}

/// Fires `sequence` with `s2 te tr`, waits two full cycles and reads the ring.
fn fire_and_read(robot: &mut sim::SimRobot, sequence: Vec<u8>, te: u16, tr: u16) -> SonarEchoes {
    let cycle = sequence.len() as u16 * (te + tr + 3);
    robot.sonar(SonarCommand::Sequence(sequence)).unwrap();
    robot
        .sonar(SonarCommand::Timing {
            echo_ms: te,
            relax_ms: tr,
        })
        .unwrap();
    robot.sonar(SonarCommand::Firing(true)).unwrap();
    robot.wait_drive(DriveWait::sleep(2 * cycle)).unwrap();
    robot.sonar_echoes().unwrap()
}

#[test]
fn echo_times_convert_to_the_wall_distance() {
    let mut robot = before_a_wall(0.0);
    let echoes = fire_and_read(&mut robot, vec![0], 50, 20);
    let desc = common::robot("pioneer-3dx");
    let s = desc.sonar.as_ref().unwrap();
    // The front transducer sits ring_radius ahead of the ring's centre.
    let truth = 2.0 - (s.center_x_m.get() + s.ring_radius_m.get());
    let got = echo_distance_m(echoes.times[0], SPEED_OF_SOUND).expect("an echo");
    // One timer unit is 0.91 mm of range; the transducer's noise is 1 cm.
    assert!(
        (got - truth).abs() < 0.04,
        "{got} m vs {truth} m ({} units)",
        echoes.times[0]
    );
}

#[test]
fn a_sonar_facing_a_wall_at_45_degrees_loses_the_echo() {
    let mut robot = before_a_wall(45.0);
    let echoes = fire_and_read(&mut robot, vec![0], 50, 20);
    assert_eq!(echoes.times[0], SONAR_NO_ECHO);
    // Head-on, the same transducer hears the wall.
    let mut robot = before_a_wall(0.0);
    assert_ne!(
        fire_and_read(&mut robot, vec![0], 50, 20).times[0],
        SONAR_NO_ECHO
    );
}

#[test]
fn the_firmware_listens_only_for_its_echo_window() {
    // With Te = 10 the echo line is listened to for 11 ticks: 11.26 ms, 1.93 m of range; the
    // front transducer is 2.33 m from a wall at x = 2.5. With Te = 15 it listens to 2.81 m.
    let mut robot = wall_at(2.5, 0.0);
    assert_eq!(
        fire_and_read(&mut robot, vec![0], 10, 10).times[0],
        SONAR_NO_ECHO
    );
    let mut robot = wall_at(2.5, 0.0);
    assert_ne!(
        fire_and_read(&mut robot, vec![0], 15, 10).times[0],
        SONAR_NO_ECHO
    );
}

#[test]
fn the_ring_fires_its_sequence_one_transducer_at_a_time() {
    let mut robot = before_a_wall(0.0);
    let echoes = fire_and_read(&mut robot, vec![15, 0, 1], 50, 20);
    assert_eq!(echoes.sequence, vec![15, 0, 1]);
    assert_eq!(echoes.times.len(), 3);
    // Consecutive positions are measured one shot apart: the fire tick, the wait tick, Te ticks,
    // Tr ticks and the step to the next — 73 ticks of 1.024 ms.
    let t: Vec<u64> = echoes
        .measured
        .iter()
        .map(|m| m.expect("measured").nanos())
        .collect();
    assert_eq!(t[1] - t[0], 73 * 1_024_000);
    assert_eq!(t[2] - t[1], 73 * 1_024_000);
    assert!(echoes.measured.iter().all(|m| m.unwrap() <= echoes.stamp));
    // While firing, the status report says so.
    assert!(robot.drive_status().unwrap().sonar_firing);
    robot.sonar(SonarCommand::Firing(false)).unwrap();
    assert!(!robot.drive_status().unwrap().sonar_firing);
}

#[test]
fn out_of_range_sonar_arguments_are_refused() {
    let mut robot = before_a_wall(0.0);
    let err = robot
        .sonar(SonarCommand::Sequence(vec![3, 16]))
        .unwrap_err();
    assert_eq!(err.kind(), ErrorKind::InvalidArgument);
    let err = robot
        .sonar(SonarCommand::Timing {
            echo_ms: 5,
            relax_ms: 20,
        })
        .unwrap_err();
    assert_eq!(err.kind(), ErrorKind::InvalidArgument);
}

#[test]
fn a_robot_without_a_ring_says_so() {
    let mut desc = common::robot("pioneer-3dx");
    desc.sonar = None;
    let twin = sim::Twin::new(&big_room(), &desc, &NoiseSettings::NONE, 1).unwrap();
    let mut robot = sim::SimRobot::new(twin, 9600);
    let err = robot.sonar_echoes().unwrap_err();
    assert_eq!(err.kind(), ErrorKind::Unsupported);
}

#[test]
fn the_sonar_ring_run_writes_one_full_reading_and_its_picture() {
    let scenario = scenario("sonar-ring");
    let record = sim::commands::run::run_scenario(
        &scenario,
        &sim::commands::run::RunOptions::default(),
        |_, _| {},
    )
    .unwrap();
    let ring = record.sonar.as_ref().expect("the scenario fires the ring");
    assert_eq!(ring.echoes.times.len(), 16);
    let heard = ring
        .echoes
        .times
        .iter()
        .filter(|&&t| t != SONAR_NO_ECHO)
        .count();
    // Turned 30° to the walls: most transducers hear something, some lose the burst.
    assert!((8..16).contains(&heard), "{heard} of 16 heard an echo");
    assert!(
        ring.echoes.measured.iter().all(Option::is_some),
        "every reading stamped"
    );
    let dir = std::env::temp_dir().join(format!("twin-sonar-ring-{}", std::process::id()));
    sim::output::write_all(&record, &scenario, &dir).unwrap();
    let svg = std::fs::read_to_string(dir.join("map.svg")).unwrap();
    assert_eq!(
        svg.matches("<title>sonar ").count(),
        16,
        "one wedge or ray each"
    );
    assert_eq!(svg.matches(": no echo</title>").count(), 16 - heard);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("sonar.json")).unwrap()).unwrap();
    assert_eq!(json["readings"].as_array().map(Vec::len), Some(16));
    let _ = std::fs::remove_dir_all(&dir);
}
