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

mod metadata;
mod missions;
mod postgres;
mod properties;
mod readings;
mod transactions;
pub use metadata::*;
pub use missions::*;
pub use postgres::*;
pub use properties::*;
pub use readings::*;
pub use transactions::*;
