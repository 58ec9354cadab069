//! Benchmark: the exploration plan of 1,000 cells (a 32 x 32 grid of 40 m cells, 30 s hovers).

use criterion::{Criterion, criterion_group, criterion_main};
use gleaner_energy::{EnergyConfig, MissionEnergyModel};
use gleaner_field::LocalPoint;
use gleaner_mission::exploration::{ExplorationOptions, plan_exploration};
use std::hint::black_box;

/// 1,000 cell centres on a 40 m grid (a 32 x 32 field, row by row).
fn points() -> Vec<LocalPoint> {
    (0..1000)
        .map(|i| LocalPoint::new(20.0 + 40.0 * (i % 32) as f64, 20.0 + 40.0 * (i / 32) as f64))
        .collect()
}

fn bench(c: &mut Criterion) {
    let model = MissionEnergyModel::new(&EnergyConfig::paper()).expect("paper preset is valid");
    let pts = points();
    let base = LocalPoint::new(0.0, 0.0);
    let service = vec![model.service_energy_j(30.0); pts.len()];
    let options = ExplorationOptions::default();
    let mut group = c.benchmark_group("exploration");
    group.sample_size(10);
    group.bench_function("plan_exploration_1000_cells", |b| {
        b.iter(|| {
            plan_exploration(&model, black_box(base), black_box(&pts), &service, &options)
                .expect("reachable")
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
