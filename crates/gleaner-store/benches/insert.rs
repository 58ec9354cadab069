//! Bulk-ingest speed: 1 M readings into a fresh temp-file database (target >= 1 M readings/s),
//! and re-inserting the same 1 M readings (all unchanged).

use std::hint::black_box;
use std::time::Duration;

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use gleaner_field::{LatLon, Modality, SensorId};
use gleaner_store::{
    ConflictPolicy, ModalityRecord, ReadingBatch, ReadingBatchBuilder, SensorRecord, SqliteStore,
    Store, StoreWrite,
};

const SENSORS: usize = 100;
const MODALITIES: usize = 5;
const STEPS: usize = 2_000; // 100 × 5 × 2000 = 1 M readings
const T0: i64 = 1_262_304_000;

fn network() -> (Vec<SensorRecord>, Vec<ModalityRecord>) {
    let sensors = (0..SENSORS)
        .map(|k| SensorRecord {
            id: SensorId::new(format!("S{k:03}")).unwrap(),
            position: LatLon::new(46.78 + k as f64 * 1e-4, -117.08).unwrap(),
            elevation_m: None,
            source: "bench".into(),
        })
        .collect();
    let modalities = (0..MODALITIES)
        .map(|k| ModalityRecord {
            modality: Modality::at_depth("vw", Some(30 * (k as u32 + 1))).unwrap(),
            unit: Some("m3/m3".into()),
        })
        .collect();
    (sensors, modalities)
}

/// Time-major order, as a wide CSV file delivers it (the store sorts by key itself).
fn readings(sensors: &[SensorRecord], modalities: &[ModalityRecord]) -> ReadingBatch {
    let mut b = ReadingBatchBuilder::new();
    for step in 0..STEPS {
        for (ks, s) in sensors.iter().enumerate() {
            for (km, m) in modalities.iter().enumerate() {
                let v = 0.2 + 0.1 * ((step * 7 + ks * 3 + km) % 97) as f64 / 97.0;
                b.push(&s.id, &m.modality, T0 + step as i64 * 3600, v);
            }
        }
    }
    b.finish()
}

fn fresh_store(
    dir: &tempfile::TempDir,
    sensors: &[SensorRecord],
    modalities: &[ModalityRecord],
) -> SqliteStore {
    let path = dir.path().join("bench.db");
    for suffix in ["", "-wal", "-shm", "-lock"] {
        let _ = std::fs::remove_file(format!("{}{suffix}", path.display()));
    }
    let mut store = SqliteStore::open(&path).unwrap();
    store
        .write(|tx| {
            tx.upsert_sensors(sensors)?;
            tx.upsert_modalities(modalities)
        })
        .unwrap();
    store
}

fn bench(c: &mut Criterion) {
    let (sensors, modalities) = network();
    let batch = readings(&sensors, &modalities);
    assert_eq!(batch.len(), 1_000_000);
    let dir = tempfile::tempdir().unwrap();
    let mut group = c.benchmark_group("insert_readings");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(20));
    group.throughput(Throughput::Elements(batch.len() as u64));
    group.bench_function("fresh_db_1M", |b| {
        b.iter_batched(
            || fresh_store(&dir, &sensors, &modalities),
            |mut store| {
                let stats = store
                    .write(|tx| tx.insert_readings(&batch, ConflictPolicy::Fail))
                    .unwrap();
                assert_eq!(stats.inserted, 1_000_000);
                black_box(store)
            },
            BatchSize::PerIteration,
        )
    });
    let mut store = fresh_store(&dir, &sensors, &modalities);
    store
        .write(|tx| tx.insert_readings(&batch, ConflictPolicy::Fail))
        .unwrap();
    group.bench_function("reinsert_unchanged_1M", |b| {
        b.iter(|| {
            let stats = store
                .write(|tx| tx.insert_readings(&batch, ConflictPolicy::Fail))
                .unwrap();
            assert_eq!(stats.unchanged, 1_000_000);
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
