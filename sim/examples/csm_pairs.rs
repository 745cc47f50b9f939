//! Writes the pairs of `twin matchers`' standard rows (300 a row) as plain text
//! (`sim::commands::matchers::plain`), for the race against CSM's own C code
//! (`studies/csm-race/`).
//!
//! `cargo run --release --example csm_pairs -- SEED > pairs.txt` (seed 1 unless given).

use sim::commands::matchers::{self, plain};
use std::path::Path;

fn main() {
    let seed: u64 = match std::env::args().nth(1).map(|s| s.parse()) {
        None => 1,
        Some(Ok(seed)) => seed,
        Some(Err(e)) => {
            eprintln!("csm_pairs: the seed must be a whole number: {e}");
            std::process::exit(2);
        }
    };
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let sets = match matchers::standard_sets(&root, 300, seed) {
        Ok(sets) => sets,
        Err(e) => {
            eprintln!("csm_pairs: {e}");
            std::process::exit(1);
        }
    };
    let out = std::io::BufWriter::new(std::io::stdout().lock());
    if let Err(e) = plain::write_pairs(&sets, out) {
        eprintln!("csm_pairs: {e}");
        std::process::exit(1);
    }
}
