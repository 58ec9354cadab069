//! The persisted utility state: scoring from it (the fast path of `compute`) equals scoring
//! from the whole history (`compute_full`) within 1e-9 relative, after ingests and a recorded
//! flight, on the real CAF network and on a synthetic farm, when the condition model is refit
//! at every write (`utility.condition_refit_growth = 0`); with a refit cadence, the model
//! kept between refits is the last one fitted (warm-started refits still equal a fresh fit).

use std::path::{Path, PathBuf};

use gleaner_app::{self as app, Silent};

mod common;
use common::{caf_files, flight_file, shared_data};

fn close(a: f64, b: f64, what: &str) {
    assert!(
        (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1e-12),
        "{what}: fast {a} vs full {b}"
    );
}

/// The project in `dir` reopened with `utility.condition_refit_growth = growth`.
fn with_refit_growth(dir: &Path, growth: f64) -> app::Project<app::AnyStore> {
    let mut settings = app::Settings::load(dir).unwrap();
    settings.utility.condition_refit_growth = growth;
    settings.save(dir).unwrap();
    app::Project::open(dir).unwrap()
}

/// Scores with the fast path and the full path and checks they agree; returns whether the
/// fast path was taken.
fn same_scores<S: app::Store>(project: &app::Project<S>, at: Option<i64>) -> bool {
    let request = app::ScoreRequest {
        at,
        dry_run: true,
        ..Default::default()
    };
    let fast = app::compute(project, &request).unwrap();
    let full = app::compute_full(project, &request).unwrap();
    assert!(full.incremental.is_none());
    assert_eq!(fast.t, full.t);
    assert_eq!(fast.warnings, full.warnings);
    assert_eq!(fast.knowledge.modalities, full.knowledge.modalities);
    assert_eq!(fast.knowledge.last_collected, full.knowledge.last_collected);
    assert_eq!(fast.knowledge.first_reading, full.knowledge.first_reading);
    assert_eq!(fast.knowledge.latest, full.knowledge.latest);
    assert_eq!(fast.terms.len(), full.terms.len());
    match (&fast.condition, &full.condition) {
        (Some(a), Some(b)) => {
            assert_eq!(a.modality, b.modality);
            assert_eq!(a.thresholds, b.thresholds, "the same model");
            for (p, q) in a.probabilities.iter().zip(&b.probabilities) {
                for (x, y) in p.iter().zip(q) {
                    close(*x, *y, "class probability");
                }
            }
        }
        (None, None) => {}
        (a, b) => panic!("condition {:?} vs {:?}", a.is_some(), b.is_some()),
    }
    for (c, (a, b)) in fast.terms.iter().zip(&full.terms).enumerate() {
        let what = format!("at {at:?} cell {c}");
        for (name, x, y) in [
            ("F", a.f, b.f),
            ("R", a.r, b.r),
            ("A", a.a, b.a),
            ("U", a.u, b.u),
            ("S", a.s, b.s),
        ] {
            close(x, y, &format!("{what} {name}"));
        }
        for (x, y) in a.a_by_modality.iter().zip(&b.a_by_modality) {
            assert_eq!(x.is_some(), y.is_some(), "{what}");
            if let (Some(x), Some(y)) = (x, y) {
                close(*x, *y, &format!("{what} A^m"));
            }
        }
        for (x, y) in a.r_by_modality.iter().zip(&b.r_by_modality) {
            assert_eq!(x.is_some(), y.is_some(), "{what}");
            if let (Some(x), Some(y)) = (x, y) {
                close(*x, *y, &format!("{what} R^m"));
            }
        }
    }
    fast.incremental.is_some()
}

/// Stores an exploration of the field and records its first sortie as flown at `at` with
/// the readings of `readings` (a function of the visited sensors).
fn record_first_sortie<S: app::Store>(
    project: &mut app::Project<S>,
    at: i64,
    readings: impl FnOnce(&[String]) -> Option<PathBuf>,
) {
    let exploration = app::explore(
        project,
        &app::ExploreRequest {
            at: Some(at),
            dry_run: false,
            wind: None,
        },
        0,
    )
    .unwrap();
    let (id, sortie) = &exploration.sorties[0];
    let id = id.unwrap();
    let view = app::field_view(project).unwrap();
    let cells: std::collections::HashSet<_> = sortie.stops.iter().map(|s| s.cell).collect();
    let sensors: Vec<String> = view
        .cells
        .iter()
        .filter(|c| cells.contains(&c.index))
        .flat_map(|c| c.sensors.iter().map(ToString::to_string))
        .collect();
    let files = readings(&sensors);
    app::record_flight(
        project,
        &app::RecordRequest {
            mission: id,
            at: Some(at),
            cells: None,
            readings: files.map(|f| app::IngestRequest {
                files: vec![f],
                ..Default::default()
            }),
            amend: false,
        },
        0,
        &Silent,
    )
    .unwrap();
}

/// A new project of the CAF network in `dir`.
fn init_caf(data: &Path, dir: &Path) {
    app::init(&app::InitRequest {
        dir: dir.to_path_buf(),
        sensors: data.join("caf/sensors/CAF_sensor_locations.csv"),
        utm_zone: Some("11N".into()),
        name: Some("caf".into()),
        ..Default::default()
    })
    .unwrap();
}

#[test]
fn fast_scoring_equals_full_scoring_on_caf() {
    let data = shared_data();
    let daily = data.join("caf/Daily");
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("caf");
    init_caf(&data, &dir);
    let mut project = with_refit_growth(&dir, 0.0);
    // 2011-2012, then 2013 as a second ingest (an incremental update of the state).
    for (k, years) in [(0, 2011..=2012), (1, 2013..=2013)] {
        let files = caf_files(&daily, &tmp.path().join(format!("in{k}")), years);
        common::ingest_files(&mut project, files);
    }
    // A bulk ingest leaves the state stale (the ingest stays as fast as the store); the first
    // scoring that writes rebuilds it, and from then on scoring takes the fast path.
    assert!(!same_scores(&project, None));
    app::score(&mut project, &app::ScoreRequest::default()).unwrap();
    assert!(same_scores(&project, None));
    let t = app::parse_timestamp("2014-03-01").unwrap();
    record_first_sortie(&mut project, t, |sensors| {
        Some(flight_file(&daily, sensors, tmp.path()).0)
    });
    let latest = app::compute(&project, &app::ScoreRequest::default())
        .unwrap()
        .knowledge
        .latest
        .unwrap();
    for at in [None, Some(latest), Some(latest + 3_600), Some(t)] {
        assert!(same_scores(&project, at), "fast path taken at {at:?}");
    }
    // Before the newest reading, or with a history window: the full path.
    let early = app::compute(
        &project,
        &app::ScoreRequest {
            at: Some(latest - 86_400),
            ..Default::default()
        },
    )
    .unwrap();
    assert!(early.incremental.is_none());
    let windowed = app::compute(
        &project,
        &app::ScoreRequest {
            history: app::History {
                until: t - 86_400 * 90,
                ..Default::default()
            },
            ..Default::default()
        },
    )
    .unwrap();
    assert!(windowed.incremental.is_none());
    // score() keeps what the fast path computed.
    let scored = app::score(&mut project, &app::ScoreRequest::default()).unwrap();
    assert!(scored.incremental.is_some());
}

#[test]
fn fast_scoring_equals_full_scoring_on_a_synthetic_farm() {
    use gleaner_synth::{SynthConfig, generate, write_readings_csv, write_sensors_csv};
    let farm = generate(&SynthConfig {
        seed: 7,
        sensor_count: 120,
        days: 80,
        scale_extent_with_sensors: true,
        vw_depths_cm: vec![30],
        t_depths_cm: vec![30],
        ..SynthConfig::default()
    })
    .unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let sensors = tmp.path().join("sensors.csv");
    write_sensors_csv(&farm, &mut std::fs::File::create(&sensors).unwrap()).unwrap();
    let mut all = Vec::new();
    write_readings_csv(&farm, &mut all).unwrap();
    let text = String::from_utf8(all).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let split = app::format_rfc3339(farm.times()[50]);
    let end = app::format_rfc3339(farm.times()[70]);
    // Days 0-49, then 50-69; days 70-79 come back with a flight.
    let (mut first, mut second, mut third) = (vec![header], vec![header], vec![header]);
    for l in lines {
        let ts = l.split(',').nth(1).unwrap();
        if ts < split.as_str() {
            first.push(l);
        } else if ts < end.as_str() {
            second.push(l);
        } else {
            third.push(l);
        }
    }
    let file = |name: &str, rows: &[&str]| {
        let p = tmp.path().join(name);
        std::fs::write(&p, rows.join("\n") + "\n").unwrap();
        p
    };
    let (f1, f2) = (file("a.csv", &first), file("b.csv", &second));
    app::init(&app::InitRequest {
        dir: tmp.path().join("farm"),
        sensors,
        base: Some(farm.base()),
        cell_size_m: Some(app::DEFAULT_CELL_SIZE_M),
        name: Some("synthetic".into()),
        ..Default::default()
    })
    .unwrap();
    let mut project = with_refit_growth(&tmp.path().join("farm"), 0.0);
    for f in [f1, f2] {
        app::ingest(
            &mut project,
            &app::IngestRequest {
                files: vec![f],
                ..Default::default()
            },
            common::INGEST_CLOCK,
            &Silent,
        )
        .unwrap();
        assert!(
            !same_scores(&project, None),
            "a bulk ingest marks the state stale"
        );
        app::score(&mut project, &app::ScoreRequest::default()).unwrap();
        assert!(same_scores(&project, None));
    }
    let at = farm.times()[79] + 86_400;
    record_first_sortie(&mut project, at, |sensors| {
        let rows: Vec<&str> = std::iter::once(header)
            .chain(
                third[1..]
                    .iter()
                    .copied()
                    .filter(|l| sensors.iter().any(|s| l.starts_with(&format!("{s},")))),
            )
            .collect();
        Some(file("flight.csv", &rows))
    });
    for at in [None, Some(at)] {
        assert!(same_scores(&project, at), "fast path taken at {at:?}");
    }
    // A corrupt state: scoring takes the full path, and `score` rebuilds the state.
    {
        use app::{Store as _, StoreWrite as _};
        let mut store = app::SqliteStore::open(&tmp.path().join("farm/gleaner.db")).unwrap();
        store
            .write(|tx| {
                tx.blob_put("utility.incremental", b"not a state")?;
                Ok::<_, app::AppError>(())
            })
            .unwrap();
    }
    let request = app::ScoreRequest::default();
    assert!(
        app::compute(&project, &request)
            .unwrap()
            .incremental
            .is_none()
    );
    // `score` rebuilds the state first, then scores from it.
    assert!(
        app::score(&mut project, &request)
            .unwrap()
            .incremental
            .is_some()
    );
    assert!(same_scores(&project, None), "rebuilt by score");
}

/// A synthetic farm project (120 sensors, days 0-69 ingested and scored) with
/// `utility.condition_refit_growth = growth`, and a flight at day 80 that brings back days
/// 70-79 of the visited sensors.
fn farm_with_growth(tmp: &Path, growth: f64) -> app::Project<app::AnyStore> {
    use gleaner_synth::{SynthConfig, generate, write_readings_csv, write_sensors_csv};
    let farm = generate(&SynthConfig {
        seed: 11,
        sensor_count: 120,
        days: 80,
        scale_extent_with_sensors: true,
        vw_depths_cm: vec![30],
        t_depths_cm: vec![30],
        ..SynthConfig::default()
    })
    .unwrap();
    let sensors = tmp.join("sensors.csv");
    write_sensors_csv(&farm, &mut std::fs::File::create(&sensors).unwrap()).unwrap();
    let mut all = Vec::new();
    write_readings_csv(&farm, &mut all).unwrap();
    let text = String::from_utf8(all).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let split = app::format_rfc3339(farm.times()[70]);
    let (mut history, mut later) = (vec![header], vec![header]);
    for l in lines {
        if l.split(',').nth(1).unwrap() < split.as_str() {
            history.push(l);
        } else {
            later.push(l);
        }
    }
    let history_file = tmp.join("history.csv");
    std::fs::write(&history_file, history.join("\n") + "\n").unwrap();
    let dir = tmp.join("farm");
    app::init(&app::InitRequest {
        dir: dir.clone(),
        sensors,
        base: Some(farm.base()),
        cell_size_m: Some(app::DEFAULT_CELL_SIZE_M),
        name: Some("synthetic".into()),
        ..Default::default()
    })
    .unwrap();
    let mut project = with_refit_growth(&dir, growth);
    app::ingest(
        &mut project,
        &app::IngestRequest {
            files: vec![history_file],
            ..Default::default()
        },
        common::INGEST_CLOCK,
        &Silent,
    )
    .unwrap();
    app::score(&mut project, &app::ScoreRequest::default()).unwrap();
    let at = farm.times()[79] + 86_400;
    record_first_sortie(&mut project, at, |visited| {
        let rows: Vec<&str> = std::iter::once(header)
            .chain(
                later[1..]
                    .iter()
                    .copied()
                    .filter(|l| visited.iter().any(|s| l.starts_with(&format!("{s},")))),
            )
            .collect();
        let p = tmp.join("flight.csv");
        std::fs::write(&p, rows.join("\n") + "\n").unwrap();
        Some(p)
    });
    project
}

#[test]
fn refit_cadence_keeps_the_last_fit_until_the_class_modality_grows() {
    // Growth 0.1%: the flight's readings exceed it, so recording refits the model (warm-started
    // from the last fit) and the fast path equals a fresh fit on the whole history after the
    // newest reading (at it, a cadence's fit also knows the newest label; the full path not).
    let tmp = tempfile::tempdir().unwrap();
    let project = farm_with_growth(tmp.path(), 0.001);
    let latest = app::compute(&project, &app::ScoreRequest::default())
        .unwrap()
        .knowledge
        .latest
        .unwrap();
    assert!(
        same_scores(&project, Some(latest + 86_400)),
        "refit at the flight"
    );
    // Growth 1000%: the flight's readings stay within it; scoring stays on the fast path with
    // the model fitted before the flight (its quantile thresholds are those of the history
    // without the flight), while the other terms take the flight into account exactly.
    let tmp2 = tempfile::tempdir().unwrap();
    let project = farm_with_growth(tmp2.path(), 10.0);
    let request = app::ScoreRequest {
        dry_run: true,
        ..Default::default()
    };
    let fast = app::compute(&project, &request).unwrap();
    let full = app::compute_full(&project, &request).unwrap();
    assert!(fast.incremental.is_some(), "fast path with a kept model");
    let (kept, fresh) = (fast.condition.unwrap(), full.condition.unwrap());
    assert_ne!(
        kept.thresholds, fresh.thresholds,
        "the flight moved the quantiles"
    );
    let every_write = {
        let tmp3 = tempfile::tempdir().unwrap();
        let p = farm_with_growth(tmp3.path(), 0.0);
        // The same farm and flight refit at every write: its thresholds are `fresh`'s.
        app::compute(&p, &request).unwrap().condition.unwrap()
    };
    assert_eq!(every_write.thresholds, fresh.thresholds);
    for (a, b) in fast.terms.iter().zip(&full.terms) {
        for (x, y) in [(a.f, b.f), (a.a, b.a), (a.r, b.r)] {
            close(x, y, "F, A, R do not depend on the refit cadence");
        }
    }
}

/// gleaner's drift freshness (`freshness_form = "drift"`): F in [0, 1] with 1 at the cell whose
/// carried-forward values are most likely wrong, 0 at the cells just collected, S = F·(1 + βA)
/// with γ = δ = 0, and the fast path still equals the full path.
#[test]
fn drift_freshness_on_caf() {
    let data = shared_data();
    let daily = data.join("caf/Daily");
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("caf");
    init_caf(&data, &dir);
    let mut settings = app::Settings::load(&dir).unwrap();
    settings.utility = settings.utility.gleaner();
    settings.utility.condition_refit_growth = 0.0;
    settings.save(&dir).unwrap();
    let mut project = app::Project::open(&dir).unwrap();
    let files = caf_files(&daily, &tmp.path().join("in"), 2013..=2013);
    common::ingest_files(&mut project, files);
    app::score(&mut project, &app::ScoreRequest::default()).unwrap();
    let t = app::parse_timestamp("2014-03-01").unwrap();
    record_first_sortie(&mut project, t, |sensors| {
        Some(flight_file(&daily, sensors, tmp.path()).0)
    });
    assert!(same_scores(&project, Some(t)), "fast path taken");
    let scoring = app::compute(
        &project,
        &app::ScoreRequest {
            at: Some(t),
            dry_run: true,
            ..Default::default()
        },
    )
    .unwrap();
    assert!(
        scoring.anomaly_form.ends_with("F drift"),
        "{}",
        scoring.anomaly_form
    );
    let top = scoring.terms.iter().map(|c| c.f).fold(0.0, f64::max);
    assert_eq!(top, 1.0);
    let beta = project.settings().utility.beta;
    let mut just_collected = 0;
    for (cell, c) in scoring.knowledge.field.cells().iter().zip(&scoring.terms) {
        assert!((0.0..=1.0).contains(&c.f), "{c:?}");
        assert!((c.s - c.f * (1.0 + beta * c.a)).abs() < 1e-12, "{c:?}");
        let fresh = cell
            .sensors
            .iter()
            .all(|&p| scoring.knowledge.last_collected[p] == Some(t));
        if fresh {
            just_collected += 1;
            assert_eq!(
                c.f, 0.0,
                "a cell collected at t has nothing to carry forward"
            );
        }
    }
    assert!(just_collected > 0);
    // The cells not collected at t were all last collected at the end of 2013: the same age,
    // yet F differs by the sensors' drift (the one-day change varies 95-fold in variance).
    let fs: Vec<f64> = scoring
        .terms
        .iter()
        .map(|c| c.f)
        .filter(|f| *f > 0.0)
        .collect();
    let low = fs.iter().copied().fold(1.0, f64::min);
    assert!(low < 0.4, "smallest F {low} of {fs:?}");
}

/// The drift freshness knows only what the scoring knows: a project holding 2012–2013 scored
/// with history until the end of 2012 gets the F of a project holding 2012 alone (not the
/// drift of the first half of 2013, which it has not been told about).
#[test]
fn drift_freshness_reads_only_the_scorings_history() {
    let data = shared_data();
    let daily = data.join("caf/Daily");
    let tmp = tempfile::tempdir().unwrap();
    let make = |name: &str, years: std::ops::RangeInclusive<i32>| {
        let dir = tmp.path().join(name);
        init_caf(&data, &dir);
        let mut settings = app::Settings::load(&dir).unwrap();
        settings.utility = settings.utility.gleaner();
        settings.save(&dir).unwrap();
        let mut project = app::Project::open(&dir).unwrap();
        let files = caf_files(&daily, &tmp.path().join(format!("in-{name}")), years);
        common::ingest_files(&mut project, files);
        project
    };
    let both = make("both", 2012..=2013);
    let first = make("first", 2012..=2012);
    let t = app::parse_timestamp("2013-07-01").unwrap();
    let request = |until: Option<i64>| app::ScoreRequest {
        at: Some(t),
        history: app::History {
            until: until.unwrap_or(i64::MAX),
            ..app::History::default()
        },
        dry_run: true,
        ..Default::default()
    };
    let until_2012 = app::parse_timestamp("2012-12-31").unwrap();
    let told = app::compute(&both, &request(Some(until_2012))).unwrap();
    let alone = app::compute(&first, &request(None)).unwrap();
    let everything = app::compute(&both, &request(None)).unwrap();
    assert!(told.anomaly_form.ends_with("F drift"));
    assert!(told.terms.iter().any(|c| c.f > 0.0));
    for (a, b) in told.terms.iter().zip(&alone.terms) {
        assert!((a.f - b.f).abs() <= 1e-12, "F {} against {}", a.f, b.f);
    }
    // Told everything, the same project's F differs (the comparison above can fail).
    let moved = told
        .terms
        .iter()
        .zip(&everything.terms)
        .filter(|(a, b)| (a.f - b.f).abs() > 1e-6)
        .count();
    assert!(moved > 0);
}
