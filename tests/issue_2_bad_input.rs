//! Bad input gets a clear error naming the file, the line and the field, never a panic: malformed
//! worlds and scenarios, a robot that does not fit its start, out-of-range commands, and the
//! `twin` binary's report of all of these.

use crate::common::*;
use robot::hardware::{DriveBase, DriveCommand, ErrorKind, HardwareError, Ramp};
use sim::config::{NoiseSettings, Scenario, WorldDescription};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Writes `files` (name, text) into a fresh folder and returns it.
fn folder(name: &str, files: &[(&str, &str)]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("twin-bad-input-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for (file, text) in files {
        std::fs::write(dir.join(file), text).unwrap();
    }
    dir
}

const WORLD: &str = r#"name = "box"
[start]
x = 1.0
y = 1.0
[[wall]]
points = [[0, 0], [4, 0], [4, 3], [0, 3]]
closed = true
"#;

fn scenario_text(steps: &str) -> String {
    let robot = repo().join("scenarios/robots/pioneer-3dx.toml");
    format!(
        "name = \"bad\"\nworld = \"world.toml\"\nrobot = {robot:?}\nseed = 1\n\n[script]\nsteps = [{steps}]\n"
    )
}

#[test]
fn a_world_with_a_wrongly_typed_coordinate_names_line_and_field() {
    let text = WORLD.replace("y = 1.0", "y = \"one\"");
    let err = WorldDescription::parse(&text, "worlds/box.toml").unwrap_err();
    let message = err.to_string();
    assert!(message.starts_with("worlds/box.toml:4:"), "{message}");
    assert!(message.contains("y = \"one\""), "{message}");
    assert_eq!(err.field.as_deref(), Some("start.y"));
}

#[test]
fn a_world_with_an_unknown_key_names_it() {
    let text = WORLD.replace("closed = true", "closed = true\ncolour = \"red\"");
    let err = WorldDescription::parse(&text, "box.toml").unwrap_err();
    assert_eq!(err.line, Some(8), "{err}");
    assert!(err.message.contains("unknown field `colour`"), "{err}");
}

#[test]
fn a_start_pose_inside_a_wall_names_the_world_file() {
    let text = WORLD.replace("x = 1.0", "x = 0.1");
    let world = WorldDescription::parse(&text, "worlds/box.toml").unwrap();
    let err = sim::Twin::new(&world, &robot("pioneer-3dx"), &NoiseSettings::NONE, 1)
        .err()
        .expect("refused");
    assert_eq!(err.path, Path::new("worlds/box.toml"));
    assert_eq!(err.field.as_deref(), Some("start"));
    assert!(err.message.contains("overlaps a wall"), "{err}");
}

#[test]
fn a_scenario_with_a_bad_step_names_the_step_and_its_line() {
    let dir = folder(
        "bad-step",
        &[
            ("world.toml", WORLD),
            ("s.toml", &scenario_text("\"move 0.5\", \"jump 3\"")),
        ],
    );
    let err = Scenario::load(dir.join("s.toml")).unwrap_err();
    assert_eq!(err.field.as_deref(), Some("script.steps[1]"), "{err}");
    assert_eq!(err.line, Some(7), "{err}");
    assert!(
        err.message.contains("unknown drive command letter `j`"),
        "{err}"
    );
}

#[test]
fn a_scenario_with_an_out_of_range_command_says_what_was_expected() {
    let dir = folder(
        "range",
        &[
            ("world.toml", WORLD),
            ("s.toml", &scenario_text("\"k5 120 50\"")),
        ],
    );
    let err = Scenario::load(dir.join("s.toml")).unwrap_err();
    assert!(
        err.message
            .contains("argument 2 (Pf) is \"120\": expected a whole number 0..=90"),
        "{err}"
    );
}

#[test]
fn a_scenario_naming_a_missing_world_points_at_its_own_line() {
    let dir = folder("missing", &[("s.toml", &scenario_text("\"move 0.5\""))]);
    let err = Scenario::load(dir.join("s.toml")).unwrap_err();
    assert_eq!(err.path, dir.join("s.toml"));
    assert_eq!(
        (err.line, err.field.as_deref()),
        (Some(2), Some("world")),
        "{err}"
    );
    assert!(err.message.contains("world.toml"), "{err}");
}

#[test]
fn an_unknown_pacing_is_refused() {
    let text = scenario_text("\"move 0.5\"") + "\n[tour]\npacing = \"sprint\"\n";
    let dir = folder("pacing", &[("world.toml", WORLD), ("s.toml", &text)]);
    let err = Scenario::load(dir.join("s.toml")).unwrap_err();
    assert_eq!(err.field.as_deref(), Some("tour.pacing"), "{err}");
    assert!(
        err.message.contains("\"stop-and-go\" or \"polling\""),
        "{err}"
    );
}

#[test]
fn out_of_range_commands_are_refused_before_anything_is_sent() {
    let mut r = pioneer_in(&big_room(), NoiseSettings::NONE, 1);
    let before = r.host_time();
    let err = r
        .drive(DriveCommand::WheelSpeeds { left: 95, right: 0 })
        .unwrap_err();
    assert_eq!(err.kind(), ErrorKind::InvalidArgument);
    assert!(err.to_string().contains("`v` argument left = 95"), "{err}");
    let err = r
        .set_ramp(Ramp {
            initial: 91,
            top: 30,
            period_ms: 50,
        })
        .unwrap_err();
    assert_eq!(err.kind(), ErrorKind::InvalidArgument);
    assert_eq!(r.host_time(), before, "nothing went on the wire");
}

#[test]
fn the_binary_reports_a_bad_scenario_and_fails() {
    let dir = folder(
        "binary",
        &[
            ("world.toml", WORLD),
            ("s.toml", &scenario_text("\"move 0.5\", \"turn left\"")),
        ],
    );
    let out = Command::new(env!("CARGO_BIN_EXE_twin"))
        .args(["run", "s.toml", "--out", "out"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("s.toml:7:"), "{stderr}");
    assert!(stderr.contains("script.steps[1]"), "{stderr}");
    assert!(
        stderr.contains("`turn` needs one finite number"),
        "{stderr}"
    );
    assert!(!dir.join("out").exists(), "nothing written");
}

#[test]
fn the_binary_refuses_a_missing_scenario_file() {
    let out = Command::new(env!("CARGO_BIN_EXE_twin"))
        .args(["run", "no-such-scenario.toml"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("no-such-scenario.toml: cannot read the file"),
        "{stderr}"
    );
}
