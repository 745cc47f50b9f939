//! Sensor throughput: laser scans per second and sonar ring cycles per second.
//!
//! - laser: 361 beams traced in 3D against the world's faces, caps, floor and ceiling, with the
//!   materials' optics (black loss, glass windows and mirrors, metal, grazing loss), Gaussian
//!   noise and, where named, the random outliers of the thesis's studies; from poses all over
//!   `worlds/lab.toml` (and `worlds/glass-door.toml`), level and tilted;
//! - sonar: one cycle of the ring, 16 transducers each sampling its cone with several rays,
//!   specular loss and multi-bounce paths.
//!
//! `cargo bench --bench laser`

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use robot::{Pose2, Stamp};
use sim::config::Outliers;
use sim::config::{RobotDescription, WorldDescription};
use sim::devices::laser::{LaserFrame, LaserModel};
use sim::devices::sonar::SonarModel;
use sim::world::WorldMap;
use std::hint::black_box;
use std::path::{Path, PathBuf};

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

fn laser(robot: &RobotDescription, outliers: &str) -> LaserModel {
    LaserModel::new(
        &robot.laser,
        robot.laser_mount(),
        robot.laser.sigma_m.get(),
        Outliers::preset(outliers).expect("a preset"),
    )
}

fn scans(c: &mut Criterion) {
    let pioneer = RobotDescription::load(root().join("scenarios/robots/pioneer-3dx.toml")).unwrap();
    let mut group = c.benchmark_group("laser");
    group.throughput(Throughput::Elements(1));
    for (world_file, outliers, tilt_deg) in [
        ("lab.toml", "none", 0.0f64),
        ("lab.toml", "thesis-2pct", 0.0),
        ("lab.toml", "thesis-20pct", 0.0),
        ("glass-door.toml", "thesis-2pct", 0.0),
        ("lab.toml", "thesis-2pct", -13.65),
    ] {
        let world = WorldDescription::load(root().join("worlds").join(world_file)).unwrap();
        let map = WorldMap::new(&world);
        let poses = poses(&map, &world);
        let model = laser(&pioneer, outliers);
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
                        tilt: f64::to_radians(tilt_deg),
                        ..level
                    }
                }
            })
            .collect();
        let mut k = 0usize;
        let mut rng = sim::rng::stream(1, "bench");
        let name = if tilt_deg == 0.0 {
            format!("{world_file} scan, materials, outliers {outliers}")
        } else {
            format!("{world_file} scan tilted {tilt_deg}°, materials, outliers {outliers}")
        };
        group.bench_function(name, |b| {
            b.iter(|| {
                k = (k + 1) % frames.len();
                black_box(model.scan(&map, None, frames[k], Stamp(k as u64), &mut rng))
            })
        });
    }
    group.finish();
}

fn sonar_ring(c: &mut Criterion) {
    let robot = RobotDescription::load(root().join("scenarios/robots/pioneer-3dx.toml")).unwrap();
    let world = WorldDescription::load(root().join("worlds/lab.toml")).unwrap();
    let map = WorldMap::new(&world);
    let poses = poses(&map, &world);
    let ring = SonarModel::new(robot.sonar.as_ref().expect("the Pioneer has a ring"));
    let mut group = c.benchmark_group("sonar");
    group.throughput(Throughput::Elements(1));
    let mut k = 0usize;
    let mut rng = sim::rng::stream(1, "bench");
    group.bench_function("lab.toml ring cycle, 16 transducers", |b| {
        b.iter(|| {
            k = (k + 1) % poses.len();
            for s in 0..ring.len() {
                black_box(ring.echo(&map, poses[k], s, &mut rng));
            }
        })
    });
    group.finish();
}

criterion_group!(benches, scans, sonar_ring);
criterion_main!(benches);
