//! The laser lies like a real one, seen through the hardware contract: mirror paths through glass
//! and off metal, the robot seen in a mirror, black surfaces lost at oblique incidence, and random
//! outliers at the rate configured (checked against the binomial 99.9 % interval); and the
//! glass-door run, whose picture shows the ghost points behind the glass.

use crate::common;

use crate::common::*;
use robot::hardware::{Laser, LaserScan};
use sim::config::NoiseSettings;
use sim::config::Outliers;
use std::time::Duration;

fn scan(robot: &mut sim::SimRobot) -> LaserScan {
    robot
        .read_scan(Duration::from_secs(2))
        .unwrap()
        .expect("the laser sends scans")
}

/// The Pioneer at the origin facing +x, in a world made of `walls` (TOML), with `optics`.
fn facing(walls: &str, optics: &str, noise: NoiseSettings) -> sim::SimRobot {
    let text = format!("name = \"test\"\n[start]\nx = 0\ny = 0\n{walls}\n[optics]\n{optics}\n");
    pioneer_in(&world_from(&text), noise, 4)
}

/// The laser's position: 18 mm ahead of the axle (`LaserX` of the Pioneer).
const LASER_X: f64 = 0.018;

#[test]
fn a_mirror_reading_is_the_glass_distance_plus_the_reflected_distance() {
    // A pane of glass that always mirrors, along x = 2; a matte wall along y = 4 behind the robot's
    // side of the pane.
    let mut robot = facing(
        r#"
[[wall]]
material = "glass"
points = [[2, -5], [2, 10]]
[[wall]]
points = [[-5, 4], [1.9, 4]]
"#,
        "glass_transparent = 0.0",
        NoiseSettings::NONE,
    );
    let s = scan(&mut robot);
    // Beam 270 points at +45°: it meets the glass after (2 − x0)·√2, at y = 2 − x0, then travels
    // up-left to y = 4, another (4 − (2 − x0))·√2.
    let to_glass = (2.0 - LASER_X) * 2f64.sqrt();
    let beyond = (4.0 - (2.0 - LASER_X)) * 2f64.sqrt();
    let got = s.range_m(270).unwrap();
    assert!(
        (got - (to_glass + beyond)).abs() <= 0.0006,
        "{got} vs {}",
        to_glass + beyond
    );
    // Head-on (beam 180) the glass returns the pulse itself.
    assert_eq!(
        s.ranges_mm[180],
        ((2.0 - LASER_X) * 1000.0f64).round() as u16
    );
}

#[test]
fn the_robot_sees_itself_in_a_perfect_mirror() {
    let mut robot = facing(
        r#"
[[wall]]
material = "metal"
points = [[1.5, -5], [1.5, 5]]
"#,
        "metal_return_deg = 0",
        NoiseSettings::NONE,
    );
    let s = scan(&mut robot);
    let desc = common::robot("pioneer-3dx");
    let front = desc.body.center_x_m.get() + desc.body.radius_m.get();
    // Straight ahead the pulse returns to the robot and meets the front of its own body.
    let expected = (1.5 - LASER_X) + (1.5 - front);
    let got = s.range_m(180).unwrap();
    assert!((got - expected).abs() <= 0.0006, "{got} vs {expected}");
}

#[test]
fn a_black_wall_is_seen_head_on_and_lost_at_sixty_degrees() {
    let mut robot = facing(
        r#"
[[wall]]
material = "black"
points = [[2, -10], [2, 10]]
"#,
        "",
        NoiseSettings::NONE,
    );
    for _ in 0..10 {
        let s = scan(&mut robot);
        // Beam 180 meets the wall head-on; beams 60 and 300 (∓60°) meet it at 60° incidence.
        assert_eq!(s.range_m(180), Some(2.0 - LASER_X));
        assert_eq!(s.range_m(60), None);
        assert_eq!(s.range_m(300), None);
    }
}

/// Counts readings more than `delta` from the noiseless ones over `scans` scans, and the count
/// expected if each beam is a uniform outlier with probability `rate`.
fn outliers_seen_and_expected(rate: f64, scans: usize) -> (usize, f64, f64) {
    let room = r#"
[[wall]]
points = [[-3, -2], [4, -2], [4, 2.5], [-3, 2.5]]
closed = true
"#;
    let truth = scan(&mut facing(room, "", NoiseSettings::NONE));
    let noise = NoiseSettings {
        outliers: Outliers {
            uniform: rate,
            ..Outliers::NONE
        },
        ..NoiseSettings::NONE
    };
    let mut robot = facing(room, "", noise);
    let delta = 0.05;
    let range_max = 32.0;
    let mut seen = 0;
    let mut mean = 0.0;
    let mut variance = 0.0;
    for _ in 0..scans {
        let s = scan(&mut robot);
        for (i, &mm) in s.ranges_mm.iter().enumerate() {
            let r = f64::from(truth.ranges_mm[i]) / 1000.0;
            if (f64::from(mm) / 1000.0 - r).abs() > delta {
                seen += 1;
            }
            // A uniform outlier lands within ±delta of the truth with this chance.
            let hidden = ((r + delta).min(range_max) - (r - delta).max(0.0)) / range_max;
            let p = rate * (1.0 - hidden);
            mean += p;
            variance += p * (1.0 - p);
        }
    }
    (seen, mean, variance.sqrt())
}

#[test]
fn outlier_rates_fall_inside_the_binomial_interval() {
    // 277 scans of 361 beams: 99,997 beams per rate.
    for rate in [0.02, 0.20] {
        let (seen, mean, sd) = outliers_seen_and_expected(rate, 277);
        // Two-sided 99.9 %: within 3.29 standard deviations.
        let lo = mean - 3.29 * sd;
        let hi = mean + 3.29 * sd;
        assert!(
            (lo..=hi).contains(&(seen as f64)),
            "rate {rate}: {seen} outliers seen, expected {mean:.0} in [{lo:.0}, {hi:.0}]"
        );
    }
}

#[test]
fn readings_stay_in_the_valid_range_whatever_the_noise() {
    // A wall 2 cm from the laser and 1 m of noise: readings are clamped, never negative or
    // wrapped, and never the no-return value when the pulse came back.
    let noise = NoiseSettings {
        laser_sigma_m: 1.0,
        ..NoiseSettings::NONE
    };
    let mut robot = facing(
        r#"
[[wall]]
points = [[0.3, -5], [0.3, 5]]
"#,
        "",
        noise,
    );
    for _ in 0..5 {
        let s = scan(&mut robot);
        let head_on = s.ranges_mm[180];
        assert!(head_on < 32_000, "{head_on}");
        assert!(s.ranges_mm.iter().all(|&mm| mm <= 32_000));
    }
}

#[test]
fn the_glass_door_run_draws_ghost_points_behind_the_glass() {
    let scenario = scenario("glass-door");
    let record = sim::commands::run::run_scenario(
        &scenario,
        &sim::commands::run::RunOptions::default(),
        |_, _| {},
    )
    .unwrap();
    // Points placed from the true laser frame that lie far from every surface: where the glass
    // mirrored the pulse, they land behind the pane (the room, y > 2.4 m).
    let map = sim::world::WorldMap::new(&scenario.world);
    let (mut ghosts, mut behind) = (0, 0);
    for r in &record.scans {
        for i in 0..r.scan.len() {
            let Some(range) = r.scan.range_m(i) else {
                continue;
            };
            let p = r.frame.point(r.scan.angle(i), range);
            if map.distance_3d(p) > 0.15 {
                ghosts += 1;
                if p[1] > 2.4 {
                    behind += 1;
                }
            }
        }
    }
    assert!(ghosts > 100, "{ghosts} ghost points");
    assert!(
        behind * 10 > ghosts * 9,
        "{behind} of {ghosts} behind the glass"
    );
    let dir = std::env::temp_dir().join(format!("twin-glass-door-{}", std::process::id()));
    sim::output::write_all(&record, &scenario, &dir).unwrap();
    let svg = std::fs::read_to_string(dir.join("map.svg")).unwrap();
    let ghost_path = svg
        .lines()
        .find(|l| l.contains(r#"<g data-layer="ghosts">"#))
        .expect("a ghost layer");
    assert!(
        svg.contains(r#"<g data-legend="ghosts">"#),
        "listed in the legend"
    );
    // A dot is a move and a segment of no length.
    assert!(
        ghost_path.matches("h0").count() > 50,
        "the ghost layer has points"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
