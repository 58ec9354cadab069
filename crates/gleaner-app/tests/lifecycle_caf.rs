//! The whole mission lifecycle through the application layer on the real CAF network:
//! init -> ingest (2011-2013) -> explore -> score -> plan -> export check -> record a flight
//! with a readings file (the visited sensors' real 2014 data) -> rescore.

use std::collections::HashSet;

use gleaner_app::{self as app, MissionId, Silent};

mod common;
use common::{caf_files, flight_file, shared_data};

#[test]
fn caf_lifecycle_through_the_app_layer() {
    lifecycle(None);
}

/// The same lifecycle on PostgreSQL, in a project (schema) of its own; then the finished
/// project (readings, ingests, cells with metadata, a flown mission, settings, the persisted
/// utility state) is migrated to an SQLite file and from that into a second PostgreSQL
/// project, and every table of each copy is compared with the original.
#[test]
fn caf_lifecycle_on_postgres_and_migrations_both_ways() {
    use app::{Store as _, StoreRead as _, StoreWrite as _};
    let url = gleaner_store::conformance::pg_test_url();
    let first = gleaner_store::conformance::pg_fresh_project("lifecycle");
    let second = gleaner_store::conformance::pg_fresh_project("lifecycle");
    let (tmp, project) = lifecycle(Some(format!("{url}#{first}")));
    assert_eq!(project.store().backend(), "postgres");

    let file = tmp.path().join("copy.db");
    let mut sqlite = app::Database::Sqlite(file.clone()).open().unwrap();
    let out = app::migrate(project.store(), &mut sqlite, &Silent).unwrap();
    assert_eq!(out.readings, project_reading_count(&project));
    assert_eq!(out.missions, 1);
    same_tables(project.store(), &sqlite);
    assert!(sqlite.integrity_check().unwrap().is_empty());

    let mut back = app::Database::Postgres {
        url: url.clone(),
        project: second.clone(),
    }
    .open()
    .unwrap();
    app::migrate(&sqlite, &mut back, &Silent).unwrap();
    same_tables(project.store(), &back);
    assert!(back.integrity_check().unwrap().is_empty());
    // A non-empty target is refused and left as it was.
    let err = app::migrate(&sqlite, &mut back, &Silent).unwrap_err();
    assert!(err.to_string().contains("empty"), "{err}");
    same_tables(project.store(), &back);
    // New missions continue after the copied ids on both backends.
    for store in [&mut sqlite, &mut back] {
        let m = store.missions().unwrap()[0].mission.clone();
        let id = store.write(|tx| tx.create_mission(&m)).unwrap();
        assert_eq!(id, MissionId(2));
    }
    drop(project);
    for p in [&first, &second] {
        app::PgStore::drop_project(&url, p).unwrap();
    }
}

/// Every table, through the store interface: equal in both stores.
fn same_tables(a: &impl app::StoreRead, b: &impl app::StoreRead) {
    let all = i64::MIN..=i64::MAX;
    assert_eq!(a.schema_version().unwrap(), b.schema_version().unwrap());
    assert_eq!(a.sensors().unwrap(), b.sensors().unwrap());
    assert_eq!(a.modalities().unwrap(), b.modalities().unwrap());
    assert!(
        a.readings_for(None, all.clone()).unwrap() == b.readings_for(None, all).unwrap(),
        "readings differ"
    );
    assert_eq!(a.ingests().unwrap(), b.ingests().unwrap());
    assert_eq!(a.cells().unwrap(), b.cells().unwrap());
    assert_eq!(a.cell_metadata().unwrap(), b.cell_metadata().unwrap());
    assert_eq!(
        a.sensor_last_collected().unwrap(),
        b.sensor_last_collected().unwrap()
    );
    assert_eq!(a.missions().unwrap(), b.missions().unwrap());
    assert_eq!(a.config_entries().unwrap(), b.config_entries().unwrap());
    let keys = a.blob_keys().unwrap();
    assert_eq!(keys, b.blob_keys().unwrap());
    assert!(!keys.is_empty(), "the persisted utility state is a blob");
    for k in &keys {
        assert!(a.blob_get(k).unwrap() == b.blob_get(k).unwrap(), "blob {k}");
    }
}

/// The lifecycle on the database `database` (default: the SQLite file).
/// Returns the finished project, for more checks.
fn lifecycle(database: Option<String>) -> (tempfile::TempDir, app::Project<app::AnyStore>) {
    let data = shared_data();
    let daily = data.join("caf/Daily");
    let tmp = tempfile::tempdir().unwrap();
    let input = tmp.path().join("input");
    std::fs::create_dir_all(&input).unwrap();
    let files = caf_files(&daily, &input, 2011..=2013);
    assert_eq!(files.len(), 42, "42 CAF stations");

    let dir = tmp.path().join("caf");
    let (mut project, init) = app::init(&app::InitRequest {
        dir: dir.clone(),
        sensors: data.join("caf/sensors/CAF_sensor_locations.csv"),
        utm_zone: Some("11N".into()),
        name: Some("caf".into()),
        database,
        ..Default::default()
    })
    .unwrap();
    assert_eq!(init.sensors, 42);
    let n_cells = init.n_cells;
    assert!((30..=42).contains(&n_cells), "{n_cells} cells");
    // The sensors file is kept relative to the project (absolute across volumes).
    assert!(dir.join(&init.settings.sensors.file).exists());

    let ingest = app::ingest(
        &mut project,
        &app::IngestRequest {
            files: files.clone(),
            ..Default::default()
        },
        common::INGEST_CLOCK,
        &Silent,
    )
    .unwrap();
    assert!(ingest.inserted > 300_000, "{} readings", ingest.inserted);
    // Re-ingesting changes nothing.
    let again = app::ingest(
        &mut project,
        &app::IngestRequest {
            files,
            ..Default::default()
        },
        common::INGEST_CLOCK,
        &Silent,
    )
    .unwrap();
    assert_eq!((again.inserted, again.unchanged), (0, ingest.inserted));

    // Exploration: every cell exactly once, every sortie within the budget.
    let t = app::parse_timestamp("2014-03-01").unwrap();
    let exploration = app::explore(
        &mut project,
        &app::ExploreRequest {
            at: Some(t),
            dry_run: true,
            wind: None,
        },
        0,
    )
    .unwrap();
    let visited: Vec<_> = exploration
        .sorties
        .iter()
        .flat_map(|(_, m)| m.stops.iter().map(|s| s.cell))
        .collect();
    assert_eq!(visited.len(), n_cells);
    assert_eq!(visited.iter().collect::<HashSet<_>>().len(), n_cells);
    for (id, m) in &exploration.sorties {
        assert!(id.is_none(), "a dry run stores nothing");
        assert!(m.energy.total_j <= m.energy.budget_j);
    }
    assert!(app::missions(&project).unwrap().is_empty());

    // Scoring at t from 2011-2013.
    let scoring = app::score(
        &mut project,
        &app::ScoreRequest {
            at: Some(t),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(scoring.terms.len(), n_cells);
    for c in &scoring.terms {
        assert!((0.0..=1.0).contains(&c.f) && (0.0..=1.0).contains(&c.r));
        assert!((0.0..=1.0).contains(&c.u) && c.a >= 0.0);
    }
    // Two months without a collection: everything is stale.
    assert!(scoring.terms.iter().all(|c| c.f > 0.99));

    // Planning with an iteration cap: a route within the paper's 66.5 kJ.
    let planned = app::plan(
        &mut project,
        &app::PlanRequest {
            at: Some(t),
            time_limit_s: Some(30.0),
            max_iterations: Some(2_000),
            ..Default::default()
        },
        1_700_000_000,
    )
    .unwrap();
    let id = planned.id.unwrap();
    let e = &planned.mission.energy;
    assert!(
        (e.budget_j - 66_500.0).abs() < 1e-6,
        "budget {}",
        e.budget_j
    );
    assert!(e.total_j <= e.budget_j && e.total_j > 0.9 * e.budget_j);
    assert!(
        planned.mission.stops.len() >= 8,
        "{} cells",
        planned.mission.stops.len()
    );
    assert!(planned.mission.total_score >= planned.greedy.total_score);
    let sum = e.travel_j + e.hover_j + e.comm_j + e.return_j;
    assert!((sum - e.total_j).abs() < 1e-6 * e.total_j);

    // The stored mission is what was planned, with typed stops.
    let stored = app::mission(&project, id).unwrap();
    assert_eq!(stored.mission, planned.mission);
    assert_eq!(stored.status, app::MissionStatus::Planned);

    // Export: the checked bundle.
    let export = app::export(&project, id).unwrap();
    assert_eq!(export.field.cells.len(), n_cells);
    assert!(
        export
            .field
            .cells
            .iter()
            .all(|c| c.metadata.scores.is_some())
    );

    // Record the flight with the visited sensors' real readings of Jan-Feb 2014.
    let visited_cells: HashSet<_> = stored.mission.stops.iter().map(|s| s.cell).collect();
    let sensors: HashSet<String> = export
        .field
        .cells
        .iter()
        .filter(|c| visited_cells.contains(&c.index))
        .flat_map(|c| c.sensors.iter().map(ToString::to_string))
        .collect();
    let (flight, n_readings) = flight_file(&daily, &sensors, tmp.path());
    assert!(n_readings > 100, "{n_readings} readings");
    let record = app::record_flight(
        &mut project,
        &app::RecordRequest {
            mission: id,
            at: Some(t),
            cells: None,
            readings: Some(app::IngestRequest {
                files: vec![flight.clone()],
                ..Default::default()
            }),
            amend: false,
        },
        1_700_000_100,
        &Silent,
    )
    .unwrap();
    assert_eq!(record.readings_inserted as usize, n_readings);
    assert_eq!(record.sensors_collected, sensors.len());
    // Recording it again is refused, and stores nothing.
    let count = project_reading_count(&project);
    let err = app::record_flight(
        &mut project,
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
    .unwrap_err();
    assert!(err.to_string().contains("already recorded"), "{err}");
    assert_eq!(project_reading_count(&project), count);

    // Rescoring at t: the visited cells are fresh (F = 0), the others still stale.
    let after = app::score(
        &mut project,
        &app::ScoreRequest {
            at: Some(t),
            ..Default::default()
        },
    )
    .unwrap();
    let k = &after.knowledge;
    for (c, terms) in after.terms.iter().enumerate() {
        let index = k.field.cells()[c].index;
        if visited_cells.contains(&index) {
            assert!(terms.f < 1e-9, "{index}: F = {}", terms.f);
        } else {
            assert!(terms.f > 0.99, "{index}: F = {}", terms.f);
        }
    }
    let missions = app::missions(&project).unwrap();
    assert_eq!(missions.len(), 1);
    assert_eq!(missions[0].status, app::MissionStatus::Flown);
    assert_eq!(missions[0].visits.len(), stored.mission.stops.len());
    let _ = MissionId(0);
    (tmp, project)
}

fn project_reading_count(p: &app::Project<app::AnyStore>) -> u64 {
    use app::StoreRead as _;
    p.store().reading_count().unwrap()
}
