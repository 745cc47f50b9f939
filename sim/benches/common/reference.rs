//! The reference every benchmark's figures are divided by, so they travel between machines: one
//! level scan of a world cast by brute force, measured in the same run.

use sim::config::WorldDescription;
use sim::world::WorldMap;
use std::time::Instant;

/// Seconds per level scan of `world` cast by brute force: 361 beams over 180° from the lab's
/// start, each against every face, the nearest crossing kept (median of 201 scans).
pub fn brute_force_scan_seconds(world: &WorldDescription) -> f64 {
    let map = WorldMap::new(world);
    let faces: Vec<([f64; 2], [f64; 2])> = map.faces().iter().map(|f| (f.a, f.b)).collect();
    let origin = [world.start.x, world.start.y];
    let mut times = Vec::new();
    let mut sink = 0.0;
    for _ in 0..201 {
        let t = Instant::now();
        for k in 0..361 {
            let angle = world.start.theta + (f64::from(k) * 0.5 - 90.0).to_radians();
            let d = [angle.cos(), angle.sin()];
            let mut best = 32.0f64;
            for (a, b) in &faces {
                let e = [b[0] - a[0], b[1] - a[1]];
                let denom = d[0] * e[1] - d[1] * e[0];
                if denom.abs() < 1e-12 {
                    continue;
                }
                let w = [a[0] - origin[0], a[1] - origin[1]];
                let t_ray = (w[0] * e[1] - w[1] * e[0]) / denom;
                let u = (w[0] * d[1] - w[1] * d[0]) / denom;
                if t_ray > 0.0 && (0.0..=1.0).contains(&u) && t_ray < best {
                    best = t_ray;
                }
            }
            sink += best;
        }
        times.push(t.elapsed().as_secs_f64());
    }
    std::hint::black_box(sink);
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}
