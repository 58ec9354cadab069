//! Large random instances: greedy + local search to a local optimum ("fast" options).
//!
//! Uniform points in a 1000 × 1000 square, depot at the centre (closed tour), rewards 1..=100,
//! budget sized so that roughly 10-20% of the nodes fit. "Locally optimal" means: no
//! improving 2-opt or Or-opt move within the candidate lists and no feasible insertion or
//! replacement move left (see `SolveOptions::fast`).

use criterion::{Criterion, criterion_group, criterion_main};
use gleaner_orienteering::{Metric, Problem, SolveOptions, evaluate, solve_default};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn instance(n: usize, seed: u64) -> Problem {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut pts = vec![[500.0, 500.0]];
    let mut rewards = vec![0.0];
    for _ in 1..n {
        pts.push([rng.random_range(0.0..1000.0), rng.random_range(0.0..1000.0)]);
        rewards.push(f64::from(rng.random_range(1u32..=100)));
    }
    // A tour through k random points of a square of area A is about 0.7 sqrt(k A) long.
    let budget = 0.7 * (0.15 * n as f64 * 1.0e6).sqrt() * 0.45;
    Problem::from_points(&pts, Metric::Euclidean, rewards, budget).expect("valid instance")
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("fast_local_optimum");
    group.sample_size(10);
    for n in [1_000usize, 10_000] {
        let p = instance(n, 7);
        let opts = SolveOptions::fast();
        let s = solve_default(&p, &opts);
        let checked = evaluate(&p, &s.routes).expect("feasible");
        eprintln!(
            "n = {n}: visited {} nodes ({:.1}%), reward {}, cost {:.1} of {:.1}",
            s.visited(),
            100.0 * s.visited() as f64 / n as f64,
            checked.reward,
            checked.costs[0],
            p.budget()
        );
        group.bench_function(format!("n{n}"), |b| b.iter(|| solve_default(&p, &opts)));
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
