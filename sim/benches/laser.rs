//! Laser scans per second in `worlds/lab.toml`: 361 beams ray-cast with parry against the lab's
//! walls and furniture, millimetre readings with Gaussian noise, from poses all over the lab.
//!
//! `cargo bench --bench laser`

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use robot::{Pose2, Stamp};
use sim::config::{RobotDescription, WorldDescription};
use sim::laser::LaserModel;
use sim::laser::outliers::Outliers;
use sim::world_map::WorldMap;
use std::hint::black_box;
use std::path::Path;

fn scans(c: &mut Criterion) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let world = WorldDescription::load(root.join("worlds/lab.toml")).unwrap();
    let robot = RobotDescription::load(root.join("scenarios/robots/pioneer-3dx.toml")).unwrap();
    let map = WorldMap::new(&world);
    let laser = LaserModel::new(
        &robot.laser,
        robot.laser_mount(),
        robot.laser.sigma_m.get(),
        Outliers::NONE,
    );
    // Poses on a grid over both labs and the corridor, away from walls.
    let poses: Vec<Pose2> = (0..8)
        .flat_map(|i| (0..4).map(move |j| (i, j)))
        .map(|(i, j)| {
            Pose2::new(
                1.0 + 1.9 * f64::from(i),
                1.2 + 1.7 * f64::from(j),
                0.7 * f64::from(i + j),
            )
        })
        .filter(|p| map.clearance([p.x, p.y]) > 0.3)
        .collect();
    let mut group = c.benchmark_group("laser");
    group.throughput(Throughput::Elements(1));
    let mut k = 0usize;
    let mut rng = sim::rng::stream(1, "bench");
    group.bench_function("lab.toml scan, 361 beams, noise", |b| {
        b.iter(|| {
            k = (k + 1) % poses.len();
            black_box(laser.scan(
                &map,
                None,
                laser.frame_on(poses[k]),
                Stamp(k as u64),
                &mut rng,
            ))
        })
    });
    group.finish();
}

criterion_group!(benches, scans);
criterion_main!(benches);
