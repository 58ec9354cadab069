//! End-to-end tests of the `gleaner` binary: each runs the real executable in a temporary
//! project directory. Output formats are pinned with insta snapshots.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn shared_data() -> PathBuf {
    std::env::var_os("GLEANER_DATA_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"))
}

fn gleaner(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_gleaner"))
        .args(args)
        .output()
        .expect("run gleaner")
}

fn ok(args: &[&str]) -> String {
    let out = gleaner(args);
    assert!(
        out.status.success(),
        "gleaner {args:?} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("utf-8 output")
}

fn fail(args: &[&str]) -> String {
    let out = gleaner(args);
    assert!(!out.status.success(), "gleaner {args:?} succeeded");
    String::from_utf8(out.stderr).expect("utf-8 output")
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn small_project() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temp dir");
    let sensors = data("sensors.csv");
    ok(&[
        "init",
        "--dir",
        s(dir.path()),
        "--sensors",
        s(&sensors),
        "--base",
        "46.7800,-117.0805",
        // These tests check the paper's formulas; gleaner's method is the default.
        "--method",
        "paper",
    ]);
    dir
}

#[test]
fn init_ingest_cells_snapshot() {
    let dir = small_project();
    let p = s(dir.path());
    let readings = data("readings.csv");
    let out = ok(&["ingest", "--project", p, s(&readings)]);
    insta::assert_snapshot!("ingest_small", out);
    let table = ok(&["cells", "--project", p]);
    insta::assert_snapshot!("cells_small", table);
    let json = ok(&["cells", "--project", p, "--json", "--sort", "sensors"]);
    let v: serde_json::Value = serde_json::from_str(&json).expect("json");
    insta::assert_json_snapshot!("cells_small_json", v);
}

#[test]
fn reingest_changes_nothing() {
    let dir = small_project();
    let p = s(dir.path());
    let readings = data("readings.csv");
    ok(&["ingest", "--project", p, s(&readings)]);
    let before = ok(&["cells", "--project", p, "--json"]);
    let again = ok(&["ingest", "--project", p, s(&readings)]);
    assert!(again.contains("(0 new, 160 already stored)"), "{again}");
    assert_eq!(before, ok(&["cells", "--project", p, "--json"]));
}

#[test]
fn failed_ingest_stores_nothing() {
    let dir = small_project();
    let p = s(dir.path());
    let bad = dir.path().join("bad.csv");
    let good = std::fs::read_to_string(data("readings.csv")).expect("read");
    std::fs::write(&bad, format!("{good}n1,2014-02-30,vw@30cm,0.3,m3/m3\n")).expect("write");
    let err = fail(&["ingest", "--project", p, s(&bad)]);
    assert!(
        err.contains(
            "bad.csv:162: column `timestamp`: invalid or impossible timestamp: \"2014-02-30\""
        ),
        "{err}"
    );
    let json = ok(&["cells", "--project", p, "--json"]);
    assert!(!json.contains("\"count\""), "something was stored: {json}");
    // A conflict with stored data rolls back the whole second ingest.
    ok(&["ingest", "--project", p, s(&data("readings.csv"))]);
    let conflict = dir.path().join("conflict.csv");
    std::fs::write(
        &conflict,
        "sensor_id,timestamp,modality,value\nn1,2015-01-01,vw@30cm,0.2\nn1,2014-01-01,vw@30cm,0.9\n",
    )
    .expect("write");
    let err = fail(&["ingest", "--project", p, s(&conflict)]);
    assert!(err.contains("nothing written"), "{err}");
    let skipped = ok(&["ingest", "--project", p, "--on-error", "skip", s(&conflict)]);
    assert!(
        skipped.contains("(1 new, 0 already stored)")
            && skipped.contains("1 conflicts kept as stored"),
        "{skipped}"
    );
}

#[test]
fn ingest_skip_mode_reports_rows() {
    let dir = small_project();
    let p = s(dir.path());
    let bad = dir.path().join("bad.csv");
    std::fs::write(&bad, "sensor_id,timestamp,modality,value\nn1,2014-01-01,vw@30cm,0.3\nghost,2014-01-01,vw@30cm,0.3\nn2,2014-01-01,vw@30cm,wet\n").expect("write");
    let out = ok(&["ingest", "--project", p, "--on-error", "skip", s(&bad)]);
    assert!(out.contains("2 rows skipped"), "{out}");
    assert!(
        out.contains("bad.csv:3: column `sensor_id`: unknown sensor"),
        "{out}"
    );
    assert!(
        out.contains("bad.csv:4: column `value`: not a number: \"wet\""),
        "{out}"
    );
}

/// `farm-token` prints a new token once and appends only its SHA-256 to the tokens file;
/// an unknown farm is refused, naming the farms there.
#[test]
fn farm_token_prints_the_token_once_and_stores_its_hash() {
    let dir = tempfile::tempdir().unwrap();
    for farm in ["north", "south"] {
        std::fs::create_dir_all(dir.path().join(farm)).unwrap();
        std::fs::write(dir.path().join(farm).join("gleaner.toml"), "").unwrap();
    }
    let farms = dir.path().to_str().unwrap();
    let token = ok(&[
        "farm-token",
        "--farms",
        farms,
        "--farm",
        "north",
        "--scope",
        "read",
    ]);
    let token = token.trim();
    assert_eq!(token.len(), 64, "{token}");
    assert!(token.bytes().all(|b| b.is_ascii_hexdigit()));
    let second = ok(&[
        "farm-token",
        "--farms",
        farms,
        "--farm",
        "south",
        "--scope",
        "write",
    ]);
    let file = std::fs::read_to_string(dir.path().join("tokens")).unwrap();
    let lines: Vec<&str> = file.lines().collect();
    assert_eq!(lines.len(), 2, "{file}");
    assert!(lines[0].starts_with("north read "), "{file}");
    assert!(lines[1].starts_with("south write "), "{file}");
    assert!(!file.contains(token) && !file.contains(second.trim()));
    let tokens = gleaner_server::FarmTokens::parse(&file).unwrap();
    assert_eq!(
        tokens.find(token.as_bytes()),
        Some(("north", gleaner_server::Scope::Read))
    );
    let err = fail(&[
        "farm-token",
        "--farms",
        farms,
        "--farm",
        "east",
        "--scope",
        "read",
    ]);
    assert!(err.contains("north, south"), "{err}");
}

#[test]
fn every_command_has_help_with_an_example() {
    for cmd in [
        "init",
        "ingest",
        "cells",
        "score",
        "plan",
        "record",
        "synth",
        "demo",
        "simulate",
        "report",
        "reconstruct",
        "farm-token",
    ] {
        let out = ok(&[cmd, "--help"]);
        assert!(
            out.contains("Example"),
            "{cmd} --help lacks an example:\n{out}"
        );
    }
}

#[test]
fn caf_project_from_real_data() {
    let dir = tempfile::tempdir().expect("temp dir");
    let p = s(dir.path());
    let d = shared_data();
    let locations = d.join("caf/sensors/CAF_sensor_locations.csv");
    let init = ok(&[
        "init",
        "--dir",
        p,
        "--sensors",
        s(&locations),
        "--utm-zone",
        "11N",
    ]);
    assert!(init.contains("sensors: 42 (42 new, 0 updated)"), "{init}");
    let mut args: Vec<String> = vec!["ingest".into(), "--project".into(), p.into()];
    let mut files: Vec<PathBuf> = std::fs::read_dir(d.join("caf/Daily"))
        .expect("CAF daily dir")
        .map(|e| e.expect("entry").path())
        .collect();
    files.sort();
    args.extend(files.iter().map(|f| s(f).to_string()));
    let argv: Vec<&str> = args.iter().map(String::as_str).collect();
    let out = ok(&argv);
    assert!(out.contains("ingested 42 file(s)"), "{out}");
    // The hourly file's midnight readings collide with the daily means (stamped at midnight):
    // a conflict with stored data, so nothing is stored...
    let hourly = d.join("caf/derived/water_content_2015_Jan_April_32_sensors.csv");
    let err = fail(&[
        "ingest",
        "--project",
        p,
        "--modality",
        "vw@30cm",
        s(&hourly),
    ]);
    assert!(
        err.contains("conflicting reading(s), nothing written; first: CAF003 vw@30cm"),
        "{err}"
    );
    // ... while as its own modality it goes in whole.
    let out = ok(&[
        "ingest",
        "--project",
        p,
        "--modality",
        "vwh@30cm",
        s(&hourly),
    ]);
    assert!(out.contains("80672 readings (80672 new"), "{out}");
    let json = ok(&["cells", "--project", p, "--json"]);
    let cells: Vec<serde_json::Value> = serde_json::from_str(&json).expect("json");
    let sensors: usize = cells
        .iter()
        .map(|c| c["sensors"].as_array().map_or(0, Vec::len))
        .sum();
    assert_eq!(sensors, 42);
    assert!(
        cells
            .iter()
            .all(|c| !c["summaries"].as_array().expect("summaries").is_empty())
    );
}

#[test]
fn score_plan_record_cycle() {
    let dir = small_project();
    let p = s(dir.path());
    ok(&["ingest", "--project", p, s(&data("readings.csv"))]);
    let json = ok(&["score", "--project", p, "--at", "2014-01-25", "--json"]);
    let doc: serde_json::Value = serde_json::from_str(&json).expect("json");
    let cells = doc["cells"].as_array().expect("cells");
    assert_eq!(cells.len(), 3);
    for c in cells {
        for term in ["f", "r", "u"] {
            let v = c[term].as_f64().expect("number");
            assert!((0.0..=1.0).contains(&v), "{term} = {v}");
        }
        assert!(c["a"].as_f64().expect("a") >= 0.0);
        // Collected on 2014-01-20, scored 5 days later with a 3-day half-life.
        let f = c["f"].as_f64().expect("f");
        assert!((f - (1.0 - 0.5f64.powf(5.0 / 3.0))).abs() < 1e-9, "F = {f}");
    }
    assert_eq!(doc["weights"], serde_json::json!([1.0, 1.0, 1.0, 1.0]));
    assert_eq!(doc["anomaly_form"], "raw");
    // The terms are kept in the cell metadata table.
    let table = ok(&["cells", "--project", p, "--sort", "score"]);
    assert!(
        !table.lines().nth(1).expect("a row").ends_with(" -"),
        "{table}"
    );

    let plan = ok(&[
        "plan",
        "--project",
        p,
        "--at",
        "2014-01-25",
        "--json",
        "--time-limit",
        "1",
    ]);
    let m: serde_json::Value = serde_json::from_str(&plan).expect("json");
    let e = &m["energy"];
    let total = e["total_j"].as_f64().expect("total");
    assert!(total <= e["budget_j"].as_f64().expect("budget"));
    let parts: f64 = ["travel_j", "hover_j", "comm_j", "return_j"]
        .iter()
        .map(|k| e[k].as_f64().expect("part"))
        .sum();
    assert!((parts - total).abs() < 1e-6 * total);
    assert_eq!(m["mission_id"], 1);
    assert!(
        m["total_score"].as_f64().expect("score")
            >= m["greedy_baseline"]["total_score"]
                .as_f64()
                .expect("greedy")
                - 1e-9
    );
    let stops = m["stops"].as_array().expect("stops");
    assert!(!stops.is_empty());
    let first = stops[0]["cell"].as_str().expect("cell").to_string();
    // Scoring and planning fill the metadata table without losing what ingest put there.
    let cells: Vec<serde_json::Value> =
        serde_json::from_str(&ok(&["cells", "--project", p, "--json"])).expect("json");
    for c in &cells {
        assert!(
            c["expected_energy_j"].as_f64().expect("energy") > 5_000.0,
            "{c}"
        );
        assert!(c["pending_bytes"].is_number(), "{c}");
        assert!(
            c["scores"].is_object() && !c["summaries"].as_array().expect("summaries").is_empty(),
            "{c}"
        );
        assert!(
            !c["class_probabilities"]
                .as_array()
                .expect("probabilities")
                .is_empty(),
            "{c}"
        );
    }

    let rec = ok(&["record", "--project", p, "--mission", "1"]);
    assert!(
        rec.contains("mission #1 recorded as flown at 2014-01-25T00:00:00Z"),
        "{rec}"
    );
    let json = ok(&["score", "--project", p, "--at", "2014-01-25", "--json"]);
    let doc: serde_json::Value = serde_json::from_str(&json).expect("json");
    let visited = doc["cells"]
        .as_array()
        .expect("cells")
        .iter()
        .find(|c| c["cell"] == first.as_str())
        .expect("visited cell");
    assert_eq!(
        visited["f"].as_f64(),
        Some(0.0),
        "a cell collected at t is perfectly fresh"
    );
    let err = fail(&["record", "--project", p, "--mission", "9"]);
    assert!(err.contains("no mission #9"), "{err}");
}

#[test]
fn plan_from_a_scores_file_and_its_errors() {
    let dir = small_project();
    let p = s(dir.path());
    ok(&["ingest", "--project", p, s(&data("readings.csv"))]);
    let scores = dir.path().join("scores.csv");
    std::fs::write(&scores, "cell_id,score\nx0y0,2.0\nx2y1,-1\n").expect("write");
    let out = ok(&[
        "plan",
        "--project",
        p,
        "--scores",
        s(&scores),
        "--solver",
        "greedy",
        "--dry-run",
    ]);
    assert!(out.contains("1 of 1 candidate cells"), "{out}");
    assert!(out.contains("x0y0"), "{out}");
    std::fs::write(&scores, "cell_id,score\nx9y9,2.0\n").expect("write");
    let err = fail(&["plan", "--project", p, "--scores", s(&scores)]);
    assert!(
        err.contains("scores.csv:2: column `cell_id`: unknown cell: \"x9y9\""),
        "{err}"
    );
    std::fs::write(&scores, "cell_id,score\nx0y0,high\n").expect("write");
    let err = fail(&["plan", "--project", p, "--scores", s(&scores)]);
    assert!(
        err.contains("scores.csv:2: column `score`: not a finite number: \"high\""),
        "{err}"
    );
}

#[test]
fn plan_several_sorties() {
    let dir = small_project();
    let p = s(dir.path());
    ok(&["ingest", "--project", p, s(&data("readings.csv"))]);
    // A battery for about one cell per sortie, so the second sortie must collect more.
    let toml = dir.path().join("gleaner.toml");
    let text = std::fs::read_to_string(&toml).expect("read settings");
    std::fs::write(
        &toml,
        text.replace("[energy]\n", "[energy]\nbattery_j = 12000\n"),
    )
    .expect("write settings");
    let one = ok(&["plan", "--project", p, "--iterations", "200", "--dry-run"]);
    assert!(!one.contains("sorties:"), "{one}");
    let out = ok(&[
        "plan",
        "--project",
        p,
        "--sorties",
        "2",
        "--iterations",
        "200",
    ]);
    let summary = &out[out.find("2 sorties:").expect("summary")..];
    insta::assert_snapshot!("plan_two_sorties", summary);
    // Both sorties were chosen from the same candidate cells, and each says how many.
    assert_eq!(out.matches(" of 3 candidate cells").count(), 2, "{out}");
    assert!(!out.contains('?'), "{out}");
    // Each sortie is its own stored mission, exportable on its own.
    ok(&[
        "export",
        "--project",
        p,
        "--mission",
        "2",
        "--out",
        s(&dir.path().join("m2")),
    ]);
    let err = fail(&["plan", "--project", p, "--sorties", "0"]);
    assert!(err.contains("sorties = 0"), "{err}");
}

#[test]
fn user_probabilities_are_validated() {
    let dir = small_project();
    let p = s(dir.path());
    ok(&["ingest", "--project", p, s(&data("readings.csv"))]);
    let probs = dir.path().join("p.csv");
    std::fs::write(
        &probs,
        "cell_id,p_1,p_2\nx0y0,0.5,0.5\nx2y0,1,0\nx2y1,0.2,0.8\n",
    )
    .expect("write");
    let json = ok(&[
        "score",
        "--project",
        p,
        "--probabilities",
        s(&probs),
        "--json",
    ]);
    let doc: serde_json::Value = serde_json::from_str(&json).expect("json");
    let u = |cell: &str| {
        doc["cells"]
            .as_array()
            .expect("cells")
            .iter()
            .find(|c| c["cell"] == cell)
            .expect("cell")["u"]
            .as_f64()
            .expect("u")
    };
    assert!((u("x0y0") - 1.0).abs() < 1e-12 && u("x2y0") == 0.0);
    std::fs::write(
        &probs,
        "cell_id,p_1,p_2\nx0y0,0.5,0.6\nx2y0,1,0\nx2y1,0.2,0.8\n",
    )
    .expect("write");
    let err = fail(&["score", "--project", p, "--probabilities", s(&probs)]);
    assert!(err.contains("x0y0"), "{err}");
}

#[test]
fn bench_op_on_a_classic_instance() {
    let d = shared_data().join("op/classic/Tsiligirides_1");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&d)
        .expect("dir")
        .map(|e| e.expect("entry").path())
        .collect();
    files.sort();
    let out = ok(&["bench", "op", s(&files[0]), "--time-limit", "1"]);
    assert!(
        out.contains("1 instances, 1 with target: 1 matched"),
        "{out}"
    );
    assert!(out.contains(" yes"), "{out}");
    // With an iteration cap the scores do not depend on the machine's speed.
    let capped = |_: u8| {
        let out = ok(&[
            "bench",
            "op",
            s(&files[3]),
            "--iterations",
            "500",
            "--time-limit",
            "60",
            "--seed",
            "4",
        ]);
        out.lines()
            .nth(1)
            .map(|l| l.split_whitespace().take(6).collect::<Vec<_>>().join(" "))
            .expect("a row")
    };
    assert_eq!(capped(1), capped(2));
}

#[test]
fn synth_is_deterministic() {
    let dir = tempfile::tempdir().expect("temp dir");
    let a = dir.path().join("a");
    let b = dir.path().join("b");
    for out in [&a, &b] {
        ok(&[
            "synth",
            "--out",
            s(out),
            "--sensors",
            "8",
            "--days",
            "20",
            "--seed",
            "5",
        ]);
    }
    for f in [
        "sensors.csv",
        "readings.csv",
        "ground_truth.csv",
        "faults.csv",
    ] {
        assert_eq!(
            std::fs::read(a.join(f)).expect("a"),
            std::fs::read(b.join(f)).expect("b"),
            "{f}"
        );
    }
}

#[test]
fn demo_runs_end_to_end() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = ok(&[
        "demo",
        "--dir",
        s(dir.path()),
        "--sensors",
        "30",
        "--days",
        "90",
    ]);
    for step in [
        "1. synthetic farm",
        "3. exploration",
        "sortie #1: selected",
        "overview map",
        "4. 5 adaptive missions",
        "J of 66,500.0 J",
        "brought back",
        "5. mission #",
    ] {
        assert!(out.contains(step), "demo output lacks {step:?}:\n{out}");
    }
    // A second run starts over in the same directory.
    ok(&[
        "demo",
        "--dir",
        s(dir.path()),
        "--sensors",
        "30",
        "--days",
        "90",
    ]);
}

#[test]
fn exploration_visits_every_cell_once_within_budget() {
    let dir = tempfile::tempdir().expect("temp dir");
    let p = s(dir.path());
    let data_dir = dir.path().join("data");
    ok(&[
        "synth",
        "--out",
        s(&data_dir),
        "--sensors",
        "80",
        "--days",
        "10",
        "--seed",
        "3",
    ]);
    ok(&[
        "init",
        "--dir",
        p,
        "--sensors",
        s(&data_dir.join("sensors.csv")),
    ]);
    ok(&["ingest", "--project", p, s(&data_dir.join("readings.csv"))]);
    let e: serde_json::Value =
        serde_json::from_str(&ok(&["explore", "--project", p, "--json"])).expect("json");
    let budget = e["budget_j"].as_f64().expect("budget");
    let mut seen: Vec<String> = Vec::new();
    for sortie in e["sorties"].as_array().expect("sorties") {
        assert!(sortie["energy"]["total_j"].as_f64().expect("energy") <= budget);
        assert_eq!(sortie["kind"], "exploration");
        seen.extend(
            sortie["stops"]
                .as_array()
                .expect("stops")
                .iter()
                .map(|c| c["cell"].as_str().expect("id").to_string()),
        );
    }
    let cells: Vec<serde_json::Value> =
        serde_json::from_str(&ok(&["cells", "--project", p, "--json"])).expect("json");
    let mut all: Vec<String> = cells
        .iter()
        .map(|c| c["cell"].as_str().expect("id").to_string())
        .collect();
    seen.sort();
    all.sort();
    assert_eq!(seen, all, "every cell exactly once");
    assert!(
        e["sorties"].as_array().expect("sorties").len()
            >= e["lower_bound_sorties"].as_u64().expect("bound") as usize
    );
}

#[test]
fn export_writes_geojson_qgc_plan_and_wpl() {
    let dir = small_project();
    let p = s(dir.path());
    ok(&["ingest", "--project", p, s(&data("readings.csv"))]);
    ok(&[
        "plan",
        "--project",
        p,
        "--at",
        "2014-01-25",
        "--solver",
        "exact",
    ]);
    let out = dir.path().join("export");
    ok(&["export", "--project", p, "--mission", "1", "--out", s(&out)]);

    let waypoints = std::fs::read_to_string(out.join("mission.waypoints")).expect("wpl");
    insta::assert_snapshot!("export_waypoints", waypoints);
    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("mission.plan")).expect("plan"))
            .expect("json");
    insta::assert_json_snapshot!("export_plan", plan);
    assert_eq!(plan["fileType"], "Plan");
    assert_eq!(plan["mission"]["version"], 2);
    assert_eq!(plan["geoFence"]["version"], 2);
    assert_eq!(plan["rallyPoints"]["version"], 2);

    let g: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("mission.geojson")).expect("geojson"),
    )
    .expect("json");
    assert_eq!(g["type"], "FeatureCollection");
    assert!(g.get("crs").is_none(), "RFC 7946: no crs member");
    let features = g["features"].as_array().expect("features");
    let polygons: Vec<&serde_json::Value> = features
        .iter()
        .filter(|f| f["geometry"]["type"] == "Polygon")
        .collect();
    assert_eq!(polygons.len(), 3);
    for f in &polygons {
        let ring: Vec<[f64; 2]> = f["geometry"]["coordinates"][0]
            .as_array()
            .expect("ring")
            .iter()
            .map(|c| [c[0].as_f64().expect("lon"), c[1].as_f64().expect("lat")])
            .collect();
        assert_eq!(ring.first(), ring.last(), "closed ring");
        // [lon, lat] order: longitudes near -117, latitudes near 46.78.
        assert!(
            ring.iter()
                .all(|c| (c[0] + 117.08).abs() < 0.01 && (c[1] - 46.78).abs() < 0.01)
        );
        let area2: f64 = ring
            .windows(2)
            .map(|w| w[0][0] * w[1][1] - w[1][0] * w[0][1])
            .sum();
        assert!(area2 > 0.0, "outer ring must be counter-clockwise");
    }
    let route = features
        .iter()
        .find(|f| f["geometry"]["type"] == "LineString")
        .expect("route");
    let line = route["geometry"]["coordinates"].as_array().expect("line");
    assert_eq!(line.first(), line.last(), "the route returns to the base");
    assert!(
        features
            .iter()
            .any(|f| f["geometry"]["type"] == "Point" && f["properties"]["kind"] == "base")
    );
}

/// `replan` after the first stop: a continuation within the energy left less the reserve,
/// its WPL without a take-off and starting where the aircraft is; too little energy for the
/// way home, a stop beyond the mission's and a flown mission are refused.
#[test]
fn replan_writes_a_continuation_within_the_energy_left() {
    let dir = small_project();
    let p = s(dir.path());
    ok(&["ingest", "--project", p, s(&data("readings.csv"))]);
    ok(&[
        "plan",
        "--project",
        p,
        "--at",
        "2014-01-25",
        "--solver",
        "exact",
    ]);
    let parent: serde_json::Value =
        serde_json::from_str(&ok(&["missions", "--project", p, "--json"])).expect("json");
    let stops = parent[0]["stops"].as_array().expect("stops").len();
    assert!(stops >= 2, "{parent}");
    let out = dir.path().join("replan");
    let args = |left: &'static str, after: &'static str| {
        vec![
            "replan",
            "--project",
            p,
            "--mission",
            "1",
            "--after-stop",
            after,
            "--energy-left",
            left,
            "--iterations",
            "100",
            "--out",
            s(&out),
        ]
    };
    let text = ok(&args("40000", "1"));
    assert!(
        text.contains("continuation of mission #1 after stop 1"),
        "{text}"
    );
    let doc: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("mission.json")).expect("mission.json"),
    )
    .expect("json");
    assert_eq!(doc["status"], "continuation");
    assert_eq!(doc["continuation"]["parent_mission_id"], 1);
    let budget = doc["energy"]["budget_j"].as_f64().expect("budget");
    let reserve = doc["continuation"]["reserve_j"].as_f64().expect("reserve");
    assert_eq!(budget, 40_000.0 - reserve);
    assert!(doc["energy"]["total_j"].as_f64().expect("total") <= budget);
    let kept = doc["stops"].as_array().expect("stops").len();
    assert_eq!(kept, stops - 1, "ample energy keeps every remaining stop");
    let wpl = std::fs::read_to_string(out.join("mission.waypoints")).expect("wpl");
    let commands: Vec<&str> = wpl
        .lines()
        .skip(1)
        .map(|l| l.split('\t').nth(3).expect("command"))
        .collect();
    // Home, speed, the waypoint where the aircraft is, the kept stops, return to launch.
    assert_eq!(commands.len(), kept + 4, "{wpl}");
    assert!(!commands.contains(&"22"), "no take-off: {wpl}");
    assert_eq!(commands[1], "178");
    assert_eq!(commands.last(), Some(&"20"));
    assert!(out.join("mission.plan").exists() && !out.join("mission.kmz").exists());
    let json: serde_json::Value = serde_json::from_str(&ok(&{
        let mut a = args("40000", "1");
        a.push("--json");
        a
    }))
    .expect("json");
    assert_eq!(json, doc, "--json prints the continuation's document");
    assert!(fail(&args("3600", "1")).contains("land now"));
    assert!(fail(&args("40000", "9")).contains("beyond"));
    assert!(fail(&args("NaN", "1")).contains("energy left"));
}

#[test]
fn hubbard_brook_project_from_real_data() {
    let dir = tempfile::tempdir().expect("temp dir");
    let p = s(dir.path());
    let d = shared_data().join("hubbard_brook");
    let meta = d.join("sensor_metadata.csv");
    let init = ok(&[
        "init",
        "--dir",
        p,
        "--sensors",
        s(&meta),
        "--sensors-format",
        "hubbard-brook",
    ]);
    assert!(init.contains("sensors: 77 (77 new"), "{init}");
    // Most water-content probes are at 50 cm (two at 30 cm): that is the condition modality.
    let toml = std::fs::read_to_string(dir.path().join("gleaner.toml")).expect("settings");
    assert!(toml.contains("condition_modality = \"vw@50cm\""), "{toml}");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&d)
        .expect("dir")
        .map(|e| e.expect("entry").path())
        .filter(|f| {
            f.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with("z6-"))
        })
        .collect();
    files.sort();
    let mut argv = vec!["ingest", "--project", p];
    argv.extend(files.iter().map(|f| s(f)));
    let out = ok(&argv);
    assert!(
        out.contains("ingested 12 file(s)") && out.contains("0 rows skipped"),
        "{out}"
    );
    let doc: serde_json::Value =
        serde_json::from_str(&ok(&["score", "--project", p, "--json"])).expect("json");
    assert!(doc["cells"].as_array().expect("cells").len() >= 10);
    let m: serde_json::Value = serde_json::from_str(&ok(&[
        "plan",
        "--project",
        p,
        "--json",
        "--time-limit",
        "1",
        "--dry-run",
    ]))
    .expect("json");
    assert!(
        m["energy"]["total_j"].as_f64().expect("total")
            <= m["energy"]["budget_j"].as_f64().expect("budget")
    );
}

#[test]
fn record_refuses_a_second_record_and_foreign_readings_unless_asked() {
    let dir = small_project();
    let p = s(dir.path());
    ok(&["ingest", "--project", p, s(&data("readings.csv"))]);
    ok(&[
        "plan",
        "--project",
        p,
        "--at",
        "2014-01-25",
        "--solver",
        "exact",
    ]);
    let m: serde_json::Value = serde_json::from_str(&ok(&[
        "missions",
        "--project",
        p,
        "--mission",
        "1",
        "--json",
    ]))
    .expect("json");
    let visited: Vec<String> = m["stops"]
        .as_array()
        .expect("stops")
        .iter()
        .map(|s| s["cell"].as_str().expect("cell").to_string())
        .collect();
    assert!(!visited.is_empty());
    let cells: Vec<serde_json::Value> =
        serde_json::from_str(&ok(&["cells", "--project", p, "--json"])).expect("json");
    // A reading from a sensor of a cell the flight did not visit is refused, naming it.
    let outside = cells
        .iter()
        .find(|c| !visited.contains(&c["cell"].as_str().expect("cell").to_string()));
    if let Some(outside) = outside {
        let sensor = outside["sensors"][0].as_str().expect("sensor");
        let file = dir.path().join("foreign.csv");
        std::fs::write(
            &file,
            format!("sensor_id,timestamp,modality,value\n{sensor},2014-01-24,vw@30cm,0.3\n"),
        )
        .expect("write");
        let err = fail(&["record", "--project", p, "--mission", "1", s(&file)]);
        assert!(
            err.contains(sensor) && err.contains("did not visit"),
            "{err}"
        );
    }
    let before = ok(&["missions", "--project", p]);
    assert!(before.contains("planned"), "{before}");
    ok(&["record", "--project", p, "--mission", "1"]);
    let err = fail(&[
        "record",
        "--project",
        p,
        "--mission",
        "1",
        "--at",
        "2014-01-26",
    ]);
    assert!(
        err.contains("already recorded") && err.contains("--amend"),
        "{err}"
    );
    let amended = ok(&[
        "record",
        "--project",
        p,
        "--mission",
        "1",
        "--at",
        "2014-01-26",
        "--amend",
    ]);
    assert!(amended.contains("(amended)"), "{amended}");
    let m: serde_json::Value = serde_json::from_str(&ok(&[
        "missions",
        "--project",
        p,
        "--mission",
        "1",
        "--json",
    ]))
    .expect("json");
    assert_eq!(m["status"], "flown");
    assert_eq!(m["flown_at"], "2014-01-26T00:00:00Z");
}

#[test]
fn a_unit_other_than_the_stored_one_is_refused() {
    let dir = small_project();
    let p = s(dir.path());
    ok(&["ingest", "--project", p, s(&data("readings.csv"))]);
    let cells: Vec<serde_json::Value> =
        serde_json::from_str(&ok(&["cells", "--project", p, "--json"])).expect("json");
    let sensor = cells[0]["sensors"][0].as_str().expect("sensor");
    let file = dir.path().join("percent.csv");
    std::fs::write(
        &file,
        format!("sensor_id,timestamp,modality,value,unit\n{sensor},2014-02-01,vw@30cm,31,%\n"),
    )
    .expect("write");
    let err = fail(&["ingest", "--project", p, s(&file)]);
    assert!(err.contains("m3/m3") && err.contains('%'), "{err}");
    // Each cause is said once.
    assert_eq!(err.matches("m3/m3").count(), 1, "{err}");
}

#[test]
fn dry_runs_write_nothing() {
    let dir = small_project();
    let p = s(dir.path());
    ok(&["ingest", "--project", p, s(&data("readings.csv"))]);
    let db = dir.path().join("gleaner.db");
    let before = std::fs::read(&db).expect("db");
    ok(&[
        "plan",
        "--project",
        p,
        "--at",
        "2014-01-25",
        "--solver",
        "exact",
        "--dry-run",
    ]);
    ok(&["explore", "--project", p, "--dry-run"]);
    let missions = ok(&["missions", "--project", p, "--json"]);
    assert_eq!(missions.trim(), "[]");
    assert_eq!(std::fs::read(&db).expect("db"), before);
}

#[test]
fn exploration_sorties_export_like_any_mission() {
    let dir = small_project();
    let p = s(dir.path());
    ok(&["ingest", "--project", p, s(&data("readings.csv"))]);
    ok(&["explore", "--project", p]);
    let out = dir.path().join("sortie");
    ok(&["export", "--project", p, "--mission", "1", "--out", s(&out)]);
    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("mission.plan")).expect("plan"))
            .expect("json");
    let items = plan["mission"]["items"].as_array().expect("items");
    assert_eq!(
        items[1]["command"], 178,
        "the cruise speed is commanded first"
    );
    ok(&["map-exploration", "--project", p]);
    assert!(dir.path().join("missions/exploration.png").exists());
}

/// `simulate` arguments for a 12-sensor synthetic farm (seed 5, 21 days of history, 3 daily
/// missions) writing into `out`, then `extra`.
fn small_farm_simulation<'a>(out: &'a Path, extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec![
        "simulate",
        "--dataset",
        "synthetic",
        "--out",
        s(out),
        "--farm-seeds",
        "5",
        "--farm-sensors",
        "12",
        "--farm-days",
        "24",
        "--farm-history-days",
        "21",
    ];
    args.extend_from_slice(extra);
    args
}

/// Seeds whose campaigns coincide are counted once: `nearest` (equal scores, greedy insertion)
/// flies the same cells whatever its seed, so its two runs are one distinct run.
#[test]
fn report_counts_identical_replicates_once() {
    let dir = tempfile::tempdir().expect("temp dir");
    let sim = dir.path().join("sim");
    ok(&small_farm_simulation(
        &sim,
        &[
            "--strategies",
            "nearest",
            "--seeds",
            "1,2",
            "--planner-iterations",
            "50",
        ],
    ));
    let report = std::fs::read_to_string(sim.join("report.md")).expect("report.md");
    assert!(report.contains("| nearest | 2 (1 distinct) | "), "{report}");
}

/// The report names runs with identical results (gleaner's no-redundancy ablation is gleaner's
/// run: γ = δ = 0) and, with several budgets, where each strategy comes within 20% of
/// exhaustive collection.
#[test]
fn report_names_identical_runs_and_the_energy_within_20_percent() {
    let dir = tempfile::tempdir().expect("temp dir");
    let sim = dir.path().join("sim");
    ok(&small_farm_simulation(
        &sim,
        &[
            "--farm-events",
            "2",
            "--strategies",
            "gleaner,no-redundancy,nearest,exhaustive",
            "--budgets",
            "1,2",
            "--planner-iterations",
            "50",
        ],
    ));
    let report = std::fs::read_to_string(sim.join("report.md")).expect("report.md");
    assert!(
        report.contains("Identical results mission by mission: `no-redundancy` = `gleaner`."),
        "{report}"
    );
    assert!(!report.contains("`nearest` = "), "{report}");
    assert!(
        report.contains("| strategy | energy / exhaustive at 1.2× |"),
        "{report}"
    );
    for name in ["gleaner", "no-redundancy", "nearest"] {
        let row = report
            .lines()
            .find(|l| {
                l.starts_with(&format!("| {name} | "))
                    && (l.contains("linear between")
                        || l.contains("smallest budget")
                        || l.contains("beyond"))
            })
            .unwrap_or_else(|| panic!("no 1.2× row for {name}: {report}"));
        assert!(!row.contains("NaN"), "{row}");
    }
}

#[test]
fn simulate_report_and_reconstruct_on_a_small_synthetic_farm() {
    let dir = tempfile::tempdir().expect("temp dir");
    let sim = dir.path().join("sim");
    let out = ok(&small_farm_simulation(
        &sim,
        &[
            "--farm-events",
            "2",
            "--strategies",
            "gleaner,nearest,exhaustive,oracle",
            "--planner-iterations",
            "50",
        ],
    ));
    assert!(out.contains("1 campaign(s), 4 runs"), "{out}");
    let missions = std::fs::read_to_string(sim.join("missions.csv")).expect("missions.csv");
    // A header, then 4 strategies x 3 missions.
    assert_eq!(missions.lines().count(), 13, "{missions}");
    let report = std::fs::read_to_string(sim.join("report.md")).expect("report.md");
    assert!(report.contains("| gleaner | 1 |"), "{report}");
    assert!(
        report.contains("## Against exhaustive collection")
            && report.contains("| exhaustive | 1 | 1.00 |")
            && report.contains("| oracle | 1 |")
            && report.contains("oracle (when run) = a clairvoyant yardstick"),
        "{report}"
    );
    // Results files of the version before the pre-flight errors still make a report
    // (without that section).
    let old = tempfile::tempdir().expect("temp dir");
    for f in [
        "campaign.csv",
        "events.csv",
        "catches.csv",
        "visits.csv",
        "command.txt",
    ] {
        std::fs::copy(sim.join(f), old.path().join(f)).expect("copy");
    }
    let v1: Vec<String> = missions
        .lines()
        .map(|l| l.split(',').take(21).collect::<Vec<_>>().join(","))
        .collect();
    std::fs::write(old.path().join("missions.csv"), v1.join("\n") + "\n").expect("write");
    ok(&["report", s(old.path())]);
    let report_v1 = std::fs::read_to_string(old.path().join("report.md")).expect("report.md");
    assert!(report_v1.contains("| gleaner | 1 |"), "{report_v1}");
    assert!(!report_v1.contains("## Against exhaustive"), "{report_v1}");
    assert!(report.contains("Reproduce with"), "{report}");
    assert!(sim.join("figures/rmse_intervals.svg").exists());
    // The report is rebuilt from the CSV files alone.
    std::fs::remove_file(sim.join("report.md")).expect("remove");
    ok(&["report", s(&sim)]);
    assert!(sim.join("report.md").exists());
    // A damaged results file is refused with its line.
    std::fs::write(
        sim.join("missions.csv"),
        format!("{missions}caf,gleaner,1\n"),
    )
    .expect("write");
    let err = fail(&["report", s(&sim)]);
    assert!(err.contains("missions.csv:14"), "{err}");

    // reconstruct on a project of its own.
    let farm = dir.path().join("farm");
    ok(&[
        "synth",
        "--out",
        s(&farm),
        "--sensors",
        "12",
        "--days",
        "30",
    ]);
    let p = dir.path().join("p");
    ok(&[
        "init",
        "--dir",
        s(&p),
        "--sensors",
        s(&farm.join("sensors.csv")),
    ]);
    ok(&["ingest", "--project", s(&p), s(&farm.join("readings.csv"))]);
    let out = ok(&["reconstruct", "--project", s(&p), "--modality", "vw@30cm"]);
    assert!(
        out.contains("vw@30cm at")
            && out.contains("model of changes")
            && out.contains("kriging of changes")
            && out.contains("kriged"),
        "{out}"
    );
    // Three lines of models and estimator, the header, one line per sensor.
    assert_eq!(out.lines().count(), 4 + 12, "{out}");
    // The same estimates as a `gleaner.reconstruction` document: every sensor once, by id,
    // the table's values (4 decimals) and sd.
    let doc: serde_json::Value = serde_json::from_str(&ok(&[
        "reconstruct",
        "--project",
        s(&p),
        "--modality",
        "vw@30cm",
        "--json",
    ]))
    .expect("JSON");
    assert_eq!(doc["format"], "gleaner.reconstruction");
    assert_eq!(doc["modality"], "vw@30cm");
    assert_eq!(doc["estimator"], "changes");
    assert!(doc["model"]["changes_range_m"].as_f64().unwrap() > 0.0);
    let sensors = doc["sensors"].as_array().unwrap();
    assert_eq!(sensors.len(), 12);
    let ids: Vec<&str> = sensors
        .iter()
        .map(|x| x["sensor"].as_str().unwrap())
        .collect();
    let mut sorted = ids.clone();
    sorted.sort_unstable();
    sorted.dedup();
    assert_eq!(ids, sorted);
    for (row, line) in sensors.iter().zip(out.lines().skip(4)) {
        let cols: Vec<&str> = line.split_whitespace().collect();
        assert_eq!(cols[0], row["sensor"].as_str().unwrap());
        let table = |k: usize| cols[cols.len() - 5 + k].parse::<f64>().unwrap();
        let json = |k: &str| row[k].as_f64().unwrap();
        assert!((table(0) - json("carried")).abs() <= 5e-5, "{line}");
        assert!((table(1) - json("estimate")).abs() <= 5e-5, "{line}");
        assert!((table(2) - json("sd")).abs() <= 5e-5, "{line}");
        assert!((table(3) - json("lo90")).abs() <= 5e-5, "{line}");
        assert!((table(4) - json("hi90")).abs() <= 5e-5, "{line}");
        // The 90% interval holds the estimate.
        assert!(
            json("lo90") <= json("estimate") && json("estimate") <= json("hi90"),
            "{line}"
        );
        let ll = row["lon_lat"].as_array().unwrap();
        assert!(ll[0].as_f64().unwrap().abs() <= 180.0 && ll[1].as_f64().unwrap().abs() <= 90.0);
    }

    // Over a range: one CSV row per time and sensor, each mean inside its 90% interval, the
    // same values as the series document; a range that ends before it starts is refused.
    let when = |k: usize| doc["at"].as_str().unwrap()[..10].to_string() + &format!("T0{k}:00:00Z");
    let (from, to) = (when(0), when(6));
    let csv = dir.path().join("series.csv");
    let printed = ok(&[
        "reconstruct",
        "--project",
        s(&p),
        "--modality",
        "vw@30cm",
        "--from",
        &from,
        "--to",
        &to,
        "--every-hours",
        "3",
        "--out",
        s(&csv),
    ]);
    assert!(printed.contains("3 times × 12 sensors"), "{printed}");
    let text = std::fs::read_to_string(&csv).expect("series.csv");
    let rows: Vec<&str> = text.lines().collect();
    assert_eq!(rows[0], "time,sensor,mean,sd,lo90,hi90");
    assert_eq!(rows.len(), 1 + 3 * 12);
    for r in &rows[1..] {
        let c: Vec<f64> = r.split(',').skip(2).map(|x| x.parse().unwrap()).collect();
        assert!(c[2] <= c[0] && c[0] <= c[3] && c[1] >= 0.0, "{r}");
    }
    let series: serde_json::Value = serde_json::from_str(&ok(&[
        "reconstruct",
        "--project",
        s(&p),
        "--modality",
        "vw@30cm",
        "--from",
        &from,
        "--to",
        &to,
        "--every-hours",
        "3",
        "--json",
    ]))
    .expect("JSON");
    assert_eq!(series["format"], "gleaner.reconstruction-series");
    assert_eq!(series["times"].as_array().unwrap().len(), 3);
    let first: Vec<&str> = rows[1].split(',').collect();
    let m = series["mean"][0][0].as_f64().unwrap();
    assert!(
        (m - first[2].parse::<f64>().unwrap()).abs() <= 5e-7,
        "{m} vs {}",
        rows[1]
    );
    let err = fail(&[
        "reconstruct",
        "--project",
        s(&p),
        "--from",
        &to,
        "--to",
        &from,
    ]);
    assert!(err.contains("ends before it starts"), "{err}");

    // The kriging of levels over the same range: its own estimator in the document.
    let levels: serde_json::Value = serde_json::from_str(&ok(&[
        "reconstruct",
        "--project",
        s(&p),
        "--from",
        &from,
        "--to",
        &to,
        "--every-hours",
        "3",
        "--levels",
        "--json",
    ]))
    .expect("JSON");
    assert_eq!(levels["estimator"], "levels");
    assert!(levels["model"].is_null());
    assert_eq!(series["estimator"], "changes");

    // The map of the estimate and its uncertainty: SVG and PNG by the extension.
    let svg_path = dir.path().join("field.svg");
    let printed = ok(&[
        "reconstruct",
        "--project",
        s(&p),
        "--at",
        &to,
        "--map",
        s(&svg_path),
    ]);
    assert!(
        printed.contains("vw@30cm") && printed.contains("sensors read"),
        "{printed}"
    );
    let svg = std::fs::read_to_string(&svg_path).expect("field.svg");
    assert!(svg.starts_with("<svg") && svg.contains(r#"width="178mm""#));
    for id in [
        "panel-value",
        "panel-sd",
        "value-outline",
        "north-arrow",
        "scale-bar",
    ] {
        assert!(svg.contains(&format!(r#"id="{id}""#)), "no #{id}");
    }
    let cells = svg.matches(r#"id="value-cell-"#).count();
    assert!(cells > 0 && cells == svg.matches(r#"id="sd-cell-"#).count());
    // Every sensor is marked on both panels, read or estimated.
    let marked = svg.matches(r#"class="sensor-read""#).count()
        + svg.matches(r#"class="sensor-estimated""#).count();
    assert_eq!(marked, 2 * 12);
    let png_path = dir.path().join("field.PNG");
    ok(&[
        "reconstruct",
        "--project",
        s(&p),
        "--at",
        &to,
        "--dynamic",
        "--map",
        s(&png_path),
    ]);
    let png = std::fs::read(&png_path).expect("field.PNG");
    assert_eq!(&png[1..4], b"PNG");
    // 178 mm at 300 dpi.
    assert_eq!(u32::from_be_bytes(png[16..20].try_into().unwrap()), 2102);
    let err = fail(&[
        "reconstruct",
        "--project",
        s(&p),
        "--map",
        s(&dir.path().join("field.pdf")),
    ]);
    assert!(err.contains(".svg or .png"), "{err}");
}

#[test]
fn simulate_refuses_up_front_a_budget_exhaustive_collection_cannot_fly() {
    let dir = tempfile::tempdir().expect("temp dir");
    let sim = dir.path().join("sim");
    let err = fail(&small_farm_simulation(
        &sim,
        &["--strategies", "gleaner,exhaustive", "--budgets", "1,0.001"],
    ));
    assert!(
        err.contains("budget 0.001") && err.contains("exhaustive collection cannot be flown"),
        "{err}"
    );
    assert!(!sim.join("missions.csv").exists());
}

/// `simulate --project` replays a project's own record: on a project made from a synthetic
/// farm's files it flies exactly the missions the `synthetic` dataset flies from the same
/// files (same history, schedule and settings; the project's record ends one period later, so
/// it has one mission more), and it leaves the project's database as it was.
#[test]
fn simulate_replays_a_projects_own_record() {
    let dir = tempfile::tempdir().expect("temp dir");
    let farm = dir.path().join("farm");
    ok(&[
        "synth",
        "--out",
        s(&farm),
        "--seed",
        "5",
        "--sensors",
        "12",
        "--days",
        "36",
    ]);
    let project = dir.path().join("p");
    ok(&[
        "init",
        "--dir",
        s(&project),
        "--sensors",
        s(&farm.join("sensors.csv")),
        "--name",
        "north-field",
    ]);
    ok(&[
        "ingest",
        "--project",
        s(&project),
        s(&farm.join("readings.csv")),
    ]);
    let db_before = std::fs::read(project.join("gleaner.db")).expect("database");
    let common = [
        "--strategies",
        "gleaner,round-robin",
        "--planner-iterations",
        "50",
    ];
    let replay = dir.path().join("replay");
    let mut args = vec![
        "simulate",
        "--project",
        s(&project),
        "--out",
        s(&replay),
        "--start",
        "2014-01-31",
    ];
    args.extend_from_slice(&common);
    let out = ok(&args);
    assert!(out.contains("1 campaign(s), 2 runs"), "{out}");
    let dataset = dir.path().join("dataset");
    let mut args = vec![
        "simulate",
        "--dataset",
        "synthetic",
        "--out",
        s(&dataset),
        "--farm-seeds",
        "5",
        "--farm-sensors",
        "12",
        "--farm-days",
        "36",
        "--farm-history-days",
        "30",
    ];
    args.extend_from_slice(&common);
    ok(&args);
    // Every column but the label and the events caught (the dataset has ground-truth events,
    // the project the real-data rule's).
    let rows = |p: &Path| -> Vec<Vec<String>> {
        let text = std::fs::read_to_string(p.join("missions.csv")).expect("missions.csv");
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().expect("header").split(',').collect();
        let skip = |k: usize| header[k] == "label" || header[k] == "events_caught";
        lines
            .map(|l| {
                l.split(',')
                    .enumerate()
                    .filter(|(k, _)| !skip(*k))
                    .map(|(_, v)| v.to_string())
                    .collect()
            })
            .collect()
    };
    let (from_project, from_files) = (rows(&replay), rows(&dataset));
    assert_eq!(from_files.len(), 2 * 6, "six missions per strategy");
    assert_eq!(from_project.len(), 2 * 7, "and one more from the project");
    for strategy in ["gleaner", "round-robin"] {
        let of = |r: &[Vec<String>]| -> Vec<Vec<String>> {
            r.iter()
                .filter(|x| x[0] == strategy)
                .take(6)
                .cloned()
                .collect()
        };
        assert_eq!(of(&from_project), of(&from_files), "{strategy}");
    }
    let report = std::fs::read_to_string(replay.join("report.md")).expect("report.md");
    assert!(
        report.starts_with("# Campaign report: north-field"),
        "{report}"
    );
    assert!(report.contains("simulate --project"), "{report}");
    assert_eq!(
        std::fs::read(project.join("gleaner.db")).expect("database"),
        db_before,
        "the replayed project is only read"
    );
    // Nothing to replay: a clear error, not a panic.
    let empty = dir.path().join("empty");
    ok(&[
        "init",
        "--dir",
        s(&empty),
        "--sensors",
        s(&farm.join("sensors.csv")),
    ]);
    let err = fail(&[
        "simulate",
        "--project",
        s(&empty),
        "--out",
        s(&dir.path().join("nothing")),
    ]);
    assert!(err.contains("no readings to replay"), "{err}");
    // A dataset and a project at once: refused by the parser.
    let err = fail(&[
        "simulate",
        "--project",
        s(&project),
        "--dataset",
        "caf-daily",
        "--out",
        s(&dir.path().join("both")),
    ]);
    assert!(err.contains("cannot be used with"), "{err}");
}

/// `init --method gleaner` (the default) writes gleaner's method into `[utility]`: the
/// scoring then reports its weights (β = 4, γ = δ = 0) and bounded anomaly; `--method paper`
/// scores by the paper's S.
#[test]
fn init_method_gleaner_scores_by_gleaners_method() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scoring = |method: &str| -> serde_json::Value {
        let p = dir.path().join(method);
        ok(&[
            "init",
            "--dir",
            s(&p),
            "--sensors",
            s(&data("sensors.csv")),
            "--base",
            "46.7800,-117.0805",
            "--method",
            method,
        ]);
        let toml = std::fs::read_to_string(p.join("gleaner.toml")).expect("gleaner.toml");
        assert_eq!(
            toml.contains("freshness_form = \"drift\""),
            method == "gleaner",
            "{toml}"
        );
        ok(&["ingest", "--project", s(&p), s(&data("readings.csv"))]);
        let json = ok(&["score", "--project", s(&p), "--at", "2014-01-25", "--json"]);
        serde_json::from_str(&json).expect("json")
    };
    let (paper, gleaner) = (scoring("paper"), scoring("gleaner"));
    assert_eq!(paper["weights"], serde_json::json!([1.0, 1.0, 1.0, 1.0]));
    assert_eq!(paper["anomaly_form"], "raw");
    assert_eq!(gleaner["weights"], serde_json::json!([1.0, 4.0, 0.0, 0.0]));
    // The form line names the bounded anomaly and the drift freshness.
    assert_eq!(gleaner["anomaly_form"], "bounded(kappa=3); F drift");
    for c in gleaner["cells"].as_array().expect("cells") {
        let f = c["f"].as_f64().expect("f");
        assert!((0.0..=1.0).contains(&f), "F = {f}");
    }
    let err = fail(&[
        "init",
        "--dir",
        s(&dir.path().join("other")),
        "--sensors",
        s(&data("sensors.csv")),
        "--method",
        "best",
    ]);
    assert!(err.contains("invalid value 'best'"), "{err}");
}

/// Runs `gleaner args` with its standard output a pipe whose reader is already closed, as
/// `gleaner cells --json | head -c0` gives.
fn with_closed_stdout(args: &[&str]) -> Output {
    let (reader, writer) = std::io::pipe().expect("pipe");
    drop(reader);
    Command::new(env!("CARGO_BIN_EXE_gleaner"))
        .args(args)
        .stdout(writer)
        .stderr(std::process::Stdio::piped())
        .output()
        .expect("run gleaner")
}

#[test]
fn a_closed_output_pipe_ends_the_output_quietly() {
    let dir = small_project();
    let p = s(dir.path());
    ok(&["ingest", "--project", p, s(&data("readings.csv"))]);
    for args in [
        vec!["cells", "--project", p, "--json"],
        vec!["cells", "--project", p],
        vec!["missions", "--project", p, "--json"],
        vec!["score", "--project", p, "--json"],
    ] {
        let out = with_closed_stdout(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{args:?}: {err}");
        assert!(err.is_empty(), "{args:?}: {err}");
    }
}

#[test]
fn export_help_names_the_speed_command() {
    let help = ok(&["export", "--help"]);
    assert!(help.contains("MAV_CMD_DO_CHANGE_SPEED"), "{help}");
}

#[test]
fn synth_takes_an_empty_depth_list_as_none() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("farm");
    ok(&[
        "synth",
        "--out",
        s(&out),
        "--sensors",
        "4",
        "--days",
        "3",
        "--seed",
        "1",
        "--t-depths",
        "",
    ]);
    let readings = std::fs::read_to_string(out.join("readings.csv")).expect("readings");
    assert!(readings.contains(",vw@30cm,"), "no soil moisture");
    assert!(!readings.contains(",t@"), "temperature written");
    let err = fail(&["synth", "--out", s(&out), "--t-depths", "30,x"]);
    assert!(
        err.contains("depth \"x\": expected whole centimetres"),
        "{err}"
    );
}

#[test]
fn init_makes_cells_under_two_metres_and_checks_the_neighbour_radius() {
    let dir = tempfile::tempdir().expect("temp dir");
    let sensors = data("sensors.csv");
    let small = dir.path().join("small");
    let out = ok(&[
        "init",
        "--dir",
        s(&small),
        "--sensors",
        s(&sensors),
        "--cell-size",
        "1",
    ]);
    assert!(out.contains("non-empty cells of 1 m"), "{out}");
    let toml = std::fs::read_to_string(small.join("gleaner.toml")).expect("toml");
    assert!(toml.contains("neighbour_radius_m = 100.0"), "{toml}");
    let explicit = dir.path().join("explicit");
    ok(&[
        "init",
        "--dir",
        s(&explicit),
        "--sensors",
        s(&sensors),
        "--cell-size",
        "1.5",
        "--neighbour-radius",
        "20",
    ]);
    let toml = std::fs::read_to_string(explicit.join("gleaner.toml")).expect("toml");
    assert!(toml.contains("neighbour_radius_m = 20.0"), "{toml}");
    let refused = dir.path().join("refused");
    let err = fail(&[
        "init",
        "--dir",
        s(&refused),
        "--sensors",
        s(&sensors),
        "--cell-size",
        "0.5",
        "--neighbour-radius",
        "60",
    ]);
    assert!(
        err.contains(
            "field.neighbour_radius_m = 60: allowed 0..=100 cell sides (50 m with cell_size_m = 0.5)"
        ),
        "{err}"
    );
    assert!(!refused.exists());
}

#[test]
fn a_changed_cell_size_is_refused_with_how_to_regrid() {
    let dir = small_project();
    let p = s(dir.path());
    ok(&["ingest", "--project", p, s(&data("readings.csv"))]);
    let toml_path = dir.path().join("gleaner.toml");
    let toml = std::fs::read_to_string(&toml_path).expect("toml");
    assert!(toml.contains("cell_size_m = 40.0"), "{toml}");
    std::fs::write(
        &toml_path,
        toml.replace("cell_size_m = 40.0", "cell_size_m = 20.0"),
    )
    .expect("write");
    let before = gleaner_store::SqliteStore::open(&dir.path().join("gleaner.db"))
        .and_then(|st| st.dump())
        .expect("dump");
    for args in [
        vec!["score", "--project", p],
        vec!["plan", "--project", p],
        vec!["explore", "--project", p],
    ] {
        let err = fail(&args);
        assert!(
            err.contains("the grid of [field] (cell_size_m = 20 m")
                && err.contains("Re-grid with `gleaner init --dir")
                && err.contains("--cell-size 20 --force`"),
            "{args:?}: {err}"
        );
        let after = gleaner_store::SqliteStore::open(&dir.path().join("gleaner.db"))
            .and_then(|st| st.dump())
            .expect("dump");
        assert_eq!(after, before, "{args:?} wrote");
    }
    // Following the hint re-grids the project, and scoring works again.
    let sensors = data("sensors.csv");
    ok(&[
        "init",
        "--dir",
        p,
        "--sensors",
        s(&sensors),
        "--base",
        "46.7800,-117.0805",
        "--cell-size",
        "20",
        "--force",
    ]);
    ok(&["score", "--project", p]);
}

#[test]
fn a_reader_does_not_wait_for_another_process_writing() {
    let dir = small_project();
    let p = s(dir.path());
    ok(&["ingest", "--project", p, s(&data("readings.csv"))]);
    let mut store = gleaner_store::SqliteStore::open(&dir.path().join("gleaner.db")).expect("open");
    // This process holds the write lock while the commands run: they only read, and opening
    // the project must not wait for the lock (it did, for the 60 s busy timeout, and then
    // failed with SQLite's raw "database is locked"). A writer's message past the timeout is
    // tested in gleaner-store.
    use gleaner_store::{Store, StoreRead};
    store
        .write(|tx| {
            tx.reading_count()?;
            for args in [
                vec!["cells", "--project", p],
                vec!["missions", "--project", p],
                vec!["reconstruct", "--project", p],
            ] {
                let out = gleaner(&args);
                assert!(
                    out.status.success(),
                    "{args:?}: {}",
                    String::from_utf8_lossy(&out.stderr)
                );
            }
            Ok::<_, gleaner_store::StoreError>(())
        })
        .expect("write");
}

#[test]
fn plan_takes_an_energy_preset_as_the_api_does() {
    let dir = small_project();
    let p = s(dir.path());
    ok(&["ingest", "--project", p, s(&data("readings.csv"))]);
    let budget = |extra: &[&str]| {
        let mut args = vec![
            "plan",
            "--project",
            p,
            "--dry-run",
            "--json",
            "--iterations",
            "50",
        ];
        args.extend_from_slice(extra);
        let doc: serde_json::Value = serde_json::from_str(&ok(&args)).expect("json");
        doc["energy"]["budget_j"].as_f64().expect("budget")
    };
    assert_eq!(budget(&[]), 66_500.0);
    assert_eq!(budget(&["--energy-preset", "paper"]), 66_500.0);
    assert!(budget(&["--energy-preset", "large-pack"]) > 200_000.0);
    let err = fail(&["plan", "--project", p, "--energy-preset", "huge"]);
    assert!(
        err.contains("energy preset \"huge\": expected paper or large-pack"),
        "{err}"
    );
}

/// The cell table's readings: every stored reading of the cell's sensors, right after the
/// ingest and right after a re-grid, before any scoring.
#[test]
fn cells_show_the_true_reading_count_before_any_scoring() {
    let dir = small_project();
    let p = s(dir.path());
    ok(&["ingest", "--project", p, s(&data("readings.csv"))]);
    let counts = |table: &str| -> Vec<(String, u64)> {
        table
            .lines()
            .skip(1)
            .map(|l| {
                let f: Vec<&str> = l.split_whitespace().collect();
                (f[0].to_string(), f[4].parse().expect("readings"))
            })
            .collect()
    };
    let before = counts(&ok(&["cells", "--project", p]));
    // x0y0 holds two sensors: 2 sensors x 2 modalities x 20 days.
    assert_eq!(
        before,
        [
            ("x0y0".into(), 80),
            ("x2y0".into(), 40),
            ("x2y1".into(), 40)
        ]
    );
    ok(&[
        "init",
        "--dir",
        p,
        "--sensors",
        s(&data("sensors.csv")),
        "--base",
        "46.7800,-117.0805",
        "--cell-size",
        "20",
        "--force",
    ]);
    let regridded = counts(&ok(&["cells", "--project", p]));
    assert_eq!(
        regridded.iter().map(|c| c.1).sum::<u64>(),
        160,
        "{regridded:?}"
    );
    assert!(regridded.iter().all(|c| c.1 > 0), "{regridded:?}");
    let json = ok(&["cells", "--project", p, "--json"]);
    assert!(
        json.contains("\"count\": 20"),
        "summaries missing after the re-grid: {json}"
    );
}

/// `plan --objective information`: the route's worth is the share of the field's posterior
/// variance its readings remove (in (0, 1], at most the sum of what each cell removes alone),
/// within the battery, and the mission says how it was routed; unknown objectives are refused.
#[test]
fn plan_by_information_reports_the_share_of_variance_removed() {
    let dir = small_project();
    let p = s(dir.path());
    ok(&["ingest", "--project", p, s(&data("readings.csv"))]);
    let args = [
        "plan",
        "--project",
        p,
        "--dry-run",
        "--json",
        "--iterations",
        "50",
        "--objective",
        "information",
    ];
    let doc: serde_json::Value = serde_json::from_str(&ok(&args)).expect("json");
    let value = doc["total_score"].as_f64().expect("total_score");
    assert!(value > 0.0 && value <= 1.0 + 1e-12, "{value}");
    assert!(
        doc["energy"]["total_j"].as_f64().expect("energy")
            <= doc["energy"]["budget_j"].as_f64().expect("budget")
    );
    assert!(!doc["stops"].as_array().expect("stops").is_empty());
    assert!(doc.to_string().contains("routed by information"), "{doc}");
    // The hybrid objective: a blend of two shares, so also in (0, 1]; at information weight
    // 1 it is the information objective's worth, at 0 the route's share of the total S.
    let mut hybrid = args.to_vec();
    *hybrid.last_mut().expect("objective") = "hybrid";
    let doc: serde_json::Value = serde_json::from_str(&ok(&hybrid)).expect("json");
    let blended = doc["total_score"].as_f64().expect("total_score");
    assert!(blended > 0.0 && blended <= 1.0 + 1e-12, "{blended}");
    assert!(
        doc.to_string().contains("routed by score and information"),
        "{doc}"
    );
    let toml = dir.path().join("gleaner.toml");
    let text = std::fs::read_to_string(&toml).expect("settings");
    std::fs::write(
        &toml,
        text.replace("[planner]\n", "[planner]\ninformation_weight = 1.0\n"),
    )
    .expect("settings");
    let doc: serde_json::Value = serde_json::from_str(&ok(&hybrid)).expect("json");
    let all_information = doc["total_score"].as_f64().expect("total_score");
    assert!(
        (all_information - value).abs() < 1e-9,
        "{all_information} vs {value}"
    );
    let err = fail(&["plan", "--project", p, "--objective", "entropy"]);
    assert!(
        err.contains("expected score, information or hybrid"),
        "{err}"
    );
}

/// `synth --layout`: a synthetic farm laid on CAF's own 42 stations keeps their ids and
/// positions (within 1e-5°, about a metre: the file's UTM coordinates are what is read).
#[test]
fn synth_lays_a_farm_on_a_real_networks_stations() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("farm");
    let layout = shared_data().join("caf/sensors/CAF_sensor_locations.csv");
    let said = ok(&[
        "synth",
        "--out",
        s(&out),
        "--layout",
        s(&layout),
        "--utm-zone",
        "11N",
        "--days",
        "10",
        "--seed",
        "100",
    ]);
    assert!(said.contains("wrote 42 sensors"), "{said}");
    let written = std::fs::read_to_string(out.join("sensors.csv")).expect("sensors");
    let caf = std::fs::read_to_string(&layout).expect("caf sensors");
    for line in caf.lines().skip(1) {
        let c: Vec<&str> = line.split(',').collect();
        let row = written
            .lines()
            .find(|l| l.starts_with(&format!("{},", c[0])))
            .unwrap_or_else(|| panic!("{} missing from {written}", c[0]));
        let w: Vec<&str> = row.split(',').collect();
        let (lat, lon): (f64, f64) = (c[3].parse().unwrap(), c[4].parse().unwrap());
        let (wlat, wlon): (f64, f64) = (w[1].parse().unwrap(), w[2].parse().unwrap());
        assert!(
            (lat - wlat).abs() < 1e-5 && (lon - wlon).abs() < 1e-5,
            "{row} vs {line}"
        );
    }
    let err = fail(&[
        "synth",
        "--out",
        s(&out),
        "--layout",
        s(&out.join("nothing.csv")),
    ]);
    assert!(err.contains("nothing.csv"), "{err}");
}

/// CAF with a geofence (the cells' box grown by 60 m) and 20 seeded no-fly polygons: `init`
/// takes the files, `explore` and `plan` fly around the zones and report the cells inside
/// them as unreachable, `export` writes the detours (waypoints without a hold) and the
/// `.plan`'s geoFence; a bad zone file is refused naming the file, feature and field.
#[test]
fn caf_with_no_fly_zones_plans_around_them() {
    let dir = tempfile::tempdir().expect("temp dir");
    let project = dir.path().join("caf");
    let p = s(&project);
    let locations = shared_data().join("caf/sensors/CAF_sensor_locations.csv");
    let caf = s(&locations);
    ok(&["init", "--dir", p, "--sensors", caf, "--utm-zone", "11N"]);
    // The zone files, in the project's local frame.
    let (_, field) = gleaner_app::Project::open(&project)
        .expect("open")
        .field()
        .expect("field");
    let centres: Vec<gleaner_field::LocalPoint> = field.cells().iter().map(|c| c.centre).collect();
    let origin = gleaner_field::LocalPoint::new(0.0, 0.0);
    let no_fly = dir.path().join("no_fly.geojson");
    std::fs::write(
        &no_fly,
        gleaner_app::airspace::seeded_no_fly_geojson(field.frame(), 20, 20, &centres, origin),
    )
    .expect("zones");
    let (mut lo, mut hi) = ((0.0f64, 0.0f64), (0.0f64, 0.0f64));
    for c in &centres {
        lo = (lo.0.min(c.e), lo.1.min(c.n));
        hi = (hi.0.max(c.e), hi.1.max(c.n));
    }
    let fence = dir.path().join("fence.geojson");
    std::fs::write(
        &fence,
        gleaner_app::airspace::polygons_geojson(
            field.frame(),
            &[gleaner_app::airspace::rectangle(
                lo.0 - 60.0,
                lo.1 - 60.0,
                hi.0 + 60.0,
                hi.1 + 60.0,
            )],
        ),
    )
    .expect("fence");
    // A bad file is refused with its feature and field.
    let bad = dir.path().join("bad.geojson");
    std::fs::write(
        &bad,
        r#"{"type":"FeatureCollection","features":[{"type":"Feature","properties":{},"geometry":{"type":"Polygon","coordinates":[[[-117.08,46.78],[-117.07,46.78],[-117.08,46.78]]]}}]}"#,
    )
    .expect("bad");
    let err = fail(&[
        "init",
        "--dir",
        p,
        "--sensors",
        caf,
        "--utm-zone",
        "11N",
        "--force",
        "--no-fly",
        s(&bad),
    ]);
    assert!(
        err.contains("bad.geojson: feature 0: `geometry`: coordinates[0]: a ring of 3 positions"),
        "{err}"
    );
    ok(&[
        "init",
        "--dir",
        p,
        "--sensors",
        caf,
        "--utm-zone",
        "11N",
        "--force",
        "--geofence",
        s(&fence),
        "--no-fly",
        s(&no_fly),
        "--no-fly-buffer",
        "5",
    ]);
    let toml = std::fs::read_to_string(project.join("gleaner.toml")).expect("toml");
    assert!(
        toml.contains("no_fly = ")
            && toml.contains("geofence = ")
            && toml.contains("no_fly_buffer_m = 5"),
        "{toml}"
    );
    // Exploration: every reachable cell once, the others reported.
    let json = ok(&["explore", "--project", p, "--at", "2014-03-01", "--json"]);
    let e: serde_json::Value = serde_json::from_str(&json).expect("json");
    let visited: usize = e["sorties"]
        .as_array()
        .expect("sorties")
        .iter()
        .map(|m| m["stops"].as_array().expect("stops").len())
        .sum();
    let unreachable = e["unreachable"].as_array().map_or(0, Vec::len);
    assert_eq!(
        visited + unreachable,
        e["cells"].as_u64().expect("cells") as usize
    );
    let turns: usize = e["sorties"]
        .as_array()
        .expect("sorties")
        .iter()
        .flat_map(|m| m["stops"].as_array().expect("stops").iter())
        .map(|s| s["via_lon_lat"].as_array().map_or(0, Vec::len))
        .sum();
    assert!(turns > 0, "no leg went around a zone");
    // A plan from given scores (every cell 1): the unreachable cells are never planned.
    let scores = dir.path().join("scores.csv");
    let mut text = String::from("cell_id,score\n");
    for c in field.cells() {
        text.push_str(&format!("{},1\n", c.index));
    }
    std::fs::write(&scores, text).expect("scores");
    let json = ok(&[
        "plan",
        "--project",
        p,
        "--at",
        "2014-03-01",
        "--scores",
        s(&scores),
        "--json",
    ]);
    let m: serde_json::Value = serde_json::from_str(&json).expect("json");
    let blocked: Vec<&str> = m["unreachable"]
        .as_array()
        .map(|u| {
            u.iter()
                .map(|c| c["cell"].as_str().expect("cell"))
                .collect()
        })
        .unwrap_or_default();
    for stop in m["stops"].as_array().expect("stops") {
        assert!(!blocked.contains(&stop["cell"].as_str().expect("cell")));
    }
    let id = m["mission_id"].as_i64().expect("id").to_string();
    let text = ok(&[
        "plan",
        "--project",
        p,
        "--at",
        "2014-03-01",
        "--scores",
        s(&scores),
        "--dry-run",
    ]);
    if !blocked.is_empty() {
        assert!(text.contains("unreachable cells"), "{text}");
    }
    let out = dir.path().join("export");
    ok(&["export", "--project", p, "--mission", &id, "--out", s(&out)]);
    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("mission.plan")).expect("plan"))
            .expect("json");
    let polygons = plan["geoFence"]["polygons"].as_array().expect("polygons");
    assert_eq!(polygons.len(), 21);
    assert_eq!(
        polygons.iter().filter(|p| p["inclusion"] == true).count(),
        1,
        "one inclusion fence"
    );
    let holds: Vec<f64> = plan["mission"]["items"]
        .as_array()
        .expect("items")
        .iter()
        .filter(|it| it["command"] == 16)
        .map(|it| it["params"][0].as_f64().expect("hold"))
        .collect();
    let stops = m["stops"].as_array().expect("stops").len();
    let vias: usize = m["stops"]
        .as_array()
        .expect("stops")
        .iter()
        .map(|s| s["via_lon_lat"].as_array().map_or(0, Vec::len))
        .sum::<usize>()
        + m["return_via_lon_lat"].as_array().map_or(0, Vec::len);
    assert_eq!(holds.len(), stops + vias);
    assert_eq!(holds.iter().filter(|&&h| h == 0.0).count(), vias);
}

/// `simulate --wind` flies the missions in drawn winds: flights.csv and the report's Flights
/// section, none over budget; a bad winds file is refused with its file, line and field.
#[test]
fn simulate_flies_in_wind_and_reads_observed_winds() {
    let dir = tempfile::tempdir().expect("temp dir");
    let sim = dir.path().join("sim");
    ok(&small_farm_simulation(
        &sim,
        &[
            "--farm-events",
            "2",
            "--strategies",
            "gleaner,nearest",
            "--planner-iterations",
            "50",
            "--wind",
            "weibull:5",
            "--gust",
            "2",
            "--leg-gust",
            "1",
            "--margin-quantile",
            "0.9",
            "--weak-battery",
            "0.2",
        ],
    ));
    let flights = std::fs::read_to_string(sim.join("flights.csv")).expect("flights.csv");
    // A header, then 2 strategies x 3 missions, none over budget.
    assert_eq!(flights.lines().count(), 7, "{flights}");
    assert!(
        flights
            .lines()
            .skip(1)
            .all(|l| l.split(',').nth(14) == Some("0")),
        "{flights}"
    );
    let report = std::fs::read_to_string(sim.join("report.md")).expect("report.md");
    assert!(
        report.contains("## Flights") && report.contains("| nearest | 3 |"),
        "{report}"
    );
    // The report is rebuilt from the files, flights included.
    std::fs::remove_file(sim.join("report.md")).expect("remove");
    ok(&["report", s(&sim)]);
    let again = std::fs::read_to_string(sim.join("report.md")).expect("report.md");
    assert!(again.contains("## Flights"), "{again}");

    let winds = dir.path().join("winds.csv");
    std::fs::write(
        &winds,
        "date,speed_mps,from_deg\n2020-01-01,3,90\n2020-01-02,fast,90\n",
    )
    .expect("write");
    let err = fail(&small_farm_simulation(
        &dir.path().join("sim2"),
        &["--wind-csv", s(&winds)],
    ));
    assert!(err.contains("winds.csv:3: speed_mps \"fast\""), "{err}");
    let err = fail(&small_farm_simulation(
        &dir.path().join("sim3"),
        &["--wind", "gale"],
    ));
    assert!(err.contains("weibull:MEAN"), "{err}");
    let err = fail(&small_farm_simulation(
        &dir.path().join("sim4"),
        &["--wind", "weibull:4", "--margin-quantile", "0.2"],
    ));
    assert!(err.contains("--margin-quantile \"0.2\""), "{err}");
}

#[test]
fn missions_page_cancel_and_delete() {
    let dir = small_project();
    let p = s(dir.path());
    ok(&["ingest", "--project", p, s(&data("readings.csv"))]);
    for _ in 0..3 {
        ok(&[
            "plan",
            "--project",
            p,
            "--at",
            "2014-01-25",
            "--solver",
            "greedy",
        ]);
    }
    let page: serde_json::Value =
        serde_json::from_str(&ok(&["missions", "--project", p, "--limit", "2", "--json"]))
            .expect("json");
    let ids: Vec<i64> = page["missions"]
        .as_array()
        .expect("missions")
        .iter()
        .map(|m| m["mission_id"].as_i64().expect("id"))
        .collect();
    assert_eq!((ids, page["next"].as_i64()), (vec![3, 2], Some(2)));
    let text = ok(&["missions", "--project", p, "--before", "2"]);
    assert!(text.contains("no older missions"), "{text}");
    ok(&["cancel", "--project", p, "--mission", "1"]);
    let err = fail(&["cancel", "--project", p, "--mission", "1"]);
    assert!(err.contains("already cancelled"), "{err}");
    let err = fail(&["record", "--project", p, "--mission", "1"]);
    assert!(err.contains("was cancelled"), "{err}");
    ok(&["record", "--project", p, "--mission", "2"]);
    let err = fail(&["delete", "--project", p, "--mission", "2"]);
    assert!(err.contains("recorded as flown"), "{err}");
    ok(&["delete", "--project", p, "--mission", "1"]);
    let err = fail(&["delete", "--project", p, "--mission", "1"]);
    assert!(err.contains("no mission #1"), "{err}");
}

/// The peer protocol on Hubbard Brook (a registered hold-out): both depths run from the real
/// files, the windows and capacities as registered, the outcomes files written.
#[test]
fn evaluate_peer_on_hubbard_brook() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("hb");
    let data = shared_data();
    let summary = ok(&[
        "evaluate",
        "peer",
        "--on",
        "hubbard-brook",
        "--data",
        s(&data),
        "--out",
        s(&out),
    ]);
    assert!(
        summary.contains("water content shallow (10-20 cm)"),
        "{summary}"
    );
    assert!(
        summary.contains("12 sites, 5780 complete hours"),
        "{summary}"
    );
    assert!(
        summary.contains("10 sites, 5778 complete hours"),
        "{summary}"
    );
    assert_eq!(summary.matches("9 windows;").count(), 2, "{summary}");
    assert_eq!(summary.matches("- registration: ").count(), 2, "{summary}");
    for name in ["outcomes-shallow.csv", "outcomes-50cm.csv"] {
        let csv = std::fs::read_to_string(out.join(name)).unwrap();
        // 7 capacities × 2 planners × 3 estimators, and the header.
        assert_eq!(csv.lines().count(), 1 + 7 * 2 * 3, "{name}");
    }
    assert_eq!(
        std::fs::read_to_string(out.join("summary.md")).unwrap(),
        summary
    );
}

/// The second Hubbard Brook hold-out: the later hours' water content (the sites still
/// reporting) and soil temperature, four data sets from the real files, each with its
/// outcomes file and verdict.
#[test]
fn evaluate_peer_on_hubbard_brook_2() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("hb2");
    let data = shared_data();
    let summary = ok(&[
        "evaluate",
        "peer",
        "--on",
        "hubbard-brook-2",
        "--data",
        s(&data),
        "--out",
        s(&out),
    ]);
    assert!(
        summary.contains("water content shallow (10-20 cm), hours after 2024-05-27T04:00:00Z"),
        "{summary}"
    );
    assert!(
        summary.contains("8 sites, 8203 complete hours"),
        "{summary}"
    );
    assert!(
        summary.contains("6 sites, 8203 complete hours"),
        "{summary}"
    );
    assert!(summary.contains("soil temperature 50 cm"), "{summary}");
    assert_eq!(summary.matches("- registration: ").count(), 4, "{summary}");
    assert_eq!(summary.matches("°C²;").count(), 2, "{summary}");
    for stem in [
        "water-late-shallow",
        "water-late-50cm",
        "temperature-shallow",
        "temperature-50cm",
    ] {
        let csv = std::fs::read_to_string(out.join(format!("outcomes-{stem}.csv"))).unwrap();
        assert_eq!(csv.lines().count(), 1 + 7 * 2 * 3, "{stem}");
    }
}
