//! Ingest speed as a project grows: a synthetic farm's first year into a new SQLite project,
//! then its second year into the same project, each as one `Store::write` transaction (what
//! `gleaner ingest` of a year's file does).
//!
//! Not a criterion benchmark (one year-2 run once took 108 s): a plain harness that repeats the
//! whole scenario and prints each run and the medians.
//!
//! ```text
//! cargo bench -p gleaner-benches --bench store_growth            # 2,000 sensors, 3 runs
//! GLEANER_GROWTH_SENSORS=500 GLEANER_GROWTH_RUNS=5 cargo bench -p gleaner-benches --bench store_growth
//! ```

use std::time::{Duration, Instant};

use gleaner_store::{
    ConflictPolicy, ModalityRecord, ReadingBatch, ReadingBatchBuilder, SensorRecord, SqliteStore,
    Store, StoreRead, StoreWrite,
};
use gleaner_synth::{SynthConfig, SynthFarm, generate};

fn env_or<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// The readings of `farm` whose time is in `[from, to)`, in the farm's (CSV) order.
fn year(farm: &SynthFarm, from: i64, to: i64) -> ReadingBatch {
    let mut b = ReadingBatchBuilder::new();
    for r in farm.readings().filter(|r| (from..to).contains(&r.time)) {
        b.push(
            &farm.sensors()[r.sensor].id,
            &farm.modalities()[r.modality].modality,
            r.time,
            r.value,
        );
    }
    b.finish()
}

fn median(mut v: Vec<Duration>) -> Duration {
    v.sort();
    v[v.len() / 2]
}

fn main() {
    // `cargo bench` passes `--bench`; any other argument is a filter this harness ignores.
    let sensors: usize = env_or("GLEANER_GROWTH_SENSORS", 2_000);
    let runs: usize = env_or("GLEANER_GROWTH_RUNS", 3);
    let config = SynthConfig {
        seed: 7,
        sensor_count: sensors,
        days: 730,
        vw_depths_cm: vec![30, 60, 90],
        t_depths_cm: vec![30],
        ..SynthConfig::default()
    };
    let farm = generate(&config).expect("valid synthetic configuration");
    let split = config.start + 365 * 86_400;
    let year1 = year(&farm, i64::MIN, split);
    let year2 = year(&farm, split, i64::MAX);
    let sensor_records: Vec<SensorRecord> = farm
        .sensors()
        .iter()
        .map(|s| SensorRecord {
            id: s.id.clone(),
            position: s.position,
            elevation_m: None,
            source: "synth".into(),
        })
        .collect();
    let modalities: Vec<ModalityRecord> = farm
        .modalities()
        .iter()
        .map(|m| ModalityRecord {
            modality: m.modality.clone(),
            unit: Some(m.unit.into()),
        })
        .collect();
    println!(
        "store_growth: {sensors} sensors, {} modalities; year 1 {} readings, year 2 {} readings",
        modalities.len(),
        year1.len(),
        year2.len()
    );

    let dir = tempfile::tempdir().expect("temporary directory");
    let (mut first, mut second, mut again) = (Vec::new(), Vec::new(), Vec::new());
    for run in 0..runs {
        let path = dir.path().join(format!("growth{run}.db"));
        let mut store = SqliteStore::open(&path).expect("new database");
        store
            .write(|tx| {
                tx.upsert_sensors(&sensor_records)?;
                tx.upsert_modalities(&modalities)
            })
            .expect("network");
        let ingest = |store: &mut SqliteStore, batch: &ReadingBatch| {
            let t = Instant::now();
            let stats = store
                .write(|tx| tx.insert_readings(batch, ConflictPolicy::Fail))
                .expect("insert");
            (t.elapsed(), stats)
        };
        let (t1, s1) = ingest(&mut store, &year1);
        assert_eq!(s1.inserted as usize, year1.len());
        let (t2, s2) = ingest(&mut store, &year2);
        assert_eq!(s2.inserted as usize, year2.len());
        // The second year again: every reading already stored (a re-ingest of the same file).
        let (t3, s3) = ingest(&mut store, &year2);
        assert_eq!(s3.unchanged as usize, year2.len());
        assert_eq!(
            store.reading_count().expect("count") as usize,
            year1.len() + year2.len()
        );
        let size = std::fs::metadata(&path).map_or(0, |m| m.len());
        println!(
            "run {run}: year 1 {:.2} s, year 2 {:.2} s ({:.1}x), year 2 again {:.2} s; file {:.0} MB",
            t1.as_secs_f64(),
            t2.as_secs_f64(),
            t2.as_secs_f64() / t1.as_secs_f64(),
            t3.as_secs_f64(),
            size as f64 / 1e6
        );
        first.push(t1);
        second.push(t2);
        again.push(t3);
        drop(store);
        for suffix in ["", "-wal", "-shm", "-lock"] {
            let _ = std::fs::remove_file(format!("{}{suffix}", path.display()));
        }
    }
    let (m1, m2, m3) = (median(first), median(second), median(again));
    println!(
        "median of {runs}: year 1 {:.2} s ({:.2} M readings/s), year 2 {:.2} s ({:.2} M readings/s, {:.2}x year 1), year 2 again {:.2} s",
        m1.as_secs_f64(),
        year1.len() as f64 / m1.as_secs_f64() / 1e6,
        m2.as_secs_f64(),
        year2.len() as f64 / m2.as_secs_f64() / 1e6,
        m2.as_secs_f64() / m1.as_secs_f64(),
        m3.as_secs_f64()
    );
}
