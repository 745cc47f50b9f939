//! The sweep that chose the unit of the thesis's σ schedule (2 → 5 → 0.5): the Lorentzian
//! matcher on twin scan pairs of the orthogonal world with 2 % and 20 % uniform outliers, the
//! thesis's motions (±50 cm or ±25°) and an odometry guess off by a few centimetres and degrees,
//! with σ counted in millimetres, centimetres, decimetres and metres.
//!
//! `cargo run --release --example sigma_sweep [PAIRS]`

use rand::{RngExt, SeedableRng};
use robot::Pose2;
use robot::geometry::wrap_angle;
use robot::localization::{Lorentz, ScanMatcher};
use sim::commands::montecarlo::pairs::PairMaker;
use sim::config::Outliers;
use sim::config::{RobotDescription, WorldDescription};

fn main() {
    let pairs: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(200);
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let world = WorldDescription::load(root.join("worlds/orthogonal.toml")).expect("world");
    let robot =
        RobotDescription::load(root.join("scenarios/robots/pioneer-3dx.toml")).expect("robot");
    let units = [("mm", 0.001), ("cm", 0.01), ("dm", 0.1), ("m", 1.0)];
    println!("| σ unit | outliers | mean e_t (mm) | max e_t (mm) | mean e_θ (°) | max e_θ (°) |");
    println!("|---|---|---|---|---|---|");
    for (preset, label) in [("thesis-2pct", "2 %"), ("thesis-20pct", "20 %")] {
        let maker = PairMaker::new(&world, &robot, Outliers::preset(preset).expect("preset"));
        let mut rng = sim::rng::SimRng::seed_from_u64(51);
        let cases: Vec<_> = (0..pairs)
            .map(|_| {
                let a = maker.free_pose(0.6, &mut rng).unwrap();
                let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
                let motion = if rng.random::<bool>() {
                    Pose2::new(0.5 * sign, 0.0, 0.0)
                } else {
                    Pose2::new(0.0, 0.0, 25f64.to_radians() * sign)
                };
                let pair = maker.pair(a, a.compose(&motion), &mut rng);
                let off = Pose2::new(
                    0.05 * (rng.random::<f64>() - 0.5),
                    0.05 * (rng.random::<f64>() - 0.5),
                    3f64.to_radians() * (rng.random::<f64>() - 0.5),
                );
                (pair.truth.compose(&off), pair)
            })
            .collect();
        for (unit, metres) in units {
            let matcher = Lorentz::with_sigma_unit(metres);
            let (mut sum_t, mut max_t, mut sum_r, mut max_r) = (0.0, 0.0f64, 0.0, 0.0f64);
            for (guess, pair) in &cases {
                let r = matcher.match_scans(&pair.reference, &pair.current, *guess);
                let et = r.pose.distance(&pair.truth) * 1e3;
                let er = wrap_angle(r.pose.theta - pair.truth.theta)
                    .to_degrees()
                    .abs();
                sum_t += et;
                sum_r += er;
                max_t = max_t.max(et);
                max_r = max_r.max(er);
            }
            let n = cases.len() as f64;
            println!(
                "| {unit} | {label} | {:.2} | {:.1} | {:.3} | {:.2} |",
                sum_t / n,
                max_t,
                sum_r / n,
                max_r
            );
        }
    }
}
