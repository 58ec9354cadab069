//! Unit and property tests of [`SqliteStore`] against the [`Store`] contract.

use std::collections::{BTreeMap, HashSet};
use std::path::Path;

use gleaner_field::{CellIndex, LatLon, Modality, SensorId, UnixSeconds};
use proptest::prelude::*;

use crate::schema::{self, Migration};
use crate::*;

const DAY: i64 = 86_400;
const T0: UnixSeconds = 1_262_304_000; // 2010-01-01T00:00:00Z

fn sid(s: &str) -> SensorId {
    SensorId::new(s).unwrap()
}

fn md(s: &str) -> Modality {
    Modality::new(s).unwrap()
}

fn sensor(id: &str, lat: f64, lon: f64) -> SensorRecord {
    SensorRecord {
        id: sid(id),
        position: LatLon::new(lat, lon).unwrap(),
        elevation_m: Some(790.0),
        source: "test".into(),
    }
}

/// A store with sensors `a`, `b`, `c` and modalities `vw@30cm`, `t@30cm`.
fn store_with_network(store: &mut SqliteStore) {
    store
        .upsert_sensors(&[
            sensor("a", 46.0, -117.0),
            sensor("b", 46.0001, -117.0),
            sensor("c", 46.001, -117.0),
        ])
        .unwrap();
    store
        .upsert_modalities(&[
            ModalityRecord {
                modality: md("vw@30cm"),
                unit: Some("m3/m3".into()),
            },
            ModalityRecord {
                modality: md("t@30cm"),
                unit: Some("degC".into()),
            },
        ])
        .unwrap();
}

fn memory_store() -> SqliteStore {
    let mut s = SqliteStore::open_in_memory().unwrap();
    store_with_network(&mut s);
    s
}

fn batch(rows: &[(&str, &str, UnixSeconds, f64)]) -> ReadingBatch {
    let mut b = ReadingBatchBuilder::new();
    for (s, m, t, v) in rows {
        b.push(&sid(s), &md(m), *t, *v);
    }
    b.finish()
}

/// Every stored reading as `(sensor, modality, t) -> value`.
fn dump(store: &SqliteStore) -> BTreeMap<(String, String, UnixSeconds), f64> {
    let all = store.readings_for(None, i64::MIN..=i64::MAX).unwrap();
    all.iter()
        .map(|(s, m, t, v)| ((s.to_string(), m.to_string(), t), v))
        .collect()
}

/// The trait stays usable as `dyn Store` (so callers can hold any backend).
#[test]
fn store_is_object_safe() {
    let mut concrete = memory_store();
    let store: &mut dyn Store = &mut concrete;
    store.set_sensor_collected(&sid("a"), T0).unwrap();
    assert_eq!(store.sensor_last_collected().unwrap(), vec![(sid("a"), T0)]);
}

#[test]
fn migration_from_empty_creates_every_table() {
    let dir = tempfile::tempdir().unwrap();
    let store = SqliteStore::open(&dir.path().join("g.db")).unwrap();
    assert_eq!(store.schema_version().unwrap(), schema_version_supported());
    let user_version: i64 = store
        .connection()
        .query_row("PRAGMA user_version", [], |r| r.get(0))
        .unwrap();
    assert_eq!(user_version, schema_version_supported());
    let mode: String = store
        .connection()
        .query_row("PRAGMA journal_mode", [], |r| r.get(0))
        .unwrap();
    assert_eq!(mode, "wal");
    let fk: i64 = store
        .connection()
        .query_row("PRAGMA foreign_keys", [], |r| r.get(0))
        .unwrap();
    assert_eq!(fk, 1);
    for table in [
        "sensors",
        "modalities",
        "readings",
        "ingests",
        "sensor_collection",
        "cells",
        "cell_sensors",
        "cell_metadata",
        "cell_class_probabilities",
        "cell_summaries",
        "cell_correlations",
        "cell_anomalies",
        "missions",
        "visits",
        "config",
    ] {
        let n: i64 = store
            .connection()
            .query_row(
                "SELECT COUNT(*) FROM sqlite_master WHERE type = 'table' AND name = ?1",
                [table],
                |r| r.get(0),
            )
            .unwrap();
        assert_eq!(n, 1, "table {table} missing");
    }
}

#[test]
fn reopening_keeps_data_and_does_not_remigrate() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.db");
    {
        let mut store = SqliteStore::open(&path).unwrap();
        store_with_network(&mut store);
        store
            .insert_readings(&batch(&[("a", "vw@30cm", T0, 0.3)]), ConflictPolicy::Fail)
            .unwrap();
        store.config_set("cell_size_m", "40").unwrap();
    }
    let store = SqliteStore::open(&path).unwrap();
    assert_eq!(store.reading_count().unwrap(), 1);
    assert_eq!(store.sensors().unwrap().len(), 3);
    assert_eq!(
        store.config_get("cell_size_m").unwrap().as_deref(),
        Some("40")
    );
    let migrations: i64 = store
        .connection()
        .query_row("SELECT COUNT(*) FROM schema_migrations", [], |r| r.get(0))
        .unwrap();
    assert_eq!(migrations, schema_version_supported());
}

#[test]
fn newer_schema_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.db");
    {
        let store = SqliteStore::open(&path).unwrap();
        store
            .connection()
            .execute(
                "INSERT INTO schema_migrations VALUES (99, 0, 'from the future')",
                [],
            )
            .unwrap();
    }
    match SqliteStore::open(&path) {
        Err(StoreError::SchemaTooNew { found, supported }) => {
            assert_eq!((found, supported), (99, schema_version_supported()));
        }
        other => panic!("expected SchemaTooNew, got {other:?}"),
    }
    // user_version alone is enough too.
    let path2 = dir.path().join("g2.db");
    {
        let c = rusqlite::Connection::open(&path2).unwrap();
        c.pragma_update(None, "user_version", 7).unwrap();
    }
    let err = SqliteStore::open(&path2).unwrap_err();
    assert!(err.to_string().contains("version 7 is newer"), "{err}");
}

#[test]
fn foreign_files_are_refused_untouched() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no/such/dir/g.db");
    let err = SqliteStore::open(&missing).unwrap_err();
    assert!(err.to_string().contains("no/such/dir/g.db"), "{err}");

    let other = dir.path().join("other.db");
    {
        let c = rusqlite::Connection::open(&other).unwrap();
        c.execute_batch("CREATE TABLE photos (x INTEGER);").unwrap();
    }
    let err = SqliteStore::open(&other).unwrap_err();
    assert!(err.to_string().contains("not a gleaner database"), "{err}");
    let c = rusqlite::Connection::open(&other).unwrap();
    let n: i64 = c
        .query_row("SELECT COUNT(*) FROM sqlite_master", [], |r| r.get(0))
        .unwrap();
    assert_eq!(n, 1, "nothing may be added to a foreign database");
    let mode: String = c
        .query_row("PRAGMA journal_mode", [], |r| r.get(0))
        .unwrap();
    assert_eq!(mode, "delete", "a foreign database keeps its journal mode");

    let text = dir.path().join("notes.txt");
    std::fs::write(&text, "this is not a database, just some text long enough to matter......................................................................................").unwrap();
    let err = SqliteStore::open(&text).unwrap_err();
    assert!(err.to_string().contains("notes.txt"), "{err}");
}

#[test]
fn later_migrations_apply_in_order_and_failed_ones_roll_back() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.db");
    drop(SqliteStore::open(&path).unwrap());
    let mut conn = rusqlite::Connection::open(&path).unwrap();
    let mut list: Vec<Migration> = schema::MIGRATIONS
        .iter()
        .map(|m| Migration {
            description: m.description,
            sql: m.sql,
        })
        .collect();
    let v1 = list.len() as i64;
    list.push(Migration {
        description: "add a column",
        sql: "ALTER TABLE sensors ADD COLUMN note TEXT;",
    });
    list.push(Migration {
        description: "broken",
        sql: "CREATE TABLE extra (x INTEGER); SELECT * FROM no_such_table;",
    });
    // The broken third step fails; the second stays applied, the third leaves nothing.
    assert!(schema::migrate_with(&mut conn, &list).is_err());
    let version: i64 = conn
        .query_row("SELECT MAX(version) FROM schema_migrations", [], |r| {
            r.get(0)
        })
        .unwrap();
    assert_eq!(version, v1 + 1);
    let extra: i64 = conn
        .query_row(
            "SELECT COUNT(*) FROM sqlite_master WHERE name = 'extra'",
            [],
            |r| r.get(0),
        )
        .unwrap();
    assert_eq!(extra, 0);
    list.pop();
    assert_eq!(schema::migrate_with(&mut conn, &list).unwrap(), v1 + 1);
}

#[test]
fn upsert_sensors_is_idempotent_and_reports_moves() {
    let mut store = SqliteStore::open_in_memory().unwrap();
    let first = store
        .upsert_sensors(&[sensor("a", 46.0, -117.0), sensor("b", 46.1, -117.0)])
        .unwrap();
    assert_eq!(first.added, vec!["a", "b"]);
    let again = store
        .upsert_sensors(&[sensor("a", 46.0, -117.0), sensor("b", 46.1, -117.0)])
        .unwrap();
    assert_eq!(
        (again.added.len(), again.updated.len(), again.unchanged),
        (0, 0, 2)
    );
    let moved = store
        .upsert_sensors(&[sensor("a", 46.0, -117.0), sensor("b", 46.2, -117.0)])
        .unwrap();
    assert_eq!(moved.updated, vec!["b"]);
    assert_eq!(store.sensors().unwrap()[1].position.lat(), 46.2);
    let err = store
        .upsert_sensors(&[sensor("c", 46.0, -117.0), sensor("c", 46.5, -117.0)])
        .unwrap_err();
    assert!(err.to_string().contains("\"c\""), "{err}");
    assert_eq!(store.sensors().unwrap().len(), 2);
}

#[test]
fn upsert_modalities_updates_units() {
    let mut store = memory_store();
    let stats = store
        .upsert_modalities(&[
            ModalityRecord {
                modality: md("vw@30cm"),
                unit: Some("%".into()),
            },
            ModalityRecord {
                modality: md("humidity"),
                unit: None,
            },
        ])
        .unwrap();
    assert_eq!(stats.updated, vec!["vw@30cm"]);
    assert_eq!(stats.added, vec!["humidity"]);
    let names: Vec<String> = store
        .modalities()
        .unwrap()
        .iter()
        .map(|m| m.modality.to_string())
        .collect();
    assert_eq!(names, ["humidity", "t@30cm", "vw@30cm"]);
}

#[test]
fn reinserting_the_same_readings_changes_nothing() {
    let mut store = memory_store();
    let b = batch(&[
        ("a", "vw@30cm", T0, 0.3),
        ("a", "vw@30cm", T0 + DAY, 0.31),
        ("b", "t@30cm", T0, 4.5),
    ]);
    let first = store.insert_readings(&b, ConflictPolicy::Fail).unwrap();
    assert_eq!((first.inserted, first.unchanged), (3, 0));
    let before = dump(&store);
    let second = store.insert_readings(&b, ConflictPolicy::Fail).unwrap();
    assert_eq!((second.inserted, second.unchanged), (0, 3));
    assert!(second.conflicts.is_empty());
    assert_eq!(dump(&store), before);
    // A value within the 1e-12 relative tolerance is the same reading.
    let close = batch(&[("a", "vw@30cm", T0, 0.3 * (1.0 + 1e-14))]);
    let s = store.insert_readings(&close, ConflictPolicy::Fail).unwrap();
    assert_eq!((s.inserted, s.unchanged), (0, 1));
}

#[test]
fn conflicts_fail_or_skip() {
    let mut store = memory_store();
    store
        .insert_readings(&batch(&[("a", "vw@30cm", T0, 0.3)]), ConflictPolicy::Fail)
        .unwrap();
    let incoming = batch(&[("a", "vw@30cm", T0 + DAY, 0.2), ("a", "vw@30cm", T0, 0.4)]);
    let err = store
        .insert_readings(&incoming, ConflictPolicy::Fail)
        .unwrap_err();
    match &err {
        StoreError::Conflicts(c) => {
            assert_eq!(c.len(), 1);
            assert_eq!((c[0].stored, c[0].incoming, c[0].t), (0.3, 0.4, T0));
        }
        other => panic!("expected conflicts, got {other:?}"),
    }
    assert!(
        err.to_string().contains("stored 0.3 vs incoming 0.4"),
        "{err}"
    );
    assert_eq!(store.reading_count().unwrap(), 1, "fail must roll back");

    let stats = store
        .insert_readings(&incoming, ConflictPolicy::Skip)
        .unwrap();
    assert_eq!(
        (stats.inserted, stats.unchanged, stats.conflicts.len()),
        (1, 0, 1)
    );
    assert_eq!(dump(&store)[&("a".into(), "vw@30cm".into(), T0)], 0.3);
}

#[test]
fn a_failed_ingest_writes_no_modality_reading_or_provenance() {
    let mut store = memory_store();
    store
        .insert_readings(&batch(&[("a", "vw@30cm", T0, 0.3)]), ConflictPolicy::Fail)
        .unwrap();
    let new_modality = ModalityRecord {
        modality: md("humidity"),
        unit: Some("%".into()),
    };
    let provenance = IngestRecord {
        file_name: "x.csv".into(),
        format: "long-csv".into(),
        rows_read: 2,
        rows_inserted: 0,
        rows_unchanged: 0,
        rows_skipped: 0,
        at: T0,
    };
    let incoming = batch(&[("b", "humidity", T0, 40.0), ("a", "vw@30cm", T0, 0.4)]);
    let err = store
        .ingest(
            std::slice::from_ref(&new_modality),
            &incoming,
            ConflictPolicy::Fail,
            std::slice::from_ref(&provenance),
        )
        .unwrap_err();
    assert!(matches!(err, StoreError::Conflicts(_)), "{err:?}");
    assert_eq!(
        store.modalities().unwrap().len(),
        2,
        "modality must roll back"
    );
    assert!(
        store.ingests().unwrap().is_empty(),
        "provenance must roll back"
    );
    assert_eq!(store.reading_count().unwrap(), 1);
    // The same ingest under Skip goes through whole, with its counts in the provenance.
    let stats = store
        .ingest(
            &[new_modality],
            &incoming,
            ConflictPolicy::Skip,
            &[provenance],
        )
        .unwrap();
    assert_eq!((stats.inserted, stats.conflicts.len()), (1, 1));
    assert_eq!(store.modalities().unwrap().len(), 3);
    let ingests = store.ingests().unwrap();
    assert_eq!((ingests.len(), ingests[0].rows_inserted), (1, 1));
}

#[test]
fn duplicates_within_a_batch() {
    let mut store = memory_store();
    let b = batch(&[
        ("a", "vw@30cm", T0, 0.3),
        ("a", "vw@30cm", T0, 0.3),
        ("a", "vw@30cm", T0 + DAY, 0.1),
        ("a", "vw@30cm", T0 + DAY, 0.2),
    ]);
    assert!(matches!(
        store.insert_readings(&b, ConflictPolicy::Fail),
        Err(StoreError::Conflicts(_))
    ));
    let s = store.insert_readings(&b, ConflictPolicy::Skip).unwrap();
    assert_eq!((s.inserted, s.unchanged, s.conflicts.len()), (2, 1, 1));
    // The first occurrence wins.
    assert_eq!(dump(&store)[&("a".into(), "vw@30cm".into(), T0 + DAY)], 0.1);
}

#[test]
fn bad_batches_are_rejected_whole() {
    let mut store = memory_store();
    let check = |store: &mut SqliteStore, b: ReadingBatch, expected: &str| {
        let err = store.insert_readings(&b, ConflictPolicy::Skip).unwrap_err();
        assert!(
            err.to_string().contains(expected),
            "{err} lacks {expected:?}"
        );
        assert_eq!(store.reading_count().unwrap(), 0);
    };
    check(
        &mut store,
        batch(&[("a", "vw@30cm", T0, 0.3), ("zz9", "vw@30cm", T0, 0.3)]),
        "unknown sensor \"zz9\"",
    );
    check(
        &mut store,
        batch(&[("a", "vw@30cm", T0, 0.3), ("a", "ec@5cm", T0, 0.3)]),
        "unknown modality \"ec@5cm\"",
    );
    check(
        &mut store,
        batch(&[("a", "vw@30cm", T0, 0.3), ("b", "vw@30cm", T0, f64::NAN)]),
        "value NaN is not finite",
    );
    let mut b = batch(&[("a", "vw@30cm", T0, 0.3)]);
    b.rows.push(Reading {
        sensor: 3,
        modality: 0,
        t: T0,
        value: 1.0,
    });
    check(&mut store, b, "sensor index 3 out of range");
}

#[test]
fn a_failure_deep_in_a_big_insert_leaves_the_exact_pre_state() {
    let mut store = memory_store();
    let seed = batch(&[
        ("b", "t@30cm", T0 + 5_000 * 60, 1.0),
        ("c", "vw@30cm", T0, 0.2),
    ]);
    store.insert_readings(&seed, ConflictPolicy::Fail).unwrap();
    let before = dump(&store);
    // 30 000 readings; the conflict sits in the middle of the key order.
    let mut b = ReadingBatchBuilder::new();
    for k in 0..10_000 {
        for (s, m) in [("a", "vw@30cm"), ("b", "t@30cm"), ("c", "t@30cm")] {
            b.push(&sid(s), &md(m), T0 + k * 60, k as f64);
        }
    }
    let err = store
        .insert_readings(&b.finish(), ConflictPolicy::Fail)
        .unwrap_err();
    assert!(matches!(err, StoreError::Conflicts(_)), "{err}");
    assert_eq!(dump(&store), before);
    assert_eq!(store.reading_count().unwrap(), 2);
}

#[test]
fn readings_for_filters_and_orders() {
    let mut store = memory_store();
    store
        .insert_readings(
            &batch(&[
                ("c", "vw@30cm", T0, 3.0),
                ("a", "vw@30cm", T0 + DAY, 2.0),
                ("a", "vw@30cm", T0, 1.0),
                ("a", "t@30cm", T0, 9.0),
                ("b", "vw@30cm", T0 + 2 * DAY, 5.0),
            ]),
            ConflictPolicy::Fail,
        )
        .unwrap();
    let check = |modality: Option<&str>,
                 range: std::ops::RangeInclusive<i64>,
                 expected: &[(&str, &str, i64, f64)]| {
        let m = modality.map(md);
        let got: Vec<(String, String, i64, f64)> = store
            .readings_for(m.as_ref(), range)
            .unwrap()
            .iter()
            .map(|(s, m, t, v)| (s.to_string(), m.to_string(), t, v))
            .collect();
        let expected: Vec<(String, String, i64, f64)> = expected
            .iter()
            .map(|(s, m, t, v)| (s.to_string(), m.to_string(), *t, *v))
            .collect();
        assert_eq!(got, expected);
    };
    check(
        None,
        i64::MIN..=i64::MAX,
        &[
            ("a", "t@30cm", T0, 9.0),
            ("a", "vw@30cm", T0, 1.0),
            ("a", "vw@30cm", T0 + DAY, 2.0),
            ("b", "vw@30cm", T0 + 2 * DAY, 5.0),
            ("c", "vw@30cm", T0, 3.0),
        ],
    );
    check(
        Some("vw@30cm"),
        T0 + DAY..=T0 + 2 * DAY,
        &[
            ("a", "vw@30cm", T0 + DAY, 2.0),
            ("b", "vw@30cm", T0 + 2 * DAY, 5.0),
        ],
    );
    check(Some("t@30cm"), T0 + 1..=T0 + DAY, &[]);
}

#[test]
fn sensor_summaries_match_hand_computed_values() {
    let mut store = memory_store();
    // a vw: 1, 2, 4 at days 0, 1, 2 (latest 4); mean 7/3, sample var = ((4/3)^2+(1/3)^2+(5/3)^2)/2 = 7/3
    store
        .insert_readings(
            &batch(&[
                ("a", "vw@30cm", T0 + 2 * DAY, 4.0),
                ("a", "vw@30cm", T0, 1.0),
                ("a", "vw@30cm", T0 + DAY, 2.0),
                ("b", "t@30cm", T0, -3.5),
            ]),
            ConflictPolicy::Fail,
        )
        .unwrap();
    let s = store.sensor_summaries().unwrap();
    assert_eq!(s.len(), 2);
    assert_eq!(
        (s[0].sensor.as_str(), s[0].modality.as_str()),
        ("a", "vw@30cm")
    );
    let st = &s[0].stats;
    assert_eq!(
        (st.count, st.min, st.max, st.latest_t, st.latest_value),
        (3, 1.0, 4.0, T0 + 2 * DAY, 4.0)
    );
    assert!((st.mean - 7.0 / 3.0).abs() < 1e-12);
    assert!((st.std.unwrap() - (7.0f64 / 3.0).sqrt()).abs() < 1e-12);
    let st = &s[1].stats;
    assert_eq!(
        (st.count, st.mean, st.std, st.latest_value),
        (1, -3.5, None, -3.5)
    );
}

fn cell(i: i32, j: i32, sensors: &[&str]) -> CellRecord {
    CellRecord {
        index: CellIndex { i, j },
        centre: LatLon::new(46.0 + f64::from(j) * 1e-3, -117.0 + f64::from(i) * 1e-3).unwrap(),
        cell_size_m: 40.0,
        sensors: sensors.iter().map(|s| sid(s)).collect(),
    }
}

fn full_metadata(c: CellIndex, neighbour: CellIndex) -> CellMetadata {
    CellMetadata {
        cell: c,
        last_collected: Some(T0),
        pending_bytes: Some(1234.0),
        expected_energy_j: Some(5_100.0),
        scores: Some(CellScores {
            freshness: 0.5,
            redundancy: 0.25,
            anomaly: 1.5,
            uncertainty: 0.75,
            score: 2.5,
            computed_at: T0 + 10,
        }),
        class_probabilities: vec![
            ClassProbability {
                class: "dry".into(),
                probability: 0.2,
            },
            ClassProbability {
                class: "adequate".into(),
                probability: 0.5,
            },
            ClassProbability {
                class: "wet".into(),
                probability: 0.3,
            },
        ],
        summaries: vec![ModalitySummary {
            modality: md("vw@30cm"),
            stats: SeriesStats {
                count: 2,
                mean: 0.3,
                std: Some(0.01),
                min: 0.29,
                max: 0.31,
                latest_t: T0,
                latest_value: 0.31,
            },
        }],
        correlations: vec![Correlation {
            neighbour,
            modality: md("vw@30cm"),
            correlation: 0.8,
            overlap: 12,
        }],
        anomalies: vec![AnomalyRecord {
            modality: md("vw@30cm"),
            t: T0,
            anomaly: 3.2,
            flagged: true,
        }],
    }
}

#[test]
fn cell_metadata_round_trips_and_upserts_by_key() {
    let mut store = memory_store();
    store
        .replace_cells(&[cell(0, 0, &["a", "b"]), cell(1, 0, &["c"])])
        .unwrap();
    let (x0, x1) = (CellIndex { i: 0, j: 0 }, CellIndex { i: 1, j: 0 });
    let empty = store.cell_metadata().unwrap();
    assert_eq!(empty, vec![CellMetadata::new(x0), CellMetadata::new(x1)]);
    let full = full_metadata(x0, x1);
    store
        .upsert_cell_metadata(std::slice::from_ref(&full))
        .unwrap();
    assert_eq!(store.cell_metadata().unwrap()[0], full);
    // A second anomaly is appended; scores replaced; empty lists leave children alone.
    let mut next = CellMetadata::new(x0);
    next.anomalies.push(AnomalyRecord {
        modality: md("vw@30cm"),
        t: T0 + DAY,
        anomaly: 0.1,
        flagged: false,
    });
    store.upsert_cell_metadata(&[next]).unwrap();
    let got = &store.cell_metadata().unwrap()[0];
    assert_eq!(got.scores, None);
    assert_eq!(got.class_probabilities, vec![]);
    assert_eq!(got.anomalies.len(), 2);
    assert_eq!(got.summaries, full.summaries);
    assert_eq!(got.correlations, full.correlations);
    // Unknown cells and out-of-range numbers are rejected without writing.
    let bad = CellMetadata::new(CellIndex { i: 9, j: 9 });
    assert!(
        store
            .upsert_cell_metadata(&[bad])
            .unwrap_err()
            .to_string()
            .contains("x9y9")
    );
    let mut bad = full_metadata(x0, x1);
    bad.class_probabilities[0].probability = 1.5;
    assert!(store.upsert_cell_metadata(&[bad]).is_err());
}

#[test]
fn replace_cells_cascades_metadata_of_changed_cells_only() {
    let mut store = memory_store();
    let (x0, x1) = (CellIndex { i: 0, j: 0 }, CellIndex { i: 1, j: 0 });
    store
        .replace_cells(&[cell(0, 0, &["a", "b"]), cell(1, 0, &["c"])])
        .unwrap();
    store
        .upsert_cell_metadata(&[full_metadata(x0, x1), full_metadata(x1, x0)])
        .unwrap();
    // Same grid again: nothing changes.
    let same = store
        .replace_cells(&[cell(1, 0, &["c"]), cell(0, 0, &["b", "a"])])
        .unwrap();
    assert_eq!((same.kept, same.removed, same.added), (2, 0, 0));
    assert_eq!(store.cell_metadata().unwrap()[0], full_metadata(x0, x1));
    // x1 loses sensor c to a new cell x2: x1 and everything pointing at it go.
    let stats = store
        .replace_cells(&[cell(0, 0, &["a", "b"]), cell(2, 0, &["c"])])
        .unwrap();
    assert_eq!((stats.kept, stats.removed, stats.added), (1, 1, 1));
    let mdata = store.cell_metadata().unwrap();
    assert_eq!(mdata.len(), 2);
    assert!(
        mdata[0].correlations.is_empty(),
        "correlation with x1 must go"
    );
    assert_eq!(mdata[0].anomalies.len(), 1);
    assert_eq!(mdata[1], CellMetadata::new(CellIndex { i: 2, j: 0 }));
    for (table, expected) in [
        ("cell_summaries", 1),
        ("cell_anomalies", 1),
        ("cell_class_probabilities", 3),
        ("cell_correlations", 0),
        ("cell_metadata", 1),
    ] {
        let n: i64 = store
            .connection()
            .query_row(&format!("SELECT COUNT(*) FROM {table}"), [], |r| r.get(0))
            .unwrap();
        assert_eq!(n, expected, "{table}");
    }
    // Invalid grids are refused whole.
    assert!(
        store
            .replace_cells(&[cell(0, 0, &["a"]), cell(1, 0, &["a"])])
            .unwrap_err()
            .to_string()
            .contains("sensor a is in cells")
    );
    assert!(store.replace_cells(&[cell(5, 5, &["nope"])]).is_err());
    assert_eq!(store.cells().unwrap().len(), 2);
    assert_eq!(store.cells().unwrap()[1].sensors, vec![sid("c")]);
}

#[test]
fn refresh_cell_summaries_matches_hand_computed_values() {
    let mut store = memory_store();
    store
        .replace_cells(&[cell(0, 0, &["a", "b"]), cell(1, 0, &["c"])])
        .unwrap();
    // Cell x0y0 vw series: day0 mean(1, 3) = 2; day1 only a = 4; day2 only b = 6 (missing skipped).
    store
        .insert_readings(
            &batch(&[
                ("a", "vw@30cm", T0, 1.0),
                ("b", "vw@30cm", T0, 3.0),
                ("a", "vw@30cm", T0 + DAY, 4.0),
                ("b", "vw@30cm", T0 + 2 * DAY, 6.0),
                ("c", "t@30cm", T0, 10.0),
            ]),
            ConflictPolicy::Fail,
        )
        .unwrap();
    store.set_sensor_collected(&sid("a"), T0 + DAY).unwrap();
    store.set_sensor_collected(&sid("a"), T0).unwrap(); // never moves back
    assert_eq!(
        store.sensor_last_collected().unwrap(),
        vec![(sid("a"), T0 + DAY)]
    );
    let written = store
        .refresh_cell_summaries(&RefreshParams {
            now: T0 + 5 * DAY,
            bytes_per_reading: 10.0,
            default_interval_s: 3600.0,
            changed_sensors: None,
        })
        .unwrap();
    assert_eq!(written, 2);
    let mdata = store.cell_metadata().unwrap();
    let s = &mdata[0].summaries[0];
    assert_eq!(s.modality, md("vw@30cm"));
    let st = &s.stats;
    assert_eq!(
        (st.count, st.min, st.max, st.latest_t, st.latest_value),
        (3, 2.0, 6.0, T0 + 2 * DAY, 6.0)
    );
    assert!((st.mean - 4.0).abs() < 1e-12);
    assert!((st.std.unwrap() - 2.0).abs() < 1e-12); // ((4 + 0 + 4) / 2)^0.5
    assert_eq!(mdata[0].last_collected, Some(T0 + DAY));
    // Pending: a's vw logs every day, latest reading day 1, collected day 1 -> 4 days = 4
    // readings; b every 2 days, latest day 2 -> 3 days / 2 = 1.5 readings. (4 + 1.5) * 10 bytes.
    assert!((mdata[0].pending_bytes.unwrap() - 55.0).abs() < 1e-9);
    // c: a single reading, default interval 1 h: 5 days = 120 readings = 1200 bytes.
    assert!((mdata[1].pending_bytes.unwrap() - 1200.0).abs() < 1e-9);
    assert_eq!(mdata[1].last_collected, None);
    assert_eq!(mdata[1].summaries[0].stats.std, None);
    // Refreshing again is stable.
    store
        .refresh_cell_summaries(&RefreshParams {
            now: T0 + 5 * DAY,
            bytes_per_reading: 10.0,
            default_interval_s: 3600.0,
            changed_sensors: None,
        })
        .unwrap();
    assert_eq!(store.cell_metadata().unwrap(), mdata);
    // New readings of one sensor: refreshing only its cell gives what a full refresh gives.
    store
        .insert_readings(
            &batch(&[("c", "t@30cm", T0 + 3 * DAY, 9.0)]),
            ConflictPolicy::Fail,
        )
        .unwrap();
    let params = |changed| RefreshParams {
        now: T0 + 5 * DAY,
        bytes_per_reading: 10.0,
        default_interval_s: 3600.0,
        changed_sensors: changed,
    };
    store
        .refresh_cell_summaries(&params(Some(vec![sid("c")])))
        .unwrap();
    let partial = store.cell_metadata().unwrap();
    assert_eq!(
        partial[0], mdata[0],
        "the untouched cell keeps its summaries"
    );
    assert_eq!(partial[1].summaries[0].stats.count, 2);
    store.refresh_cell_summaries(&params(None)).unwrap();
    assert_eq!(store.cell_metadata().unwrap(), partial);
}

#[test]
fn missions_and_visits() {
    let mut store = memory_store();
    let new = NewMission {
        created_at: T0,
        kind: MissionKind::Adaptive,
        planned_at: T0 + 60,
        solver: "ils".into(),
        budget_j: 66_500.0,
        energy_j: 60_000.0,
        summary_json: "{\"cells\":2}".into(),
    };
    let id = store.create_mission(&new).unwrap();
    let visits = vec![
        VisitRecord {
            order: 0,
            cell: CellIndex { i: 0, j: -3 },
            arrived_at: Some(T0 + 100),
            energy_j: Some(7000.0),
        },
        VisitRecord {
            order: 1,
            cell: CellIndex { i: 12, j: 1 },
            arrived_at: None,
            energy_j: None,
        },
    ];
    let missions = store.missions().unwrap();
    assert_eq!(missions[0].status, MissionStatus::Planned);
    store.record_visits(id, &visits).unwrap();
    let missions = store.missions().unwrap();
    assert_eq!(
        missions,
        vec![MissionRecord {
            id,
            mission: new,
            status: MissionStatus::Flown,
            visits
        }]
    );
    assert!(
        store
            .record_visits(MissionId(77), &[])
            .unwrap_err()
            .to_string()
            .contains("mission \"77\"")
    );
}

#[test]
fn ingests_and_config() {
    let mut store = memory_store();
    let rec = IngestRecord {
        file_name: "CAF_daily.csv".into(),
        format: "caf-daily".into(),
        rows_read: 10,
        rows_inserted: 7,
        rows_unchanged: 2,
        rows_skipped: 1,
        at: T0,
    };
    store.record_ingest(&rec).unwrap();
    assert_eq!(store.ingests().unwrap(), vec![rec]);
    assert_eq!(store.config_get("k").unwrap(), None);
    store.config_set("k", "1").unwrap();
    store.config_set("k", "2").unwrap();
    assert_eq!(store.config_get("k").unwrap().as_deref(), Some("2"));
}

/// Inserts ever new batches in separate transactions until killed (run as a child process by
/// [`a_killed_writer_leaves_whole_transactions_only`]); a no-op in a normal test run.
#[test]
fn killed_writer_child() {
    let Ok(path) = std::env::var("GLEANER_STORE_KILL_TEST_DB") else {
        return;
    };
    let mut store = SqliteStore::open(Path::new(&path)).unwrap();
    for round in 0.. {
        let mut b = ReadingBatchBuilder::new();
        for k in 0..KILL_BATCH {
            b.push(&sid("a"), &md("vw@30cm"), round * KILL_BATCH + k, 1.0);
        }
        store
            .insert_readings(&b.finish(), ConflictPolicy::Fail)
            .unwrap();
    }
}

const KILL_BATCH: i64 = 50_000;

#[test]
fn a_killed_writer_leaves_whole_transactions_only() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.db");
    {
        let mut store = SqliteStore::open(&path).unwrap();
        store_with_network(&mut store);
    }
    let exe = std::env::current_exe().unwrap();
    let mut child = std::process::Command::new(exe)
        .args(["--exact", "tests::killed_writer_child", "--test-threads=1"])
        .env("GLEANER_STORE_KILL_TEST_DB", &path)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Kill at some point while it writes (after at least one commit most of the time).
    std::thread::sleep(std::time::Duration::from_millis(1500));
    child.kill().unwrap();
    child.wait().unwrap();
    let store = SqliteStore::open(&path).unwrap();
    let ok: String = store
        .connection()
        .query_row("PRAGMA integrity_check", [], |r| r.get(0))
        .unwrap();
    assert_eq!(ok, "ok");
    let n = store.reading_count().unwrap() as i64;
    eprintln!("killed writer left {n} readings");
    assert_eq!(
        n % KILL_BATCH,
        0,
        "{n} readings: a partial transaction survived"
    );
    let max_t: Option<i64> = store
        .connection()
        .query_row("SELECT MAX(t) FROM readings", [], |r| r.get(0))
        .unwrap();
    assert_eq!(max_t.map_or(0, |t| t + 1), n);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn inserting_twice_inserts_nothing_the_second_time(
        rows in proptest::collection::vec((0usize..3, 0usize..2, 0i64..40, -3i32..3), 0..300)
    ) {
        let mut store = memory_store();
        let sensors = ["a", "b", "c"];
        let modalities = ["vw@30cm", "t@30cm"];
        let mut b = ReadingBatchBuilder::new();
        for (s, m, t, v) in &rows {
            b.push(&sid(sensors[*s]), &md(modalities[*m]), T0 + t * 60, f64::from(*v) * 0.5);
        }
        let b = b.finish();
        let first = store.insert_readings(&b, ConflictPolicy::Skip).unwrap();
        let distinct: HashSet<(usize, usize, i64)> = rows.iter().map(|(s, m, t, _)| (*s, *m, *t)).collect();
        prop_assert_eq!(first.inserted as usize, distinct.len());
        prop_assert_eq!(first.inserted as usize + first.unchanged as usize + first.conflicts.len(), rows.len());
        let second = store.insert_readings(&b, ConflictPolicy::Skip).unwrap();
        prop_assert_eq!(second.inserted, 0);
        prop_assert_eq!(second.unchanged as usize + second.conflicts.len(), rows.len());
        prop_assert_eq!(store.reading_count().unwrap() as usize, distinct.len());
    }
}

/// Naive statistics of a series given as `t -> value`.
fn naive_stats(series: &BTreeMap<i64, f64>) -> SeriesStats {
    let n = series.len() as f64;
    let mean = series.values().sum::<f64>() / n;
    let ss: f64 = series.values().map(|v| (v - mean) * (v - mean)).sum();
    let (&latest_t, &latest_value) = series.iter().next_back().unwrap();
    SeriesStats {
        count: series.len() as u64,
        mean,
        std: (series.len() >= 2).then(|| (ss / (n - 1.0)).sqrt()),
        min: series.values().copied().fold(f64::INFINITY, f64::min),
        max: series.values().copied().fold(f64::NEG_INFINITY, f64::max),
        latest_t,
        latest_value,
    }
}

fn assert_stats_close(got: &SeriesStats, want: &SeriesStats) {
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * (1.0 + a.abs().max(b.abs()));
    assert_eq!((got.count, got.latest_t), (want.count, want.latest_t));
    assert!(close(got.mean, want.mean), "{got:?} vs {want:?}");
    assert!(
        close(got.min, want.min) && close(got.max, want.max),
        "{got:?} vs {want:?}"
    );
    assert!(
        close(got.latest_value, want.latest_value),
        "{got:?} vs {want:?}"
    );
    match (got.std, want.std) {
        (Some(a), Some(b)) => assert!(close(a, b), "{got:?} vs {want:?}"),
        (a, b) => assert_eq!(a, b),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]
    /// Readings come back exactly; SQL summaries (per sensor, and per cell over the cell series)
    /// agree with a naive computation in Rust.
    #[test]
    fn stored_readings_and_summaries_match_a_naive_model(
        rows in proptest::collection::vec((0usize..3, 0usize..2, 0i64..30, -1e3f64..1e3), 1..200)
    ) {
        let mut store = memory_store();
        store.replace_cells(&[cell(0, 0, &["a", "b"]), cell(1, 0, &["c"])]).unwrap();
        let sensors = ["a", "b", "c"];
        let modalities = ["vw@30cm", "t@30cm"];
        // First occurrence of a key wins (as the store keeps it under Skip).
        let mut model: BTreeMap<(usize, usize, i64), f64> = BTreeMap::new();
        let mut b = ReadingBatchBuilder::new();
        for &(s, m, t, v) in &rows {
            model.entry((s, m, t)).or_insert(v);
            b.push(&sid(sensors[s]), &md(modalities[m]), T0 + t * DAY, v);
        }
        store.insert_readings(&b.finish(), ConflictPolicy::Skip).unwrap();
        let stored = dump(&store);
        let expected: BTreeMap<(String, String, i64), f64> = model
            .iter()
            .map(|(&(s, m, t), &v)| ((sensors[s].to_string(), modalities[m].to_string(), T0 + t * DAY), v))
            .collect();
        prop_assert_eq!(&stored, &expected);

        let mut per_sensor: BTreeMap<(String, String), BTreeMap<i64, f64>> = BTreeMap::new();
        for ((s, m, t), v) in &stored {
            per_sensor.entry((s.clone(), m.clone())).or_default().insert(*t, *v);
        }
        let summaries = store.sensor_summaries().unwrap();
        prop_assert_eq!(summaries.len(), per_sensor.len());
        for (s, ((sensor, modality), series)) in summaries.iter().zip(&per_sensor) {
            prop_assert_eq!((s.sensor.as_str(), s.modality.as_str()), (sensor.as_str(), modality.as_str()));
            assert_stats_close(&s.stats, &naive_stats(series));
        }

        // Cell series: mean over the cell's sensors present at each t.
        let cell_of = |s: &str| if s == "c" { 1 } else { 0 };
        let mut sums: BTreeMap<(usize, String), BTreeMap<i64, (f64, f64)>> = BTreeMap::new();
        for ((s, m, t), v) in &stored {
            let e = sums.entry((cell_of(s), m.clone())).or_default().entry(*t).or_insert((0.0, 0.0));
            e.0 += v;
            e.1 += 1.0;
        }
        store.refresh_cell_summaries(&RefreshParams { now: T0, bytes_per_reading: 1.0, default_interval_s: 1.0, changed_sensors: None }).unwrap();
        let mdata = store.cell_metadata().unwrap();
        let mut got = 0;
        for (k, md) in mdata.iter().enumerate() {
            for s in &md.summaries {
                let series: BTreeMap<i64, f64> = sums[&(k, s.modality.to_string())]
                    .iter()
                    .map(|(t, (sum, n))| (*t, sum / n))
                    .collect();
                assert_stats_close(&s.stats, &naive_stats(&series));
                got += 1;
            }
        }
        prop_assert_eq!(got, sums.len());
    }
}
