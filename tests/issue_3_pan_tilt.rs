//! Issue 3: the pan-tilt unit — power-up homing, moves that take time under the ramps, the
//! status report as the firmware's `l` writes it — and the laser riding on it, tilted onto the
//! floor where trigonometry says and level seeing exactly what the 2D model sees.

use crate::common;

use crate::common::{big_room, thesis_in, world_from};
use robot::Stamp;
use robot::hardware::{
    Laser, LaserScan, PanTilt, PanTiltCommand, PanTiltPosition, PanTiltWait, Ramp,
};
use sim::config::NoiseSettings;
use sim::{GroundTruth, SimRobot, Twin};
use std::time::Duration;

/// One tilt position, degrees (thesis-roca.toml).
const TILT_STEP_DEG: f64 = 0.65;
/// The tilt position that levels the laser.
const LEVEL: u8 = 31;

fn scan_since(robot: &mut SimRobot, since: Stamp) -> LaserScan {
    robot
        .read_scan_since(since, Duration::from_secs(3))
        .unwrap()
        .expect("the laser sends scans")
}

/// Moves the head to `pan`, `tilt`, waits until it has stopped there, and returns the first
/// scan measured after that.
fn scan_at(robot: &mut SimRobot, pan: u8, tilt: u8) -> LaserScan {
    let status = robot
        .move_pan_tilt_to(PanTiltPosition { pan, tilt }, 20, 1000)
        .unwrap();
    assert!(status.idle(), "{status:?}");
    assert_eq!((status.pan, status.tilt), (i16::from(pan), i16::from(tilt)));
    let now = robot.host_time();
    scan_since(robot, now)
}

fn homed(seed: u64) -> SimRobot {
    let mut robot = thesis_in(&big_room(), NoiseSettings::NONE, seed);
    robot.wait_pan_tilt_ready().unwrap();
    robot
}

#[test]
fn power_up_homing_narrates_and_ends_at_pan_zero_and_tilt_minus_twenty() {
    let robot = common::robot("thesis-roca");
    let mut twin = Twin::new(&big_room(), &robot, &NoiseSettings::NONE, 1).unwrap();
    let mut text = Vec::new();
    while twin.now() < Stamp::from_millis(20_000) && !text.ends_with(b"Listo\n") {
        twin.step();
        let board = twin.pan_tilt_board_mut().unwrap();
        text.extend(std::iter::from_fn(|| board.pop_output()).map(|(_, b)| b));
    }
    let text = String::from_utf8(text).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(
        lines,
        [
            "Sistema ROCA-PANT-TILT v1.0",
            "Girando a la derecha",
            "Se alcanzó el tope derecho",
            "Girando a la izquierda",
            "Se liberó el tope derecho",
            "Giro de 1 unidad",
            "Motor de giro apagado",
            "Hacia abajo",
            "Se alcanzó el tope inferior",
            "Hacia arriba",
            "Se liberó el tope inferior",
            "Hacia arriba 1 unidad",
            "Motor de inclinación apagado",
            "Listo",
        ]
    );
    // The head rested at pan 25°, tilt +5°: homing takes seconds, not ticks.
    assert!(twin.now() > Stamp::from_millis(3_000), "{:?}", twin.now());
    let fw = twin.pan_tilt_board().unwrap().firmware();
    assert_eq!(fw.positions(), (0, 0));
    assert_eq!(fw.motors_on(), (false, false));
    let angles = twin.head_angles_at(twin.now()).unwrap();
    assert!(
        angles.pan.to_degrees().abs() < 0.2,
        "pan {}°",
        angles.pan.to_degrees()
    );
    let tilt = angles.tilt.to_degrees();
    assert!(
        (tilt + f64::from(LEVEL) * TILT_STEP_DEG).abs() < 0.2,
        "tilt {tilt}°: about −20° at position 0"
    );
}

#[test]
fn a_move_takes_time_under_its_ramp_and_stops_on_its_position() {
    let mut robot = homed(1);
    let start = robot.host_time();
    robot.pan_tilt(PanTiltCommand::Tilt(LEVEL)).unwrap();
    let moving = robot.pan_tilt_status().unwrap();
    assert!(moving.tilt_on && !moving.pan_on);
    let done = robot
        .move_pan_tilt_to(
            PanTiltPosition {
                pan: 0,
                tilt: LEVEL,
            },
            20,
            1000,
        )
        .unwrap();
    assert!(done.idle());
    assert_eq!((done.pan, done.tilt), (0, i16::from(LEVEL)));
    let default_ramp = robot.host_time().saturating_since(start);
    // The motor cannot turn 31 times faster than the ramp's top speed (50 clicks per tick,
    // 1000 clicks per turn): at least 0.63 s.
    assert!(
        default_ramp > Duration::from_millis(630),
        "{default_ramp:?}"
    );
    let tilt = robot
        .twin()
        .head_angles_at(robot.twin().now())
        .unwrap()
        .tilt
        .to_degrees();
    assert!(
        tilt.abs() < 0.1,
        "level within a tenth of a degree: {tilt}°"
    );

    // A gentler ramp (top speed 15 clicks per tick) makes the same distance take longer.
    robot
        .pan_tilt(PanTiltCommand::TiltRamp(Ramp {
            initial: 3,
            top: 15,
            period_ms: 30,
        }))
        .unwrap();
    let start = robot.host_time();
    let done = robot
        .move_pan_tilt_to(PanTiltPosition { pan: 0, tilt: 0 }, 20, 1000)
        .unwrap();
    assert_eq!(done.tilt, 0);
    let gentle = robot.host_time().saturating_since(start);
    assert!(
        gentle > default_ramp + Duration::from_millis(500),
        "{gentle:?} vs {default_ramp:?}"
    );
    // And no move goes below the lower switch: the head is back at position 0, switch free.
    assert!(!done.lower_limit);
}

#[test]
fn the_status_line_is_the_nine_fields_of_report_status() {
    let mut robot = homed(2);
    robot.pan_tilt(PanTiltCommand::Pan(20)).unwrap();
    robot
        .wait_pan_tilt(PanTiltWait {
            max_ms: 600,
            pan: false,
            tilt: false,
        })
        .unwrap();
    let status = robot.pan_tilt_status().unwrap();
    // Mid-move: the pan counts up, clicks since the last index are even (2 per B edge).
    assert!(status.pan_on && !status.tilt_on);
    assert!((1..20).contains(&status.pan), "{status:?}");
    assert_eq!(status.pan_clicks % 2, 0);
    assert!(!status.left_limit && !status.right_limit && !status.lower_limit);
    // The same request on the raw line reads the same nine fields.
    let twin = robot.twin_mut();
    let t = twin.now();
    let board = twin.pan_tilt_board_mut().unwrap();
    board.deliver(t, b"l\n".to_vec());
    let mut reply = Vec::new();
    while !reply.ends_with(b"\n") {
        twin.step();
        let board = twin.pan_tilt_board_mut().unwrap();
        reply.extend(std::iter::from_fn(|| board.pop_output()).map(|(_, b)| b));
    }
    let reply = String::from_utf8(reply).unwrap();
    let fields: Vec<&str> = reply
        .trim_end()
        .trim_start_matches('l')
        .split(' ')
        .collect();
    assert_eq!(fields.len(), 9, "{reply:?}");
    let parsed = robot::protocol::pan_tilt::parse_status(&reply, Stamp::ZERO).unwrap();
    assert!(parsed.pan >= status.pan);
}

#[test]
fn waiting_for_both_motors_waits_its_full_time_as_the_firmware_is_written() {
    let mut robot = homed(3);
    let wait = |pan, tilt| PanTiltWait {
        max_ms: 1000,
        pan,
        tilt,
    };
    // Idle motors: waiting for the pan alone ends at once.
    let t0 = robot.host_time();
    robot.wait_pan_tilt(wait(true, false)).unwrap();
    let pan_only = robot.host_time().saturating_since(t0);
    assert!(pan_only < Duration::from_millis(100), "{pan_only:?}");
    // Waiting for both, or the tilt, takes the whole second (`check_end_wait`).
    for (pan, tilt) in [(true, true), (false, true)] {
        let t0 = robot.host_time();
        robot.wait_pan_tilt(wait(pan, tilt)).unwrap();
        let waited = robot.host_time().saturating_since(t0);
        assert!(
            waited >= Duration::from_millis(1024),
            "{pan} {tilt}: {waited:?}"
        );
    }
}

#[test]
fn a_stop_request_gets_no_answer_from_the_firmware() {
    let mut robot = homed(4);
    robot.pan_tilt(PanTiltCommand::Pan(100)).unwrap();
    let twin = robot.twin_mut();
    let t = twin.now();
    twin.pan_tilt_board_mut()
        .unwrap()
        .deliver(t, b"p\n".to_vec());
    for _ in 0..60 {
        twin.step();
    }
    let board = twin.pan_tilt_board_mut().unwrap();
    assert_eq!(board.pop_output(), None, "`do_command` has no `p`");
    assert!(
        board.firmware().motors_on().0,
        "the pan keeps moving towards its target"
    );
}

#[test]
fn out_of_range_positions_are_refused_before_sending() {
    let mut robot = homed(5);
    let err = robot.pan_tilt(PanTiltCommand::Tilt(101)).unwrap_err();
    assert_eq!(
        robot::hardware::HardwareError::kind(&err),
        robot::hardware::ErrorKind::InvalidArgument
    );
    assert!(err.to_string().contains("expected 0..=100"), "{err}");
}

#[test]
fn the_laser_pans_with_the_head() {
    // Pan 64 positions (90.7°) left: the middle beam looks at the wall at y = 10.
    let mut robot = homed(6);
    let scan = scan_at(&mut robot, 64, LEVEL);
    let frame = robot.laser_frame_at(scan.stamp).unwrap();
    let expected = (10.0 - frame.origin[1]) / frame.yaw.sin();
    assert!(
        (frame.yaw.to_degrees() - 64.0 * 360.0 / 254.0).abs() < 0.3,
        "{}",
        frame.yaw.to_degrees()
    );
    let got = scan.range_m(180).unwrap();
    assert!((got - expected).abs() < 0.002, "{got} vs {expected}");
}

#[test]
fn a_tilted_beam_hits_the_floor_where_trigonometry_says() {
    // At the home position the scan plane is tilted 20° down: a beam at angle a in the plane
    // descends at sin(tilt)·cos(a) and meets the floor after z / (sin(−tilt)·cos(a)).
    let mut robot = homed(7);
    let scan = {
        let now = robot.host_time();
        scan_since(&mut robot, now)
    };
    let frame = robot.laser_frame_at(scan.stamp).unwrap();
    let tilt = frame.tilt;
    assert!(
        (tilt.to_degrees() + 20.15).abs() < 0.2,
        "{}",
        tilt.to_degrees()
    );
    let z = frame.origin[2];
    for beam in [120usize, 150, 180, 210, 240] {
        let a = scan.angle(beam);
        let expected = z / (-tilt.sin() * a.cos());
        let got = scan.range_m(beam).unwrap();
        assert!(
            (got - expected).abs() < 0.001,
            "beam {beam}: {got} vs {expected}"
        );
    }
    // About 3 m ahead, from the nominal geometry alone: 20.15° down, the laser 45 mm ahead of
    // and 8 mm above the tilt axis (1.042 m high) in the tilting frame.
    let t = (-20.15f64).to_radians();
    let nominal = (1.042 + 0.045 * t.sin() + 0.008 * t.cos()) / -t.sin();
    assert!((scan.range_m(180).unwrap() - nominal).abs() < 0.02);
    // The beams along the tilt axis stay level: they reach the side walls 10 m away.
    assert!((scan.range_m(0).unwrap() - 10.0).abs() < 0.01);
    assert!((scan.range_m(360).unwrap() - 10.0).abs() < 0.01);
}

/// A room with a low box right in front of the laser and walls written with and without their
/// full height.
fn room(explicit_heights: bool, low_box: bool) -> sim::config::WorldDescription {
    let z = if explicit_heights {
        "z = [0.0, 2.6]"
    } else {
        ""
    };
    let mut text = format!(
        r#"
name = "room"
[start]
x = 0
y = 0
[[wall]]
points = [[-6, -4], [7, -4], [7, 5], [-6, 5]]
closed = true
{z}
[[box]]
center = [4, 2]
size = [1, 1]
{z}
"#
    );
    if low_box {
        text.push_str("[[box]]\ncenter = [2, 0]\nsize = [0.4, 3]\nz = [0.0, 0.6]\n");
    }
    world_from(&text)
}

#[test]
fn the_level_laser_sees_exactly_what_the_2d_model_saw() {
    let desc = common::robot("thesis-roca");
    let scan_in = |world: &sim::config::WorldDescription| {
        let twin = Twin::new(world, &desc, &NoiseSettings::NONE, 8).unwrap();
        let laser = twin.laser().clone();
        let map = sim::world::WorldMap::new(world);
        let frame = laser.frame_on(world.start);
        assert_eq!(frame.tilt, 0.0);
        let mut rng = sim::rng::stream(8, "laser");
        laser.scan(&map, None, frame, Stamp::ZERO, &mut rng)
    };
    let flat = scan_in(&room(false, false));
    assert_eq!(flat.ranges_mm, scan_in(&room(true, false)).ranges_mm);
    assert_eq!(
        flat.ranges_mm,
        scan_in(&room(false, true)).ranges_mm,
        "a box below the scan plane is invisible to the level laser"
    );
    // Levelled by the pan-tilt itself (within a few hundredths of a degree of tilt and pan), the
    // laser reads what the 2D model reads from the same place and heading.
    let world = room(false, true);
    let mut robot = thesis_in(&world, NoiseSettings::NONE, 8);
    robot.wait_pan_tilt_ready().unwrap();
    let levelled = scan_at(&mut robot, 0, LEVEL);
    let frame = robot.laser_frame_at(levelled.stamp).unwrap();
    assert!(frame.tilt.abs() < 0.1f64.to_radians(), "{}", frame.tilt);
    let flat_frame = sim::devices::laser::LaserFrame { tilt: 0.0, ..frame };
    let mut rng = sim::rng::stream(8, "laser");
    let in_2d = robot.twin().laser().scan(
        &sim::world::WorldMap::new(&world),
        None,
        flat_frame,
        Stamp::ZERO,
        &mut rng,
    );
    let worst = in_2d
        .ranges_mm
        .iter()
        .zip(&levelled.ranges_mm)
        .map(|(a, b)| a.abs_diff(*b))
        .max()
        .unwrap();
    assert!(worst <= 1, "worst difference {worst} mm");
    // Tilted 17° down, the same laser now sees the low box's face 1.8 m ahead, at 0.5 m.
    let tilted = scan_at(&mut robot, 0, 5);
    let frame = robot.laser_frame_at(tilted.stamp).unwrap();
    let box_face = (1.8 - frame.origin[0]) / frame.tilt.cos();
    let got = tilted.range_m(180).unwrap();
    assert!((got - box_face).abs() < 0.002, "{got} vs {box_face}");
}

#[test]
fn the_tilted_scan_scenario_writes_its_picture_with_floor_hits_where_trigonometry_says() {
    let scenario = common::scenario("tilted-scan");
    let record = sim::commands::run::run_scenario(
        &scenario,
        &sim::commands::run::RunOptions::default(),
        |_, _| {},
    )
    .unwrap();
    let head = record.pan_tilt.expect("the head was positioned");
    assert_eq!((head.pan, head.tilt), (0, 10));
    let scan = sim::output::last_tilted(&record).expect("scans were tilted");
    let frame = scan.frame;
    assert!((frame.tilt.to_degrees() + 21.0 * TILT_STEP_DEG).abs() < 0.2);
    // Every return within 3 cm of the floor lies where the floor is by trigonometry, to the
    // laser's noise (σ = 1 cm).
    let mut floor = 0;
    for i in 0..scan.scan.len() {
        let Some(range) = scan.scan.range_m(i) else {
            continue;
        };
        if frame.point(scan.scan.angle(i), range)[2].abs() < 0.03 {
            let trig = frame.origin[2] / (-frame.tilt.sin() * scan.scan.angle(i).cos());
            assert!((range - trig).abs() < 0.05, "beam {i}: {range} vs {trig}");
            floor += 1;
        }
    }
    assert!(floor > 30, "{floor} floor hits");
    let dir = std::env::temp_dir().join(format!("twin-tilted-{}", std::process::id()));
    let written = sim::output::write_all(&record, &scenario, &dir).unwrap();
    let svg = dir.join("tilted-scan.svg");
    assert!(written.files.contains(&svg));
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.contains("floor hits") && text.contains("by trigonometry"));
    // A level run writes no tilted picture.
    let level = common::scenario("orthogonal-doors");
    let record = sim::commands::run::run_scenario(
        &level,
        &sim::commands::run::RunOptions::default(),
        |_, _| {},
    )
    .unwrap();
    assert!(sim::output::last_tilted(&record).is_none());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Writes a scenario for `robot` with `pan_tilt` as its `[pan_tilt]` table, and loads it.
#[allow(clippy::result_large_err)]
fn scenario_with(
    name: &str,
    robot: &str,
    pan_tilt: &str,
) -> Result<sim::config::Scenario, sim::config::ConfigError> {
    let dir = std::env::temp_dir().join(format!("twin-pan-tilt-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let world = common::repo().join("worlds/lab.toml");
    let robot = common::repo().join("scenarios/robots").join(robot);
    let text = format!(
        "name = \"{name}\"\nworld = {world:?}\nrobot = {robot:?}\nseed = 1\n\n{pan_tilt}\n\n[script]\nsteps = [\"pause 1\"]\n"
    );
    let path = dir.join("scenario.toml");
    std::fs::write(&path, text).unwrap();
    sim::config::Scenario::load(&path)
}

#[test]
fn bad_pan_tilt_settings_name_their_field() {
    let err = scenario_with("tilt", "thesis-roca.toml", "[pan_tilt]\ntilt = 101").unwrap_err();
    assert_eq!(err.field.as_deref(), Some("pan_tilt.tilt"), "{err}");
    assert!(err.message.contains("0..=100"), "{err}");
    let err = scenario_with("pan", "thesis-roca.toml", "[pan_tilt]\npan = 300").unwrap_err();
    assert_eq!(err.field.as_deref(), Some("pan_tilt.pan"), "{err}");
    let err = scenario_with("none", "pioneer-3dx.toml", "[pan_tilt]\ntilt = 10").unwrap_err();
    assert!(err.message.contains("has no pan-tilt"), "{err}");
    // Defaults: pan 0, the robot's level position.
    let s = scenario_with("default", "thesis-roca.toml", "").unwrap();
    assert_eq!(
        s.pan_tilt,
        Some(PanTiltPosition {
            pan: 0,
            tilt: LEVEL
        })
    );
    // A robot whose laser rides on the pan-tilt must not also give a fixed mount.
    let text = std::fs::read_to_string(common::repo().join("scenarios/robots/thesis-roca.toml"))
        .unwrap()
        .replace(
            "[laser]                       # LMS209-S02; it rides on the pan-tilt, which gives its position\n",
            "[laser]\nz_m = 1.0\n",
        );
    let err = sim::config::RobotDescription::parse(&text, "robot.toml").unwrap_err();
    assert_eq!(err.field.as_deref(), Some("laser.z_m"), "{err}");
    assert!(err.message.contains("rides on the pan-tilt"), "{err}");
}
