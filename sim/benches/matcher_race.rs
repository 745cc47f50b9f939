//! `lorentz-lines` against `pl-icp`, the reference, on the pairs of `twin matchers`
//! (seed 1 unless `RACE_SEED` says, 300 a row), timed pair by pair in turn: each pair is matched by one and then the
//! other, the order swapped from pair to pair and from round to round, and each matcher's time
//! on a pair is its best of the rounds. A busy moment of the host then slows both alike, where
//! `twin matchers`, which runs one matcher over a whole row and then the next, can hand it to
//! one of them. Prints each row's median time a pair for both and their ratio (the issue's
//! figure), the ratio of their whole times over the row (what a log's user waits for: the slow
//! pairs, restarts and all, weigh on it as they do not on the median), the share of the
//! pairs `lorentz-lines` matched sooner, and the ratio of their whole times over `pl-icp`'s
//! quicker half of the pairs and over its slower half. The halves show where a ratio of
//! medians near 1 comes from: on a real log's dense scans `pl-icp`'s times fall in two heaps
//! (the pairs it settles at once, and those whose mean distance above 1 cm sends it round its
//! restarts), and the median pair lies between them. Each match prepares its reference, as in
//! `twin matchers`.
//!
//! `cargo bench --bench matcher_race` (`RACE_ROUNDS`, default 5, sets the rounds; `RACE_ROW`,
//! a part of a row's name such as `1°, 0`, races that row alone; `RACE_SEED`, default 1, draws
//! the rows of another seed of `twin matchers`, to race pairs no constant was chosen on;
//! `RACE_CSV=DIR` writes each raced row's pairs with their two best times, microseconds, to
//! `DIR/<row>.csv`)

use robot::localization::{MatcherKind, Reference};
use sim::commands::matchers;
use std::path::Path;
use std::time::Instant;

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let rounds: usize = setting("RACE_ROUNDS", 5, 1);
    let seed: u64 = setting("RACE_SEED", 1, 0);
    let sets = matchers::standard_sets(&root, 300, seed).expect("the bundled worlds and logs load");
    let racers = [MatcherKind::LorentzLines, MatcherKind::PointToLine].map(|k| k.build());
    // Only the rows whose names hold `RACE_ROW`, when set (to profile one row).
    let only = std::env::var("RACE_ROW").ok();
    let raced: Vec<_> = sets
        .iter()
        .filter(|s| only.as_deref().is_none_or(|o| s.name.contains(o)))
        .collect();
    if raced.is_empty() {
        let names: Vec<&str> = sets.iter().map(|s| s.name.as_str()).collect();
        eprintln!(
            "RACE_ROW={:?} is part of no row's name: {names:?}",
            only.as_deref().unwrap_or_default()
        );
        std::process::exit(2);
    }
    println!(
        "seed {seed}, best of {rounds} rounds\n\
         | row | lorentz-lines | pl-icp | ratio | whole row, ratio | pairs sooner | \
         pl-icp's quicker half, ratio | its slower half, ratio |\n\
         |---|---|---|---|---|---|---|---|"
    );
    for set in raced {
        let mut best = vec![[f64::INFINITY; 2]; set.cases.len()];
        for round in 0..rounds {
            for (pair, case) in set.cases.iter().enumerate() {
                for turn in 0..2 {
                    let k = (turn + round + pair) % 2;
                    let clock = Instant::now();
                    let reference = Reference::new(case.reference.points());
                    let answer = racers[k].align(&reference, &case.current.points(), case.guess);
                    std::hint::black_box(answer);
                    let micros = clock.elapsed().as_secs_f64() * 1e6;
                    best[pair][k] = best[pair][k].min(micros);
                }
            }
        }
        let median = |k: usize| {
            let mut times: Vec<f64> = best.iter().map(|b| b[k]).collect();
            times.sort_by(f64::total_cmp);
            times[times.len() / 2]
        };
        let (ll, pl) = (median(0), median(1));
        let whole = |k: usize| best.iter().map(|b| b[k]).sum::<f64>();
        let sooner = best.iter().filter(|b| b[0] < b[1]).count();
        // The pairs by `pl-icp`'s time, and the ratio of the summed times over each half.
        let mut by_reference = best.clone();
        by_reference.sort_by(|a, b| a[1].total_cmp(&b[1]));
        let (quicker, slower) = by_reference.split_at(by_reference.len() / 2);
        let ratio = |pairs: &[[f64; 2]]| {
            pairs.iter().map(|b| b[0]).sum::<f64>() / pairs.iter().map(|b| b[1]).sum::<f64>()
        };
        if let Ok(dir) = std::env::var("RACE_CSV") {
            let mut csv = String::from("pair,lorentz_lines_us,pl_icp_us\n");
            for (pair, b) in best.iter().enumerate() {
                csv += &format!("{pair},{:.1},{:.1}\n", b[0], b[1]);
            }
            let file =
                Path::new(&dir).join(format!("{}.csv", set.name.replace([' ', ',', '/'], "_")));
            let written = std::fs::create_dir_all(&dir).and_then(|()| std::fs::write(&file, csv));
            if let Err(error) = written {
                eprintln!("RACE_CSV={dir:?}: cannot write {}: {error}", file.display());
                std::process::exit(2);
            }
        }
        println!(
            "| {} | {:.0} µs | {:.0} µs | {:.3} | {:.3} | {:.2} | {:.3} | {:.3} |",
            set.name,
            ll,
            pl,
            ll / pl,
            whole(0) / whole(1),
            sooner as f64 / best.len() as f64,
            ratio(quicker),
            ratio(slower)
        );
    }
}

/// The whole number the environment variable `name` holds (at least `least`), `default` when
/// unset; anything else ends the race with a message naming the variable.
fn setting<T>(name: &str, default: T, least: T) -> T
where
    T: std::str::FromStr + PartialOrd + std::fmt::Display,
{
    match std::env::var(name) {
        Err(std::env::VarError::NotPresent) => default,
        Ok(text) => match text.trim().parse::<T>() {
            Ok(value) if value >= least => value,
            _ => {
                eprintln!("{name}={text:?}: expected a whole number of at least {least}");
                std::process::exit(2);
            }
        },
        Err(error) => {
            eprintln!("{name}: {error}");
            std::process::exit(2);
        }
    }
}
