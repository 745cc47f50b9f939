//! The matchers side by side on the same pairs, the table `twin matchers` prints: success,
//! median and 95th-percentile errors, median time (with its ratio to `ls` on the same pairs in
//! the same run, so it travels between machines) and the precision and recall of each answer's
//! `converged` flag, and the closure of the logs' triangles — on synthetic pairs of the twin in
//! four worlds at 0 % and 20 % outliers and on consecutive pairs of the three SLAM-corrected
//! real logs, from guesses σ 5 cm / 2° off, and σ 20 cm / 10° in the last row. 100 pairs a row
//! here; `twin matchers` gives 300.
//!
//! `cargo bench --bench matcher_table`

use robot::localization::MatcherKind;
use sim::commands::matchers;
use std::path::Path;

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let sets = matchers::standard_sets(&root, 100, 1).expect("the bundled worlds and logs load");
    let mut outcomes = Vec::new();
    let mut rows: Vec<matchers::Row> = sets
        .iter()
        .flat_map(|set| {
            matchers::evaluate(set, &MatcherKind::ALL, &mut |m| {
                if let matchers::Matched::Pair(o) = m {
                    outcomes.push(o)
                }
            })
        })
        .collect();
    matchers::mark_agreed(&mut outcomes, &mut rows);
    print!("{}", matchers::table(&rows));
}
