//! Targets: generic long CSV parsing >= 1,000,000 readings/s; all 42 CAF daily files parsed.

use std::io::Write;
use std::path::PathBuf;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use gleaner_ingest::{IngestOptions, read_caf_daily, read_long_csv};

fn shared_data() -> PathBuf {
    std::env::var_os("GLEANER_DATA_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data"))
        })
}

fn long_csv(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("readings.csv");
    let n_sensors = 1_000;
    let n_days = 500;
    {
        let mut w = std::io::BufWriter::new(std::fs::File::create(&path).expect("create"));
        writeln!(w, "sensor_id,timestamp,modality,value,unit").expect("write");
        for s in 0..n_sensors {
            for d in 0..n_days {
                // 28-day months keep every generated date valid.
                let (m, dd) = (1 + (d / 28) % 12, 1 + d % 28);
                writeln!(
                    w,
                    "S{s:05},{}-{m:02}-{dd:02}T00:00:00Z,vw@30cm,{:.4},m3/m3",
                    2014 + d / 336,
                    0.2 + (s as f64 * 0.001 + d as f64 * 0.0001) % 0.2
                )
                .expect("write");
            }
        }
    }
    let mut group = c.benchmark_group("ingest");
    group.sample_size(10);
    group.throughput(Throughput::Elements((n_sensors * n_days) as u64));
    group.bench_function("long_csv_500k_readings", |b| {
        b.iter(|| read_long_csv(&path, &IngestOptions::default()).expect("parse"))
    });
    let files: Vec<PathBuf> = std::fs::read_dir(shared_data().join("caf/Daily"))
        .expect("CAF data (set GLEANER_DATA_DIR)")
        .map(|e| e.expect("entry").path())
        .collect();
    group.throughput(Throughput::Elements(files.len() as u64));
    group.bench_function("caf_daily_42_files_parse", |b| {
        b.iter(|| {
            files
                .iter()
                .map(|f| {
                    read_caf_daily(f, &IngestOptions::default())
                        .expect("parse")
                        .0
                        .rows
                        .len()
                })
                .sum::<usize>()
        })
    });
    group.bench_function("caf_daily_42_files_into_fresh_db", |b| {
        b.iter_with_setup(
            || tempfile::tempdir().expect("temp dir"),
            |dir| caf_into_fresh_db(&files, &dir.path().join("caf.db")),
        )
    });
    group.finish();
}

/// What `gleaner ingest` does with the CAF daily files: parse all 42, then one store
/// transaction (sensors, modalities, readings).
fn caf_into_fresh_db(files: &[PathBuf], db: &std::path::Path) -> u64 {
    use gleaner_store::{
        ConflictPolicy, ModalityRecord, Reading, ReadingBatch, SensorRecord, SqliteStore, Store,
        StoreWrite,
    };
    let mut all = gleaner_ingest::Readings::default();
    for f in files {
        all.append(
            read_caf_daily(f, &IngestOptions::default())
                .expect("parse")
                .0,
        );
    }
    let mut store = SqliteStore::open(db).expect("open");
    let sensors: Vec<SensorRecord> = all
        .sensors
        .iter()
        .map(|id| SensorRecord {
            id: id.clone(),
            position: gleaner_field::LatLon::new(46.78, -117.08).expect("valid"),
            elevation_m: None,
            source: "bench".into(),
        })
        .collect();
    let modalities: Vec<ModalityRecord> = all
        .modalities
        .iter()
        .map(|m| ModalityRecord {
            modality: m.modality.clone(),
            unit: m.unit.clone(),
        })
        .collect();
    let batch = ReadingBatch {
        sensors: all.sensors.clone(),
        modalities: all.modalities.iter().map(|m| m.modality.clone()).collect(),
        rows: all
            .rows
            .iter()
            .map(|r| Reading {
                sensor: r.sensor,
                modality: r.modality,
                t: r.t,
                value: r.value,
            })
            .collect(),
    };
    store
        .write(|tx| {
            tx.upsert_sensors(&sensors)?;
            tx.upsert_modalities(&modalities)?;
            tx.insert_readings(&batch, ConflictPolicy::Fail)
        })
        .expect("insert")
        .inserted
}

criterion_group!(benches, long_csv);
criterion_main!(benches);
