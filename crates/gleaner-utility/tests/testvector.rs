//! Reproduces the shared test vector `testvectors/utility.json` (docs/method.md §2) to a relative 1e-9.

use std::collections::BTreeMap;

use gleaner_utility::{
    CellInputs, IncrementalState, Reading, Series, TimeGrid, UtilityConfig, cell_series,
    score_cells,
};
use serde_json::Value;

fn shared_dir() -> std::path::PathBuf {
    match std::env::var("GLEANER_DATA_DIR") {
        Ok(d) => std::path::PathBuf::from(d).join(".."),
        Err(_) => std::path::PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared")),
    }
}

fn close(got: f64, want: f64, what: &str) {
    let tol = 1e-9 * want.abs().max(1e-300);
    assert!(
        (got - want).abs() <= tol || (want == 0.0 && got.abs() < 1e-15),
        "{what}: got {got}, expected {want}"
    );
}

/// One sensor: times (s), values, last collection time (s).
type SensorData = (Vec<i64>, Vec<f64>, Option<i64>);

struct Vector {
    t: i64,
    config: UtilityConfig,
    cells: Vec<String>,
    /// Per cell: per sensor (times, values, last collected).
    sensors: Vec<Vec<SensorData>>,
    neighbours: Vec<Vec<usize>>,
    probabilities: Vec<Vec<f64>>,
    expected: Value,
}

fn load() -> Vector {
    let path = shared_dir().join("testvectors/utility.json");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    let v: Value = serde_json::from_str(&text).unwrap();
    let config = UtilityConfig {
        freshness_half_life_s: v["half_life_s"].as_f64().unwrap(),
        min_overlap: v["min_overlap"].as_u64().unwrap() as usize,
        epsilon: v["epsilon"].as_f64().unwrap(),
        ..UtilityConfig::default()
    };
    let cells: Vec<String> = v["neighbours"]
        .as_object()
        .unwrap()
        .keys()
        .cloned()
        .collect();
    let pos = |c: &str| cells.iter().position(|x| x == c).unwrap();
    let mut sensors: Vec<Vec<_>> = vec![Vec::new(); cells.len()];
    let by_sensor: BTreeMap<_, _> = v["sensors"].as_object().unwrap().iter().collect();
    for (_, s) in by_sensor {
        let (times, values): (Vec<i64>, Vec<f64>) = s["readings"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| (p[0].as_i64().unwrap(), p[1].as_f64().unwrap()))
            .unzip();
        sensors[pos(s["cell"].as_str().unwrap())].push((
            times,
            values,
            s["last_collected_s"].as_i64(),
        ));
    }
    let neighbours = cells
        .iter()
        .map(|c| {
            v["neighbours"][c]
                .as_array()
                .unwrap()
                .iter()
                .map(|n| pos(n.as_str().unwrap()))
                .collect()
        })
        .collect();
    let probabilities = cells
        .iter()
        .map(|c| {
            v["class_probabilities"][c]
                .as_array()
                .unwrap()
                .iter()
                .map(|p| p.as_f64().unwrap())
                .collect()
        })
        .collect();
    Vector {
        t: v["t_s"].as_i64().unwrap(),
        config,
        cells,
        sensors,
        neighbours,
        probabilities,
        expected: v["expected"].clone(),
    }
}

#[test]
fn from_scratch_matches_the_test_vector() {
    let v = load();
    let series: Vec<_> = v
        .sensors
        .iter()
        .map(|ss| {
            let views: Vec<Series> = ss.iter().map(|(t, x, _)| Series::new(t, x)).collect();
            cell_series(&views, TimeGrid::DAILY)
        })
        .collect();
    let last: Vec<Vec<Option<i64>>> = v
        .sensors
        .iter()
        .map(|ss| ss.iter().map(|s| s.2).collect())
        .collect();
    let inputs: Vec<CellInputs> = (0..v.cells.len())
        .map(|i| CellInputs {
            last_collected: &last[i],
            series: vec![series[i].as_series()],
            neighbours: &v.neighbours[i],
            probabilities: &v.probabilities[i],
        })
        .collect();
    let terms = score_cells(&inputs, v.t, &v.config).unwrap();
    for (i, c) in v.cells.iter().enumerate() {
        let e = &v.expected[c];
        let cs: Vec<(i64, f64)> = e["cell_series"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| (p[0].as_i64().unwrap(), p[1].as_f64().unwrap()))
            .collect();
        assert_eq!(
            series[i].times,
            cs.iter().map(|p| p.0).collect::<Vec<_>>(),
            "cell {c}"
        );
        for (k, p) in cs.iter().enumerate() {
            close(
                series[i].values[k],
                p.1,
                &format!("cell {c} series at {}", p.0),
            );
        }
        for (name, got) in [
            ("F", terms[i].f),
            ("R", terms[i].r),
            ("A", terms[i].a),
            ("U", terms[i].u),
            ("S", terms[i].s),
        ] {
            close(got, e[name].as_f64().unwrap(), &format!("cell {c} {name}"));
        }
    }
}

#[test]
fn incremental_matches_the_test_vector() {
    let v = load();
    let counts: Vec<usize> = v.sensors.iter().map(Vec::len).collect();
    let mut state = IncrementalState::new(&counts, &v.neighbours, 1, TimeGrid::DAILY).unwrap();
    // Feed the readings newest first, cell by cell, to exercise out-of-order arrival.
    let mut readings = Vec::new();
    for (cell, ss) in v.sensors.iter().enumerate() {
        for (sensor, (times, values, last)) in ss.iter().enumerate() {
            for (&time, &value) in times.iter().zip(values) {
                readings.push(Reading {
                    cell,
                    sensor,
                    modality: 0,
                    time,
                    value,
                });
            }
            if let Some(l) = last {
                state.record_collection(cell, sensor, *l).unwrap();
            }
        }
    }
    readings.reverse();
    state.add_readings(&readings).unwrap();
    let terms = state.score(v.t, &v.config, &v.probabilities).unwrap();
    for (i, c) in v.cells.iter().enumerate() {
        let e = &v.expected[c];
        for (name, got) in [
            ("F", terms[i].f),
            ("R", terms[i].r),
            ("A", terms[i].a),
            ("U", terms[i].u),
            ("S", terms[i].s),
        ] {
            close(
                got,
                e[name].as_f64().unwrap(),
                &format!("incremental cell {c} {name}"),
            );
        }
    }
}
