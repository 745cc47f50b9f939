//! Large worlds for speed measurements: the lab (`worlds/lab.toml`) with N small boxes scattered
//! over the LIC (the room east of x = 9 m, which the lab tour never enters), from a fixed seed —
//! the same boxes for the same N. Used by `cargo run --example clutter` and `cargo bench --bench
//! scaling`.

use rand::{RngExt, SeedableRng};
use std::fmt::Write as _;

/// `lab` (the text of `worlds/lab.toml`) with `boxes` boxes of 8 × 8 cm, 0.5 m tall, added.
pub fn lab_with_boxes(lab: &str, boxes: usize) -> String {
    let mut rng = crate::rng::SimRng::seed_from_u64(800);
    let mut text = lab.replace("name = \"lab\"", &format!("name = \"lab-{boxes}-boxes\""));
    text.push('\n');
    for _ in 0..boxes {
        let x = 9.3 + rng.random::<f64>() * 6.4;
        let y = 0.2 + rng.random::<f64>() * 6.1;
        let _ = writeln!(
            text,
            "[[box]]\ncenter = [{x:.3}, {y:.3}]\nsize = [0.08, 0.08]\nmaterial = \"matte\"\nz = [0.0, 0.5]\n"
        );
    }
    text
}
