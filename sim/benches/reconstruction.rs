//! 3D reconstruction speed (issue 13), on one core:
//!
//! - **one scene**: its 100 scans × 361 readings put in 3D through Eq. 4.1, meshed with the
//!   thesis's rule (quadrilaterals and triangles counted), normals per vertex, merged into a
//!   model — target ≤ 0.5 ms; timed in the steady state (the scene and the model rebuilt into
//!   the memory of the last ones, as a robot reconstructing scene after scene does) and, for
//!   comparison, in fresh memory (which adds the kernel's page faults);
//! - **scoring** the merged model of `survey-lab` (8 scenes, about 250,000 vertices) against the
//!   true surfaces: point error, phantom area, coverage, seam — target ≤ 50 ms;
//! - **survey-lab end to end**: simulation, reconstruction in three placements, scoring, and
//!   every output file — target a real-time factor ≥ 1000×.
//!
//! Each figure is also given as a ratio to a reference workload timed in the same run (sorting
//! one million pseudo-random `f64`), so figures from different machines can be compared.
//!
//! `cargo bench --bench reconstruction`

use robot::reconstruction::{MeshOptions, MeshRule, Model, Scene, SceneScan};
use sim::commands::run::{RunOptions, run_scenario};
use sim::config::Scenario;
use sim::world::WorldMap;
use sim::world::score::score;
use std::hint::black_box;
use std::path::Path;
use std::time::{Duration, Instant};

/// The median of `runs` timings of `f`, after one warm-up.
fn median_time(runs: usize, f: impl FnMut()) -> Duration {
    time_spread(runs, f).0
}

/// The median and the fastest of `runs` timings of `f`, after one warm-up.
fn time_spread(runs: usize, mut f: impl FnMut()) -> (Duration, Duration) {
    f();
    let mut times: Vec<Duration> = (0..runs)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed()
        })
        .collect();
    times.sort();
    (times[runs / 2], times[0])
}

/// The reference: sorting a million pseudo-random numbers.
fn reference() -> Duration {
    let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
    let values: Vec<f64> = (0..1_000_000)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64
        })
        .collect();
    median_time(15, || {
        let mut v = values.clone();
        v.sort_unstable_by(f64::total_cmp);
        black_box(v);
    })
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios");
    let reference = reference();
    println!("reference (sort 1,000,000 f64): {:.2} ms", ms(reference));
    let ratio = |d: Duration| d.as_secs_f64() / reference.as_secs_f64();

    // One scene: the scans of scene-lab, as the robot received them.
    let scenario = Scenario::load(root.join("scene-lab.toml")).unwrap();
    let record = run_scenario(&scenario, &RunOptions::default(), |_, _| {}).unwrap();
    let mount = scenario.robot.mount();
    let scans: Vec<_> = record.scans.iter().filter(|r| r.scene.is_some()).collect();
    let tag = scans[0].scene.unwrap();
    let rows: Vec<SceneScan<'_>> = scans
        .iter()
        .map(|r| SceneScan::mounted(&r.scan, r.odometry, &mount))
        .collect();
    for (name, rule) in [
        ("thesis rule [5, 200] mm", MeshRule::THESIS),
        ("incidence rule", MeshRule::INCIDENCE),
    ] {
        let options = MeshOptions {
            rule,
            trim_beams: 0,
        };
        // Steady state: the scene and the model rebuilt into the memory of the last ones, as a
        // robot reconstructing scene after scene does.
        let (mut scene, mut model) = (Scene::build(tag, &rows).unwrap(), Model::default());
        let (warm, warm_min) = time_spread(301, || {
            scene.rebuild(tag, &rows).unwrap();
            model.rebuild(std::slice::from_ref(&scene), &options);
            black_box(&model);
        });
        // Cold: fresh memory each time, whose first touch costs the kernel a page fault per
        // 4 KiB (about 500 here), returned to it after every build.
        let (cold, cold_min) = time_spread(301, || {
            let scene = Scene::build(tag, &rows).unwrap();
            black_box(Model::build(std::slice::from_ref(&scene), &options));
        });
        println!(
            "one scene ({} scans x 361), {name}: points + mesh + normals + merge: {:.3} ms median, {:.3} ms best (target <= 0.5 ms); {:.4} x reference; in fresh memory {:.3} ms median, {:.3} ms best",
            rows.len(),
            ms(warm),
            ms(warm_min),
            ratio(warm),
            ms(cold),
            ms(cold_min),
        );
    }

    // Scoring the merged model of survey-lab.
    let scenario = Scenario::load(root.join("survey-lab.toml")).unwrap();
    let record = run_scenario(&scenario, &RunOptions::default(), |_, _| {}).unwrap();
    let recon = record.reconstruction.as_ref().unwrap();
    let model = &recon.main().model;
    let map = WorldMap::new(&scenario.world);
    let t = median_time(15, || {
        black_box(score(model, &map));
    });
    println!(
        "scoring survey-lab's model ({} scenes, {} vertices, {} triangles): {:.1} ms (target <= 50 ms); {:.3} x reference",
        model.scenes.len(),
        model.vertices.len(),
        model.triangles.len(),
        ms(t),
        ratio(t)
    );

    // survey-lab end to end, files included.
    let out = std::env::temp_dir().join("twin-bench-reconstruction");
    let mut factors = Vec::new();
    let mut sim_seconds = 0.0;
    for _ in 0..7 {
        let t = Instant::now();
        let record = run_scenario(&scenario, &RunOptions::default(), |_, _| {}).unwrap();
        sim::output::write_all(&record, &scenario, &out).unwrap();
        sim_seconds = record.sim_seconds();
        factors.push(sim_seconds / t.elapsed().as_secs_f64());
    }
    let _ = std::fs::remove_dir_all(&out);
    factors.sort_by(f64::total_cmp);
    println!(
        "survey-lab end to end ({sim_seconds:.0} s simulated, 810 scans, 3 models scored, files written): real-time factor median {:.0}x (min {:.0}x, max {:.0}x; target >= 1000x)",
        factors[3], factors[0], factors[6]
    );
}
