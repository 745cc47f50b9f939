//! The coarse correlative search of `lorentz-lines`' rescue (`correlative::best_starts`, its
//! window ±60 cm and ±30° in 5 cm and 1° steps, the three best headings 3° apart) against
//! the same search without its economies (`best_starts_plain`: every point added on its own,
//! in 32-bit sums), on the pairs of `twin matchers` (seed 1, 100 a row) from each pair's
//! guess. The two are timed pair
//! by pair in turn, the order swapped from pair to pair, each one's time on a pair its best of
//! three rounds; the answers are checked equal. Prints each row's median time a pair for both,
//! the ratio of the medians and of the whole row's times.
//!
//! `cargo bench --bench coarse_search`

use robot::localization::correlative::{Window, best_starts, best_starts_plain};
use robot::localization::{Reference, ScanPoints};
use sim::commands::matchers;
use std::path::Path;
use std::time::Instant;

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let sets = matchers::standard_sets(&root, 100, 1).expect("the bundled worlds and logs load");
    let searches = [best_starts, best_starts_plain];
    println!(
        "| row | best_starts, median pair | best_starts_plain | ratio of medians | whole row, ratio |\n\
         |---|---|---|---|---|"
    );
    for set in &sets {
        let mut best = vec![[f64::INFINITY; 2]; set.cases.len()];
        for round in 0..3 {
            for (pair, case) in set.cases.iter().enumerate() {
                let reference = Reference::new(case.reference.points());
                let current: ScanPoints = case.current.points();
                let mut answers = Vec::new();
                for turn in 0..2 {
                    let k = (turn + round + pair) % 2;
                    let clock = Instant::now();
                    let starts = searches[k](
                        &reference.points.xy,
                        &current.xy,
                        case.guess,
                        &Window::WIDE,
                        (3, 3),
                    );
                    best[pair][k] = best[pair][k].min(clock.elapsed().as_secs_f64() * 1e6);
                    answers.push(starts);
                }
                assert_eq!(answers[0], answers[1], "{} pair {pair}", set.name);
            }
        }
        let median = |k: usize| {
            let mut times: Vec<f64> = best.iter().map(|b| b[k]).collect();
            times.sort_by(f64::total_cmp);
            times[times.len() / 2]
        };
        let whole = |k: usize| best.iter().map(|b| b[k]).sum::<f64>();
        println!(
            "| {} | {:.0} µs | {:.0} µs | {:.3} | {:.3} |",
            set.name,
            median(0),
            median(1),
            median(0) / median(1),
            whole(0) / whole(1)
        );
    }
}
