//! Benchmark: re-planning in the air on a 42-cell field (CAF's size) — the continuation after
//! 2 of 12 stops (10 remaining), and the bound with all 42 cells remaining — at the default
//! planner with the replan command's 1 s time limit.

use criterion::{Criterion, criterion_group, criterion_main};
use gleaner_energy::{EnergyConfig, MissionEnergyModel};
use gleaner_field::LocalPoint;
use gleaner_mission::{Candidate, PlanOptions, replan};
use std::hint::black_box;
use std::time::Duration;

/// 42 cells on a 7 x 6 grid of 60 m cells, scores 1..3, 30.25 s hovers.
fn cells() -> Vec<Candidate> {
    (0..42)
        .map(|i| Candidate {
            centre: LocalPoint::new(
                30.0 + 60.0 * f64::from(i % 7),
                30.0 + 60.0 * f64::from(i / 7),
            ),
            score: 1.0 + f64::from((i * 7) % 3),
            hover_s: 30.25,
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let model = MissionEnergyModel::new(&EnergyConfig::paper())
        .expect("paper preset is valid")
        .for_flight()
        .expect("flight model");
    let all = cells();
    let base = LocalPoint::new(0.0, 0.0);
    let options = PlanOptions {
        time_limit: Duration::from_secs(1),
        ..PlanOptions::default()
    };
    let mut group = c.benchmark_group("replan");
    group.sample_size(20);
    let remaining: Vec<Candidate> = all.iter().step_by(4).skip(2).copied().collect();
    group.bench_function("after_2_of_12_stops_10_remaining", |b| {
        b.iter(|| {
            replan(
                &model,
                (all[4].centre, base),
                black_box(&remaining),
                30_000.0,
                &options,
            )
            .expect("feasible")
        })
    });
    group.bench_function("all_42_cells_remaining", |b| {
        b.iter(|| {
            replan(
                &model,
                (all[20].centre, base),
                black_box(&all),
                40_000.0,
                &options,
            )
            .expect("feasible")
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
