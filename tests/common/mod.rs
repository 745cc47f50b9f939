//! Helpers shared by the integration tests: the repository's data files and small worlds.
#![allow(dead_code)]

use sim::config::{NoiseSettings, RobotDescription, Scenario, WorldDescription};
use sim::{SimRobot, Twin};
use std::path::PathBuf;

/// The repository's root folder.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// A shipped robot description (`scenarios/robots/NAME.toml`).
pub fn robot(name: &str) -> RobotDescription {
    let path = repo().join("scenarios/robots").join(format!("{name}.toml"));
    RobotDescription::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// A shipped world (`worlds/NAME.toml`).
pub fn world(name: &str) -> WorldDescription {
    let path = repo().join("worlds").join(format!("{name}.toml"));
    WorldDescription::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// A shipped scenario (`scenarios/NAME.toml`).
pub fn scenario(name: &str) -> Scenario {
    let path = repo().join("scenarios").join(format!("{name}.toml"));
    Scenario::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// A world from TOML text.
pub fn world_from(text: &str) -> WorldDescription {
    WorldDescription::parse(text, "test-world.toml").unwrap_or_else(|e| panic!("{e}"))
}

/// A square room 20 m wide with the robot at its centre facing +x.
pub fn big_room() -> WorldDescription {
    world_from(
        r#"
name = "big room"
[start]
x = 0
y = 0
[[wall]]
points = [[-10, -10], [10, -10], [10, 10], [-10, 10]]
closed = true
"#,
    )
}

/// The Pioneer in `world` with the given noise, seen through the hardware contract.
pub fn pioneer_in(world: &WorldDescription, noise: NoiseSettings, seed: u64) -> SimRobot {
    let robot = robot("pioneer-3dx");
    let twin = Twin::new(world, &robot, &noise, seed).unwrap_or_else(|e| panic!("{e}"));
    SimRobot::new(twin, robot.drive.serial_baud)
}

/// The thesis's robot (laser on the pan-tilt) in `world`, seen through the hardware contract.
pub fn thesis_in(world: &WorldDescription, noise: NoiseSettings, seed: u64) -> SimRobot {
    let robot = robot("thesis-roca");
    let twin = Twin::new(world, &robot, &noise, seed).unwrap_or_else(|e| panic!("{e}"));
    SimRobot::new(twin, robot.drive.serial_baud)
}
