//! Tests of [`SqliteStore`]: the backend-neutral [`crate::conformance`] suite, and what only
//! SQLite has (files, migrations, locking, crash safety).

use std::path::Path;

use gleaner_field::{CellIndex, LatLon, UnixSeconds};

use crate::conformance::{batch, md, sensor, sid};
use crate::schema::{self, Migration};
use crate::sqlite::migrate_with;
use crate::*;

const T0: UnixSeconds = 1_262_304_000; // 2010-01-01T00:00:00Z

/// Sensors `a`, `b`, `c` and modalities `vw@30cm`, `t@30cm`.
fn store_with_network(store: &mut SqliteStore) {
    store
        .write(|tx| {
            tx.upsert_sensors(&[
                sensor("a", 46.0, -117.0),
                sensor("b", 46.0001, -117.0),
                sensor("c", 46.001, -117.0),
            ])?;
            tx.upsert_modalities(&[
                ModalityRecord {
                    modality: md("vw@30cm"),
                    unit: Some("m3/m3".into()),
                },
                ModalityRecord {
                    modality: md("t@30cm"),
                    unit: Some("degC".into()),
                },
            ])
        })
        .unwrap();
}

fn count(store: &SqliteStore, sql: &str) -> i64 {
    store.raw().query_row(sql, [], |r| r.get(0)).unwrap()
}

#[test]
fn an_in_memory_copy_is_equal_and_independent() {
    let mut store = SqliteStore::open_in_memory().unwrap();
    store_with_network(&mut store);
    let mut copy = store.copy_in_memory().unwrap();
    assert_eq!(copy.dump().unwrap(), store.dump().unwrap());
    copy.write(|tx| tx.upsert_sensors(&[sensor("d", 46.002, -117.0)]))
        .unwrap();
    assert_eq!(count(&copy, "SELECT COUNT(*) FROM sensors"), 4);
    assert_eq!(count(&store, "SELECT COUNT(*) FROM sensors"), 3);
}

/// The kept reading count follows this connection's commits (not its rolled-back writes)
/// and another connection's commits to the same file, inside transactions and out.
#[test]
fn the_kept_reading_count_follows_every_commit() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.db");
    let mut a = SqliteStore::open(&path).unwrap();
    store_with_network(&mut a);
    let mut b = SqliteStore::open(&path).unwrap();
    let real = |s: &SqliteStore| count(s, "SELECT COUNT(*) FROM readings") as u64;
    assert_eq!(a.reading_count().unwrap(), 0);
    a.write(|tx| {
        assert_eq!(tx.reading_count()?, 0);
        let stats = tx.insert_readings(
            &batch(&[("a", "vw@30cm", T0, 0.3), ("b", "vw@30cm", T0, 0.2)]),
            ConflictPolicy::Fail,
        )?;
        assert_eq!(stats.inserted, 2);
        assert_eq!(tx.reading_count()?, 2);
        // The same again: nothing new.
        tx.insert_readings(&batch(&[("a", "vw@30cm", T0, 0.3)]), ConflictPolicy::Fail)?;
        assert_eq!(tx.reading_count()?, 2);
        Ok::<_, StoreError>(())
    })
    .unwrap();
    assert_eq!((a.reading_count().unwrap(), real(&a)), (2, 2));
    // A rolled-back write leaves it.
    let failed: std::result::Result<(), StoreError> = a.write(|tx| {
        tx.insert_readings(&batch(&[("c", "vw@30cm", T0, 0.1)]), ConflictPolicy::Fail)?;
        assert_eq!(tx.reading_count()?, 3);
        Err(StoreError::Backend("give up".into()))
    });
    assert!(failed.is_err());
    assert_eq!((a.reading_count().unwrap(), real(&a)), (2, 2));
    // Another connection's commit.
    assert_eq!(b.reading_count().unwrap(), 2);
    b.write(|tx| tx.insert_readings(&batch(&[("c", "t@30cm", T0, 9.0)]), ConflictPolicy::Fail))
        .unwrap();
    assert_eq!((a.reading_count().unwrap(), real(&a)), (3, 3));
    a.write(|tx| {
        assert_eq!(tx.reading_count()?, 3);
        tx.insert_readings(
            &batch(&[("c", "t@30cm", T0 + 86_400, 8.0)]),
            ConflictPolicy::Fail,
        )
    })
    .unwrap();
    assert_eq!(a.reading_count().unwrap(), 4);
    assert_eq!(b.reading_count().unwrap(), 4);
}

#[test]
fn conformance_in_memory() {
    conformance::run_all(|| SqliteStore::open_in_memory().unwrap());
}

#[test]
fn conformance_on_files() {
    let dir = tempfile::tempdir().unwrap();
    let mut k = 0;
    conformance::run_all(|| {
        k += 1;
        SqliteStore::open(&dir.path().join(format!("g{k}.db"))).unwrap()
    });
}

#[test]
fn migration_from_empty_creates_every_table() {
    let dir = tempfile::tempdir().unwrap();
    let store = SqliteStore::open(&dir.path().join("g.db")).unwrap();
    assert_eq!(store.schema_version().unwrap(), schema_version_supported());
    assert_eq!(schema_version_supported(), 4);
    assert_eq!(
        count(&store, "PRAGMA user_version"),
        schema_version_supported()
    );
    let mode: String = store
        .raw()
        .query_row("PRAGMA journal_mode", [], |r| r.get(0))
        .unwrap();
    assert_eq!(mode, "wal");
    assert_eq!(count(&store, "PRAGMA foreign_keys"), 1);
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
        "mission_stops",
        "visits",
        "config",
        "blobs",
    ] {
        let n: i64 = store
            .raw()
            .query_row(
                "SELECT COUNT(*) FROM sqlite_master WHERE type = 'table' AND name = ?1",
                [table],
                |r| r.get(0),
            )
            .unwrap();
        assert_eq!(n, 1, "table {table} missing");
    }
    // No table of the migration's intermediate names survives, and the children of missions
    // point at the final table.
    assert_eq!(
        count(
            &store,
            "SELECT COUNT(*) FROM sqlite_master WHERE name LIKE '%_v2' OR sql LIKE '%_v2%'"
        ),
        0
    );
}

#[test]
fn reopening_keeps_data_and_does_not_remigrate() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.db");
    {
        let mut store = SqliteStore::open(&path).unwrap();
        store_with_network(&mut store);
        store
            .write(|tx| {
                tx.insert_readings(&batch(&[("a", "vw@30cm", T0, 0.3)]), ConflictPolicy::Fail)?;
                tx.config_set("cell_size_m", "40")?;
                tx.blob_put("state", b"\x01\x02")
            })
            .unwrap();
    }
    let store = SqliteStore::open(&path).unwrap();
    assert_eq!(store.reading_count().unwrap(), 1);
    assert_eq!(store.sensors().unwrap().len(), 3);
    assert_eq!(
        store.config_get("cell_size_m").unwrap().as_deref(),
        Some("40")
    );
    assert_eq!(store.blob_get("state").unwrap(), Some(vec![1, 2]));
    assert_eq!(
        count(&store, "SELECT COUNT(*) FROM schema_migrations"),
        schema_version_supported()
    );
}

#[test]
fn newer_schema_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.db");
    {
        let store = SqliteStore::open(&path).unwrap();
        store
            .raw()
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
    assert!(matches!(err, StoreError::Open { .. }), "{err:?}");
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
    assert!(matches!(err, StoreError::Open { .. }), "{err:?}");
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
    assert!(migrate_with(&mut conn, &list).is_err());
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
    assert_eq!(migrate_with(&mut conn, &list).unwrap(), v1 + 1);
}

/// A version-1 database as the previous gleaner wrote it: an adaptive mission with the old
/// planner's JSON summary, a flown exploration sortie, a mission with an unreadable summary.
fn legacy_v1_database(path: &Path) {
    let mut conn = rusqlite::Connection::open(path).unwrap();
    conn.pragma_update(None, "foreign_keys", true).unwrap();
    migrate_with(&mut conn, &schema::MIGRATIONS[..1]).unwrap();
    let adaptive = r#"{"mission_id":null,"planned_at":"2010-01-01T00:01:00Z","planner":"default",
        "seed":42,"time_limit_s":2.0,"weights":[1.0,0.5,2.0,0.25],"anomaly_form":"raw",
        "base_lon_lat":[-117.0867,46.7788],"cruise_speed_mps":10.2,
        "stops":[{"order":1,"cell":"x0y-3","centre_lon_lat":[-117.0,45.997],"s":2.5,
                  "terms":[0.5,0.25,1.75,0.125],"leg_distance_m":120.5,"leg_energy_j":1510.25,
                  "collection_s":12.5,"hover_s":14.0,"hover_j":2380.0,"comm_j":6.25},
                 {"order":2,"cell":"x12y1","centre_lon_lat":[-116.988,46.001],"s":1.0,
                  "terms":null,"leg_distance_m":80.0,"leg_energy_j":900.0,
                  "collection_s":1.0,"hover_s":2.0,"hover_j":3.0,"comm_j":4.0}],
        "return_distance_m":140.0,
        "energy":{"travel_j":30000.0,"hover_j":4760.0,"comm_j":12.5,"return_j":1700.0,
                  "total_j":36472.5,"budget_j":66500.0,"utilisation":0.55,
                  "distance_m":2400.75,"flight_time_s":321.5},
        "total_score":3.5,"candidates":10,
        "greedy_baseline":{"planner":"greedy","cells":2,"total_score":3.0,"energy_j":1.0}}"#;
    conn.execute_batch(&format!(
        "INSERT INTO sensors (name, lat, lon, elevation_m, source)
             VALUES ('a', 46.0, -117.0, NULL, 't'), ('b', 46.002, -117.002, NULL, 't');
         INSERT INTO cells (label, i, j, lat, lon, cell_size_m) VALUES ('x1y0', 1, 0, 46.0, -116.999, 40);
         INSERT INTO missions (created_at, kind, planned_at, solver, budget_j, energy_j, status, summary_json)
             VALUES ({T0}, 'adaptive', {p}, 'default', 66500.0, 36472.5, 'planned', '{adaptive}');
         INSERT INTO missions (created_at, kind, planned_at, solver, budget_j, energy_j, status, summary_json)
             VALUES ({T0}, 'exploration', {p}, 'exploration', 66500.0, 5000.0, 'flown',
                     '{{\"stops\":[{{\"cell\":\"x1y0\"}},{{\"cell\":\"x9y9\"}}],\"energy_j\":5000.0}}');
         INSERT INTO visits (mission, position, cell, arrived_at, energy_j)
             VALUES (2, 0, 'x1y0', {v}, 10.0), (2, 1, 'x9y9', NULL, NULL);
         INSERT INTO missions (created_at, kind, planned_at, solver, budget_j, energy_j, status, summary_json)
             VALUES ({T0}, 'adaptive', {p}, 'greedy', 100.0, 50.0, 'flown', 'not json');",
        p = T0 + 60,
        v = T0 + 400,
    ))
    .unwrap();
}

#[test]
fn migration_2_converts_legacy_missions() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.db");
    legacy_v1_database(&path);
    let store = SqliteStore::open(&path).unwrap();
    assert_eq!(store.schema_version().unwrap(), 4);
    let missions = store.missions().unwrap();
    assert_eq!(missions.len(), 3);

    let m = &missions[0];
    assert_eq!(
        (m.id, m.status, m.flown_at),
        (MissionId(1), MissionStatus::Planned, None)
    );
    let n = &m.mission;
    assert_eq!((n.seed, n.weights), (42, [1.0, 0.5, 2.0, 0.25]));
    assert_eq!((n.anomaly_form.as_str(), n.total_score), ("raw", 3.5));
    assert_eq!(n.profile.base, LatLon::new(46.7788, -117.0867).unwrap());
    assert_eq!(n.profile.cruise_speed_mps, 10.2);
    // Migration 3: missions planned before winds were planned are still-air plans.
    assert_eq!((n.profile.wind_mps, n.profile.wind_from_deg), (0.0, 0.0));
    assert_eq!(
        n.energy,
        EnergyBreakdown {
            travel_j: 30000.0,
            hover_j: 4760.0,
            comm_j: 12.5,
            return_j: 1700.0,
            total_j: 36472.5,
            budget_j: 66500.0,
            distance_m: 2400.75,
            flight_time_s: 321.5,
        }
    );
    assert_eq!(n.return_distance_m, 140.0);
    assert_eq!(n.stops.len(), 2);
    assert_eq!(
        n.stops[0],
        StopRecord {
            order: 0,
            cell: CellIndex { i: 0, j: -3 },
            centre: LatLon::new(45.997, -117.0).unwrap(),
            score: 2.5,
            terms: Some([0.5, 0.25, 1.75, 0.125]),
            leg_distance_m: 120.5,
            leg_energy_j: 1510.25,
            collection_s: 12.5,
            hover_s: 14.0,
            hover_j: 2380.0,
            comm_j: 6.25,
        }
    );
    assert_eq!((n.stops[1].order, n.stops[1].terms), (1, None));

    // Exploration: stops by label, centres from the grid where the cell still exists (else the
    // base, here the sensors' mean position); flown at its latest visit.
    let e = &missions[1];
    assert_eq!(
        (e.status, e.flown_at),
        (MissionStatus::Flown, Some(T0 + 400))
    );
    assert_eq!(e.visits.len(), 2);
    let base = e.mission.profile.base;
    assert!((base.lat() - 46.001).abs() < 1e-9 && (base.lon() + 117.001).abs() < 1e-9);
    assert_eq!(e.mission.energy.total_j, 5000.0);
    assert_eq!(e.mission.anomaly_form, "n/a");
    let stops = &e.mission.stops;
    assert_eq!(stops.len(), 2);
    assert_eq!(stops[0].centre, LatLon::new(46.0, -116.999).unwrap());
    assert_eq!(stops[1].centre, base);
    assert_eq!((stops[0].score, stops[0].terms), (0.0, None));

    // Unreadable summary: defaults, flown at its planned time (no arrivals recorded).
    let g = &missions[2];
    assert_eq!(
        (g.status, g.flown_at, g.mission.stops.len()),
        (MissionStatus::Flown, Some(T0 + 60), 0)
    );
    assert_eq!(g.mission.energy.budget_j, 100.0);

    // The legacy summary is kept; foreign keys of the recreated tables are intact, and
    // deleting a mission cascades to its stops and visits.
    assert_eq!(
        count(
            &store,
            "SELECT COUNT(*) FROM missions WHERE summary_json IS NOT NULL"
        ),
        3
    );
    assert_eq!(
        count(&store, "SELECT COUNT(*) FROM pragma_foreign_key_check"),
        0
    );
    store
        .raw()
        .execute("DELETE FROM missions WHERE id = 2", [])
        .unwrap();
    assert_eq!(count(&store, "SELECT COUNT(*) FROM visits"), 0);
    assert_eq!(count(&store, "SELECT COUNT(*) FROM mission_stops"), 2);
    // A recorded legacy flight is refused a second record.
    let mut store = store;
    let err = store
        .write(|tx| tx.record_visits(MissionId(3), &[], T0, false))
        .unwrap_err();
    assert!(
        matches!(err, StoreError::AlreadyFlown { mission: 3, .. }),
        "{err:?}"
    );
}

#[test]
fn replace_cells_leaves_no_orphan_rows() {
    let mut store = SqliteStore::open_in_memory().unwrap();
    store_with_network(&mut store);
    let cell = |i: i32, sensors: &[&str]| CellRecord {
        index: CellIndex { i, j: 0 },
        centre: LatLon::new(46.0, -117.0 + f64::from(i) * 1e-3).unwrap(),
        cell_size_m: 40.0,
        sensors: sensors.iter().map(|s| sid(s)).collect(),
    };
    let meta = |c: i32, n: i32| {
        let mut m = CellMetadata::new(CellIndex { i: c, j: 0 });
        m.correlations.push(Correlation {
            neighbour: CellIndex { i: n, j: 0 },
            modality: md("vw@30cm"),
            correlation: 0.5,
            overlap: 3,
        });
        m.anomalies.push(AnomalyRecord {
            modality: md("vw@30cm"),
            t: T0,
            anomaly: 1.0,
            flagged: false,
        });
        m.class_probabilities.push(ClassProbability {
            class: "dry".into(),
            probability: 1.0,
        });
        m
    };
    store
        .write(|tx| {
            tx.replace_cells(&[cell(0, &["a", "b"]), cell(1, &["c"])])?;
            tx.upsert_cell_metadata(&[meta(0, 1), meta(1, 0)])
        })
        .unwrap();
    store
        .write(|tx| tx.replace_cells(&[cell(0, &["a", "b"]), cell(2, &["c"])]))
        .unwrap();
    for (table, expected) in [
        ("cell_anomalies", 1),
        ("cell_class_probabilities", 1),
        ("cell_correlations", 0),
        ("cell_metadata", 1),
        ("cell_sensors", 3),
    ] {
        assert_eq!(
            count(&store, &format!("SELECT COUNT(*) FROM {table}")),
            expected,
            "{table}"
        );
    }
}

/// A second writer on the same file waits for the first (IMMEDIATE transactions and the busy
/// timeout) instead of failing with "database is locked". Explicit synchronisation, no sleeps:
/// the first writer holds its transaction until the second has been started, and the second
/// must see the first's commit.
#[test]
fn a_second_writer_waits_for_the_first() {
    use std::sync::mpsc::channel;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.db");
    let mut first = SqliteStore::open(&path).unwrap();
    store_with_network(&mut first);
    let mut second = SqliteStore::open(&path).unwrap();
    let (in_tx, in_rx) = channel();
    let (go_tx, go_rx) = channel::<()>();
    let writer = std::thread::spawn(move || {
        first
            .write(|tx| {
                // Read first, as a use case does; a deferred transaction would then fail to
                // upgrade to a write while the other connection writes.
                let n = tx.reading_count()?;
                in_tx.send(()).unwrap();
                go_rx.recv().unwrap();
                tx.insert_readings(
                    &batch(&[("a", "vw@30cm", T0 + n as i64, 1.0)]),
                    ConflictPolicy::Fail,
                )
            })
            .unwrap();
    });
    in_rx.recv().unwrap();
    let (started_tx, started_rx) = channel();
    let other = std::thread::spawn(move || {
        started_tx.send(()).unwrap();
        second
            .write(|tx| {
                let n = tx.reading_count()?;
                assert_eq!(n, 1, "the second writer must see the first's commit");
                tx.insert_readings(&batch(&[("b", "vw@30cm", T0, 2.0)]), ConflictPolicy::Fail)
            })
            .unwrap();
        second
    });
    started_rx.recv().unwrap();
    go_tx.send(()).unwrap();
    writer.join().unwrap();
    let second = other.join().unwrap();
    assert_eq!(second.reading_count().unwrap(), 2);
}

/// Past the busy timeout a second writer fails with the documented message, not SQLite's raw
/// "database is locked"; opening the database and reading meanwhile do not wait for the lock.
/// Explicit synchronisation: the first writer holds its transaction until the second is done.
#[test]
fn a_writer_past_the_busy_timeout_is_told_another_process_is_writing() {
    use std::sync::mpsc::channel;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.db");
    let mut first = SqliteStore::open(&path).unwrap();
    store_with_network(&mut first);
    let (held_tx, held_rx) = channel();
    let (done_tx, done_rx) = channel::<()>();
    let holder = std::thread::spawn(move || {
        first
            .write(|tx| {
                tx.reading_count()?;
                held_tx.send(()).unwrap();
                done_rx.recv().unwrap();
                Ok::<_, StoreError>(())
            })
            .unwrap();
    });
    held_rx.recv().unwrap();
    let mut second = SqliteStore::open(&path).expect("opening does not wait for the writer");
    second.reading_count().expect("reading does not wait");
    second
        .set_busy_timeout(std::time::Duration::from_millis(20))
        .unwrap();
    let err = second
        .write(|tx| tx.reading_count().map(|_| ()))
        .expect_err("the write lock is held")
        .to_string();
    done_tx.send(()).unwrap();
    holder.join().unwrap();
    assert!(
        err.contains(&format!(
            "another gleaner process has been writing to {} for more than 0.02 s",
            path.display()
        )),
        "{err}"
    );
    assert!(!err.contains("database is locked"), "{err}");
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
        let b = b.finish();
        store
            .write(|tx| tx.insert_readings(&b, ConflictPolicy::Fail))
            .unwrap();
        // Tell the parent what has been committed.
        println!("committed {round}");
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
        .args([
            "--exact",
            "tests::killed_writer_child",
            "--test-threads=1",
            "--nocapture",
        ])
        .env("GLEANER_STORE_KILL_TEST_DB", &path)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Kill it in the middle of a write, driven by what it has committed (no sleeps): right
    // after it reports its third commit it is inside the fourth transaction.
    let mut lines = std::io::BufRead::lines(std::io::BufReader::new(child.stdout.take().unwrap()));
    let mut commits = 0;
    while commits < 3 {
        let line = lines.next().expect("the writer stopped early").unwrap();
        if line.starts_with("committed ") {
            commits += 1;
        }
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let store = SqliteStore::open(&path).unwrap();
    let ok: String = store
        .raw()
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
        .raw()
        .query_row("SELECT MAX(t) FROM readings", [], |r| r.get(0))
        .unwrap();
    assert_eq!(max_t.map_or(0, |t| t + 1), n);
}

/// The project's exclusion on SQLite is a lock on `gleaner.db-lock`: it keeps out another
/// connection's `lock_project` and (while the holder is inside a write) its writes; a store
/// in memory takes nothing but counts its holds.
#[test]
fn the_project_exclusion_holds_across_connections() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("gleaner.db");
    let mut first = SqliteStore::open(&path).unwrap();
    let second = SqliteStore::open(&path).unwrap();
    let third = SqliteStore::open(&path).unwrap();
    crate::conformance::exclusion_holds_across_connections(&mut first, second, third);
    assert!(dir.path().join("gleaner.db-lock").exists());
    let memory = SqliteStore::open_in_memory().unwrap();
    memory.lock_project().unwrap();
    memory.lock_project().unwrap();
    memory.unlock_project();
    memory.unlock_project();
}
