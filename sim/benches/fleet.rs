//! Many robots in one world (`sim::twin::fleet`): wall-clock seconds per simulated second for
//! fleets of 1, 10 and 100 Pioneers in the lab, each on an arc of its own with every laser scan
//! measured, on one thread and on every thread of the machine — with the results checked equal.
//!
//! Beside each figure, its ratio to a reference measured in the same run (one level scan of the
//! lab cast by brute force), so the table travels between machines.
//!
//! `cargo bench --bench fleet`

use robot::Stamp;
use sim::config::{NoiseSettings, RobotDescription, WorldDescription};
use sim::twin::fleet::{Fleet, grid_starts};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

#[path = "common/reference.rs"]
mod reference;

/// Simulated seconds per run.
const SECONDS: f64 = 10.0;

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let world = WorldDescription::load(root.join("worlds/lab.toml")).unwrap();
    let robot = RobotDescription::load(root.join("scenarios/robots/pioneer-3dx.toml")).unwrap();
    let noise = NoiseSettings::defaults_for(&robot);
    let reference = reference::brute_force_scan_seconds(&world);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!(
        "reference: one level scan of the lab by brute force: {:.1} µs; {cores} threads",
        reference * 1e6
    );
    println!();
    println!(
        "| robots | threads | scans | wall s per simulated s | per robot | ratio to the reference, per robot | speed-up |"
    );
    println!("|---|---|---|---|---|---|---|");
    for n in [1usize, 10, 100] {
        let starts = grid_starts(&world, n, 0.8, robot.body.radius_m.get());
        assert_eq!(starts.len(), n, "the lab has room for {n} robots");
        let mut single = None;
        for threads in [1, cores] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut fleet = Fleet::new(&world, &robot, &noise, 1, &starts).unwrap();
            for (k, twin) in fleet.robots_mut().iter_mut().enumerate() {
                let line = format!("v{} {}\n", 150 + 5 * (k % 7), 130 + 5 * (k % 5));
                twin.board_mut().deliver(Stamp::ZERO, line.into_bytes());
            }
            let steps = (SECONDS / sim::twin::STEP.as_secs_f64()).ceil() as usize;
            let scans = AtomicU64::new(0);
            let digest = AtomicU64::new(0);
            let t = Instant::now();
            pool.install(|| {
                for _ in 0..steps {
                    fleet.step(|k, twin| {
                        while let Some((_, scan)) = twin.pop_scan() {
                            scans.fetch_add(1, Ordering::Relaxed);
                            let sum: u64 = scan.ranges_mm.iter().map(|&r| u64::from(r)).sum();
                            digest.fetch_add(sum.wrapping_mul(k as u64 + 1), Ordering::Relaxed);
                        }
                    });
                }
            });
            let wall = t.elapsed().as_secs_f64() / SECONDS;
            let result = (
                digest.into_inner(),
                fleet
                    .robots()
                    .iter()
                    .map(|t| t.true_pose())
                    .collect::<Vec<_>>(),
            );
            let speed_up = match &single {
                None => {
                    single = Some((wall, result));
                    1.0
                }
                Some((one, same)) => {
                    assert_eq!(
                        same, &result,
                        "{n} robots: the same bits on {threads} threads"
                    );
                    one / wall
                }
            };
            println!(
                "| {n} | {threads} | {} | {wall:.4} | {:.5} | {:.0} | {speed_up:.2} |",
                scans.into_inner(),
                wall / n as f64,
                wall / n as f64 / reference
            );
        }
    }
}
