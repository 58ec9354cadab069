//! Races on one project, on both backends: two ingests, an ingest and a scoring, a plan and
//! a record, each pair started together from a barrier in two threads with a connection of
//! their own. Whatever the interleaving, the second writer waits for the first (SQLite's
//! IMMEDIATE transactions with the busy timeout; PostgreSQL's per-project advisory lock) and
//! then succeeds: no reading is lost or doubled, every mission keeps its stops and visits.
//! No sleeps: the threads meet at a barrier, the stores serialise them.

use std::path::{Path, PathBuf};
use std::sync::Barrier;

use gleaner_app::{self as app, AnyStore, Project, Silent, StoreRead as _};

#[allow(dead_code)] // not every fixture is used here
mod common;
use common::{caf_files, shared_data};

/// A CAF project (2011 readings of the given files ingested) on SQLite (`None`) or in a fresh
/// PostgreSQL project; returns its directory, the database option and the year's files.
fn project(
    tmp: &Path,
    postgres: bool,
    preload: impl Fn(&[PathBuf]) -> Vec<PathBuf>,
) -> (PathBuf, Option<String>, Vec<PathBuf>) {
    let data = shared_data();
    let files = caf_files(&data.join("caf/Daily"), &tmp.join("input"), 2011..=2011);
    let database = postgres.then(|| {
        format!(
            "{}#{}",
            gleaner_store::conformance::pg_test_url(),
            gleaner_store::conformance::pg_fresh_project("race")
        )
    });
    let dir = tmp.join("farm");
    let (mut p, _) = app::init(&app::InitRequest {
        dir: dir.clone(),
        sensors: data.join("caf/sensors/CAF_sensor_locations.csv"),
        utm_zone: Some("11N".into()),
        name: Some("race".into()),
        database: database.clone(),
        ..Default::default()
    })
    .unwrap();
    let first = preload(&files);
    if !first.is_empty() {
        ingest(&mut p, &first).unwrap();
    }
    (dir, database, files)
}

fn open(dir: &Path, database: &Option<String>) -> Project<AnyStore> {
    Project::open_with(dir, database.as_deref()).unwrap()
}

fn ingest(p: &mut Project<AnyStore>, files: &[PathBuf]) -> app::Result<app::IngestOutcome> {
    app::ingest(
        p,
        &app::IngestRequest {
            files: files.to_vec(),
            ..Default::default()
        },
        0,
        &Silent,
    )
}

/// Runs `a` and `b` at once on their own connections to the project.
fn race<A: Send, B: Send>(
    dir: &Path,
    database: &Option<String>,
    a: impl FnOnce(&mut Project<AnyStore>) -> A + Send,
    b: impl FnOnce(&mut Project<AnyStore>) -> B + Send,
) -> (A, B) {
    let barrier = Barrier::new(2);
    std::thread::scope(|s| {
        let ha = s.spawn(|| {
            let mut p = open(dir, database);
            barrier.wait();
            a(&mut p)
        });
        let hb = s.spawn(|| {
            let mut p = open(dir, database);
            barrier.wait();
            b(&mut p)
        });
        (ha.join().unwrap(), hb.join().unwrap())
    })
}

fn drop_pg(database: &Option<String>) {
    if let Some(db) = database {
        let (url, project) = db.rsplit_once('#').unwrap();
        app::PgStore::drop_project(url, project).unwrap();
    }
}

fn two_ingests(postgres: bool) {
    let tmp = tempfile::tempdir().unwrap();
    let (dir, database, files) = project(tmp.path(), postgres, |_| Vec::new());
    // Disjoint halves at once: every reading of both arrives exactly once.
    let (left, right) = files.split_at(files.len() / 2);
    let (l, r) = (left.to_vec(), right.to_vec());
    let (a, b) = race(
        &dir,
        &database,
        move |p| ingest(p, &l).unwrap(),
        move |p| ingest(p, &r).unwrap(),
    );
    let p = open(&dir, &database);
    let count = p.store().reading_count().unwrap();
    assert_eq!(count, a.inserted + b.inserted);
    assert!(a.inserted > 0 && b.inserted > 0);
    // The same files twice at once: stored once, the later ingest finds them all unchanged.
    let (same1, same2) = (files.clone(), files.clone());
    let (c, d) = race(
        &dir,
        &database,
        move |p| ingest(p, &same1).unwrap(),
        move |p| ingest(p, &same2).unwrap(),
    );
    assert_eq!((c.inserted, d.inserted), (0, 0));
    assert_eq!(c.unchanged, count);
    assert_eq!(d.unchanged, count);
    assert_eq!(p.store().reading_count().unwrap(), count);
    // Every ingest left its provenance: none was lost to the race.
    assert!(p.store().ingests().unwrap().len() >= 3 * files.len());
    assert!(p.store().integrity_check().unwrap().is_empty());
    drop(p);
    drop_pg(&database);
}

fn ingest_and_score(postgres: bool) {
    let tmp = tempfile::tempdir().unwrap();
    let half = |f: &[PathBuf]| f[..f.len() / 2].to_vec();
    let (dir, database, files) = project(tmp.path(), postgres, half);
    let rest = files[files.len() / 2..].to_vec();
    let t = app::parse_timestamp("2012-01-01").unwrap();
    let (a, b) = race(
        &dir,
        &database,
        move |p| ingest(p, &rest).unwrap(),
        move |p| {
            app::score(
                p,
                &app::ScoreRequest {
                    at: Some(t),
                    ..Default::default()
                },
            )
            .unwrap()
        },
    );
    assert!(a.inserted > 0);
    assert!(!b.terms.is_empty());
    let mut p = open(&dir, &database);
    // Nothing lost: a second ingest of everything finds every reading stored.
    let again = ingest(&mut p, &files).unwrap();
    assert_eq!(again.inserted, 0);
    assert_eq!(again.unchanged, p.store().reading_count().unwrap());
    assert!(p.store().integrity_check().unwrap().is_empty());
    drop(p);
    drop_pg(&database);
}

fn plan_and_record(postgres: bool) {
    let tmp = tempfile::tempdir().unwrap();
    let (dir, database, _) = project(tmp.path(), postgres, |f| f.to_vec());
    let t = app::parse_timestamp("2012-01-01").unwrap();
    let request = app::PlanRequest {
        at: Some(t),
        time_limit_s: Some(30.0),
        max_iterations: Some(200),
        ..Default::default()
    };
    let first = {
        let mut p = open(&dir, &database);
        app::plan(&mut p, &request, 0).unwrap()
    };
    let id = first.id.unwrap();
    let (planned, recorded) = race(
        &dir,
        &database,
        move |p| app::plan(p, &request, 0).unwrap(),
        move |p| {
            app::record_flight(
                p,
                &app::RecordRequest {
                    mission: id,
                    at: Some(t),
                    cells: None,
                    readings: None,
                    amend: false,
                },
                0,
                &Silent,
            )
            .unwrap()
        },
    );
    let p = open(&dir, &database);
    let missions = app::missions(&p).unwrap();
    assert_eq!(missions.len(), 2);
    let second = planned.id.unwrap();
    assert_ne!(second, id);
    for m in &missions {
        assert!(!m.mission.stops.is_empty(), "mission {} has no stops", m.id);
        if m.id == id {
            assert_eq!(m.status, app::MissionStatus::Flown);
            assert_eq!(m.visits.len(), m.mission.stops.len());
            assert_eq!(recorded.cells.len(), m.visits.len());
        } else {
            assert_eq!(m.status, app::MissionStatus::Planned);
            assert!(m.visits.is_empty());
            assert_eq!(m.mission, planned.mission);
        }
    }
    assert!(p.store().integrity_check().unwrap().is_empty());
    drop(p);
    drop_pg(&database);
}

#[test]
fn two_ingests_on_sqlite() {
    two_ingests(false);
}

#[test]
fn two_ingests_on_postgres() {
    two_ingests(true);
}

#[test]
fn ingest_and_score_on_sqlite() {
    ingest_and_score(false);
}

#[test]
fn ingest_and_score_on_postgres() {
    ingest_and_score(true);
}

#[test]
fn plan_and_record_on_sqlite() {
    plan_and_record(false);
}

#[test]
fn plan_and_record_on_postgres() {
    plan_and_record(true);
}
