//! The hostile-input corpus: malformed files for every reader, each refused with the exact
//! error expected, and the store unchanged afterwards.
//!
//! Layout (`tests/data/hostile/`): one folder per reader, named after the command that reads
//! it (see [`command`]); in it each case is an input file and, beside it, `<case>.expected`:
//! the exact standard error of the refused command, with the input's path written `$FILE`.
//! `base/` holds the Hubbard Brook metadata of the valid projects the cases run against (the
//! generic one is built from `tests/data/sensors.csv` and `readings.csv`). Every case runs on a fresh copy of
//! the base project; the test compares a dump of every table before and after (a refused
//! `init` must leave no project directory). With `GLEANER_BLESS=1` missing expected files are
//! written instead (review them before committing).

use std::path::{Path, PathBuf};
use std::process::Command;

use gleaner_store::SqliteStore;

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/hostile")
}

fn gleaner(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_gleaner"))
        .args(args)
        .output()
        .expect("run gleaner")
}

fn ok(args: &[&str]) {
    let out = gleaner(args);
    assert!(
        out.status.success(),
        "gleaner {args:?} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("mkdir");
    for entry in std::fs::read_dir(from).expect("read dir") {
        let entry = entry.expect("entry");
        if entry.file_type().expect("type").is_file() {
            std::fs::copy(entry.path(), to.join(entry.file_name())).expect("copy");
        }
    }
}

fn dump(project: &Path) -> String {
    SqliteStore::open(&project.join("gleaner.db"))
        .and_then(|s| s.dump())
        .expect("dump the store")
}

/// The valid projects the cases run against: `farm` (generic sensors and readings, one
/// planned mission) and `hb` (a Hubbard Brook-style logger network).
struct Bases {
    _dir: tempfile::TempDir,
    farm: PathBuf,
    hb: PathBuf,
}

fn bases() -> Bases {
    let dir = tempfile::tempdir().expect("temp dir");
    let base = corpus().join("base");
    let farm = dir.path().join("farm");
    ok(&[
        "init",
        "--dir",
        s(&farm),
        "--sensors",
        s(&base.join("../../sensors.csv")),
        "--base",
        "46.7800,-117.0805",
        // Planned at the latest reading, where nothing is stale: gleaner's method (the
        // default) finds nothing worth flying there; these tests need a mission.
        "--method",
        "paper",
    ]);
    ok(&[
        "ingest",
        "--project",
        s(&farm),
        s(&base.join("../../readings.csv")),
    ]);
    ok(&["plan", "--project", s(&farm), "--time-limit", "0.2"]);
    let hb = dir.path().join("hb");
    ok(&[
        "init",
        "--dir",
        s(&hb),
        "--sensors",
        s(&base.join("hb_metadata.csv")),
        "--sensors-format",
        "hubbard-brook",
    ]);
    Bases {
        _dir: dir,
        farm,
        hb,
    }
}

/// What a case runs: the arguments, given the project copy, the input file and a scratch
/// directory; `None` for a folder that is not a reader's.
fn command(reader: &str, case: &Path, project: &Path, scratch: &Path) -> Option<Vec<String>> {
    let p = s(project).to_string();
    let f = s(case).to_string();
    let new = s(&scratch.join("new")).to_string();
    let name = case.file_name()?.to_str()?;
    let args: Vec<&str> = match reader {
        "sensors" if name.starts_with("utm_") => {
            vec!["init", "--dir", &new, "--sensors", &f, "--utm-zone", "11N"]
        }
        "sensors" => vec!["init", "--dir", &new, "--sensors", &f],
        "hubbard_metadata" => vec![
            "init",
            "--dir",
            &new,
            "--sensors",
            &f,
            "--sensors-format",
            "hubbard-brook",
        ],
        "long" => vec!["ingest", "--project", &p, "--format", "long-csv", &f],
        "wide" => vec![
            "ingest",
            "--project",
            &p,
            "--format",
            "wide-csv",
            "--modality",
            "vw@30cm",
            &f,
        ],
        "caf" => vec!["ingest", "--project", &p, "--format", "caf-daily", &f],
        "hubbard" => vec![
            "ingest",
            "--project",
            &p,
            "--format",
            "hubbard-brook",
            "--metadata",
            "METADATA",
            &f,
        ],
        "scores" => vec![
            "plan",
            "--project",
            &p,
            "--time-limit",
            "0.1",
            "--scores",
            &f,
        ],
        "probabilities" => vec!["score", "--project", &p, "--probabilities", &f],
        "toml" => vec!["score", "--project", &p],
        // The collection time given (without it, a flight is dated by the newest reading it
        // brings back, so no reading could be after it).
        "flight" => vec![
            "record",
            "--project",
            &p,
            "--mission",
            "1",
            "--at",
            "2014-01-20",
            &f,
        ],
        _ => return None,
    };
    Some(args.into_iter().map(str::to_string).collect())
}

/// Runs one case; `Err` describes how it went wrong.
fn check(reader: &str, case: &Path, bases: &Bases) -> Result<(), String> {
    let scratch = tempfile::tempdir().expect("temp dir");
    let project = scratch.path().join("project");
    let base = if reader == "hubbard" {
        &bases.hb
    } else {
        &bases.farm
    };
    copy_dir(base, &project);
    // The input the command reads: the case itself, or a copy where the reader needs a name.
    let input = match reader {
        // A logger file's name is its logger id.
        "hubbard" => scratch.path().join("z9-1.csv"),
        "toml" => project.join("gleaner.toml"),
        _ => case.to_path_buf(),
    };
    if input != case {
        std::fs::copy(case, &input).expect("copy the case");
    }
    let Some(mut args) = command(reader, &input, &project, scratch.path()) else {
        return Ok(());
    };
    for a in &mut args {
        if a == "METADATA" {
            *a = s(&corpus().join("base/hb_metadata.csv")).to_string();
        }
    }
    let before = dump(&project);
    let argv: Vec<&str> = args.iter().map(String::as_str).collect();
    let out = gleaner(&argv);
    if out.status.success() {
        return Err(format!("accepted (expected a refusal): gleaner {args:?}"));
    }
    let stderr = String::from_utf8_lossy(&out.stderr).replace(s(&input), "$FILE");
    if stderr.contains("panicked") {
        return Err(format!("panicked:\n{stderr}"));
    }
    if dump(&project) != before {
        return Err("the store changed".into());
    }
    if scratch.path().join("new").exists() {
        return Err("a refused init left a project directory".into());
    }
    let expected_path = case.with_extension(format!(
        "{}.expected",
        case.extension().and_then(|e| e.to_str()).unwrap_or("")
    ));
    match std::fs::read_to_string(&expected_path) {
        Ok(expected) if expected == stderr => Ok(()),
        Ok(expected) => Err(format!("expected:\n{expected}got:\n{stderr}")),
        Err(_) if std::env::var_os("GLEANER_BLESS").is_some() => {
            std::fs::write(&expected_path, &stderr).expect("write expected");
            Ok(())
        }
        Err(_) => Err(format!(
            "no {} (GLEANER_BLESS=1 writes it); got:\n{stderr}",
            expected_path.display()
        )),
    }
}

#[test]
fn every_malformed_file_is_refused_with_its_error_and_the_store_unchanged() {
    let bases = bases();
    let mut readers: Vec<PathBuf> = std::fs::read_dir(corpus())
        .expect("corpus")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.is_dir() && !p.ends_with("base"))
        .collect();
    readers.sort();
    let mut failures = Vec::new();
    let mut cases = 0;
    for dir in &readers {
        let reader = dir.file_name().and_then(|n| n.to_str()).expect("name");
        let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
            .expect("reader dir")
            .map(|e| e.expect("entry").path())
            .filter(|p| p.extension().is_none_or(|e| e != "expected"))
            .collect();
        files.sort();
        assert!(!files.is_empty(), "{reader}: no cases");
        for case in files {
            cases += 1;
            if let Err(e) = check(reader, &case, &bases) {
                failures.push(format!("{reader}/{}: {e}", case.display()));
            }
        }
    }
    assert!(cases >= 100, "only {cases} cases");
    assert!(
        failures.is_empty(),
        "{} of {cases} cases failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// A fresh copy of the generic base project.
fn farm_copy(bases: &Bases) -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temp dir");
    copy_dir(&bases.farm, dir.path());
    dir
}

#[test]
fn a_reading_dated_after_the_clock_is_refused_naming_file_and_line() {
    let bases = bases();
    let project = farm_copy(&bases);
    let p = project.path();
    let file = p.join("future.csv");
    std::fs::write(
        &file,
        "sensor_id,timestamp,modality,value\nn1,2014-02-01,vw@30cm,0.3\nn1,2150-01-01,vw@30cm,0.3\n",
    )
    .expect("write");
    let before = dump(p);
    let out = gleaner(&["ingest", "--project", s(p), s(&file)]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(&format!(
            "{}:3: reading of n1 vw@30cm dated 2150-01-01T00:00:00Z, after the clock",
            file.display()
        )),
        "{err}"
    );
    assert_eq!(dump(p), before);
}

#[test]
fn value_limits_override_admits_what_the_default_range_refuses() {
    let bases = bases();
    let project = farm_copy(&bases);
    let p = project.path();
    let file = p.join("wet.csv");
    std::fs::write(
        &file,
        "sensor_id,timestamp,modality,value\nn1,2014-02-01,vw@30cm,1.5\n",
    )
    .expect("write");
    let refused = gleaner(&["ingest", "--project", s(p), s(&file)]);
    assert!(!refused.status.success());
    let toml = std::fs::read_to_string(p.join("gleaner.toml")).expect("toml");
    let toml = toml.replace(
        "[ingest]\n",
        "[ingest]\nvalue_limits = { vw = [0.0, 2.0] }\n",
    );
    std::fs::write(p.join("gleaner.toml"), toml).expect("write toml");
    ok(&["ingest", "--project", s(p), s(&file)]);
}

#[test]
fn pipes_fifos_and_devices_are_refused_without_blocking() {
    let bases = bases();
    let project = farm_copy(&bases);
    let p = project.path();
    let fifo = p.join("fifo.csv");
    let made = Command::new("mkfifo").arg(&fifo).status().expect("mkfifo");
    assert!(made.success());
    // Nobody ever writes to the FIFO: opening it would block forever.
    let scratch = tempfile::tempdir().expect("temp dir");
    let new = scratch.path().join("new");
    for args in [
        vec!["ingest", "--project", s(p), s(&fifo)],
        vec![
            "ingest",
            "--project",
            s(p),
            "--format",
            "long-csv",
            s(&fifo),
        ],
        vec!["record", "--project", s(p), "--mission", "1", s(&fifo)],
        vec!["score", "--project", s(p), "--probabilities", s(&fifo)],
        vec!["plan", "--project", s(p), "--scores", s(&fifo)],
        vec!["init", "--dir", s(&new), "--sensors", s(&fifo)],
        vec!["ingest", "--project", s(p), "/dev/null"],
    ] {
        let out = gleaner(&args);
        assert!(!out.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("not a regular file"), "{args:?}: {err}");
        assert!(!new.exists());
    }
    // Piped standard input, the same.
    let mut child = Command::new(env!("CARGO_BIN_EXE_gleaner"))
        .args(["ingest", "--project", s(p), "/dev/stdin"])
        .stdin(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawn");
    drop(child.stdin.take());
    let out = child.wait_with_output().expect("wait");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("not a regular file"));
}

#[test]
fn a_refused_init_into_an_existing_directory_leaves_no_database() {
    let dir = tempfile::tempdir().expect("temp dir");
    let sensors = dir.path().join("sensors.csv");
    std::fs::write(&sensors, "id,easting,northing\nn1,1e12,5181000\n").expect("write");
    let out = gleaner(&[
        "init",
        "--dir",
        s(dir.path()),
        "--sensors",
        s(&sensors),
        "--utm-zone",
        "11N",
    ]);
    assert!(!out.status.success());
    let left: Vec<String> = std::fs::read_dir(dir.path())
        .expect("read dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(left, vec!["sensors.csv".to_string()]);
}

/// Hostile command-line values and settings, each refused with its message and nothing
/// written (regressions of the hostile-user session: panics in `Duration::from_secs_f64`,
/// overflowing UTC offsets, a sensor counted twice, an export at −30 m).
#[test]
fn hostile_arguments_are_refused_and_write_nothing() {
    let bases = bases();
    let project = farm_copy(&bases);
    let p = s(project.path());
    let readings = corpus().join("../readings.csv");
    let sensors = corpus().join("../sensors.csv");
    let scratch = tempfile::tempdir().expect("temp dir");
    let new = scratch.path().join("new");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["plan", "--project", p, "--time-limit", "inf"],
            "time limit inf s: expected a number of seconds in [0, 86400]",
        ),
        (
            vec!["plan", "--project", p, "--time-limit", "1e20"],
            "expected a number of seconds in [0, 86400]",
        ),
        (
            vec!["plan", "--project", p, "--time-limit=-1"],
            "time limit -1 s",
        ),
        (
            vec!["plan", "--project", p, "--time-limit", "NaN"],
            "time limit NaN s",
        ),
        (
            vec![
                "ingest",
                "--project",
                p,
                "--modality",
                "vw@30cm",
                "--utc-offset",
                "1e18",
                s(&readings),
            ],
            "expected hours in [-14, 14]",
        ),
        (
            vec![
                "ingest",
                "--project",
                p,
                "--modality",
                "vw@30cm",
                "--utc-offset",
                "NaN",
                s(&readings),
            ],
            "UTC offset NaN h",
        ),
        (
            vec![
                "record",
                "--project",
                p,
                "--mission",
                "1",
                "--cells",
                "x0y0,x0y0",
            ],
            "cell x0y0 is listed twice",
        ),
        (
            vec![
                "init",
                "--dir",
                s(&new),
                "--sensors",
                s(&sensors),
                "--cell-size",
                "0.001",
            ],
            "field.cell_size_m = 0.001: allowed [0.5, 10000] m",
        ),
    ];
    let before = dump(project.path());
    for (args, expected) in &cases {
        let out = gleaner(args);
        assert!(!out.status.success(), "{args:?} succeeded");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(expected), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert_eq!(dump(project.path()), before, "{args:?} wrote");
        assert!(!new.exists());
    }
    // An altitude the flight files must not carry: refused before anything is exported.
    for altitude in ["-30", "nan", "1e300"] {
        let toml = std::fs::read_to_string(project.path().join("gleaner.toml")).expect("toml");
        let edited = toml.replace(
            "[energy]\n",
            &format!("[energy]\naltitude_m = {altitude}\n"),
        );
        let dir = tempfile::tempdir().expect("temp dir");
        copy_dir(project.path(), dir.path());
        std::fs::write(dir.path().join("gleaner.toml"), edited).expect("write");
        let out = gleaner(&["export", "--project", s(dir.path()), "--mission", "1"]);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("energy.altitude_m = "), "{err}");
        assert!(
            !dir.path().join("missions").exists(),
            "{altitude}: files written"
        );
    }
}

/// A farm copy with a second mission that visits one cell only (x2y1, from a scores file):
/// returns the copy and that mission's id.
fn farm_with_a_one_cell_mission(bases: &Bases) -> (tempfile::TempDir, String) {
    let project = farm_copy(bases);
    let p = project.path();
    let scores = p.join("scores.csv");
    std::fs::write(&scores, "cell_id,score\nx2y1,1.0\n").expect("write");
    let out = gleaner(&[
        "plan",
        "--project",
        s(p),
        "--scores",
        s(&scores),
        "--time-limit",
        "0.2",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    let stops: Vec<&str> = doc["stops"]
        .as_array()
        .expect("stops")
        .iter()
        .map(|s| s["cell"].as_str().expect("cell"))
        .collect();
    assert_eq!(stops, ["x2y1"]);
    let id = doc["mission_id"].as_i64().expect("stored").to_string();
    (project, id)
}

/// Recording a flight is checked against the mission: only its stops can be visited, at or
/// after its planned time, at a plausible date; each refusal writes nothing.
#[test]
fn record_refuses_cells_outside_the_mission_and_implausible_times() {
    let bases = bases();
    let (project, id) = farm_with_a_one_cell_mission(&bases);
    let p = s(project.path());
    let readings = project.path().join("flight.csv");
    // n1 is in x0y0, which the mission does not visit.
    std::fs::write(
        &readings,
        "sensor_id,timestamp,modality,value\nn1,2014-01-20,vw@30cm,0.3\n",
    )
    .expect("write");
    let not_a_stop = format!("cell x0y0 is not a stop of mission #{id} (its stops: x2y1)");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec![
                "record",
                "--project",
                p,
                "--mission",
                &id,
                "--cells",
                "x0y0",
                s(&readings),
            ],
            &not_a_stop,
        ),
        (
            vec![
                "record",
                "--project",
                p,
                "--mission",
                &id,
                "--cells",
                "x2y1,x0y0",
            ],
            "cell x0y0 is not a stop of mission #",
        ),
        (
            vec![
                "record",
                "--project",
                p,
                "--mission",
                &id,
                "--at",
                "0001-01-01",
            ],
            "collection time 0001-01-01T00:00:00Z: outside the years 1900..=2199",
        ),
        (
            vec![
                "record",
                "--project",
                p,
                "--mission",
                &id,
                "--at",
                "9999-12-31",
            ],
            "collection time 9999-12-31T00:00:00Z: outside the years 1900..=2199",
        ),
        (
            vec![
                "record",
                "--project",
                p,
                "--mission",
                &id,
                "--at",
                "2014-01-19",
            ],
            "collection time 2014-01-19T00:00:00Z is before mission #",
        ),
        (
            vec!["score", "--project", p, "--at", "0001-01-01"],
            "mission time 0001-01-01T00:00:00Z: outside the years 1900..=2199",
        ),
        (
            vec!["score", "--project", p, "--at", "9999-12-31"],
            "mission time 9999-12-31T00:00:00Z: outside the years 1900..=2199",
        ),
        (
            vec!["plan", "--project", p, "--at", "9999-12-31"],
            "mission time 9999-12-31T00:00:00Z: outside the years",
        ),
        (
            vec!["explore", "--project", p, "--at", "0001-01-01"],
            "mission time 0001-01-01T00:00:00Z: outside the years",
        ),
    ];
    let before = dump(project.path());
    for (args, expected) in &cases {
        let out = gleaner(args);
        assert!(!out.status.success(), "{args:?} succeeded");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(expected), "{args:?}: {err}");
        assert_eq!(dump(project.path()), before, "{args:?} wrote");
    }
    // The mission's own stop, at its planned time, is recorded.
    ok(&[
        "record",
        "--project",
        p,
        "--mission",
        &id,
        "--cells",
        "x2y1",
    ]);
}

/// A scoring refused after the persisted utility state went stale (a bulk ingest) writes
/// nothing: not the scores, not the rebuilt `utility.incremental` blob.
#[test]
fn a_refused_score_writes_nothing_not_even_the_utility_state() {
    let bases = bases();
    let project = farm_copy(&bases);
    let p = project.path();
    let more = p.join("more.csv");
    std::fs::write(
        &more,
        "sensor_id,timestamp,modality,value\nn1,2014-01-21,vw@30cm,0.3\n",
    )
    .expect("write");
    ok(&["ingest", "--project", s(p), s(&more)]);
    let toml = std::fs::read_to_string(p.join("gleaner.toml")).expect("toml");
    let edited = toml.replace(
        "[utility]\n",
        "[utility]\ncondition_modality = \"vw@99cm\"\n",
    );
    assert_ne!(edited, toml);
    std::fs::write(p.join("gleaner.toml"), edited).expect("write");
    let before = dump(p);
    let out = gleaner(&["score", "--project", s(p)]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("utility.condition_modality = \"vw@99cm\" has no readings"),
        "{err}"
    );
    assert_eq!(dump(p), before, "the refused score wrote");
    // With the setting back, the same scoring stores the state and the scores.
    std::fs::write(p.join("gleaner.toml"), toml).expect("write");
    ok(&["score", "--project", s(p)]);
    assert_ne!(dump(p), before);
}

/// A plan with no cell worth visiting is refused (nothing stored); a mission without stops
/// cannot be recorded.
#[test]
fn an_empty_mission_is_neither_stored_nor_recordable() {
    let bases = bases();
    let project = farm_copy(&bases);
    let p = project.path();
    let scores = p.join("zero.csv");
    std::fs::write(&scores, "cell_id,score\nx0y0,0\nx2y0,-1\n").expect("write");
    let before = dump(p);
    let out = gleaner(&["plan", "--project", s(p), "--scores", s(&scores)]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("no cell to visit: of 3 cells none scores S > 0"),
        "{err}"
    );
    assert_eq!(dump(p), before);
    // A dry run still shows the empty plan.
    ok(&[
        "plan",
        "--project",
        s(p),
        "--scores",
        s(&scores),
        "--dry-run",
    ]);
    assert_eq!(dump(p), before);
}

/// `-` (standard input) is refused with a clear message by every file argument.
#[test]
fn standard_input_as_dash_is_refused_clearly() {
    let bases = bases();
    let project = farm_copy(&bases);
    let p = s(project.path());
    let scratch = tempfile::tempdir().expect("temp dir");
    let new = scratch.path().join("new");
    for args in [
        vec!["ingest", "--project", p, "-"],
        vec!["ingest", "--project", p, "--format", "long-csv", "-"],
        vec!["record", "--project", p, "--mission", "1", "-"],
        vec!["score", "--project", p, "--probabilities", "-"],
        vec!["plan", "--project", p, "--scores", "-"],
        vec!["init", "--dir", s(&new), "--sensors", "-"],
    ] {
        let out = gleaner(&args);
        assert!(!out.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("standard input (`-`) is not read: save the data to a file"),
            "{args:?}: {err}"
        );
        assert!(!new.exists());
    }
}

/// Numbers far out of range are echoed short (1e300, not 301 digits), whatever the option.
#[test]
fn out_of_range_numbers_are_not_echoed_in_full() {
    let bases = bases();
    let project = farm_copy(&bases);
    let p = s(project.path());
    let sensors = corpus().join("../sensors.csv");
    let readings = corpus().join("../readings.csv");
    let scratch = tempfile::tempdir().expect("temp dir");
    let new = scratch.path().join("new");
    let big = "1e300";
    let cases: Vec<Vec<&str>> = vec![
        vec!["plan", "--project", p, "--time-limit", big],
        vec![
            "init",
            "--dir",
            s(&new),
            "--sensors",
            s(&sensors),
            "--cell-size",
            big,
        ],
        vec![
            "init",
            "--dir",
            s(&new),
            "--sensors",
            s(&sensors),
            "--base-alt",
            big,
        ],
        vec![
            "init",
            "--dir",
            s(&new),
            "--sensors",
            s(&sensors),
            "--base",
            "1e300,0",
        ],
        vec![
            "init",
            "--dir",
            s(&new),
            "--sensors",
            s(&sensors),
            "--neighbour-radius",
            big,
        ],
        vec![
            "init",
            "--dir",
            s(&new),
            "--sensors",
            s(&sensors),
            "--altitude",
            big,
            "--half-angle",
            "30",
        ],
        vec![
            "ingest",
            "--project",
            p,
            "--modality",
            "vw@30cm",
            "--utc-offset",
            big,
            s(&readings),
        ],
    ];
    for args in &cases {
        let out = gleaner(args);
        assert!(!out.status.success(), "{args:?} succeeded");
        let err = String::from_utf8_lossy(&out.stderr);
        let longest = err
            .split(|c: char| !c.is_ascii_digit())
            .map(str::len)
            .max()
            .unwrap_or(0);
        assert!(longest < 30, "{args:?}: {err}");
        assert!(!new.exists());
    }
    // A setting edited into gleaner.toml, the same.
    let toml = std::fs::read_to_string(project.path().join("gleaner.toml")).expect("toml");
    for (section, line) in [
        ("[utility]", "redundancy_weights = { vw = 1e300 }"),
        ("[utility]", "condition_thresholds = [0.1, 1e300]"),
        ("[field]", "neighbour_radius_m = 1e300"),
        ("[field]", "cell_size_m = 1e300"),
    ] {
        let edited = set_setting(&toml, section, line);
        std::fs::write(project.path().join("gleaner.toml"), &edited).expect("write");
        let out = gleaner(&["score", "--project", p]);
        assert!(!out.status.success(), "{line} accepted");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!err.contains("0000000000"), "{line}: {err}");
    }
}

/// A number typed with hundreds of digits is not echoed back in full by the usage error.
#[test]
fn numbers_typed_with_hundreds_of_digits_are_echoed_short() {
    let bases = bases();
    let project = farm_copy(&bases);
    let p = s(project.path());
    let long = format!("1{}", "0".repeat(300));
    for args in [
        vec!["score", "--project", p, "--at", &long],
        vec!["plan", "--project", p, "--seed", &long],
        vec!["missions", "--project", p, "--mission", &long],
    ] {
        let out = gleaner(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("100000…(301 digits)"), "{args:?}: {err}");
        assert!(!err.contains(&"0".repeat(31)), "{args:?}: {err}");
    }
}

/// `toml` with `line` (`key = value`) in `section`: replacing the key's line, else added
/// at the top of the section.
fn set_setting(toml: &str, section: &str, line: &str) -> String {
    let key = line.split('=').next().expect("key").trim();
    let mut out = Vec::new();
    let (mut in_section, mut done) = (false, false);
    for l in toml.lines() {
        if l.starts_with('[') {
            in_section = l.trim() == section;
            out.push(l.to_string());
            if in_section && !done && !toml_has_key(toml, section, key) {
                out.push(line.to_string());
                done = true;
            }
            continue;
        }
        if in_section && l.split('=').next().map(str::trim) == Some(key) {
            out.push(line.to_string());
            done = true;
        } else {
            out.push(l.to_string());
        }
    }
    assert!(done, "no section {section}");
    out.join("\n") + "\n"
}

fn toml_has_key(toml: &str, section: &str, key: &str) -> bool {
    let mut in_section = false;
    toml.lines().any(|l| {
        if l.starts_with('[') {
            in_section = l.trim() == section;
            return false;
        }
        in_section && l.split('=').next().map(str::trim) == Some(key)
    })
}
