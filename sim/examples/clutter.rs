//! A large world for speed measurements: the lab with N small boxes scattered over the LIC
//! (`sim::world::clutter`), printed as a world file.
//!
//! `cargo run --release --example clutter -- 800 > /tmp/lab-800.toml`
//! (then point a copy of a scenario's `world` at it, with absolute paths).

fn main() {
    let boxes: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(800);
    let lab = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../worlds/lab.toml");
    let text = std::fs::read_to_string(&lab).expect("worlds/lab.toml is readable");
    print!("{}", sim::world::clutter::lab_with_boxes(&text, boxes));
}
