//! The flight files against their real consumers: pymavlink's `MAVWPLoader`, MAVSDK's QGC
//! and Mission Planner importers (through a mavsdk_server talking to a fake vehicle on
//! loopback), the `geojson` and `shapely` Python packages, and lxml with `fastkml`'s OGC KML
//! 2.2 schema for the DJI WPML archive. The checks live in
//! `consumers/*.py` and compute what the files must command from the mission document itself.
//!
//! The interpreter is `$GLEANER_PYTHON`, by default `<workspace>/.venv/bin/python`, created by
//! `scripts/python-env.sh`. Without it these tests fail: they are never skipped.

use std::path::{Path, PathBuf};
use std::process::Command;

use gleaner_wire::samples::{adaptive_mission, continuation, exploration_sortie, field};
use gleaner_wire::{
    FieldDoc, MissionDoc, WpmlOptions, flight_notes, geojson, qgc_plan, wpl, wpml_kmz,
};

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn python() -> PathBuf {
    let path = std::env::var_os("GLEANER_PYTHON")
        .map_or_else(|| workspace().join(".venv/bin/python"), PathBuf::from);
    assert!(
        path.exists(),
        "no Python interpreter at {} (GLEANER_PYTHON): run scripts/python-env.sh to create \
         <workspace>/.venv with pymavlink, mavsdk, geojson and shapely",
        path.display()
    );
    path
}

/// The files of one mission, written to a fresh temporary directory.
struct Files {
    _dir: tempfile::TempDir,
    mission: PathBuf,
    field: PathBuf,
    plan: PathBuf,
    waypoints: PathBuf,
    geojson: PathBuf,
    kmz: PathBuf,
}

fn write(field_doc: &FieldDoc, m: &MissionDoc) -> Files {
    let dir = tempfile::tempdir().expect("temporary directory");
    let p = |name: &str| dir.path().join(name);
    let files = Files {
        mission: p("mission.json"),
        field: p("field.json"),
        plan: p("mission.plan"),
        waypoints: p("mission.waypoints"),
        geojson: p("mission.geojson"),
        kmz: p("mission.kmz"),
        _dir: dir,
    };
    let put = |path: &Path, text: String| std::fs::write(path, text).expect("write");
    put(&files.mission, serde_json::to_string_pretty(m).unwrap());
    put(
        &files.field,
        serde_json::to_string_pretty(field_doc).unwrap(),
    );
    put(&files.plan, qgc_plan(m).unwrap());
    put(&files.waypoints, wpl(m).unwrap());
    put(&files.geojson, geojson(field_doc, m).unwrap());
    // A continuation has no DJI form (a wayline mission takes off by itself).
    if m.continuation.is_none() {
        std::fs::write(&files.kmz, wpml_kmz(m, WpmlOptions::default()).unwrap()).expect("write");
    }
    put(
        &files.field.with_file_name("mission.txt"),
        flight_notes(m).unwrap(),
    );
    files
}

/// Runs `consumers/<script>` with `args`; fails the test with its output unless it passes.
fn run(script: &str, args: &[&Path]) {
    let out = Command::new(python())
        .arg(workspace().join("consumers").join(script))
        .args(args)
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .output()
        .unwrap_or_else(|e| panic!("cannot run {script}: {e}"));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "{script} failed ({}):\n{stdout}\n{stderr}",
        out.status
    );
    assert!(
        stdout.contains("ok: "),
        "{script} printed no verdict:\n{stdout}\n{stderr}"
    );
    println!("{}", stdout.trim());
}

fn missions() -> [(&'static str, MissionDoc); 3] {
    [
        ("adaptive", adaptive_mission()),
        ("exploration", exploration_sortie()),
        ("continuation", continuation()),
    ]
}

#[test]
fn pymavlink_loads_the_wpl() {
    for (_, m) in missions() {
        let f = write(&field(), &m);
        run("check_wpl.py", &[&f.waypoints, &f.mission]);
    }
}

#[test]
fn mavsdk_imports_the_plan_and_the_wpl() {
    for (_, m) in missions() {
        let f = write(&field(), &m);
        run("check_plan.py", &[&f.plan, &f.mission, &f.waypoints]);
    }
}

#[test]
fn geojson_and_shapely_accept_the_map() {
    for (_, m) in missions() {
        let f = write(&field(), &m);
        run("check_geojson.py", &[&f.geojson, &f.mission, &f.field]);
    }
}

#[test]
fn lxml_and_the_kml_schema_accept_the_dji_archive() {
    for (_, m) in missions()
        .into_iter()
        .filter(|(_, m)| m.continuation.is_none())
    {
        let f = write(&field(), &m);
        run("check_kml.py", &[&f.kmz, &f.mission]);
    }
}

/// The shared data folder (`GLEANER_DATA_DIR`, default `<workspace>/../shared/data`).
fn shared_data() -> PathBuf {
    std::env::var_os("GLEANER_DATA_DIR")
        .map_or_else(|| workspace().join("../shared/data"), PathBuf::from)
}

/// The CAF network with a geofence (the cells' box grown by 60 m) and 20 seeded no-fly
/// polygons (seed 20, none within 60 m of the base): its exploration sorties at 2014-03-01,
/// each exported as the CLI exports it (field and mission documents).
fn zoned_caf_exports() -> (tempfile::TempDir, Vec<(FieldDoc, MissionDoc)>) {
    use gleaner_app as app;
    let tmp = tempfile::tempdir().expect("temporary directory");
    let dir = tmp.path().join("caf");
    let sensors = shared_data().join("caf/sensors/CAF_sensor_locations.csv");
    let init = |no_fly: Option<PathBuf>, geofence: Option<PathBuf>| {
        app::init(&app::InitRequest {
            dir: dir.clone(),
            sensors: sensors.clone(),
            utm_zone: Some("11N".into()),
            force: true,
            no_fly,
            geofence,
            ..Default::default()
        })
        .expect("init CAF")
        .0
    };
    let p = init(None, None);
    let (_, field) = p.field().expect("field");
    let centres: Vec<gleaner_field::LocalPoint> = field.cells().iter().map(|c| c.centre).collect();
    let origin = gleaner_field::LocalPoint::new(0.0, 0.0);
    let no_fly = tmp.path().join("no_fly.geojson");
    std::fs::write(
        &no_fly,
        app::airspace::seeded_no_fly_geojson(field.frame(), 20, 20, &centres, origin),
    )
    .expect("write zones");
    let (mut lo, mut hi) = ((0.0f64, 0.0f64), (0.0f64, 0.0f64));
    for c in &centres {
        lo = (lo.0.min(c.e), lo.1.min(c.n));
        hi = (hi.0.max(c.e), hi.1.max(c.n));
    }
    let fence = app::airspace::rectangle(lo.0 - 60.0, lo.1 - 60.0, hi.0 + 60.0, hi.1 + 60.0);
    let geofence = tmp.path().join("fence.geojson");
    std::fs::write(
        &geofence,
        app::airspace::polygons_geojson(field.frame(), &[fence]),
    )
    .expect("write fence");
    drop(p);
    let mut p = init(Some(no_fly), Some(geofence));
    let e = app::explore(
        &mut p,
        &app::ExploreRequest {
            at: Some(1_393_632_000),
            dry_run: false,
            wind: None,
        },
        0,
    )
    .expect("explore");
    let docs = e
        .sorties
        .iter()
        .map(|(id, _)| {
            let x = app::export(&p, id.expect("stored")).expect("export");
            (
                gleaner_wire::convert::field(&x.field),
                gleaner_wire::convert::export_mission(&x),
            )
        })
        .collect();
    (tmp, docs)
}

fn turn_points(m: &MissionDoc) -> usize {
    m.stops.iter().map(|s| s.via_lon_lat.len()).sum::<usize>() + m.return_via_lon_lat.len()
}

#[test]
fn shapely_finds_no_path_crossing_a_zone_and_mavsdk_still_imports_the_plan() {
    let (_tmp, docs) = zoned_caf_exports();
    assert!(docs.len() >= 3, "{} sorties", docs.len());
    let turns: usize = docs.iter().map(|(_, m)| turn_points(m)).sum();
    assert!(
        turns > 0,
        "no leg went around a zone: the test would prove nothing"
    );
    for (field_doc, m) in &docs {
        assert_eq!(m.zones.len(), 21);
        let f = write(field_doc, m);
        run(
            "check_zones.py",
            &[&f.mission, &f.plan, &f.waypoints, &f.geojson, &f.kmz],
        );
    }
    // The sortie with the most turn points through every consumer.
    let (field_doc, m) = docs
        .iter()
        .max_by_key(|(_, m)| turn_points(m))
        .expect("a sortie");
    let f = write(field_doc, m);
    run("check_plan.py", &[&f.plan, &f.mission, &f.waypoints]);
    run("check_wpl.py", &[&f.waypoints, &f.mission]);
    run("check_geojson.py", &[&f.geojson, &f.mission, &f.field]);
    run("check_kml.py", &[&f.kmz, &f.mission]);
}

/// The checker is not vacuous: a zone laid across a straight leg of the sample mission is
/// reported (the file, the zone and the segment).
#[test]
fn shapely_reports_a_path_across_a_zone() {
    let mut m = adaptive_mission();
    let [bx, by] = m.profile.base_lon_lat;
    let [sx, sy] = m.stops[0].centre_lon_lat;
    // A small square on the middle of the first leg.
    let (cx, cy) = (0.5 * (bx + sx), 0.5 * (by + sy));
    let d = 2e-5;
    m.zones = vec![gleaner_wire::ZoneDoc {
        kind: "no-fly".into(),
        name: Some("shed".into()),
        feature: 0,
        polygons_lon_lat: vec![vec![vec![
            [cx - d, cy - d],
            [cx + d, cy - d],
            [cx + d, cy + d],
            [cx - d, cy + d],
            [cx - d, cy - d],
        ]]],
        lines_lon_lat: Vec::new(),
        buffer_m: 5.0,
    }];
    let f = write(&field(), &m);
    let out = Command::new(python())
        .arg(workspace().join("consumers/check_zones.py"))
        .args([&f.mission, &f.plan])
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .output()
        .expect("run check_zones.py");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "a crossing passed: {stderr}");
    assert!(
        stderr.contains("mission.plan: the path crosses no-fly zone 0 (shed) on segment(s) [0]"),
        "{stderr}"
    );
}
