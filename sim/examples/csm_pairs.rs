//! Writes the pairs of `twin matchers`' standard rows (300 a row) as plain text
//! (`sim::commands::matchers::plain`), for the race against CSM's own C code
//! (`studies/csm-race/`); given worlds, the four rows `twin matchers --world` draws in each
//! instead (the LMS at 0.5° and 1°, 0 % and 20 % outliers).
//!
//! `cargo run --release --example csm_pairs -- [SEED [WORLD.toml ...]] > pairs.txt` (seed 1
//! unless given).

use sim::commands::matchers::{self, CaseSet, plain};
use std::path::Path;

fn main() {
    let mut args = std::env::args().skip(1);
    let seed: u64 = match args.next().map(|s| s.parse()) {
        None => 1,
        Some(Ok(seed)) => seed,
        Some(Err(e)) => {
            eprintln!("csm_pairs: the seed must be a whole number: {e}");
            std::process::exit(2);
        }
    };
    let worlds: Vec<String> = args.collect();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let sets = if worlds.is_empty() {
        matchers::standard_sets(&root, 300, seed)
    } else {
        let mut sets = Vec::new();
        for world in &worlds {
            match matchers::extra_world_sets(&root, Path::new(world), 300, seed) {
                Ok(four) => sets.extend(four),
                Err(e) => fail(e),
            }
        }
        Ok(sets)
    };
    let sets: Vec<CaseSet> = sets.unwrap_or_else(|e| fail(e));
    let out = std::io::BufWriter::new(std::io::stdout().lock());
    if let Err(e) = plain::write_pairs(&sets, out) {
        fail(e);
    }
}

/// Prints `error` and ends the process with status 1.
fn fail(error: impl std::fmt::Display) -> ! {
    eprintln!("csm_pairs: {error}");
    std::process::exit(1);
}
