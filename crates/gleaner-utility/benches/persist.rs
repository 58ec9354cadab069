//! The persisted incremental state: what `gleaner score` pays when it loads the state instead
//! of reloading the history (see `IncrementalState::to_bytes`).
//!
//! Two synthetic farms from `gleaner-synth`, gridded with 40 m cells like `gleaner init`:
//! - CAF-size: 42 sensors, 10 modalities (VW and temperature at 5 depths), 8 years daily;
//! - large: 10,000 sensors (extent scaled to CAF's density), 2 modalities, 365 days.
//!
//! The state keeps 32 days of grid slots and at least 5 points per series (the retention the
//! application layer uses). Measured per farm: encoding, decoding, scoring from the decoded
//! state, the condition model's prediction from the retained series (decoding the model
//! included), the whole load-and-score path, and the update after a mission (new readings of
//! 10 cells over 14 days, then trim and encode). The one-off build from every reading is
//! measured too, with fewer samples.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use gleaner_field::{Field, FieldConfig};
use gleaner_synth::{SynthConfig, SynthFarm, generate};
use gleaner_utility::{
    ConditionConfig, ConditionModel, IncrementalState, OwnedSeries, Reading, Series, TimeGrid,
    UtilityConfig,
};

const DAY: i64 = 86_400;
const RETENTION_S: i64 = 32 * DAY;
const MIN_POINTS: usize = 5;

struct Fixture {
    name: &'static str,
    neighbours: Vec<Vec<usize>>,
    sensors_per_cell: Vec<usize>,
    n_modalities: usize,
    /// Readings before the mission, and the mission's readings.
    history: Vec<Reading>,
    mission: Vec<Reading>,
    class_modality: usize,
    /// Days of history the fixture's condition model is trained on (keeps set-up quick).
    train_days: i64,
}

fn fixture(name: &'static str, config: SynthConfig, train_days: i64) -> Fixture {
    let farm: SynthFarm = generate(&config).expect("valid synthetic configuration");
    let field = Field::build(farm.sensors(), farm.base(), &FieldConfig::default())
        .expect("synthetic sensors grid");
    let neighbours: Vec<Vec<usize>> = field
        .all_neighbours()
        .iter()
        .map(|n| n.iter().map(|c| c.index()).collect())
        .collect();
    let sensors_per_cell: Vec<usize> = field.cells().iter().map(|c| c.sensors.len()).collect();
    // Sensor -> (cell, position in the cell).
    let mut place = vec![(0, 0); farm.sensors().len()];
    for (c, cell) in field.cells().iter().enumerate() {
        for (k, &s) in cell.sensors.iter().enumerate() {
            place[s] = (c, k);
        }
    }
    let last_day = *farm.times().last().expect("at least one day");
    let mission_from = last_day - 13 * DAY;
    let mission_cells: Vec<usize> = (0..field.cells().len())
        .step_by(field.cells().len().div_ceil(10))
        .collect();
    let (mut history, mut mission) = (Vec::new(), Vec::new());
    for r in farm.readings() {
        let (cell, sensor) = place[r.sensor];
        let reading = Reading {
            cell,
            sensor,
            modality: r.modality,
            time: r.time,
            value: r.value,
        };
        if r.time >= mission_from && mission_cells.contains(&cell) {
            mission.push(reading);
        } else {
            history.push(reading);
        }
    }
    Fixture {
        name,
        neighbours,
        sensors_per_cell,
        n_modalities: farm.modalities().len(),
        history,
        mission,
        class_modality: farm.modality_index("vw@30cm").unwrap_or(0),
        train_days,
    }
}

fn build(f: &Fixture) -> IncrementalState {
    let mut state = IncrementalState::new(
        &f.sensors_per_cell,
        &f.neighbours,
        f.n_modalities,
        TimeGrid::DAILY,
    )
    .expect("valid state");
    state.set_retention(Some(RETENTION_S));
    state.set_min_points(MIN_POINTS);
    state.add_readings(&f.history).expect("valid readings");
    state.trim();
    state
}

fn views(s: &[OwnedSeries]) -> Vec<Series<'_>> {
    s.iter().map(OwnedSeries::as_series).collect()
}

fn bench_farm(c: &mut Criterion, f: &Fixture) {
    let state = build(f);
    let bytes = state.to_bytes();
    let newest = state.newest().expect("readings");
    let t = newest;
    let config = UtilityConfig::default();
    // A model trained once on the full class-modality history (what ingest would persist).
    let model = {
        let mut full = IncrementalState::new(
            &f.sensors_per_cell,
            &f.neighbours,
            f.n_modalities,
            TimeGrid::DAILY,
        )
        .expect("valid state");
        let class: Vec<Reading> = f
            .history
            .iter()
            .filter(|r| r.modality == f.class_modality)
            .copied()
            .collect();
        full.add_readings(&class).expect("valid readings");
        let series = full.recent_series(f.class_modality);
        let from = series
            .iter()
            .filter_map(|s| s.times.first())
            .min()
            .copied()
            .unwrap_or(0);
        let from = from.max(newest - f.train_days * DAY);
        ConditionModel::fit(
            &views(&series),
            &f.neighbours,
            from,
            newest,
            &ConditionConfig::default(),
        )
        .expect("model fits")
    };
    let model_bytes = model.to_bytes();
    eprintln!(
        "{}: {} cells, {} modalities, {} history readings, {} mission readings, state {} bytes, model {} bytes",
        f.name,
        f.sensors_per_cell.len(),
        f.n_modalities,
        f.history.len(),
        f.mission.len(),
        bytes.len(),
        model_bytes.len()
    );
    let mut g = c.benchmark_group(format!("persist/{}", f.name));
    g.bench_function("encode", |b| b.iter(|| black_box(state.to_bytes())));
    g.bench_function("decode", |b| {
        b.iter(|| black_box(IncrementalState::from_bytes(black_box(&bytes)).expect("decodes")))
    });
    // Scoring on a pool of one thread, as these figures were first taken (`score` spreads
    // the cells over rayon's pool).
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread pool");
    g.bench_function("score", |b| {
        b.iter(|| one_thread.install(|| black_box(state.score(t, &config, &[]).expect("scores"))))
    });
    let recent = state.recent_series(f.class_modality);
    g.bench_function("predict_from_recent", |b| {
        b.iter(|| {
            let m = ConditionModel::from_bytes(&model_bytes).expect("decodes");
            black_box(m.predict_proba(&views(&recent), &f.neighbours, t))
        })
    });
    g.bench_function("load_and_score", |b| {
        b.iter(|| {
            let s = IncrementalState::from_bytes(black_box(&bytes)).expect("decodes");
            let m = ConditionModel::from_bytes(&model_bytes).expect("decodes");
            let recent = s.recent_series(f.class_modality);
            let p = m.predict_proba(&views(&recent), &f.neighbours, t);
            black_box(one_thread.install(|| s.score(t, &config, &p).expect("scores")))
        })
    });
    g.bench_function("mission_update", |b| {
        b.iter_batched(
            || state.clone(),
            |mut s| {
                s.add_readings(&f.mission).expect("valid readings");
                s.trim();
                black_box(s.to_bytes())
            },
            criterion::BatchSize::LargeInput,
        )
    });
    g.sample_size(10);
    g.bench_function("build_from_history", |b| b.iter(|| black_box(build(f))));
    g.finish();
}

fn persist(c: &mut Criterion) {
    let caf = fixture(
        "caf_size",
        SynthConfig {
            days: 8 * 365,
            vw_depths_cm: vec![30, 60, 90, 120, 150],
            t_depths_cm: vec![30, 60, 90, 120, 150],
            ..SynthConfig::default()
        },
        730,
    );
    bench_farm(c, &caf);
    drop(caf);
    let large = fixture(
        "10k_sensors",
        SynthConfig {
            sensor_count: 10_000,
            days: 365,
            scale_extent_with_sensors: true,
            vw_depths_cm: vec![30],
            t_depths_cm: vec![30],
            ..SynthConfig::default()
        },
        10,
    );
    bench_farm(c, &large);
}

criterion_group!(benches, persist);
criterion_main!(benches);
