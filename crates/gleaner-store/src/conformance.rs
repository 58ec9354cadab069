//! The backend conformance suite: the [`Store`] contract as executable checks, written once
//! against the traits, so that every backend (SQLite today, PostgreSQL tomorrow) runs the same
//! tests unchanged.
//!
//! A backend's test calls [`run_all`] with a function that returns a fresh, empty store:
//!
//! ```
//! # #[cfg(feature = "conformance")]
//! gleaner_store::conformance::run_all(|| gleaner_store::SqliteStore::open_in_memory().unwrap());
//! ```
//!
//! Each check gets its own fresh store and panics (with the check's name printed first, on
//! stderr) on the first broken promise: this is test code. Available with the `conformance`
//! cargo feature. Data are fixed or drawn from a seeded generator, so every run is the same.

use std::collections::{BTreeMap, HashSet};

use gleaner_field::{CellIndex, LatLon, Modality, SensorId, UnixSeconds};

use crate::{
    AnomalyRecord, CellMetadata, CellRecord, CellScores, ClassProbability, ConflictPolicy,
    Correlation, EnergyBreakdown, FlightProfile, IngestRecord, MissionId, MissionKind,
    MissionStatus, ModalityRecord, ModalitySummary, NewMission, Reading, ReadingBatch,
    ReadingBatchBuilder, Result, SensorRecord, SeriesStats, StopRecord, Store, StoreError,
    StoreRead, StoreWrite, VisitRecord,
};

const DAY: i64 = 86_400;
/// 2010-01-01T00:00:00Z, s.
const T0: UnixSeconds = 1_262_304_000;

/// Runs every check, each on a store returned by `fresh` (which must be empty and migrated).
///
/// # Panics
/// On the first check the backend fails, naming it.
pub fn run_all<S: Store>(mut fresh: impl FnMut() -> S) {
    macro_rules! run {
        ($($check:ident),* $(,)?) => {
            $(
                eprintln!("conformance: {}", stringify!($check));
                $check(&mut fresh());
            )*
        };
    }
    run!(
        empty_store_reads_empty,
        sensors_upsert_idempotently_and_report_moves,
        modalities_keep_their_unit,
        reinserting_readings_changes_nothing,
        conflicts_fail_or_skip,
        duplicates_within_a_batch,
        bad_batches_are_rejected_whole,
        a_failure_deep_in_a_big_insert_leaves_the_exact_pre_state,
        readings_for_filters_and_orders,
        latest_readings_are_the_last_rows_of_readings_for,
        readings_of_sensors_selects_and_orders,
        a_failed_write_closure_rolls_everything_back,
        a_failed_method_undoes_only_itself,
        a_transaction_reads_its_own_writes,
        write_traits_are_dyn_compatible,
        ingests_and_config,
        blobs_round_trip,
        sensors_collected_never_move_back,
        cell_metadata_round_trips_and_upserts_by_key,
        metadata_child_rows_hold_the_last_values_written,
        cell_metadata_scalars_are_the_rows_without_children,
        replace_cells_keeps_or_deletes_metadata,
        missions_round_trip_with_stops,
        record_visits_refuses_a_flown_mission_unless_amend,
        missions_cancel_delete_and_page,
        invalid_missions_write_nothing,
        results_come_in_a_deterministic_order,
        inserting_twice_inserts_nothing_the_second_time,
        stored_readings_match_a_naive_model,
    );
}

// ---- fixtures -------------------------------------------------------------------------------

pub(crate) fn sid(s: &str) -> SensorId {
    SensorId::new(s).unwrap()
}

pub(crate) fn md(s: &str) -> Modality {
    Modality::new(s).unwrap()
}

pub(crate) fn sensor(id: &str, lat: f64, lon: f64) -> SensorRecord {
    SensorRecord {
        id: sid(id),
        position: LatLon::new(lat, lon).unwrap(),
        elevation_m: Some(790.0),
        source: "test".into(),
    }
}

fn modality(name: &str, unit: Option<&str>) -> ModalityRecord {
    ModalityRecord {
        modality: md(name),
        unit: unit.map(String::from),
    }
}

/// One write transaction with the store's error type.
fn w<S: Store, R>(store: &mut S, f: impl FnOnce(&mut S::Tx<'_>) -> Result<R>) -> Result<R> {
    store.write(f)
}

/// Sensors `a`, `b`, `c`; modalities `vw@30cm` (m3/m3), `t@30cm` (degC).
fn network<S: Store>(store: &mut S) {
    w(store, |tx| {
        tx.upsert_sensors(&[
            sensor("a", 46.0, -117.0),
            sensor("b", 46.0001, -117.0),
            sensor("c", 46.001, -117.0),
        ])?;
        tx.upsert_modalities(&[
            modality("vw@30cm", Some("m3/m3")),
            modality("t@30cm", Some("degC")),
        ])
    })
    .unwrap();
}

pub(crate) fn batch(rows: &[(&str, &str, UnixSeconds, f64)]) -> ReadingBatch {
    let mut b = ReadingBatchBuilder::new();
    for (s, m, t, v) in rows {
        b.push(&sid(s), &md(m), *t, *v);
    }
    b.finish()
}

fn insert<S: Store>(
    store: &mut S,
    b: &ReadingBatch,
    policy: ConflictPolicy,
) -> Result<crate::InsertStats> {
    w(store, |tx| tx.insert_readings(b, policy))
}

type Dump = BTreeMap<(String, String, UnixSeconds), f64>;

/// Every stored reading as `(sensor, modality, t) -> value`.
fn dump(store: &impl StoreRead) -> Dump {
    let all = store.readings_for(None, i64::MIN..=i64::MAX).unwrap();
    all.iter()
        .map(|(s, m, t, v)| ((s.to_string(), m.to_string(), t), v))
        .collect()
}

/// A batch as `(sensor, modality, t, value)` rows in batch order.
fn rows_of(b: &ReadingBatch) -> Vec<(String, String, i64, f64)> {
    b.iter()
        .map(|(s, m, t, v)| (s.to_string(), m.to_string(), t, v))
        .collect()
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

fn stop(order: u32, i: i32, j: i32, terms: Option<[f64; 4]>) -> StopRecord {
    StopRecord {
        order,
        cell: CellIndex { i, j },
        centre: LatLon::new(46.0 + f64::from(j) * 1e-3, -117.0 + f64::from(i) * 1e-3).unwrap(),
        score: terms.map_or(0.0, |t| t.iter().sum()),
        terms,
        leg_distance_m: 120.5 + f64::from(order),
        leg_energy_j: 1_510.25,
        collection_s: 12.5,
        hover_s: 14.0,
        hover_j: 2_380.0,
        comm_j: 6.25,
    }
}

/// An adaptive mission with two scored stops (or an exploration sortie without terms).
pub fn new_mission(kind: MissionKind) -> NewMission {
    let scored = kind == MissionKind::Adaptive;
    let terms = |k: f64| scored.then_some([0.5, 0.25 + k, 1.75, 0.125]);
    NewMission {
        created_at: T0,
        kind,
        planned_at: T0 + 60,
        solver: if scored { "default" } else { "exploration" }.into(),
        seed: u64::MAX - 6, // above i64::MAX: must survive a signed column
        weights: [1.0, 0.5, 2.0, 0.25],
        anomaly_form: if scored { "bounded(kappa=3)" } else { "n/a" }.into(),
        total_score: 7.0,
        profile: FlightProfile {
            base: LatLon::new(46.7788, -117.0867).unwrap(),
            base_alt_m: 790.5,
            altitude_m: 30.0,
            cruise_speed_mps: 10.2,
            wind_mps: 6.5,
            wind_from_deg: 292.5,
        },
        energy: EnergyBreakdown {
            travel_j: 30_000.125,
            hover_j: 4_760.0,
            comm_j: 12.5,
            return_j: 1_700.0,
            total_j: 36_472.625,
            budget_j: 66_500.0,
            distance_m: 2_400.75,
            flight_time_s: 321.5,
        },
        return_distance_m: 140.0,
        stops: vec![stop(0, 0, -3, terms(0.0)), stop(1, 12, 1, terms(0.5))],
    }
}

fn visits() -> Vec<VisitRecord> {
    vec![
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
    ]
}

fn ingest_record(file: &str) -> IngestRecord {
    IngestRecord {
        file_name: file.into(),
        format: "long-csv".into(),
        rows_read: 10,
        rows_inserted: 7,
        rows_unchanged: 2,
        rows_skipped: 1,
        at: T0,
    }
}

/// Everything a store holds, for "nothing changed" comparisons.
#[derive(Debug, PartialEq)]
struct Snapshot {
    sensors: Vec<SensorRecord>,
    modalities: Vec<ModalityRecord>,
    readings: Dump,
    ingests: Vec<IngestRecord>,
    cells: Vec<CellRecord>,
    metadata: Vec<CellMetadata>,
    collected: Vec<(SensorId, UnixSeconds)>,
    missions: Vec<crate::MissionRecord>,
    config: Option<String>,
    blob: Option<Vec<u8>>,
}

fn snapshot(store: &impl StoreRead) -> Snapshot {
    Snapshot {
        sensors: store.sensors().unwrap(),
        modalities: store.modalities().unwrap(),
        readings: dump(store),
        ingests: store.ingests().unwrap(),
        cells: store.cells().unwrap(),
        metadata: store.cell_metadata().unwrap(),
        collected: store.sensor_last_collected().unwrap(),
        missions: store.missions().unwrap(),
        config: store.config_get("k").unwrap(),
        blob: store.blob_get("state").unwrap(),
    }
}

/// A small deterministic generator (xorshift64*), so the randomised checks need no crate.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in `0..n`.
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

// ---- checks ---------------------------------------------------------------------------------

/// A fresh store is empty and reports a schema version.
pub fn empty_store_reads_empty<S: Store>(store: &mut S) {
    assert!(store.schema_version().unwrap() >= 1);
    assert_eq!(store.reading_count().unwrap(), 0);
    assert!(store.sensor_reading_counts().unwrap().is_empty());
    assert!(store.sensors().unwrap().is_empty());
    assert!(store.missions().unwrap().is_empty());
    assert_eq!(store.mission(MissionId(1)).unwrap(), None);
    assert_eq!(store.config_get("k").unwrap(), None);
    assert_eq!(store.blob_get("k").unwrap(), None);
    assert!(store.cell_metadata().unwrap().is_empty());
}

/// Sensor upserts are idempotent, report new, moved and unchanged sensors, and refuse a sensor
/// listed twice with different content without writing anything.
pub fn sensors_upsert_idempotently_and_report_moves<S: Store>(store: &mut S) {
    let two = [sensor("a", 46.0, -117.0), sensor("b", 46.1, -117.0)];
    let first = w(store, |tx| tx.upsert_sensors(&two)).unwrap();
    assert_eq!(first.added, vec!["a", "b"]);
    let again = w(store, |tx| tx.upsert_sensors(&two)).unwrap();
    assert_eq!(
        (again.added.len(), again.updated.len(), again.unchanged),
        (0, 0, 2)
    );
    let moved = w(store, |tx| {
        tx.upsert_sensors(&[sensor("a", 46.0, -117.0), sensor("b", 46.2, -117.0)])
    })
    .unwrap();
    assert_eq!(moved.updated, vec!["b"]);
    assert_eq!(store.sensors().unwrap()[1].position.lat(), 46.2);
    let err = w(store, |tx| {
        tx.upsert_sensors(&[sensor("c", 46.0, -117.0), sensor("c", 46.5, -117.0)])
    })
    .unwrap_err();
    assert!(err.to_string().contains("\"c\""), "{err}");
    let mut nan = sensor("d", 46.0, -117.0);
    nan.elevation_m = Some(f64::NAN);
    assert!(w(store, |tx| tx.upsert_sensors(&[nan])).is_err());
    assert_eq!(store.sensors().unwrap().len(), 2);
}

/// A modality keeps its unit: the same unit or none is unchanged, a unit for a unit-less
/// modality is recorded, a different unit is `UnitMismatch` naming both and writes nothing.
pub fn modalities_keep_their_unit<S: Store>(store: &mut S) {
    network(store);
    let stats = w(store, |tx| {
        tx.upsert_modalities(&[
            modality("vw@30cm", Some("m3/m3")),
            modality("t@30cm", None),
            modality("humidity", None),
        ])
    })
    .unwrap();
    assert_eq!(stats.added, vec!["humidity"]);
    assert_eq!(stats.unchanged, 2);
    let stats = w(store, |tx| {
        tx.upsert_modalities(&[modality("humidity", Some("%"))])
    })
    .unwrap();
    assert_eq!(stats.updated, vec!["humidity"]);
    let before = store.modalities().unwrap();
    assert_eq!(
        before,
        vec![
            modality("humidity", Some("%")),
            modality("t@30cm", Some("degC")),
            modality("vw@30cm", Some("m3/m3")),
        ]
    );
    let err = w(store, |tx| {
        tx.upsert_modalities(&[
            modality("ec@5cm", Some("dS/m")),
            modality("vw@30cm", Some("%")),
        ])
    })
    .unwrap_err();
    match &err {
        StoreError::UnitMismatch {
            modality,
            stored,
            incoming,
        } => {
            assert_eq!(
                (modality.as_str(), stored.as_str(), incoming.as_str()),
                ("vw@30cm", "m3/m3", "%")
            );
        }
        other => panic!("expected UnitMismatch, got {other:?}"),
    }
    assert!(
        err.to_string().contains("m3/m3") && err.to_string().contains('%'),
        "{err}"
    );
    assert_eq!(
        store.modalities().unwrap(),
        before,
        "nothing may be written"
    );
    let err = w(store, |tx| {
        tx.upsert_modalities(&[modality("x", Some("a")), modality("x", Some("b"))])
    })
    .unwrap_err();
    assert!(matches!(err, StoreError::Invalid { .. }), "{err:?}");
}

/// Re-inserting stored readings inserts nothing and counts them unchanged (also within the
/// 1e-12 relative tolerance).
pub fn reinserting_readings_changes_nothing<S: Store>(store: &mut S) {
    network(store);
    let b = batch(&[
        ("a", "vw@30cm", T0, 0.3),
        ("a", "vw@30cm", T0 + DAY, 0.31),
        ("b", "t@30cm", T0, 4.5),
    ]);
    let first = insert(store, &b, ConflictPolicy::Fail).unwrap();
    assert_eq!((first.inserted, first.unchanged), (3, 0));
    let before = dump(store);
    let second = insert(store, &b, ConflictPolicy::Fail).unwrap();
    assert_eq!((second.inserted, second.unchanged), (0, 3));
    assert!(second.conflicts.is_empty());
    assert_eq!(dump(store), before);
    let close = batch(&[("a", "vw@30cm", T0, 0.3 * (1.0 + 1e-14))]);
    let s = insert(store, &close, ConflictPolicy::Fail).unwrap();
    assert_eq!((s.inserted, s.unchanged), (0, 1));
    assert_eq!(store.reading_count().unwrap(), 3);
    assert_eq!(
        store.sensor_reading_counts().unwrap(),
        vec![(sid("a"), 2), (sid("b"), 1)]
    );
}

/// A conflicting reading under `Fail` writes nothing (not even the batch's new readings);
/// under `Skip` the stored value stays and the conflict is reported.
pub fn conflicts_fail_or_skip<S: Store>(store: &mut S) {
    network(store);
    insert(
        store,
        &batch(&[("a", "vw@30cm", T0, 0.3)]),
        ConflictPolicy::Fail,
    )
    .unwrap();
    let incoming = batch(&[("a", "vw@30cm", T0 + DAY, 0.2), ("a", "vw@30cm", T0, 0.4)]);
    let err = insert(store, &incoming, ConflictPolicy::Fail).unwrap_err();
    match &err {
        StoreError::Conflicts(c) => {
            assert_eq!(c.len(), 1);
            assert_eq!(
                (c[0].sensor.as_str(), c[0].modality.as_str()),
                ("a", "vw@30cm")
            );
            assert_eq!((c[0].stored, c[0].incoming, c[0].t), (0.3, 0.4, T0));
        }
        other => panic!("expected conflicts, got {other:?}"),
    }
    assert!(
        err.to_string().contains("stored 0.3 vs incoming 0.4"),
        "{err}"
    );
    assert_eq!(store.reading_count().unwrap(), 1, "fail must write nothing");
    let stats = insert(store, &incoming, ConflictPolicy::Skip).unwrap();
    assert_eq!(
        (stats.inserted, stats.unchanged, stats.conflicts.len()),
        (1, 0, 1)
    );
    assert_eq!(dump(store)[&("a".into(), "vw@30cm".into(), T0)], 0.3);
}

/// Duplicates within one batch: identical ones are unchanged, differing ones conflict, the
/// first occurrence wins.
pub fn duplicates_within_a_batch<S: Store>(store: &mut S) {
    network(store);
    let b = batch(&[
        ("a", "vw@30cm", T0, 0.3),
        ("a", "vw@30cm", T0, 0.3),
        ("a", "vw@30cm", T0 + DAY, 0.1),
        ("a", "vw@30cm", T0 + DAY, 0.2),
    ]);
    assert!(matches!(
        insert(store, &b, ConflictPolicy::Fail),
        Err(StoreError::Conflicts(_))
    ));
    assert_eq!(store.reading_count().unwrap(), 0);
    let s = insert(store, &b, ConflictPolicy::Skip).unwrap();
    assert_eq!((s.inserted, s.unchanged, s.conflicts.len()), (2, 1, 1));
    assert_eq!(dump(store)[&("a".into(), "vw@30cm".into(), T0 + DAY)], 0.1);
}

/// Unknown sensors or modalities, bad indices and non-finite values reject the whole batch.
pub fn bad_batches_are_rejected_whole<S: Store>(store: &mut S) {
    network(store);
    let mut check = |b: ReadingBatch, expected: &str| {
        let err = insert(store, &b, ConflictPolicy::Skip).unwrap_err();
        assert!(
            err.to_string().contains(expected),
            "{err} lacks {expected:?}"
        );
        assert_eq!(store.reading_count().unwrap(), 0);
    };
    check(
        batch(&[("a", "vw@30cm", T0, 0.3), ("zz9", "vw@30cm", T0, 0.3)]),
        "unknown sensor \"zz9\"",
    );
    check(
        batch(&[("a", "vw@30cm", T0, 0.3), ("a", "ec@5cm", T0, 0.3)]),
        "unknown modality \"ec@5cm\"",
    );
    check(
        batch(&[("a", "vw@30cm", T0, 0.3), ("b", "vw@30cm", T0, f64::NAN)]),
        "value NaN is not finite",
    );
    check(
        batch(&[
            ("a", "vw@30cm", T0, 0.3),
            ("b", "vw@30cm", T0, f64::INFINITY),
        ]),
        "not finite",
    );
    let mut b = batch(&[("a", "vw@30cm", T0, 0.3)]);
    b.rows.push(Reading {
        sensor: 3,
        modality: 0,
        t: T0,
        value: 1.0,
    });
    check(b, "sensor index 3 out of range");
    let mut b = batch(&[("a", "vw@30cm", T0, 0.3)]);
    b.rows.push(Reading {
        sensor: 0,
        modality: 7,
        t: T0,
        value: 1.0,
    });
    check(b, "modality index 7 out of range");
}

/// A conflict in the middle of a 30 000-reading insert leaves exactly the previous readings.
pub fn a_failure_deep_in_a_big_insert_leaves_the_exact_pre_state<S: Store>(store: &mut S) {
    network(store);
    let seed = batch(&[
        ("b", "t@30cm", T0 + 5_000 * 60, 1.0),
        ("c", "vw@30cm", T0, 0.2),
    ]);
    insert(store, &seed, ConflictPolicy::Fail).unwrap();
    let before = dump(store);
    let mut b = ReadingBatchBuilder::new();
    for k in 0..10_000 {
        for (s, m) in [("a", "vw@30cm"), ("b", "t@30cm"), ("c", "t@30cm")] {
            b.push(&sid(s), &md(m), T0 + k * 60, k as f64);
        }
    }
    let err = insert(store, &b.finish(), ConflictPolicy::Fail).unwrap_err();
    assert!(matches!(err, StoreError::Conflicts(_)), "{err}");
    assert_eq!(dump(store), before);
    assert_eq!(store.reading_count().unwrap(), 2);
}

/// `latest_readings` gives, per sensor with a reading of the modality in the range, the last
/// row of `readings_for` over the same range, sorted by sensor id; also inside a transaction.
pub fn latest_readings_are_the_last_rows_of_readings_for<S: Store>(store: &mut S) {
    network(store);
    assert!(
        store
            .latest_readings(&md("vw@30cm"), i64::MIN..=i64::MAX)
            .unwrap()
            .is_empty()
    );
    insert(
        store,
        &batch(&[
            ("c", "vw@30cm", T0, 3.0),
            ("a", "vw@30cm", T0 + DAY, 2.0),
            ("a", "vw@30cm", T0, 1.0),
            ("a", "t@30cm", T0 + 5 * DAY, 9.0),
            ("b", "vw@30cm", T0 + 2 * DAY, 5.0),
            ("b", "vw@30cm", T0 + 3 * DAY, 6.0),
        ]),
        ConflictPolicy::Fail,
    )
    .unwrap();
    let naive = |store: &S, m: &str, range: std::ops::RangeInclusive<i64>| {
        let got = store.readings_for(Some(&md(m)), range).unwrap();
        let mut last: Vec<(SensorId, i64, f64)> = Vec::new();
        for r in &got.rows {
            let s = got.sensors[r.sensor as usize].clone();
            match last.last_mut() {
                Some(l) if l.0 == s => *l = (s, r.t, r.value),
                _ => last.push((s, r.t, r.value)),
            }
        }
        last
    };
    let ranges = [
        i64::MIN..=i64::MAX,
        T0..=T0,
        T0..=T0 + 2 * DAY,
        T0 + DAY..=T0 + 2 * DAY,
        T0 + 4 * DAY..=T0 + 9 * DAY,
        std::ops::RangeInclusive::new(T0 + 9 * DAY, T0), // empty: starts after it ends
    ];
    for m in ["vw@30cm", "t@30cm", "vw@60cm"] {
        for range in &ranges {
            let want = naive(store, m, range.clone());
            assert_eq!(
                store.latest_readings(&md(m), range.clone()).unwrap(),
                want,
                "{m} {range:?}"
            );
        }
    }
    assert_eq!(
        store
            .latest_readings(&md("vw@30cm"), T0..=T0 + 2 * DAY)
            .unwrap(),
        vec![
            (sid("a"), T0 + DAY, 2.0),
            (sid("b"), T0 + 2 * DAY, 5.0),
            (sid("c"), T0, 3.0)
        ]
    );
    let in_tx = w(store, |tx| tx.latest_readings(&md("vw@30cm"), T0..=T0)).unwrap();
    assert_eq!(in_tx, vec![(sid("a"), T0, 1.0), (sid("c"), T0, 3.0)]);
}

/// `readings_for` filters by modality and inclusive time range and orders by sensor, modality,
/// time; the batch lists only the sensors and modalities it uses.
pub fn readings_for_filters_and_orders<S: Store>(store: &mut S) {
    network(store);
    insert(
        store,
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
        let got = store.readings_for(m.as_ref(), range).unwrap();
        let expected: Vec<(String, String, i64, f64)> = expected
            .iter()
            .map(|(s, m, t, v)| (s.to_string(), m.to_string(), *t, *v))
            .collect();
        assert_eq!(rows_of(&got), expected);
        let used: HashSet<&str> = expected.iter().map(|r| r.0.as_str()).collect();
        assert_eq!(got.sensors.len(), used.len());
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
    check(Some("ec@5cm"), i64::MIN..=i64::MAX, &[]);
}

/// `readings_of_sensors` returns the given sensors' readings only (all modalities, in range),
/// ordered by sensor, modality, time whatever the order asked in; duplicates are ignored and
/// an unknown sensor is an error.
pub fn readings_of_sensors_selects_and_orders<S: Store>(store: &mut S) {
    network(store);
    insert(
        store,
        &batch(&[
            ("c", "vw@30cm", T0, 3.0),
            ("a", "vw@30cm", T0 + DAY, 2.0),
            ("a", "vw@30cm", T0, 1.0),
            ("a", "t@30cm", T0 + 3 * DAY, 9.0),
            ("b", "vw@30cm", T0 + 2 * DAY, 5.0),
            ("c", "t@30cm", T0 - DAY, 7.0),
        ]),
        ConflictPolicy::Fail,
    )
    .unwrap();
    let got = store
        .readings_of_sensors(&[sid("c"), sid("a"), sid("c")], T0..=T0 + 2 * DAY)
        .unwrap();
    let expected = vec![
        ("a".to_string(), "vw@30cm".to_string(), T0, 1.0),
        ("a".into(), "vw@30cm".into(), T0 + DAY, 2.0),
        ("c".into(), "vw@30cm".into(), T0, 3.0),
    ];
    assert_eq!(rows_of(&got), expected);
    assert_eq!(got.sensors, vec![sid("a"), sid("c")]);
    let all = store
        .readings_of_sensors(&[sid("c")], i64::MIN..=i64::MAX)
        .unwrap();
    assert_eq!(
        rows_of(&all),
        vec![
            ("c".to_string(), "t@30cm".to_string(), T0 - DAY, 7.0),
            ("c".into(), "vw@30cm".into(), T0, 3.0),
        ]
    );
    assert!(
        store
            .readings_of_sensors(&[], i64::MIN..=i64::MAX)
            .unwrap()
            .is_empty()
    );
    let err = store
        .readings_of_sensors(&[sid("a"), sid("nope")], i64::MIN..=i64::MAX)
        .unwrap_err();
    assert!(
        matches!(err, StoreError::UnknownSensor(ref s) if s.as_str() == "nope"),
        "{err:?}"
    );
    // The same answer inside a transaction.
    let inside = w(store, |tx| {
        tx.readings_of_sensors(&[sid("c"), sid("a")], T0..=T0 + 2 * DAY)
    })
    .unwrap();
    assert_eq!(rows_of(&inside), expected);
}

/// A write closure that returns `Err` leaves nothing of any of its writes: sensors,
/// modalities, readings, provenance, cells, metadata, collection times, missions, visits,
/// settings, blobs.
pub fn a_failed_write_closure_rolls_everything_back<S: Store>(store: &mut S) {
    network(store);
    let mission = w(store, |tx| {
        tx.replace_cells(&[cell(0, 0, &["a", "b"])])?;
        tx.create_mission(&new_mission(MissionKind::Exploration))
    })
    .unwrap();
    let before = snapshot(store);
    let out: Result<()> = w(store, |tx| {
        tx.upsert_sensors(&[sensor("d", 46.0, -117.1)])?;
        tx.upsert_modalities(&[modality("humidity", Some("%"))])?;
        tx.insert_readings(
            &batch(&[("d", "humidity", T0, 40.0), ("a", "vw@30cm", T0, 0.3)]),
            ConflictPolicy::Fail,
        )?;
        tx.record_ingest(&ingest_record("x.csv"))?;
        tx.replace_cells(&[cell(0, 0, &["a"]), cell(1, 0, &["b", "d"])])?;
        tx.upsert_cell_metadata(&[full_metadata(
            CellIndex { i: 0, j: 0 },
            CellIndex { i: 1, j: 0 },
        )])?;
        tx.set_sensors_collected(&[(sid("a"), T0)])?;
        tx.create_mission(&new_mission(MissionKind::Adaptive))?;
        tx.record_visits(mission, &visits(), T0 + 500, false)?;
        tx.config_set("k", "v")?;
        tx.blob_put("state", b"\x00\x01")?;
        // Everything is visible inside the transaction ...
        assert_eq!(tx.reading_count()?, 2);
        assert_eq!(tx.missions()?.len(), 2);
        Err(StoreError::Invalid {
            what: "test",
            detail: "the use case gives up".into(),
        })
    });
    assert!(matches!(out, Err(StoreError::Invalid { what: "test", .. })));
    // ... and nothing after the rollback.
    assert_eq!(snapshot(store), before);
    // A caller error type converts from StoreError and rolls back the same way.
    #[derive(Debug)]
    enum AppError {
        Store,
        Gave,
    }
    impl From<StoreError> for AppError {
        fn from(_: StoreError) -> Self {
            AppError::Store
        }
    }
    let out: Result<(), AppError> = store.write(|tx| {
        tx.config_set("k", "v")?;
        Err(AppError::Gave)
    });
    assert!(matches!(out, Err(AppError::Gave)));
    let out: Result<(), AppError> = store.write(|tx| {
        tx.config_set("k", "v")?;
        tx.insert_readings(&batch(&[("zz", "vw@30cm", T0, 1.0)]), ConflictPolicy::Fail)?;
        Ok(())
    });
    assert!(matches!(out, Err(AppError::Store)));
    assert_eq!(snapshot(store), before);
}

/// A write method that fails inside a transaction undoes its own writes only: the closure may
/// handle the error and commit the rest.
pub fn a_failed_method_undoes_only_itself<S: Store>(store: &mut S) {
    network(store);
    let failed = w(store, |tx| {
        tx.config_set("k", "kept")?;
        tx.insert_readings(&batch(&[("a", "vw@30cm", T0, 0.3)]), ConflictPolicy::Fail)?;
        // Conflicts half-way through: the new reading of this batch must not stay.
        let err = tx
            .insert_readings(
                &batch(&[("b", "vw@30cm", T0, 0.5), ("a", "vw@30cm", T0, 0.4)]),
                ConflictPolicy::Fail,
            )
            .unwrap_err();
        // A unit mismatch after a new modality in the same list: the new one must not stay.
        tx.upsert_modalities(&[
            modality("ec@5cm", Some("dS/m")),
            modality("vw@30cm", Some("%")),
        ])
        .unwrap_err();
        Ok(err)
    })
    .unwrap();
    assert!(matches!(failed, StoreError::Conflicts(_)));
    assert_eq!(store.config_get("k").unwrap().as_deref(), Some("kept"));
    assert_eq!(
        dump(store).into_iter().collect::<Vec<_>>(),
        vec![(("a".into(), "vw@30cm".into(), T0), 0.3)]
    );
    assert_eq!(store.modalities().unwrap().len(), 2);
}

/// Reads inside a transaction see its writes; the committed state is what the store reads.
pub fn a_transaction_reads_its_own_writes<S: Store>(store: &mut S) {
    network(store);
    let id = w(store, |tx| {
        tx.insert_readings(&batch(&[("a", "vw@30cm", T0, 0.3)]), ConflictPolicy::Fail)?;
        assert_eq!(tx.reading_count()?, 1);
        assert_eq!(rows_of(&tx.readings_for(None, T0..=T0)?).len(), 1);
        tx.config_set("k", "1")?;
        assert_eq!(tx.config_get("k")?.as_deref(), Some("1"));
        tx.blob_put("state", b"abc")?;
        assert_eq!(tx.blob_get("state")?.as_deref(), Some(&b"abc"[..]));
        let id = tx.create_mission(&new_mission(MissionKind::Adaptive))?;
        assert_eq!(
            tx.mission(id)?.map(|m| m.status),
            Some(MissionStatus::Planned)
        );
        Ok(id)
    })
    .unwrap();
    assert_eq!(store.reading_count().unwrap(), 1);
    assert!(store.mission(id).unwrap().is_some());
}

/// The read and write traits can be used as trait objects (callers can hold any backend's
/// transaction behind `&mut dyn StoreWrite`).
pub fn write_traits_are_dyn_compatible<S: Store>(store: &mut S) {
    network(store);
    fn collect(tx: &mut dyn StoreWrite) -> Result<()> {
        tx.set_sensors_collected(&[(sid("a"), T0)])
    }
    fn read(r: &dyn StoreRead) -> Vec<(SensorId, UnixSeconds)> {
        r.sensor_last_collected().unwrap()
    }
    w(store, |tx| collect(tx)).unwrap();
    assert_eq!(read(store), vec![(sid("a"), T0)]);
}

/// Ingest records come back oldest first with their ids increasing; settings are replaced.
pub fn ingests_and_config<S: Store>(store: &mut S) {
    let (r1, r2) = (ingest_record("one.csv"), ingest_record("two.csv"));
    let (id1, id2) = w(store, |tx| {
        Ok((tx.record_ingest(&r1)?, tx.record_ingest(&r2)?))
    })
    .unwrap();
    assert!(id2 > id1);
    assert_eq!(store.ingests().unwrap(), vec![r1, r2]);
    w(store, |tx| tx.config_set("k", "1")).unwrap();
    w(store, |tx| tx.config_set("k", "2")).unwrap();
    assert_eq!(store.config_get("k").unwrap().as_deref(), Some("2"));
    assert_eq!(store.config_get("other").unwrap(), None);
}

/// Blobs come back byte for byte (empty, NUL bytes, large), replaced by key.
pub fn blobs_round_trip<S: Store>(store: &mut S) {
    let big: Vec<u8> = (0..300_000u32).map(|k| (k * 7 % 251) as u8).collect();
    w(store, |tx| {
        tx.blob_put("empty", b"")?;
        tx.blob_put("nul", b"\x00a\x00\xff")?;
        tx.blob_put("big", &big)
    })
    .unwrap();
    assert_eq!(store.blob_get("empty").unwrap(), Some(Vec::new()));
    assert_eq!(
        store.blob_get("nul").unwrap(),
        Some(b"\x00a\x00\xff".to_vec())
    );
    assert_eq!(store.blob_get("big").unwrap(), Some(big));
    w(store, |tx| tx.blob_put("nul", b"second")).unwrap();
    assert_eq!(store.blob_get("nul").unwrap(), Some(b"second".to_vec()));
    assert_eq!(store.blob_get("missing").unwrap(), None);
}

/// Last collection times only move forward; unknown sensors are refused.
pub fn sensors_collected_never_move_back<S: Store>(store: &mut S) {
    network(store);
    w(store, |tx| {
        tx.set_sensors_collected(&[(sid("b"), T0), (sid("a"), T0 + DAY)])
    })
    .unwrap();
    w(store, |tx| {
        tx.set_sensors_collected(&[(sid("a"), T0), (sid("b"), T0 + 5)])
    })
    .unwrap();
    assert_eq!(
        store.sensor_last_collected().unwrap(),
        vec![(sid("a"), T0 + DAY), (sid("b"), T0 + 5)]
    );
    let err = w(store, |tx| {
        tx.set_sensors_collected(&[(sid("c"), T0), (sid("zz"), T0)])
    })
    .unwrap_err();
    assert!(matches!(err, StoreError::UnknownSensor(_)), "{err:?}");
    assert_eq!(store.sensor_last_collected().unwrap().len(), 2);
}

/// Cell metadata round-trips; scalars, scores and class probabilities are replaced, summaries,
/// correlations and anomalies upserted by key; unknown cells and out-of-range numbers write
/// nothing.
pub fn cell_metadata_round_trips_and_upserts_by_key<S: Store>(store: &mut S) {
    network(store);
    w(store, |tx| {
        tx.replace_cells(&[cell(0, 0, &["a", "b"]), cell(1, 0, &["c"])])
    })
    .unwrap();
    let (x0, x1) = (CellIndex { i: 0, j: 0 }, CellIndex { i: 1, j: 0 });
    assert_eq!(
        store.cell_metadata().unwrap(),
        vec![CellMetadata::new(x0), CellMetadata::new(x1)]
    );
    let full = full_metadata(x0, x1);
    w(store, |tx| {
        tx.upsert_cell_metadata(std::slice::from_ref(&full))
    })
    .unwrap();
    assert_eq!(store.cell_metadata().unwrap()[0], full);
    let mut next = CellMetadata::new(x0);
    next.anomalies.push(AnomalyRecord {
        modality: md("vw@30cm"),
        t: T0 + DAY,
        anomaly: 0.1,
        flagged: false,
    });
    let mut summary = full.summaries[0].clone();
    summary.stats.count = 3;
    next.summaries.push(summary.clone());
    w(store, |tx| tx.upsert_cell_metadata(&[next])).unwrap();
    let got = &store.cell_metadata().unwrap()[0];
    assert_eq!(got.scores, None);
    assert_eq!(got.class_probabilities, vec![]);
    assert_eq!(got.anomalies.len(), 2);
    assert_eq!(got.summaries, vec![summary]);
    assert_eq!(got.correlations, full.correlations);
    let before = store.cell_metadata().unwrap();
    let err = w(store, |tx| {
        tx.upsert_cell_metadata(&[
            full_metadata(x1, x0),
            CellMetadata::new(CellIndex { i: 9, j: 9 }),
        ])
    })
    .unwrap_err();
    assert!(err.to_string().contains("x9y9"), "{err}");
    for bad in [
        {
            let mut m = full_metadata(x0, x1);
            m.class_probabilities[0].probability = 1.5;
            m
        },
        {
            let mut m = full_metadata(x0, x1);
            m.correlations[0].correlation = -1.01;
            m
        },
        {
            let mut m = full_metadata(x0, x1);
            m.pending_bytes = Some(f64::NAN);
            m
        },
        {
            let mut m = full_metadata(x0, x1);
            m.summaries[0].modality = md("ec@5cm");
            m
        },
    ] {
        assert!(w(store, |tx| tx.upsert_cell_metadata(&[bad])).is_err());
    }
    let twice = [CellMetadata::new(x0), CellMetadata::new(x0)];
    assert!(w(store, |tx| tx.upsert_cell_metadata(&twice)).is_err());
    assert_eq!(store.cell_metadata().unwrap(), before);
}

/// Rewriting a cell's summaries and correlations with the same values leaves them as they
/// are; changed values replace them; a row listed twice in one write holds the last values
/// given, whether those equal the stored ones or not.
pub fn metadata_child_rows_hold_the_last_values_written<S: Store>(store: &mut S) {
    network(store);
    w(store, |tx| {
        tx.replace_cells(&[cell(0, 0, &["a", "b"]), cell(1, 0, &["c"])])
    })
    .unwrap();
    let (x0, x1) = (CellIndex { i: 0, j: 0 }, CellIndex { i: 1, j: 0 });
    let full = full_metadata(x0, x1);
    let put = |store: &mut S, m: &CellMetadata| {
        w(store, |tx| tx.upsert_cell_metadata(std::slice::from_ref(m))).unwrap();
        store.cell_metadata().unwrap()[0].clone()
    };
    assert_eq!(put(store, &full), full);
    assert_eq!(put(store, &full), full);
    let mut changed = full.clone();
    changed.summaries[0].stats.count += 1;
    changed.summaries[0].stats.mean += 0.25;
    changed.correlations[0].correlation = -changed.correlations[0].correlation / 2.0;
    changed.correlations[0].overlap += 1;
    assert_eq!(put(store, &changed), changed);
    // Listed twice: stored values last (the first entry differs from them), then changed
    // values last (the first entry equals the stored ones).
    let mut twice = changed.clone();
    twice.summaries.push(full.summaries[0].clone());
    twice.correlations.push(full.correlations[0].clone());
    let got = put(store, &twice);
    assert_eq!(got.summaries, full.summaries);
    assert_eq!(got.correlations, full.correlations);
    let mut twice = full.clone();
    twice.summaries.push(changed.summaries[0].clone());
    twice.correlations.push(changed.correlations[0].clone());
    let got = put(store, &twice);
    assert_eq!(got.summaries, changed.summaries);
    assert_eq!(got.correlations, changed.correlations);
}

/// `cell_metadata_scalars` gives what `cell_metadata` gives with the child lists emptied, in
/// a transaction and outside one, for described and undescribed cells.
pub fn cell_metadata_scalars_are_the_rows_without_children<S: Store>(store: &mut S) {
    network(store);
    w(store, |tx| {
        tx.replace_cells(&[cell(0, 0, &["a", "b"]), cell(1, 0, &["c"]), cell(2, 0, &[])])
    })
    .unwrap();
    let (x0, x1) = (CellIndex { i: 0, j: 0 }, CellIndex { i: 1, j: 0 });
    let mut second = full_metadata(x1, x0);
    second.class_probabilities.reverse();
    second.scores = None;
    w(store, |tx| {
        tx.upsert_cell_metadata(&[full_metadata(x0, x1), second])
    })
    .unwrap();
    let stripped = |rows: Vec<CellMetadata>| -> Vec<CellMetadata> {
        rows.into_iter()
            .map(|mut m| {
                m.summaries.clear();
                m.correlations.clear();
                m.anomalies.clear();
                m
            })
            .collect()
    };
    let want = stripped(store.cell_metadata().unwrap());
    assert_eq!(want.len(), 3);
    assert!(!want[0].class_probabilities.is_empty());
    assert_eq!(store.cell_metadata_scalars().unwrap(), want);
    let in_tx = w(store, |tx| tx.cell_metadata_scalars()).unwrap();
    assert_eq!(in_tx, want);
}

/// `replace_cells` keeps identical cells with their metadata and deletes every other stored
/// cell with all its metadata, including correlations pointing at it.
pub fn replace_cells_keeps_or_deletes_metadata<S: Store>(store: &mut S) {
    network(store);
    let (x0, x1) = (CellIndex { i: 0, j: 0 }, CellIndex { i: 1, j: 0 });
    w(store, |tx| {
        tx.replace_cells(&[cell(0, 0, &["a", "b"]), cell(1, 0, &["c"])])?;
        tx.upsert_cell_metadata(&[full_metadata(x0, x1), full_metadata(x1, x0)])
    })
    .unwrap();
    let same = w(store, |tx| {
        tx.replace_cells(&[cell(1, 0, &["c"]), cell(0, 0, &["b", "a"])])
    })
    .unwrap();
    assert_eq!((same.kept, same.removed, same.added), (2, 0, 0));
    assert_eq!(store.cell_metadata().unwrap()[0], full_metadata(x0, x1));
    let stats = w(store, |tx| {
        tx.replace_cells(&[cell(0, 0, &["a", "b"]), cell(2, 0, &["c"])])
    })
    .unwrap();
    assert_eq!((stats.kept, stats.removed, stats.added), (1, 1, 1));
    let mdata = store.cell_metadata().unwrap();
    assert_eq!(mdata.len(), 2);
    assert!(
        mdata[0].correlations.is_empty(),
        "correlation with x1 must go"
    );
    assert_eq!(mdata[0].anomalies.len(), 1);
    assert_eq!(mdata[0].summaries.len(), 1);
    assert_eq!(mdata[0].class_probabilities.len(), 3);
    assert_eq!(mdata[1], CellMetadata::new(CellIndex { i: 2, j: 0 }));
    // A cell whose side changes is a new cell.
    let mut wider = cell(0, 0, &["a", "b"]);
    wider.cell_size_m = 50.0;
    let stats = w(store, |tx| {
        tx.replace_cells(&[wider.clone(), cell(2, 0, &["c"])])
    })
    .unwrap();
    assert_eq!((stats.kept, stats.removed, stats.added), (1, 1, 1));
    assert_eq!(store.cell_metadata().unwrap()[0], CellMetadata::new(x0));
    // Invalid grids are refused whole.
    let before = store.cells().unwrap();
    let err = w(store, |tx| {
        tx.replace_cells(&[cell(0, 0, &["a"]), cell(1, 0, &["a"])])
    })
    .unwrap_err();
    assert!(err.to_string().contains("sensor a is in cells"), "{err}");
    assert!(w(store, |tx| tx.replace_cells(&[cell(5, 5, &["nope"])])).is_err());
    assert!(
        w(store, |tx| tx
            .replace_cells(&[cell(5, 5, &["a"]), cell(5, 5, &["b"])]))
        .is_err()
    );
    let mut zero = cell(5, 5, &["a"]);
    zero.cell_size_m = 0.0;
    assert!(w(store, |tx| tx.replace_cells(&[zero])).is_err());
    assert_eq!(store.cells().unwrap(), before);
    assert_eq!(before[0], wider);
}

/// A mission comes back exactly as created (profile, energies, seed above `i64::MAX`, stops
/// with and without terms), planned; `mission(id)` agrees with `missions()`.
pub fn missions_round_trip_with_stops<S: Store>(store: &mut S) {
    let adaptive = new_mission(MissionKind::Adaptive);
    let exploration = new_mission(MissionKind::Exploration);
    let mut empty = new_mission(MissionKind::Exploration);
    empty.stops.clear();
    let ids = w(store, |tx| {
        Ok([
            tx.create_mission(&adaptive)?,
            tx.create_mission(&exploration)?,
            tx.create_mission(&empty)?,
        ])
    })
    .unwrap();
    assert!(ids[0] < ids[1] && ids[1] < ids[2]);
    let all = store.missions().unwrap();
    assert_eq!(all.len(), 3);
    for ((record, id), new) in all.iter().zip(ids).zip([&adaptive, &exploration, &empty]) {
        assert_eq!(record.id, id);
        assert_eq!(&record.mission, new);
        assert_eq!(record.status, MissionStatus::Planned);
        assert_eq!(record.flown_at, None);
        assert!(record.visits.is_empty());
        assert_eq!(store.mission(id).unwrap().as_ref(), Some(record));
    }
    assert_eq!(store.mission(MissionId(ids[2].0 + 100)).unwrap(), None);
}

/// Recording visits marks a mission flown at the given time; recording again is
/// `AlreadyFlown` (naming the mission and the first time) unless `amend`, which replaces the
/// visits and the time. Unknown missions and bad visit lists are refused without writing.
pub fn record_visits_refuses_a_flown_mission_unless_amend<S: Store>(store: &mut S) {
    let new = new_mission(MissionKind::Adaptive);
    let (id, other) = w(store, |tx| {
        Ok((tx.create_mission(&new)?, tx.create_mission(&new)?))
    })
    .unwrap();
    let v = visits();
    w(store, |tx| tx.record_visits(id, &v, T0 + 900, false)).unwrap();
    let flown = store.mission(id).unwrap().unwrap();
    assert_eq!(
        flown,
        crate::MissionRecord {
            id,
            mission: new.clone(),
            status: MissionStatus::Flown,
            flown_at: Some(T0 + 900),
            visits: v.clone(),
        }
    );
    let err = w(store, |tx| tx.record_visits(id, &v[..1], T0 + 2_000, false)).unwrap_err();
    match &err {
        StoreError::AlreadyFlown { mission, flown_at } => {
            assert_eq!((*mission, *flown_at), (id.0, T0 + 900));
        }
        other => panic!("expected AlreadyFlown, got {other:?}"),
    }
    assert_eq!(store.mission(id).unwrap().unwrap(), flown);
    w(store, |tx| tx.record_visits(id, &v[..1], T0 + 2_000, true)).unwrap();
    let amended = store.mission(id).unwrap().unwrap();
    assert_eq!(
        (amended.flown_at, amended.visits.as_slice()),
        (Some(T0 + 2_000), &v[..1])
    );
    // amend on a planned mission simply records it.
    w(store, |tx| tx.record_visits(other, &[], T0 + 50, true)).unwrap();
    assert_eq!(
        store.mission(other).unwrap().unwrap().flown_at,
        Some(T0 + 50)
    );
    let err = w(store, |tx| tx.record_visits(MissionId(777), &[], T0, false)).unwrap_err();
    assert!(err.to_string().contains("777"), "{err}");
    let mut twice = visits();
    twice[1].order = 0;
    let before = store.missions().unwrap();
    assert!(w(store, |tx| tx.record_visits(id, &twice, T0, true)).is_err());
    let mut nan = visits();
    nan[0].energy_j = Some(f64::NAN);
    assert!(w(store, |tx| tx.record_visits(id, &nan, T0, true)).is_err());
    assert_eq!(store.missions().unwrap(), before);
}

/// A planned mission can be cancelled once (status `Cancelled`, nothing else changes) and a
/// cancelled one never recorded; a flown one cannot be cancelled. Deleting removes a mission
/// with its stops and visits; an unknown id is refused. A cancelled mission survives an
/// import. Pages are newest first, below `before`, at most `limit` long.
pub fn missions_cancel_delete_and_page<S: Store>(store: &mut S) {
    let new = new_mission(MissionKind::Adaptive);
    let ids = w(store, |tx| {
        (0..5)
            .map(|_| tx.create_mission(&new))
            .collect::<Result<Vec<_>>>()
    })
    .unwrap();
    let v = visits();
    w(store, |tx| tx.record_visits(ids[1], &v, T0 + 900, false)).unwrap();

    w(store, |tx| tx.cancel_mission(ids[0])).unwrap();
    let cancelled = store.mission(ids[0]).unwrap().unwrap();
    assert_eq!(cancelled.status, MissionStatus::Cancelled);
    assert_eq!((cancelled.flown_at, cancelled.visits.len()), (None, 0));
    assert_eq!(cancelled.mission, new);
    // Not twice, not a flown one, not an unknown one; and never recorded once cancelled.
    assert!(w(store, |tx| tx.cancel_mission(ids[0])).is_err());
    assert!(w(store, |tx| tx.cancel_mission(ids[1])).is_err());
    assert!(w(store, |tx| tx.cancel_mission(MissionId(777))).is_err());
    assert!(w(store, |tx| tx.record_visits(ids[0], &v, T0, true)).is_err());
    assert_eq!(store.mission(ids[0]).unwrap().unwrap(), cancelled);
    assert_eq!(
        store.mission(ids[1]).unwrap().unwrap().status,
        MissionStatus::Flown
    );

    // Delete a flown one (the store does not judge) and a cancelled one, then import it back.
    w(store, |tx| tx.delete_mission(ids[1])).unwrap();
    assert_eq!(store.mission(ids[1]).unwrap(), None);
    let err = w(store, |tx| tx.delete_mission(ids[1])).unwrap_err();
    assert!(err.to_string().contains(&ids[1].to_string()), "{err}");
    w(store, |tx| tx.delete_mission(ids[0])).unwrap();
    w(store, |tx| tx.import_mission(&cancelled)).unwrap();
    assert_eq!(store.mission(ids[0]).unwrap().unwrap(), cancelled);

    // Pages: newest first, no gap and no repeat.
    let left: Vec<MissionId> = [ids[4], ids[3], ids[2], ids[0]].into();
    let page = |before, limit| -> Vec<MissionId> {
        store
            .missions_page(before, limit)
            .unwrap()
            .iter()
            .map(|m| m.id)
            .collect()
    };
    assert_eq!(page(None, 10), left);
    assert_eq!(page(None, 2), left[..2]);
    assert_eq!(page(Some(ids[3]), 2), left[2..]);
    assert_eq!(page(Some(ids[0]), 2), Vec::<MissionId>::new());
    assert_eq!(page(None, 0), Vec::<MissionId>::new());
}

/// Missions with a non-finite number or a stop order used twice are refused, nothing written.
pub fn invalid_missions_write_nothing<S: Store>(store: &mut S) {
    let mut bad = Vec::new();
    let mut m = new_mission(MissionKind::Adaptive);
    m.energy.total_j = f64::NAN;
    bad.push(m);
    let mut m = new_mission(MissionKind::Adaptive);
    m.weights[2] = f64::INFINITY;
    bad.push(m);
    let mut m = new_mission(MissionKind::Adaptive);
    m.stops[1].terms = Some([0.0, f64::NAN, 0.0, 0.0]);
    bad.push(m);
    let mut m = new_mission(MissionKind::Adaptive);
    m.stops[1].order = 0;
    bad.push(m);
    let mut m = new_mission(MissionKind::Adaptive);
    m.profile.cruise_speed_mps = f64::NEG_INFINITY;
    bad.push(m);
    let mut m = new_mission(MissionKind::Adaptive);
    m.profile.wind_mps = -1.0;
    bad.push(m);
    let mut m = new_mission(MissionKind::Adaptive);
    m.profile.wind_from_deg = f64::NAN;
    bad.push(m);
    for m in &bad {
        let err = w(store, |tx| tx.create_mission(m)).unwrap_err();
        assert!(matches!(err, StoreError::Invalid { .. }), "{err:?}");
    }
    assert!(store.missions().unwrap().is_empty());
}

/// Lists come sorted by name or index whatever the insertion order, missions oldest first.
pub fn results_come_in_a_deterministic_order<S: Store>(store: &mut S) {
    w(store, |tx| {
        tx.upsert_sensors(&[
            sensor("z1", 46.0, -117.0),
            sensor("B", 46.0, -117.0),
            sensor("a10", 46.0, -117.0),
            sensor("a9", 46.0, -117.0),
        ])?;
        tx.upsert_modalities(&[modality("vw@90cm", None), modality("t@30cm", None)])?;
        tx.replace_cells(&[
            cell(1, 0, &["z1"]),
            cell(-1, 2, &["B"]),
            cell(0, 5, &["a10"]),
            cell(0, -1, &["a9"]),
        ])?;
        tx.set_sensors_collected(&[(sid("z1"), T0), (sid("B"), T0)])
    })
    .unwrap();
    let names: Vec<String> = store
        .sensors()
        .unwrap()
        .iter()
        .map(|s| s.id.to_string())
        .collect();
    assert_eq!(names, ["B", "a10", "a9", "z1"]);
    let mods: Vec<String> = store
        .modalities()
        .unwrap()
        .iter()
        .map(|m| m.modality.to_string())
        .collect();
    assert_eq!(mods, ["t@30cm", "vw@90cm"]);
    let cells: Vec<String> = store
        .cells()
        .unwrap()
        .iter()
        .map(|c| c.index.to_string())
        .collect();
    let mut sorted = vec![
        CellIndex { i: 1, j: 0 },
        CellIndex { i: -1, j: 2 },
        CellIndex { i: 0, j: 5 },
        CellIndex { i: 0, j: -1 },
    ];
    sorted.sort();
    let expected: Vec<String> = sorted.iter().map(ToString::to_string).collect();
    assert_eq!(cells, expected);
    let md_cells: Vec<CellIndex> = store
        .cell_metadata()
        .unwrap()
        .iter()
        .map(|m| m.cell)
        .collect();
    assert_eq!(md_cells, sorted);
    let collected: Vec<String> = store
        .sensor_last_collected()
        .unwrap()
        .iter()
        .map(|(s, _)| s.to_string())
        .collect();
    assert_eq!(collected, ["B", "z1"]);
    // The same reads twice give the same answer.
    assert_eq!(snapshot(store), snapshot(store));
}

/// Randomised (seeded): inserting any batch twice inserts nothing the second time, and the
/// counts add up.
pub fn inserting_twice_inserts_nothing_the_second_time<S: Store>(store: &mut S) {
    network(store);
    let sensors = ["a", "b", "c"];
    let modalities = ["vw@30cm", "t@30cm"];
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let mut stored: BTreeMap<(usize, usize, i64), f64> = BTreeMap::new();
    for round in 0..24 {
        let n = rng.below(300) as usize;
        let mut b = ReadingBatchBuilder::new();
        let mut distinct_new = HashSet::new();
        let mut first_in_batch: BTreeMap<(usize, usize, i64), f64> = BTreeMap::new();
        for _ in 0..n {
            let (s, m) = (rng.below(3) as usize, rng.below(2) as usize);
            let t = (rng.below(40) + 40 * round) as i64;
            let v = (rng.below(6) as f64 - 3.0) * 0.5;
            b.push(&sid(sensors[s]), &md(modalities[m]), T0 + t * 60, v);
            if !stored.contains_key(&(s, m, t)) {
                distinct_new.insert((s, m, t));
            }
            first_in_batch.entry((s, m, t)).or_insert(v);
        }
        let b = b.finish();
        let first = insert(store, &b, ConflictPolicy::Skip).unwrap();
        assert_eq!(first.inserted as usize, distinct_new.len());
        assert_eq!(
            first.inserted as usize + first.unchanged as usize + first.conflicts.len(),
            n
        );
        for (k, v) in first_in_batch {
            stored.entry(k).or_insert(v);
        }
        let second = insert(store, &b, ConflictPolicy::Skip).unwrap();
        assert_eq!(second.inserted, 0);
        assert_eq!(second.unchanged as usize + second.conflicts.len(), n);
        assert_eq!(store.reading_count().unwrap() as usize, stored.len());
    }
}

/// Randomised (seeded): what comes back is exactly the first value inserted for each key, in
/// key order, over the whole range and over sub-ranges.
pub fn stored_readings_match_a_naive_model<S: Store>(store: &mut S) {
    network(store);
    let sensors = ["a", "b", "c"];
    let modalities = ["t@30cm", "vw@30cm"];
    let mut rng = Rng(0x0123_4567_89AB_CDEF);
    let mut model: BTreeMap<(usize, usize, i64), f64> = BTreeMap::new();
    for _ in 0..8 {
        let mut b = ReadingBatchBuilder::new();
        for _ in 0..rng.below(200) + 1 {
            let (s, m, t) = (
                rng.below(3) as usize,
                rng.below(2) as usize,
                rng.below(30) as i64,
            );
            let v = (rng.next() >> 11) as f64 / (1u64 << 53) as f64 * 2e3 - 1e3;
            model.entry((s, m, t)).or_insert(v);
            b.push(&sid(sensors[s]), &md(modalities[m]), T0 + t * DAY, v);
        }
        insert(store, &b.finish(), ConflictPolicy::Skip).unwrap();
    }
    let expected: Vec<(String, String, i64, f64)> = model
        .iter()
        .map(|(&(s, m, t), &v)| {
            (
                sensors[s].to_string(),
                modalities[m].to_string(),
                T0 + t * DAY,
                v,
            )
        })
        .collect();
    let all = store.readings_for(None, i64::MIN..=i64::MAX).unwrap();
    assert_eq!(rows_of(&all), expected);
    let (lo, hi) = (T0 + 7 * DAY, T0 + 19 * DAY);
    let part: Vec<_> = expected
        .iter()
        .filter(|r| (lo..=hi).contains(&r.2) && r.0 != "b")
        .cloned()
        .collect();
    let got = store
        .readings_of_sensors(&[sid("c"), sid("a")], lo..=hi)
        .unwrap();
    assert_eq!(rows_of(&got), part);
}

/// The PostgreSQL server the tests use: `GLEANER_TEST_PG_URL` (`scripts/test.sh` starts a
/// throwaway cluster and sets it; `scripts/pg-cluster.sh` does it by hand).
///
/// # Panics
/// When the variable is not set: a PostgreSQL test fails rather than skips without a server.
pub fn pg_test_url() -> String {
    std::env::var("GLEANER_TEST_PG_URL").unwrap_or_else(|_| {
        panic!(
            "GLEANER_TEST_PG_URL is not set: the PostgreSQL tests need a server. Run \
             scripts/test.sh (which starts one), or `d=$(scripts/pg-cluster.sh start) && \
             eval \"$(scripts/pg-cluster.sh env $d)\"` first"
        )
    })
}

/// A project (schema) name no other test uses: `t_<tag>_<pid>_<n>`, for tests that run in
/// parallel against one server. `tag` must be lower-case letters, digits or `_`.
pub fn pg_fresh_project(tag: &str) -> String {
    use std::sync::atomic::{AtomicU64, Ordering};
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let n = NEXT.fetch_add(1, Ordering::Relaxed);
    format!("t_{tag}_{}_{n}", std::process::id())
}

/// The project's exclusion ([`Store::lock_project`]) across two connections to one project
/// (`first` and `second`, e.g. two server replicas): re-entrant for its holder, which may
/// write inside it; the other connection's `lock_project` and its plain writes wait until
/// every hold is given back, then see what the holder wrote. Synchronised by channels and a
/// flag, never by sleeps: `second` can only pass its lock after `first` set the flag just
/// before its last unlock.
///
/// # Panics
/// When the exclusion does not exclude.
pub fn exclusion_holds_across_connections<S: Store + Send + 'static>(
    first: &mut S,
    second: S,
    third: S,
) {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::{Arc, mpsc};
    first.lock_project().unwrap();
    first.lock_project().unwrap();
    first.write(|tx| tx.config_set("holder", "first")).unwrap();
    let released = Arc::new(AtomicBool::new(false));
    let (waiting_tx, waiting_rx) = mpsc::channel::<()>();
    let spawn = |store: S, key: &'static str, lock: bool| {
        let released = Arc::clone(&released);
        let waiting = waiting_tx.clone();
        std::thread::spawn(move || {
            let mut store = store;
            waiting.send(()).unwrap();
            // Once the hold (or the write transaction) is had, the first holder must be gone.
            let locked_after = !lock || {
                store.lock_project().unwrap();
                released.load(Ordering::SeqCst)
            };
            let out = store.write(|tx| {
                let seen = locked_after && released.load(Ordering::SeqCst);
                let holder = tx.config_get("holder")?;
                tx.config_set(key, "done")?;
                Ok::<_, StoreError>((seen, holder))
            });
            if lock {
                store.unlock_project();
            }
            out.unwrap()
        })
    };
    let locker = spawn(second, "second", true);
    let writer = spawn(third, "third", false);
    waiting_rx.recv().unwrap();
    waiting_rx.recv().unwrap();
    // Still held once after this; the holder's own writes go on.
    first.unlock_project();
    first
        .write(|tx| tx.config_set("holder", "first, again"))
        .unwrap();
    released.store(true, Ordering::SeqCst);
    first.unlock_project();
    for (name, t) in [("lock_project", locker), ("a write", writer)] {
        let (seen, holder) = t.join().unwrap();
        assert!(
            seen,
            "{name} of another connection ran while the exclusion was held"
        );
        assert_eq!(holder.as_deref(), Some("first, again"), "{name}");
    }
    assert_eq!(first.config_get("second").unwrap().as_deref(), Some("done"));
    assert_eq!(first.config_get("third").unwrap().as_deref(), Some("done"));
    // Given back: the first takes it again at once.
    first.lock_project().unwrap();
    first.unlock_project();
}
