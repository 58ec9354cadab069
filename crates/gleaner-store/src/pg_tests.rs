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
