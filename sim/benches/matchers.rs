//! Scan matching speed: time per pair of 361-beam scans, for each matcher, on one core.
//!
//! - `twin`: pairs of the twin's SICK in `worlds/orthogonal.toml` with 2 % uniform outliers, the
//!   thesis's motions (up to ±25 cm, ±23°) and an odometry guess a few centimetres and degrees
//!   off;
//! - `mit`: consecutive real scans of `tests/data/mit-csail.clf` (the B21's SICK, 361 beams),
//!   guessed from the log's odometry.
//!
//! Every match includes preparing the reference (its k-d tree; its lines for `lorentz-lines`).
//! Targets (issue 4): ≤ 1 ms for `ls` and `mbicp`, ≤ 2 ms for `lorentz`, ≤ 3 ms for
//! `lorentz-lines`. `cargo bench --bench matchers`

use criterion::{Criterion, criterion_group, criterion_main};
use rand::{RngExt, SeedableRng};
use robot::Pose2;
use robot::localization::{MatcherKind, RangeScan};
use robot::logs::LogEvent;
use sim::commands::montecarlo::pairs::PairMaker;
use sim::config::Outliers;
use sim::config::{RobotDescription, WorldDescription};
use std::hint::black_box;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

type Case = (RangeScan, RangeScan, Pose2);

fn twin_pairs() -> Vec<Case> {
    let world = WorldDescription::load(root().join("worlds/orthogonal.toml")).unwrap();
    let robot = RobotDescription::load(root().join("scenarios/robots/pioneer-3dx.toml")).unwrap();
    let maker = PairMaker::new(&world, &robot, Outliers::preset("thesis-2pct").unwrap());
    let mut rng = sim::rng::SimRng::seed_from_u64(7);
    (0..40)
        .map(|_| {
            let a = maker.free_pose(0.6, &mut rng).unwrap();
            let u = |rng: &mut sim::rng::SimRng| rng.random::<f64>() - 0.5;
            let motion = Pose2::new(0.5 * u(&mut rng), 0.1 * u(&mut rng), 0.8 * u(&mut rng));
            let pair = maker.pair(a, a.compose(&motion), &mut rng);
            let off = Pose2::new(0.06 * u(&mut rng), 0.06 * u(&mut rng), 0.05 * u(&mut rng));
            (pair.reference, pair.current, pair.truth.compose(&off))
        })
        .collect()
}

fn mit_pairs() -> Vec<Case> {
    let log = robot::logs::read_log(&root().join("tests/data/mit-csail.clf")).unwrap();
    let mut scans = Vec::new();
    let mut odometry = Pose2::IDENTITY;
    for event in log.events {
        match event {
            LogEvent::Odometry { pose, .. } => odometry = pose,
            LogEvent::Scan(scan) => scans.push((scan, odometry)),
            LogEvent::Points { .. } => {}
        }
    }
    scans
        .windows(2)
        .step_by(50)
        .map(|w| (w[0].0.clone(), w[1].0.clone(), w[0].1.relative(&w[1].1)))
        .collect()
}

fn matchers(c: &mut Criterion) {
    for (set, cases) in [("twin", twin_pairs()), ("mit", mit_pairs())] {
        let mut group = c.benchmark_group(format!("match/{set}"));
        for kind in MatcherKind::ALL {
            let matcher = kind.build();
            let mut i = 0;
            group.bench_function(kind.name(), |b| {
                b.iter(|| {
                    let (reference, current, guess) = &cases[i % cases.len()];
                    i += 1;
                    black_box(matcher.match_scans(reference, current, *guess))
                })
            });
        }
        group.finish();
    }
}

criterion_group!(benches, matchers);
criterion_main!(benches);
