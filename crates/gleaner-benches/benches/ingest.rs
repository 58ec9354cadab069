//! Targets: generic long CSV parsing >= 1,000,000 readings/s; all 42 CAF daily files parsed;
//! the CAF readings inserted into a new store (SQLite, and PostgreSQL's binary `COPY` when
//! `GLEANER_TEST_PG_URL` names a server: target >= 500,000 readings/s).

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
    let rows = CafRows::parse(files);
    let mut store = gleaner_store::SqliteStore::open(db).expect("open");
    rows.insert(&mut store)
}

/// The CAF daily readings as the store's input: sensors, modalities and one batch.
struct CafRows {
    sensors: Vec<gleaner_store::SensorRecord>,
    modalities: Vec<gleaner_store::ModalityRecord>,
    batch: gleaner_store::ReadingBatch,
}

impl CafRows {
    fn parse(files: &[PathBuf]) -> Self {
        let mut all = gleaner_ingest::Readings::default();
        for f in files {
            all.append(
                read_caf_daily(f, &IngestOptions::default())
                    .expect("parse")
                    .0,
            );
        }
        let sensors = all
            .sensors
            .iter()
            .map(|id| gleaner_store::SensorRecord {
                id: id.clone(),
                position: gleaner_field::LatLon::new(46.78, -117.08).expect("valid"),
                elevation_m: None,
                source: "bench".into(),
            })
            .collect();
        // The same conversion `gleaner ingest` makes.
        let (modalities, batch) = gleaner_app::batch_of(&all);
        CafRows {
            sensors,
            modalities,
            batch,
        }
    }

    /// One write transaction: sensors, modalities, readings; returns the readings inserted.
    fn insert<S: gleaner_store::Store>(&self, store: &mut S) -> u64 {
        use gleaner_store::{ConflictPolicy, StoreWrite};
        store
            .write(|tx| {
                tx.upsert_sensors(&self.sensors)?;
                tx.upsert_modalities(&self.modalities)?;
                tx.insert_readings(&self.batch, ConflictPolicy::Fail)
            })
            .expect("insert")
            .inserted
    }
}

/// The 759,915 CAF daily readings, already parsed, inserted into a new project: SQLite, and
/// PostgreSQL when `GLEANER_TEST_PG_URL` is set (a new schema per iteration, dropped after).
fn store_insert(c: &mut Criterion) {
    let files: Vec<PathBuf> = std::fs::read_dir(shared_data().join("caf/Daily"))
        .expect("CAF data (set GLEANER_DATA_DIR)")
        .map(|e| e.expect("entry").path())
        .collect();
    let rows = CafRows::parse(&files);
    let mut group = c.benchmark_group("store_insert");
    group.sample_size(10);
    group.throughput(Throughput::Elements(rows.batch.rows.len() as u64));
    group.bench_function("caf_daily_sqlite", |b| {
        b.iter_with_setup(
            || tempfile::tempdir().expect("temp dir"),
            |dir| {
                let mut store =
                    gleaner_store::SqliteStore::open(&dir.path().join("caf.db")).expect("open");
                rows.insert(&mut store)
            },
        )
    });
    match std::env::var("GLEANER_TEST_PG_URL") {
        Ok(url) => {
            let mut k = 0u32;
            let project = |k: u32| format!("bench_insert_{}_{k}", std::process::id());
            group.bench_function("caf_daily_postgres_copy", |b| {
                b.iter_with_setup(
                    || {
                        // The previous iteration's project is dropped here, untimed.
                        gleaner_store::PgStore::drop_project(&url, &project(k)).expect("drop");
                        k += 1;
                        gleaner_store::PgStore::open(&url, &project(k)).expect("open")
                    },
                    |mut store| rows.insert(&mut store),
                )
            });
            gleaner_store::PgStore::drop_project(&url, &project(k)).expect("drop");
        }
        Err(_) => eprintln!(
            "store_insert/caf_daily_postgres_copy skipped: set GLEANER_TEST_PG_URL \
             (scripts/pg-cluster.sh start; scripts/pg-cluster.sh env DIR)"
        ),
    }
    group.finish();
}

criterion_group!(benches, long_csv, store_insert);
criterion_main!(benches);
