//! Sensor throughput: laser scans per second and sonar ring cycles per second, each beside a
//! reference measured in the same run, interleaved, so the ratios travel between machines.
//!
//! - laser: 361 beams traced in 3D against the world's faces, caps, floor and ceiling, with the
//!   materials' optics (black loss, glass windows and mirrors, metal, grazing loss), Gaussian
//!   noise and, where named, the random outliers of the thesis's studies; from poses all over
//!   the world, level and tilted. `scan` casts the beams' first legs in one sweep of the faces
//!   (`WorldMap::cast_plane_fan`); the reference, `Casting::PerBeam`, casts each beam down the
//!   world's tree — the same readings, bit for bit (tests/issue_17_fast_laser.rs);
//! - sonar: one cycle of the ring, 16 transducers each sampling its cone with several rays,
//!   specular loss and multi-bounce paths; the reference is the same ring with every ray cast on
//!   its own to its end.
//!
//! The sweep is also measured as compiled for AVX2 (`Casting::SweepAvx2`) and for the baseline
//! x86-64 processor (`Casting::SweepBaseline`): the default picks an AVX-512 build where the
//! processor has one, else an AVX2 one (`sim/src/wide.rs`), with the same readings. In a world
//! no fan is swept or walked in (`WorldMap::casts_fans`: the 1430 faces traced from the map) the
//! default takes the reference's way, and only those two columns measure the sweep's code.
//!
//! Beside them, the sweep's geometry alone (`cast_plane_fan` and each beam's first surface, no
//! optics, no noise): the ray-casting limit a whole scan is measured against.
//!
//! The last two worlds are made from images: walls traced around the lab tour's occupancy map
//! (`worlds/lab-from-map.toml`) and around the lab drawn as a Stage bitmap with a palette
//! (`worlds/lab-stage.toml`), to compare with the hand-written lab.
//!
//! Figures are the best of 15 rounds (the least disturbed by the machine's other work).
//!
//! `cargo bench --bench laser`

use robot::{Pose2, Stamp};
use sim::config::Outliers;
use sim::config::{RobotDescription, WorldDescription};
use sim::devices::laser::{Casting, LaserFrame, LaserModel};
use sim::devices::sonar::SonarModel;
use sim::world::{FanCast, WorldMap};
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Instant;

const ROUNDS: usize = 15;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Poses on a grid over the world, away from walls.
fn poses(map: &WorldMap, world: &WorldDescription) -> Vec<Pose2> {
    let (min, max) = world.bounds();
    (0..8)
        .flat_map(|i| (0..6).map(move |j| (i, j)))
        .map(|(i, j)| {
            Pose2::new(
                min[0] + (max[0] - min[0]) * (f64::from(i) + 0.5) / 8.0,
                min[1] + (max[1] - min[1]) * (f64::from(j) + 0.5) / 6.0,
                0.7 * f64::from(i + j),
            )
        })
        .filter(|p| map.clearance([p.x, p.y]) > 0.3)
        .collect()
}

/// Seconds per call of `f` (called `n` times a round), best of [`ROUNDS`], for two functions
/// measured in alternate rounds.
fn best_of(n: usize, mut a: impl FnMut(usize), mut b: impl FnMut(usize)) -> (f64, f64) {
    let (mut ta, mut tb) = (f64::MAX, f64::MAX);
    for _ in 0..ROUNDS {
        let t = Instant::now();
        (0..n).for_each(&mut a);
        ta = ta.min(t.elapsed().as_secs_f64() / n as f64);
        let t = Instant::now();
        (0..n).for_each(&mut b);
        tb = tb.min(t.elapsed().as_secs_f64() / n as f64);
    }
    (ta, tb)
}

fn main() {
    let pioneer = RobotDescription::load(root().join("scenarios/robots/pioneer-3dx.toml")).unwrap();
    let lab_text = std::fs::read_to_string(root().join("worlds/lab.toml")).unwrap();
    println!(
        "The sweep's default build on this processor: {}.\n",
        if sim::wide::avx512() {
            "AVX-512"
        } else if sim::wide::avx2() {
            "AVX2"
        } else {
            "baseline"
        }
    );
    println!(
        "| world | scan | first surfaces only, scans/s | sweep, scans/s | sweep, AVX2 build, scans/s | sweep, baseline build, scans/s | reference, scans/s | speed-up | speed-up, baseline build |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let cluttered = sim::world::clutter::lab_with_boxes(&lab_text, 72);
    let worlds = [
        (
            "lab",
            WorldDescription::load(root().join("worlds/lab.toml")).unwrap(),
        ),
        (
            "glass door",
            WorldDescription::load(root().join("worlds/glass-door.toml")).unwrap(),
        ),
        (
            "lab + 72 boxes",
            WorldDescription::parse(&cluttered, "lab-80.toml").unwrap(),
        ),
        (
            "lab from its map",
            WorldDescription::load(root().join("worlds/lab-from-map.toml")).unwrap(),
        ),
        (
            "lab from a Stage bitmap",
            WorldDescription::load(root().join("worlds/lab-stage.toml")).unwrap(),
        ),
    ];
    for (name, world) in &worlds {
        let map = WorldMap::new(world);
        let poses = poses(&map, world);
        for (outliers, tilt_deg) in [
            ("none", 0.0f64),
            ("thesis-2pct", 0.0),
            ("thesis-20pct", 0.0),
            ("thesis-2pct", -13.65),
        ] {
            if *name != "lab" && (outliers != "thesis-2pct" || tilt_deg != 0.0) {
                continue;
            }
            let model = LaserModel::new(
                &pioneer.laser,
                pioneer.laser_mount(),
                pioneer.laser.sigma_m.get(),
                Outliers::preset(outliers).expect("a preset"),
            );
            let reference = model.clone().with_casting(Casting::PerBeam);
            // Tilted: the thesis robot's laser height on its pan-tilt, the plane pitched down.
            let frames: Vec<LaserFrame> = poses
                .iter()
                .map(|&p| {
                    let level = model.frame_on(p);
                    if tilt_deg == 0.0 {
                        level
                    } else {
                        LaserFrame {
                            origin: [level.origin[0], level.origin[1], 1.05],
                            tilt: tilt_deg.to_radians(),
                            ..level
                        }
                    }
                })
                .collect();
            // The first surface of every beam and nothing else: what the geometry alone costs.
            let mut fan = FanCast::default();
            let (geometry, _) = best_of(
                2000,
                |k| {
                    let f = frames[k % frames.len()];
                    let range = model.range_max_m();
                    map.cast_plane_fan(f.origin, f.axes(), model.beams(), range, &mut fan);
                    for j in 0..fan.len() {
                        black_box(fan.hit(&map, j));
                    }
                },
                |_| {},
            );
            let mut rng = sim::rng::stream(1, "bench");
            let mut rng2 = sim::rng::stream(1, "bench");
            let (sweep, reference) = best_of(
                2000,
                |k| {
                    let f = frames[k % frames.len()];
                    black_box(model.scan(&map, None, f, Stamp(k as u64), &mut rng));
                },
                |k| {
                    let f = frames[k % frames.len()];
                    black_box(reference.scan(&map, None, f, Stamp(k as u64), &mut rng2));
                },
            );
            // The same sweep compiled for the baseline x86-64 processor (no AVX2) and for AVX2
            // (where the default is an AVX-512 build).
            let other_build = |casting: Casting| {
                let built = model.clone().with_casting(casting);
                let mut rng = sim::rng::stream(1, "bench");
                best_of(
                    2000,
                    |k| {
                        let f = frames[k % frames.len()];
                        black_box(built.scan(&map, None, f, Stamp(k as u64), &mut rng));
                    },
                    |_| {},
                )
                .0
            };
            let baseline = other_build(Casting::SweepBaseline);
            let avx2 = other_build(Casting::SweepAvx2);
            let what = if tilt_deg == 0.0 {
                format!("level, outliers {outliers}")
            } else {
                format!("tilted {tilt_deg}°, outliers {outliers}")
            };
            println!(
                "| {name} ({} faces) | {what} | {:.0} | {:.0} | {:.0} | {:.0} | {:.0} | {:.2} | {:.2} |",
                map.faces().len(),
                1.0 / geometry,
                1.0 / sweep,
                1.0 / avx2,
                1.0 / baseline,
                1.0 / reference,
                reference / sweep,
                reference / baseline,
            );
        }
    }
    sonar_ring();
}

fn sonar_ring() {
    let robot = RobotDescription::load(root().join("scenarios/robots/pioneer-3dx.toml")).unwrap();
    let world = WorldDescription::load(root().join("worlds/lab.toml")).unwrap();
    let map = WorldMap::new(&world);
    let poses = poses(&map, &world);
    let ring = SonarModel::new(robot.sonar.as_ref().expect("the Pioneer has a ring"));
    let mut rng = sim::rng::stream(1, "bench");
    let mut rng2 = sim::rng::stream(1, "bench");
    let (ring_s, reference) = best_of(
        2000,
        |k| {
            for s in 0..ring.len() {
                black_box(ring.echo(&map, poses[k % poses.len()], s, &mut rng));
            }
        },
        |k| {
            for s in 0..ring.len() {
                black_box(ring.echo_per_ray(&map, poses[k % poses.len()], s, &mut rng2));
            }
        },
    );
    println!();
    println!("| sonar | cycles/s | reference, cycles/s | speed-up |");
    println!("|---|---|---|---|");
    println!(
        "| lab, ring of {} | {:.0} | {:.0} | {:.2} |",
        ring.len(),
        1.0 / ring_s,
        1.0 / reference,
        reference / ring_s
    );
}
