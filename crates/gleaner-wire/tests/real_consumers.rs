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
