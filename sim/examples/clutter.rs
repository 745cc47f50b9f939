//! A large world for speed measurements: the lab (`worlds/lab.toml`) with N small boxes scattered
//! over the LIC (the room east of x = 9 m, which the lab tour never enters), from a fixed seed.
//!
//! `cargo run --release --example clutter -- 800 > /tmp/lab-800.toml`
//! (then point a copy of a scenario's `world` at it, with absolute paths).

use rand::{RngExt, SeedableRng};

fn main() {
    let boxes: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(800);
    let lab = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../worlds/lab.toml");
    let text = std::fs::read_to_string(&lab).expect("worlds/lab.toml is readable");
    let mut rng = sim::rng::SimRng::seed_from_u64(800);
    println!(
        "{}",
        text.replace("name = \"lab\"", &format!("name = \"lab-{boxes}-boxes\""))
    );
    for _ in 0..boxes {
        let x = 9.3 + rng.random::<f64>() * 6.4;
        let y = 0.2 + rng.random::<f64>() * 6.1;
        println!(
            "[[box]]\ncenter = [{x:.3}, {y:.3}]\nsize = [0.08, 0.08]\nmaterial = \"matte\"\nz = [0.0, 0.5]\n"
        );
    }
}
