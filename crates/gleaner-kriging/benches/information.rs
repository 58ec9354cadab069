//! The information objective's kernel: `FieldFilter::information` of a route's sensors on a
//! farm-sized dynamic model (42 sensors on a 7 × 6 grid 100 m apart, exponential
//! covariance with a 300 m range, φ = 0.97 per day, reading noise 1e-6), after 30 days of
//! readings of a third of the sensors each day. The marginal planner calls it once per
//! candidate route.

use criterion::{Criterion, criterion_group, criterion_main};
use gleaner_kriging::DynamicModel;
use std::hint::black_box;

fn model() -> DynamicModel {
    let n = 42;
    let pos: Vec<[f64; 2]> = (0..n)
        .map(|k| [100.0 * (k % 7) as f64, 100.0 * (k / 7) as f64])
        .collect();
    let mut cov = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            let d = ((pos[i][0] - pos[j][0]).powi(2) + (pos[i][1] - pos[j][1]).powi(2)).sqrt();
            cov[i * n + j] = 1e-3 * (-d / 300.0).exp() + if i == j { 1e-4 } else { 0.0 };
        }
    }
    DynamicModel::new(vec![0.3; n], cov, 0.97, 86_400.0, 1e-6).expect("valid model")
}

fn bench(c: &mut Criterion) {
    let m = model();
    let mut f = m.filter(0.0);
    for day in 1..=30 {
        f.advance(day as f64 * 86_400.0);
        for k in (day % 3..42).step_by(3) {
            f.observe(k, 0.3 + 0.001 * ((k * day) % 7) as f64);
        }
    }
    let route: Vec<usize> = vec![3, 10, 17, 24, 25, 26, 33, 40];
    let mut group = c.benchmark_group("information_42_sensors");
    for len in [1usize, 4, 8] {
        group.bench_function(format!("route_{len}"), |b| {
            b.iter(|| f.information(black_box(&route[..len])))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
