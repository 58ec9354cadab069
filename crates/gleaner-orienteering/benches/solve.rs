//! Large random instances.
//!
//! `fast_local_optimum`: greedy + local search to a local optimum ("fast" options). Uniform
//! points in a 1000 × 1000 square, depot at the centre (closed tour), rewards 1..=100,
//! budget sized so that roughly 10-20% of the nodes fit. "Locally optimal" means: no
//! improving 2-opt or Or-opt move within the candidate lists and no feasible insertion or
//! replacement move left (see `SolveOptions::fast`).
//!
//! `short_reach_300_iterations`: the default solver at a 300-iteration cap on 10,000 nodes
//! spread over a 15 km × 6 km rectangle, depot at the middle of a long side, costs 12.3 per
//! metre (scaled points), service 5,000 per node and a budget of 66,500: the budget reaches a
//! few hundred nodes and a route holds only a handful. Measures how the search scales with
//! what the budget reaches rather than with the instance.
//!
//! `marginal_43_nodes`: the set-function search (`solve_marginal`, default options) on a
//! farm-sized instance: 42 sites in a 900 m × 600 m field with the base at a corner, 12.3
//! per metre, service 5,000 per site, budget 66,500, and a coverage objective (each site
//! covers the sites within 250 m with weight e^(−d/150 m), the value the sum over sites of
//! the best cover): correlated sites tell less together, as with the information objective.

use criterion::{Criterion, criterion_group, criterion_main};
use gleaner_orienteering::{
    MarginalOptions, Metric, Problem, SolveOptions, evaluate, solve_default, solve_marginal,
};
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

/// Counts, by exhaustive scans, unvisited nodes that could still be inserted somewhere within
/// the budget, and improving 2-opt moves (all position pairs).
fn local_optimality(p: &Problem, route: &[usize], cost: f64) -> (usize, usize) {
    let mut on = vec![false; p.len()];
    route.iter().for_each(|&v| on[v] = true);
    let slack = p.budget() - cost;
    let fits = (0..p.len())
        .filter(|&v| !on[v] && p.reward(v) > 0.0)
        .filter(|&v| {
            route.windows(2).any(|w| {
                p.cost(w[0], v) + p.cost(v, w[1]) - p.cost(w[0], w[1]) + p.service(v) <= slack
            })
        })
        .count();
    let m = route.len();
    let mut two_opt = 0;
    for i in 0..m - 1 {
        for j in (i + 2)..m - 1 {
            let g = p.cost(route[i], route[j]) + p.cost(route[i + 1], route[j + 1])
                - p.cost(route[i], route[i + 1])
                - p.cost(route[j], route[j + 1]);
            if g < -1e-9 {
                two_opt += 1;
            }
        }
    }
    (fits, two_opt)
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("fast_local_optimum");
    group.sample_size(10);
    for n in [1_000usize, 10_000] {
        let p = instance(n, 7);
        let opts = SolveOptions::fast();
        let s = solve_default(&p, &opts);
        let checked = evaluate(&p, &s.routes).expect("feasible");
        let (fits, two_opt) = local_optimality(&p, &s.routes[0], checked.costs[0]);
        eprintln!(
            "n = {n}: visited {} nodes ({:.1}%), reward {}, cost {:.1} of {:.1}; \
             feasible insertions left (full scan): {fits}; improving 2-opt moves (full scan): {two_opt}",
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

/// 10,000 nodes over 15 km × 6 km, depot at (7.5 km, 0), 12.3 per metre, service 5,000,
/// budget 66,500, rewards uniform in (0, 1].
fn short_reach_instance(seed: u64) -> Problem {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = 10_000;
    let mut pts = vec![[12.3 * 7_500.0, 0.0]];
    let mut rewards = vec![0.0];
    for _ in 1..n {
        // Coordinates in cost units (12.3 per metre).
        pts.push([
            12.3 * rng.random_range(0.0..15_000.0),
            12.3 * rng.random_range(0.0..6_000.0),
        ]);
        rewards.push(rng.random_range(1e-3..=1.0));
    }
    let mut service = vec![5_000.0; n];
    service[0] = 0.0;
    Problem::from_points(&pts, Metric::Euclidean, rewards, 66_500.0)
        .and_then(|p| p.with_service_costs(service))
        .expect("valid instance")
}

fn bench_short_reach(c: &mut Criterion) {
    let mut group = c.benchmark_group("short_reach_300_iterations");
    group.sample_size(10);
    let p = short_reach_instance(3);
    let opts = SolveOptions::default()
        .with_iterations(300)
        .with_time_limit(std::time::Duration::from_secs(3_600));
    let s = solve_default(&p, &opts);
    let checked = evaluate(&p, &s.routes).expect("feasible");
    eprintln!(
        "n = 10000: {} reachable nodes, visited {}, reward {:.4}, cost {:.1} of {:.1}",
        (1..p.len())
            .filter(|&v| p.cost(0, v) * 2.0 + p.service(v) <= p.budget())
            .count(),
        s.visited(),
        checked.reward,
        checked.costs[0],
        p.budget()
    );
    group.bench_function("n10000", |b| b.iter(|| solve_default(&p, &opts)));
    group.finish();
}

fn bench_marginal(c: &mut Criterion) {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let n = 43;
    let metres: Vec<[f64; 2]> = std::iter::once([0.0, 0.0])
        .chain((1..n).map(|_| [rng.random_range(0.0..900.0), rng.random_range(0.0..600.0)]))
        .collect();
    let pts: Vec<[f64; 2]> = metres.iter().map(|p| [12.3 * p[0], 12.3 * p[1]]).collect();
    let mut service = vec![5_000.0; n];
    service[0] = 0.0;
    let mut rewards = vec![1.0; n];
    rewards[0] = 0.0;
    let p = Problem::from_points(&pts, Metric::Euclidean, rewards, 66_500.0)
        .and_then(|p| p.with_service_costs(service))
        .expect("valid instance");
    let cover: Vec<Vec<f64>> = metres
        .iter()
        .map(|a| {
            metres
                .iter()
                .map(|b| {
                    let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
                    if d <= 250.0 { (-d / 150.0).exp() } else { 0.0 }
                })
                .collect()
        })
        .collect();
    let f = |s: &[usize]| -> f64 {
        (1..n)
            .map(|j| s.iter().map(|&v| cover[v][j]).fold(0.0, f64::max))
            .sum()
    };
    let opts = MarginalOptions::default();
    let got = solve_marginal(&p, f, &opts);
    eprintln!(
        "marginal, 43 nodes: visited {}, value {:.3}, cost {:.1} of {:.1}",
        got.solution.visited(),
        got.value,
        got.solution.costs[0],
        p.budget()
    );
    let mut group = c.benchmark_group("marginal_43_nodes");
    group.sample_size(10);
    group.bench_function("coverage", |b| b.iter(|| solve_marginal(&p, f, &opts)));
    group.finish();
}

criterion_group!(benches, bench, bench_short_reach, bench_marginal);
criterion_main!(benches);
