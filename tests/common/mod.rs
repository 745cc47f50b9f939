//! Helpers shared by the integration tests: the repository's data files and small worlds.
#![allow(dead_code)]

pub mod svg;

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

/// Drives `scenario` through the real backend: the twin served byte for byte on local TCP ports
/// (base, pan-tilt, laser) at `speed` × real time, `SerialRobot` with a clock scaled to match,
/// the same `drive_scenario` as `twin drive`. Returns the drive and the link events.
pub fn drive_served(
    scenario: &Scenario,
    speed: f64,
) -> (
    Result<
        sim::commands::drive::DriveRecord,
        sim::commands::drive::DriveError<robot::serial::SerialError>,
    >,
    Vec<robot::serial::LinkEvent>,
) {
    use sim::commands::serve::{Offer, ServeOptions, Served, Server, WallClock};
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};
    let twin = Twin::new(
        &scenario.world,
        &scenario.robot,
        &scenario.noise,
        scenario.seed,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let options = ServeOptions {
        speed,
        base: Offer::Tcp("127.0.0.1:0".into()),
        pan_tilt: scenario
            .robot
            .pan_tilt
            .as_ref()
            .map(|_| Offer::Tcp("127.0.0.1:0".into())),
        laser: Some(Offer::Tcp("127.0.0.1:0".into())),
        live: None,
    };
    let mut server = Server::new(twin, &options).unwrap();
    let at = |device: Served| {
        server
            .addresses()
            .into_iter()
            .find(|(d, _)| *d == device)
            .map(|(_, a)| a.parse().unwrap())
    };
    let config = sim::commands::drive::serial_config(
        scenario,
        at(Served::Base).unwrap(),
        at(Served::PanTilt),
        at(Served::Laser),
    );
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    let handle = std::thread::spawn(move || server.run(&flag, None, |_, _| {}));
    let clock: Arc<dyn robot::Clock> = Arc::new(WallClock::new(speed));
    // Taped, as `twin drive` tapes the real robot: the record carries its tape.
    let mut robot =
        robot::replay::Taped::new(robot::serial::SerialRobot::open(config, clock).unwrap());
    let drive = sim::commands::drive::drive_scenario(&mut robot, scenario, None, |_, _| {});
    let (mut serial, tape) = robot.into_parts();
    let drive = drive.map(|mut d| {
        d.tape = tape;
        d
    });
    let events = serial.take_events();
    stop.store(true, Ordering::Relaxed);
    handle.join().unwrap();
    (drive, events)
}

/// Runs `twin ARGS --out DIR` from the repository into a fresh folder named after `name`;
/// panics with the program's error output when it fails.
pub fn twin_into(name: &str, args: &[&str]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("twin-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_twin"))
        .args(args)
        .arg("--out")
        .arg(&dir)
        .current_dir(repo())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "twin {args:?}: {stderr}");
    dir
}
