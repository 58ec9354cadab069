//! Speed targets of the utility engine (see the crate docs):
//! - scoring 100,000 cells (8 neighbours, 3 modalities) from maintained statistics, one thread;
//! - scoring the same cells from scratch over 365 daily points each, all cores (rayon), with
//!   complete series and with 10% of the days missing;
//! - the incremental update after a 10-cell mission (7 days × 3 modalities per cell).

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use gleaner_utility::{
    CellInputs, IncrementalState, Reading, Series, TimeGrid, UtilityConfig, score_cells_parallel,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const DAY: i64 = 86_400;
const COLS: usize = 400;
const ROWS: usize = 250; // 100,000 cells
const MODALITIES: usize = 3;

/// 8-neighbourhoods on a COLS × ROWS grid.
fn grid_neighbours() -> Vec<Vec<usize>> {
    let mut out = Vec::with_capacity(COLS * ROWS);
    for r in 0..ROWS as i64 {
        for c in 0..COLS as i64 {
            let mut nb = Vec::with_capacity(8);
            for dr in -1..=1 {
                for dc in -1..=1 {
                    let (rr, cc) = (r + dr, c + dc);
                    if (dr, dc) != (0, 0)
                        && (0..ROWS as i64).contains(&rr)
                        && (0..COLS as i64).contains(&cc)
                    {
                        nb.push((rr * COLS as i64 + cc) as usize);
                    }
                }
            }
            out.push(nb);
        }
    }
    out
}

/// A pool of smooth random-walk values; each cell and modality reads a window of it.
fn value_pool(len: usize, rng: &mut ChaCha8Rng) -> Vec<f64> {
    let mut x = 0.3;
    (0..len)
        .map(|_| {
            x = 0.3 + 0.98 * (x - 0.3) + rng.random_range(-0.005..0.005);
            x
        })
        .collect()
}

fn probabilities(n: usize) -> Vec<Vec<f64>> {
    (0..n)
        .map(|i| {
            let a = 0.1 + 0.8 * ((i * 7919) % 1000) as f64 / 1000.0;
            vec![a * 0.5, a * 0.5, 1.0 - a]
        })
        .collect()
}

/// State holding 30 days of history for every cell (1 sensor, 3 modalities).
fn filled_state(pool: &[f64], rng: &mut ChaCha8Rng) -> IncrementalState {
    let neighbours = grid_neighbours();
    let n = neighbours.len();
    let mut state =
        IncrementalState::new(&vec![1; n], &neighbours, MODALITIES, TimeGrid::DAILY).unwrap();
    state.set_retention(Some(30 * DAY));
    for d in 0..30i64 {
        let readings: Vec<Reading> = (0..n)
            .flat_map(|cell| (0..MODALITIES).map(move |m| (cell, m)))
            .map(|(cell, m)| {
                let off = (cell * 31 + m * 7_777) % (pool.len() - 400);
                Reading {
                    cell,
                    sensor: 0,
                    modality: m,
                    time: d * DAY,
                    value: pool[off + d as usize],
                }
            })
            .collect();
        state.add_readings(&readings).unwrap();
    }
    for cell in 0..n {
        state
            .record_collection(cell, 0, rng.random_range(0..30) * DAY)
            .unwrap();
    }
    state
}

fn benches(c: &mut Criterion) {
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let pool = value_pool(16_000_000, &mut rng);
    let config = UtilityConfig::default();
    let p = probabilities(COLS * ROWS);

    // 1. From maintained statistics, one thread (`score` spreads the cells over rayon's pool:
    // a pool of one keeps the figure the algorithm's cost, comparable across machines).
    let mut state = filled_state(&pool, &mut rng);
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread pool");
    c.bench_function("score_100k_cells_from_statistics_1_thread", |b| {
        b.iter(|| one_thread.install(|| black_box(state.score(31 * DAY, &config, &p).unwrap())))
    });

    // 3. Incremental update after a 10-cell mission: 7 days x 3 modalities per cell.
    let n = COLS * ROWS;
    let mut day = 30i64;
    c.bench_function("incremental_update_10_cell_mission", |b| {
        b.iter(|| {
            day += 1;
            let mut readings = Vec::with_capacity(10 * 7 * MODALITIES);
            for k in 0..10 {
                let cell = ((day as usize) * 7_919 + k * 104_729) % n;
                for m in 0..MODALITIES {
                    for back in 0..7 {
                        let t = day - back;
                        readings.push(Reading {
                            cell,
                            sensor: 0,
                            modality: m,
                            time: t * DAY,
                            value: pool[(cell + t as usize * 13 + m) % pool.len()],
                        });
                    }
                }
                state.record_collection(cell, 0, day * DAY).unwrap();
            }
            state.add_readings(&readings).unwrap();
        })
    });
    drop(state);

    // 2. From scratch over 365 daily points, all cores.
    let neighbours = grid_neighbours();
    let times: Vec<i64> = (0..365).map(|d| d * DAY).collect();
    let last: Vec<[Option<i64>; 1]> = (0..n)
        .map(|i| [Some(((i % 30) as i64 + 335) * DAY)])
        .collect();
    let inputs: Vec<CellInputs> = (0..n)
        .map(|i| CellInputs {
            last_collected: &last[i],
            series: (0..MODALITIES)
                .map(|m| {
                    let off = (i * 151 + m * 5_003_003) % (pool.len() - 365);
                    Series::new(&times, &pool[off..off + 365])
                })
                .collect(),
            neighbours: &neighbours[i],
            probabilities: &p[i],
        })
        .collect();
    let mut group = c.benchmark_group("scratch");
    group.sample_size(10);
    group.bench_function("score_100k_cells_365_days_from_scratch_all_cores", |b| {
        b.iter(|| black_box(score_cells_parallel(&inputs, 365 * DAY, &config).unwrap()))
    });

    // 2b. The same with 10% of the days missing (64 gap patterns): the merge-join path.
    let patterns: Vec<Vec<i64>> = (0..64)
        .map(|_| {
            (0..365)
                .filter(|_| rng.random_bool(0.9))
                .map(|d| d * DAY)
                .collect()
        })
        .collect();
    let gappy: Vec<CellInputs> = (0..n)
        .map(|i| CellInputs {
            last_collected: &last[i],
            series: (0..MODALITIES)
                .map(|m| {
                    let times = &patterns[(i * 7 + m * 13) % patterns.len()];
                    let off = (i * 151 + m * 5_003_003) % (pool.len() - 365);
                    Series::new(times, &pool[off..off + times.len()])
                })
                .collect(),
            neighbours: &neighbours[i],
            probabilities: &p[i],
        })
        .collect();
    group.bench_function(
        "score_100k_cells_365_days_10pct_missing_from_scratch_all_cores",
        |b| b.iter(|| black_box(score_cells_parallel(&gappy, 365 * DAY, &config).unwrap())),
    );
    group.finish();
}

criterion_group!(scoring, benches);
criterion_main!(scoring);
