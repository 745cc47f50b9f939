//! Monte Carlo throughput: trials of the default Table 5.1 study (`studies/table-5-1.toml`) per
//! second on one core. A trial builds a twin at a random free pose, drives one motion through the
//! firmware, casts two scans with outliers and runs every matcher the study names (five). The
//! target of issue 6 is the full study — 10,000 trials at each of the two rates — in under 2
//! minutes on this 2-core machine, i.e. at least 167 trials/s with both cores (84 per core):
//! `cargo bench --bench montecarlo`, and for the whole study
//! `time cargo run --release -- montecarlo studies/table-5-1.toml --threads 2`.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use sim::commands::montecarlo::Trials;
use sim::config::Study;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let study = Study::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../studies/table-5-1.toml"
    ))
    .expect("the default study loads");
    let trials = Trials::new(&study);
    // 16 trials at 2 % (0..) and 16 at 20 % (10_000..), the same ones every iteration.
    let indices: Vec<u64> = (0..16).chain(10_000..10_016).collect();
    let mut group = c.benchmark_group("montecarlo");
    group.throughput(Throughput::Elements(indices.len() as u64));
    group.sample_size(10);
    group.bench_function("table-5-1 trials, one core", |b| {
        b.iter(|| {
            for &i in &indices {
                black_box(trials.run(i).expect("a trial runs"));
            }
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
