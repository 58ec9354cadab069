//! Tests of [`PgStore`] on a real server (`GLEANER_TEST_PG_URL`; they fail without one): the
//! backend-neutral [`crate::conformance`] suite, and what only PostgreSQL has (projects as
//! schemas, migrations under the advisory lock, writers serialised per project).

use std::sync::{Arc, Barrier, mpsc};

use crate::conformance::{self, batch, md, pg_fresh_project, pg_test_url, sensor};
use crate::*;

/// Opens a fresh project; the returned guard drops its schema at the end of the test.
struct Fresh {
    url: String,
    projects: Vec<String>,
}

impl Fresh {
    fn new() -> Self {
        Self {
            url: pg_test_url(),
            projects: Vec::new(),
        }
    }
    fn open(&mut self, tag: &str) -> PgStore {
        let p = pg_fresh_project(tag);
        self.projects.push(p.clone());
        PgStore::open(&self.url, &p).unwrap()
    }
}

impl Drop for Fresh {
    fn drop(&mut self) {
        for p in &self.projects {
            let _ = PgStore::drop_project(&self.url, p);
        }
    }
}

#[test]
fn conformance_on_postgres() {
    let mut fresh = Fresh::new();
    conformance::run_all(|| fresh.open("conf"));
}

#[test]
fn projects_are_isolated() {
    let mut fresh = Fresh::new();
    let mut a = fresh.open("iso");
    let b = fresh.open("iso");
    a.write(|tx| {
        tx.upsert_sensors(&[sensor("a", 46.0, -117.0)])?;
        tx.config_set("k", "v")
    })
    .unwrap();
    assert_eq!(a.sensors().unwrap().len(), 1);
    assert!(b.sensors().unwrap().is_empty());
    assert_eq!(b.config_get("k").unwrap(), None);
    // Reopening finds the project as it was, at the latest version.
    let again = PgStore::open(&fresh.url, a.project()).unwrap();
    assert_eq!(again.sensors().unwrap().len(), 1);
    assert_eq!(again.schema_version().unwrap(), schema_version_supported());
    assert!(again.integrity_check().unwrap().is_empty());
}

#[test]
fn bad_project_names_and_foreign_schemas_are_refused() {
    let url = pg_test_url();
    for bad in ["", "Farm", "a-b", "pg_x", "x;drop", &"a".repeat(64)] {
        let e = PgStore::open(&url, bad).unwrap_err();
        assert!(e.to_string().contains("cannot name"), "{bad:?}: {e}");
    }
    let p = pg_fresh_project("foreign");
    let mut c = ::postgres::Client::connect(&url, ::postgres::NoTls).unwrap();
    c.batch_execute(&format!(
        "CREATE SCHEMA {p}; CREATE TABLE {p}.stuff (x INT)"
    ))
    .unwrap();
    let e = PgStore::open(&url, &p).unwrap_err();
    assert!(matches!(e, StoreError::NotAGleanerDatabase { .. }), "{e}");
    PgStore::drop_project(&url, &p).unwrap();
}

#[test]
fn a_newer_schema_is_refused() {
    let mut fresh = Fresh::new();
    let s = fresh.open("newer");
    let mut c = ::postgres::Client::connect(&fresh.url, ::postgres::NoTls).unwrap();
    c.execute(
        &format!(
            "INSERT INTO {}.schema_migrations VALUES (99, 0, 'from the future')",
            s.project()
        ),
        &[],
    )
    .unwrap();
    let e = PgStore::open(&fresh.url, s.project()).unwrap_err();
    assert!(
        matches!(e, StoreError::SchemaTooNew { found: 99, .. }),
        "{e}"
    );
}

#[test]
fn concurrent_opens_of_a_new_project_migrate_once() {
    let url = pg_test_url();
    let p = pg_fresh_project("race_open");
    let barrier = Arc::new(Barrier::new(4));
    let handles: Vec<_> = (0..4)
        .map(|_| {
            let (url, p, barrier) = (url.clone(), p.clone(), barrier.clone());
            std::thread::spawn(move || {
                barrier.wait();
                PgStore::open(&url, &p).map(|s| s.schema_version().unwrap())
            })
        })
        .collect();
    for h in handles {
        assert_eq!(h.join().unwrap().unwrap(), schema_version_supported());
    }
    PgStore::drop_project(&url, &p).unwrap();
}

/// A second writer waits for the first (the project's advisory lock) and then sees its
/// commit: two use cases that each read the count and insert the next readings never lose or
/// double a reading. Synchronised with a channel, no sleeps: the first writer holds its
/// transaction open until the second has started waiting.
#[test]
fn writers_of_one_project_are_serialised() {
    let mut fresh = Fresh::new();
    let mut first = fresh.open("writers");
    let project = first.project().to_string();
    first
        .write(|tx| {
            tx.upsert_sensors(&[sensor("a", 46.0, -117.0)])?;
            tx.upsert_modalities(&[ModalityRecord {
                modality: md("vw@30cm"),
                unit: None,
            }])
        })
        .unwrap();
    let url = fresh.url.clone();
    let (started_tx, started_rx) = mpsc::channel::<()>();
    let (go_tx, go_rx) = mpsc::channel::<()>();
    let mut second = PgStore::open(&url, &project).unwrap();
    let second = std::thread::spawn(move || {
        go_rx.recv().unwrap();
        // Blocks on the lock until the first writer commits.
        started_tx.send(()).unwrap();
        second
            .write(|tx| {
                let n = tx.reading_count()? as i64;
                tx.insert_readings(
                    &batch(&[("a", "vw@30cm", 1000 + n, 0.5)]),
                    ConflictPolicy::Fail,
                )
            })
            .unwrap()
    });
    let stats = first
        .write(|tx| {
            let n = tx.reading_count()? as i64;
            assert_eq!(n, 0);
            go_tx.send(()).unwrap();
            started_rx.recv().unwrap();
            tx.insert_readings(
                &batch(&[("a", "vw@30cm", 1000 + n, 0.25)]),
                ConflictPolicy::Fail,
            )
        })
        .unwrap();
    assert_eq!(stats.inserted, 1);
    let stats = second.join().unwrap();
    // The second saw the first's reading (t = 1000) and wrote the next one (t = 1001).
    assert_eq!(stats.inserted, 1);
    let all = first.readings_for(None, i64::MIN..=i64::MAX).unwrap();
    let ts: Vec<i64> = all.rows.iter().map(|r| r.t).collect();
    assert_eq!(ts, vec![1000, 1001]);
}

/// The project's exclusion is PostgreSQL's session advisory lock: it keeps out another
/// connection's `lock_project` and its write transactions (two server replicas).
#[test]
fn the_project_exclusion_holds_across_connections() {
    let mut fresh = Fresh::new();
    let mut first = fresh.open("exclusion");
    let project = first.project().to_string();
    let second = PgStore::open(&fresh.url, &project).unwrap();
    let third = PgStore::open(&fresh.url, &project).unwrap();
    // The waiting shows in pg_locks (what `lock_waiters` counts), then the wait ends.
    first.lock_project().unwrap();
    let waiter = PgStore::open(&fresh.url, &project).unwrap();
    assert_eq!(first.lock_waiters().unwrap(), 0);
    let t = std::thread::spawn(move || {
        waiter.lock_project().unwrap();
        waiter.unlock_project();
    });
    let mut polls = 0;
    while first.lock_waiters().unwrap() == 0 {
        polls += 1;
        assert!(polls < 1_000_000, "the second lock_project never waited");
    }
    first.unlock_project();
    t.join().unwrap();
    assert_eq!(first.lock_waiters().unwrap(), 0);
    conformance::exclusion_holds_across_connections(&mut first, second, third);
    // Another project's exclusion is another lock.
    let other = fresh.open("exclusion");
    first.lock_project().unwrap();
    other.lock_project().unwrap();
    other.unlock_project();
    first.unlock_project();
}

/// [`AnyStore`] forwards every method faithfully, on both backends.
#[test]
fn conformance_through_any_store() {
    let mut fresh = Fresh::new();
    conformance::run_all(|| AnyStore::Sqlite(SqliteStore::open_in_memory().unwrap()));
    conformance::run_all(|| AnyStore::Postgres(Box::new(fresh.open("any"))));
}

#[test]
fn database_settings_name_a_backend_and_a_schema() {
    let dir = std::path::Path::new("/farm");
    assert_eq!(
        Database::parse("gleaner.db", dir, "x").unwrap(),
        Database::Sqlite(dir.join("gleaner.db"))
    );
    assert_eq!(
        Database::parse("postgres://u:secret@h/db", dir, "Farm A-1").unwrap(),
        Database::Postgres {
            url: "postgres://u:secret@h/db".into(),
            project: "farm_a_1".into()
        }
    );
    let db = Database::parse("postgresql://u:secret@h/db#north", dir, "x").unwrap();
    assert_eq!(db.to_string(), "postgresql://u:***@h/db#north");
    assert!(Database::parse("postgres://h/db#No", dir, "x").is_err());
    assert_eq!(schema_for_name("2024 trial"), "p_2024_trial");
    assert_eq!(schema_for_name("pg_farm"), "p_pg_farm");
}

/// Whether the project's `readings` table has its primary key (asked on a connection of
/// its own).
fn has_readings_pkey(store: &PgStore) -> bool {
    ::postgres::Client::connect(&pg_test_url(), ::postgres::NoTls)
        .unwrap()
        .query_one(
            "SELECT count(*) FROM pg_constraint c JOIN pg_namespace n ON n.oid = c.connamespace
             WHERE c.conname = 'readings_pkey' AND c.contype = 'p' AND n.nspname = $1",
            &[&store.project()],
        )
        .unwrap()
        .get::<_, i64>(0)
        == 1
}

/// `n` readings of `s` at t = t0, t0 + 1, ... with value t / 1000.
fn run_of(s: &str, t0: i64, n: i64) -> ReadingBatch {
    let rows: Vec<(String, i64)> = (t0..t0 + n).map(|t| (s.to_string(), t)).collect();
    let rows: Vec<(&str, &str, i64, f64)> = rows
        .iter()
        .map(|(s, t)| (s.as_str(), "vw@30cm", *t, *t as f64 / 1000.0))
        .collect();
    batch(&rows)
}

#[test]
fn a_bulk_load_classifies_like_an_indexed_table_and_restores_the_key() {
    let mut fresh = Fresh::new();
    let mut store = fresh.open("bulk");
    let setup = |tx: &mut PgTx<'_>| -> Result<()> {
        tx.upsert_sensors(&[sensor("a", 46.0, -117.0), sensor("b", 46.1, -117.0)])?;
        tx.upsert_modalities(&[ModalityRecord {
            modality: md("vw@30cm"),
            unit: Some("m3/m3".into()),
        }])?;
        Ok(())
    };
    // A load that fails after its first large insert leaves nothing, the key in place.
    let failed: Result<()> = store.write(|tx| {
        setup(tx)?;
        tx.insert_readings(&run_of("a", 0, 5000), ConflictPolicy::Fail)?;
        Err(StoreError::Invalid {
            what: "test",
            detail: "abandoned".into(),
        })
    });
    assert!(failed.is_err());
    assert_eq!(store.reading_count().unwrap(), 0);
    assert!(has_readings_pkey(&store));

    let seen = store
        .write(|tx| {
            setup(tx)?;
            assert!(!tx.bulk_loading());
            let first = tx.insert_readings(&run_of("a", 0, 5000), ConflictPolicy::Fail)?;
            assert!(
                tx.bulk_loading(),
                "a large insert into an empty table starts a load"
            );
            let other = tx.insert_readings(&run_of("b", 0, 5000), ConflictPolicy::Fail)?;
            assert!(
                tx.bulk_loading(),
                "disjoint rows need no lookup and keep the load"
            );
            // Meets the load's rows: 10 identical (unchanged), 10 new.
            let overlap = tx.insert_readings(&run_of("a", 4990, 20), ConflictPolicy::Fail)?;
            assert!(
                !tx.bulk_loading(),
                "rows meeting the load's need the key back"
            );
            // A conflicting value is refused and the refusal changes nothing.
            let conflict = tx.insert_readings(
                &batch(&[("b", "vw@30cm", 10, 9.0), ("b", "vw@30cm", 99_999, 1.0)]),
                ConflictPolicy::Fail,
            );
            assert!(
                matches!(conflict, Err(StoreError::Conflicts(_))),
                "{conflict:?}"
            );
            // A second large load after the key came back keeps it (the table is not empty).
            let later = tx.insert_readings(&run_of("b", 10_000, 5000), ConflictPolicy::Fail)?;
            Ok::<_, StoreError>((
                first.inserted,
                other.inserted,
                overlap.inserted,
                overlap.unchanged,
                later.inserted,
                tx.reading_count()?,
            ))
        })
        .unwrap();
    assert_eq!(seen, (5000, 5000, 10, 10, 5000, 15_010));
    assert!(has_readings_pkey(&store));
    assert_eq!(store.reading_count().unwrap(), 15_010);
    // Stored rows are found again by the indexed path: re-inserting changes nothing.
    let again = store
        .write(|tx| tx.insert_readings(&run_of("b", 0, 5000), ConflictPolicy::Fail))
        .unwrap();
    assert_eq!((again.inserted, again.unchanged), (0, 5000));
}
