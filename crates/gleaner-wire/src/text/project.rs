//! A project's state as text: the cell table, a scoring, the mission history, the one-line
//! summaries of `init`, `ingest`, `record` and a migration, a reconstruction (a table, or a
//! range as CSV) and the crash-safety sweeps. Lengths m, energies J, times RFC 3339 (UTC),
//! positions WGS84 degrees.

use std::collections::HashMap;
use std::fmt::Write as _;

use gleaner_app::crash_test::{Sweep, Tally};
use gleaner_app::{self as app, Estimator, Reconstruction, ReconstructionSeries, format_rfc3339};
use gleaner_field::CellIndex;
use gleaner_kriging::Mean;

use crate::docs::{CellRowDoc, ScoringDoc};

/// The cell table as aligned text, one line per cell; `readings` is each cell's stored
/// readings (every sensor and modality; a cell missing from it has none).
pub fn cells_table(rows: &[CellRowDoc], readings: &HashMap<CellIndex, u64>) -> String {
    let mut out = format!(
        "{:<10} {:>10} {:>11} {:>7} {:>8} {:>20} {:>10} {:>6} {:>6} {:>6} {:>6} {:>7}\n",
        "cell",
        "lat",
        "lon",
        "sensors",
        "readings",
        "latest",
        "pending_kB",
        "F",
        "R",
        "A",
        "U",
        "S"
    );
    for r in rows {
        let readings: u64 = CellIndex::parse(&r.cell)
            .and_then(|c| readings.get(&c).copied())
            .unwrap_or(0);
        let latest = r
            .summaries
            .iter()
            .map(|s| s.latest_t.as_str())
            .max()
            .unwrap_or("-");
        let f = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.3}"));
        let s = r.scores.as_ref();
        out.push_str(&format!(
            "{:<10} {:>10.6} {:>11.6} {:>7} {:>8} {:>20} {:>10} {:>6} {:>6} {:>6} {:>6} {:>7}\n",
            r.cell,
            r.centre_lon_lat[1],
            r.centre_lon_lat[0],
            r.sensors.len(),
            readings,
            latest,
            r.pending_bytes
                .map_or("-".to_string(), |b| format!("{:.1}", b / 1000.0)),
            f(s.map(|s| s.freshness)),
            f(s.map(|s| s.redundancy)),
            f(s.map(|s| s.anomaly)),
            f(s.map(|s| s.uncertainty)),
            f(s.map(|s| s.score)),
        ));
    }
    out
}

/// A scoring: header lines with the weights, then one line per cell, the first `limit`.
pub fn scoring_table(doc: &ScoringDoc, limit: usize) -> String {
    let mut out =
        format!(
            "scored at {}  S = {}·F + {}·A + {}·U − {}·R  (anomaly: {}{})\n",
            doc.t,
            doc.weights[0],
            doc.weights[1],
            doc.weights[2],
            doc.weights[3],
            doc.anomaly_form,
            doc.condition.as_ref().map_or(
                String::from(", no condition model: U = 0"),
                |c| format!(", U from {}: {}", c.modality, c.classes.join("/"))
            )
        );
    out.push_str(&format!(
        "{:<10} {:>7} {:>6} {:>6} {:>8} {:>6} {:>8}  {}\n",
        "cell", "sensors", "F", "R", "A", "U", "S", "driver"
    ));
    for c in doc.cells.iter().take(limit) {
        out.push_str(&format!(
            "{:<10} {:>7} {:>6.3} {:>6.3} {:>8.3} {:>6.3} {:>8.3}  {}\n",
            c.cell, c.sensors, c.f, c.r, c.a, c.u, c.s, c.driver
        ));
    }
    out
}

/// The mission history, one line per mission (energy J, its share of the budget).
pub fn missions_table(missions: &[app::MissionRecord]) -> String {
    let mut out = format!(
        "{:>4} {:<11} {:<8} {:<20} {:<11} {:>5} {:>9} {:>11} {:>6}\n",
        "id", "kind", "status", "planned_at", "planner", "cells", "total_S", "energy_J", "use"
    );
    for m in missions {
        let e = &m.mission.energy;
        out.push_str(&format!(
            "{:>4} {:<11} {:<8} {:<20} {:<11} {:>5} {:>9.3} {:>11.1} {:>5.1}%\n",
            m.id,
            m.mission.kind.as_str(),
            m.status.as_str(),
            format_rfc3339(m.mission.planned_at),
            m.mission.solver,
            m.mission.stops.len(),
            m.mission.total_score,
            e.total_j,
            if e.budget_j > 0.0 {
                100.0 * e.total_j / e.budget_j
            } else {
                0.0
            }
        ));
    }
    out
}

/// What `init` made of the project in `dir` (base WGS84 degrees, cell side m).
pub fn init_lines(o: &app::InitOutcome, dir: &std::path::Path) -> String {
    format!(
        "project {} in {}\n  sensors: {} ({} new, {} updated)\n  base station: {:.6}, {:.6}\n  cells: {} non-empty cells of {} m ({} kept, {} added, {} removed)",
        o.settings.project.name,
        dir.display(),
        o.sensors,
        o.upsert.added.len(),
        o.upsert.updated.len(),
        o.settings.field.base_lat,
        o.settings.field.base_lon,
        o.n_cells,
        o.settings.field.cell_size_m,
        o.cells.kept,
        o.cells.added,
        o.cells.removed,
    )
}

/// The one-line summary of an ingest, then a line per skipped row.
pub fn ingest_line(o: &app::IngestOutcome) -> String {
    let r = &o.report;
    let mut out = format!(
        "ingested {} file(s): {} rows read, {} readings ({} new, {} already stored), {} missing values, {} duplicate rows, {} rows skipped, {} conflicts kept as stored",
        o.files,
        r.rows_read,
        r.readings,
        o.inserted,
        o.unchanged,
        r.missing,
        r.duplicates,
        r.skipped,
        o.conflicts
    );
    for s in &r.skipped_rows {
        out.push_str(&format!("\n  skipped: {}", s.reason));
    }
    out
}

/// The one-line summary of a recorded flight.
pub fn record_line(o: &app::RecordOutcome) -> String {
    format!(
        "mission #{} recorded as flown at {}{}: {} cells, {} sensors collected, {} readings brought back ({} new)",
        o.mission,
        format_rfc3339(o.at),
        if o.amended { " (amended)" } else { "" },
        o.cells.len(),
        o.sensors_collected,
        o.readings_inserted + o.readings_unchanged,
        o.readings_inserted
    )
}

/// What a migration copied, and whether the project now uses the target.
pub fn migration_lines(m: &app::ProjectMigration) -> String {
    let o = &m.outcome;
    let mut line = format!(
        "copied {} sensors, {} modalities, {} readings, {} ingests, {} cells, {} missions, {} settings and blobs from {} to {}",
        o.sensors,
        o.modalities,
        o.readings,
        o.ingests,
        o.cells,
        o.missions,
        o.config_and_blobs,
        m.from,
        m.to,
    );
    if m.switched {
        line.push_str(&format!("\nthe project now uses {}", m.to));
    }
    line
}

/// `wrote FILES` and a `not written: REASON` line per file skipped, each line ending in a
/// newline.
pub fn written_lines(files: &[std::path::PathBuf], skipped: &[String]) -> String {
    let names: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
    let mut t = format!("wrote {}\n", names.join(", "));
    for note in skipped {
        t.push_str(&format!("not written: {note}\n"));
    }
    t
}

/// The reconstruction as a text table (values in the modality's unit, sd its square root,
/// lo90/hi90 the 90% prediction interval; ranges m, time scales d).
pub fn reconstruction_table(r: &Reconstruction) -> String {
    let mut out = String::new();
    let c = r.model.covariance;
    let _ = writeln!(
        out,
        "{} at {}: field model sill {:.3e}, nugget {:.3e}, range {:.0} m, time scale {:.1} d",
        r.modality,
        format_rfc3339(r.at),
        c.sill,
        c.nugget,
        c.range_m,
        c.time_scale_s / 86_400.0
    );
    let m = r.changes;
    let _ = writeln!(
        out,
        "model of changes: shared variogram {:.3e} + {:.3e}·(1 − exp(−h/{:.1} d)), range {:.0} m; \
         own {:.3e} + {:.3e}·(1 − exp(−h/{:.1} d))",
        m.shared.nugget,
        m.shared.partial,
        m.shared.scale_s / 86_400.0,
        m.range_m,
        m.own.nugget,
        m.own.partial,
        m.own.scale_s / 86_400.0
    );
    let _ = writeln!(
        out,
        "estimate (\"kriged\"): {}",
        match r.estimator {
            Estimator::Changes => "kriging of changes (last value + neighbours' known changes)",
            Estimator::Levels(Mean::Unknown) => "ordinary kriging of levels",
            Estimator::Levels(Mean::Known) => "simple kriging of levels",
            Estimator::Dynamic =>
                "dynamic field model (learned covariance of levels, AR(1) dynamics, Kalman filter)",
        }
    );
    let _ = writeln!(
        out,
        "{:<16} {:<21} {:>10} {:>10} {:>10} {:>10} {:>10}",
        "sensor", "last reading", "carried", "kriged", "sd", "lo90", "hi90"
    );
    for s in &r.sensors {
        let _ = writeln!(
            out,
            "{:<16} {:<21} {:>10.4} {:>10.4} {:>10.4} {:>10.4} {:>10.4}",
            s.sensor.as_str(),
            s.last_time.map_or("never".into(), format_rfc3339),
            s.carried,
            s.kriged,
            s.variance.sqrt(),
            s.kriged - s.half90,
            s.kriged + s.half90
        );
    }
    out
}

/// A range reconstruction as CSV: `time,sensor,mean,sd,lo90,hi90` (RFC 3339 times; the
/// modality's unit), one row per time and sensor.
pub fn series_csv(r: &ReconstructionSeries) -> String {
    let mut out = String::from("time,sensor,mean,sd,lo90,hi90\n");
    let n = r.sensors.len();
    for (t, &time) in r.times.iter().enumerate() {
        let stamp = format_rfc3339(time);
        for (s, (id, _)) in r.sensors.iter().enumerate() {
            let k = t * n + s;
            let (lo, hi) = r.interval90(t, s);
            let _ = writeln!(
                out,
                "{stamp},{},{:.6},{:.6},{:.6},{:.6}",
                id.as_str(),
                r.mean[k],
                r.variance[k].sqrt(),
                lo,
                hi
            );
        }
    }
    out
}

/// The crash-safety sweeps as a table, a `FAIL` line per failure, and the totals; with
/// whether every trial passed.
pub fn crash_report(sweeps: Vec<Sweep>) -> (String, bool) {
    let mut report = String::from(
        "backend   use case  steps  trials  rolled back  committed  completed  failures\n",
    );
    let mut totals = Tally::default();
    for s in sweeps {
        let t = s.tally;
        let _ = writeln!(
            report,
            "{:<9} {:<9} {:>5}  {:>6}  {:>11}  {:>9}  {:>9}  {:>8}",
            s.backend.name(),
            s.case.name(),
            s.steps,
            t.trials,
            t.rolled_back,
            t.committed,
            t.completed,
            t.failures.len()
        );
        for f in &t.failures {
            let _ = writeln!(report, "  FAIL {f}");
        }
        totals.trials += t.trials;
        totals.rolled_back += t.rolled_back;
        totals.committed += t.committed;
        totals.completed += t.completed;
        totals.failures.extend(t.failures);
    }
    let _ = writeln!(
        report,
        "total: {} kill points, {} rolled back, {} committed, {} completed, {} failures (integrity, partial state, lost readings, rerun)",
        totals.trials,
        totals.rolled_back,
        totals.committed,
        totals.completed,
        totals.failures.len()
    );
    (report, totals.failures.is_empty())
}

#[cfg(test)]
mod tests {
    use super::*;
    use gleaner_app::crash_test::{Backend, UseCase};

    #[test]
    fn a_failed_trial_fails_the_crash_report() {
        let sweep = |failures: Vec<String>| Sweep {
            backend: Backend::Sqlite,
            case: UseCase::Plan,
            steps: 12,
            tally: Tally {
                trials: 3,
                rolled_back: 2,
                committed: 1,
                completed: 0,
                failures,
            },
        };
        let (text, ok) = crash_report(vec![sweep(Vec::new())]);
        assert!(ok, "{text}");
        assert!(text.ends_with("total: 3 kill points, 2 rolled back, 1 committed, 0 completed, 0 failures (integrity, partial state, lost readings, rerun)\n"), "{text}");
        let (text, ok) = crash_report(vec![sweep(Vec::new()), sweep(vec!["lost".into()])]);
        assert!(!ok);
        assert!(
            text.contains("  FAIL lost\n") && text.contains("total: 6 kill points"),
            "{text}"
        );
    }

    #[test]
    fn a_cell_table_without_rows_is_its_header() {
        let t = cells_table(&[], &HashMap::new());
        assert_eq!(t.lines().count(), 1);
        assert!(t.starts_with("cell "));
    }
}
