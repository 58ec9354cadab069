//! Benchmarks: breakdown of a 1,000-cell route and a 1,000 x 1,000 travel-cost matrix (the
//! exploration plan's benchmark lives in `gleaner-mission`).

use criterion::{Criterion, criterion_group, criterion_main};
use gleaner_energy::{CellVisit, EnergyConfig, MissionEnergyModel};
use gleaner_field::LocalPoint;
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
    let route: Vec<CellVisit> = pts
        .iter()
        .map(|&centre| CellVisit {
            centre,
            hover_s: 30.0,
        })
        .collect();
    let base = LocalPoint::new(0.0, 0.0);
    c.bench_function("breakdown_1000_cells", |b| {
        b.iter(|| {
            model
                .breakdown(black_box(base), black_box(&route))
                .expect("valid route")
        })
    });
    c.bench_function("travel_cost_matrix_1000", |b| {
        b.iter(|| model.travel_cost_matrix(black_box(&pts)))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
