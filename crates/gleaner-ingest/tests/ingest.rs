//! Integration tests: the bad-input corpus under `tests/data/` and the real CAF files.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use gleaner_field::Modality;
use gleaner_ingest::{
    IngestOptions, OnError, Readings, SensorsOptions, WideOptions, read_caf_daily, read_long_csv,
    read_sensors_csv, read_wide_csv,
};

fn corpus(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn shared_data() -> PathBuf {
    std::env::var_os("GLEANER_DATA_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"))
}

fn known(ids: &[&str]) -> IngestOptions {
    IngestOptions {
        on_error: OnError::Fail,
        known_sensors: Some(ids.iter().map(|s| s.to_string()).collect::<HashSet<_>>()),
        ..IngestOptions::default()
    }
}

/// Reads `file` as a long CSV with sensors s1, s2 known; under `Fail` expects either
/// `Ok(readings)` or an error whose message contains every fragment of `expected_err`; under
/// `Skip` expects `skipped` skipped rows.
fn check_long(file: &str, expected: Result<usize, &[&str]>, skipped: u64) {
    let path = corpus(file);
    let result = read_long_csv(&path, &known(&["s1", "s2"]));
    match (result, expected) {
        (Ok((r, _)), Ok(n)) => assert_eq!(r.rows.len(), n, "{file}"),
        (Err(e), Err(fragments)) => {
            let msg = e.to_string();
            for f in fragments {
                assert!(msg.contains(f), "{file}: {msg:?} lacks {f:?}");
            }
        }
        (got, want) => panic!("{file}: got {got:?}, want {want:?}"),
    }
    let mut skip = known(&["s1", "s2"]);
    skip.on_error = OnError::Skip;
    match read_long_csv(&path, &skip) {
        Ok((_, report)) => assert_eq!(report.skipped, skipped, "{file} skip mode"),
        Err(e) => assert!(skipped == u64::MAX, "{file} skip mode failed: {e}"),
    }
}

#[test]
fn long_csv_corpus() {
    check_long("long_ok.csv", Ok(3), 0);
    check_long("long_bom_crlf.csv", Ok(2), 0);
    check_long("long_identical_dup.csv", Ok(1), 0);
    check_long(
        "long_unknown_sensor.csv",
        Err(&[
            "long_unknown_sensor.csv:3:",
            "column `sensor_id`",
            "unknown sensor",
            "\"ghost\"",
        ]),
        1,
    );
    check_long(
        "long_not_number.csv",
        Err(&[
            "long_not_number.csv:3:",
            "column `value`",
            "not a number",
            "\"wet\"",
        ]),
        1,
    );
    check_long(
        "long_nan.csv",
        Err(&[":2:", "not a finite number", "\"NaN\""]),
        1,
    );
    check_long(
        "long_inf.csv",
        Err(&[":3:", "not a finite number", "\"inf\""]),
        1,
    );
    check_long(
        "long_bad_timestamp.csv",
        Err(&[
            ":3:",
            "column `timestamp`",
            "impossible timestamp",
            "2014-02-30",
        ]),
        1,
    );
    check_long(
        "long_conflict.csv",
        Err(&[":4:", "conflicts with line 2", "0.31"]),
        1,
    );
    check_long(
        "long_field_count.csv",
        Err(&[":2:", "wrong number of fields"]),
        1,
    );
    check_long(
        "long_bad_modality.csv",
        Err(&[":2:", "column `modality`", "VW 30"]),
        1,
    );
    check_long(
        "long_unit_mismatch.csv",
        Err(&[":3:", "column `unit`", "m3/m3", "percent"]),
        1,
    );
    // Structural problems fail in both modes.
    check_long(
        "long_missing_column.csv",
        Err(&["long_missing_column.csv:1:", "missing column `modality`"]),
        u64::MAX,
    );
    check_long("empty.csv", Err(&["empty.csv", "empty file"]), u64::MAX);
    check_long(
        "does_not_exist.csv",
        Err(&["does_not_exist.csv", "cannot read"]),
        u64::MAX,
    );
}

#[test]
fn long_csv_values_and_units() {
    let (r, report) = read_long_csv(&corpus("long_ok.csv"), &IngestOptions::default()).unwrap();
    assert_eq!(report.missing, 1);
    assert_eq!(report.rows_read, 4);
    let names: Vec<_> = r
        .modalities
        .iter()
        .map(|m| (m.modality.as_str(), m.unit.as_deref()))
        .collect();
    assert_eq!(
        names,
        [("vw@30cm", Some("m3/m3")), ("t@30cm", Some("degC"))]
    );
    let first = r.rows[0];
    assert_eq!((first.t, first.value), (1_388_534_400, 0.31));
}

#[test]
fn skipped_rows_are_reported_with_their_reason() {
    let mut opts = known(&["s1", "s2"]);
    opts.on_error = OnError::Skip;
    let (r, report) = read_long_csv(&corpus("long_not_number.csv"), &opts).unwrap();
    assert_eq!(r.rows.len(), 1);
    assert_eq!(report.skipped_rows.len(), 1);
    assert_eq!(report.skipped_rows[0].line, 3);
    assert!(report.skipped_rows[0].reason.contains("not a number"));
}

#[test]
fn sensors_corpus() {
    let (s, _) = read_sensors_csv(&corpus("sensors_ok.csv"), &SensorsOptions::default()).unwrap();
    assert_eq!(s.len(), 2);
    assert_eq!(s[0].sensor.elevation_m, Some(790.0));
    assert_eq!(s[1].sensor.elevation_m, None);
    let e =
        read_sensors_csv(&corpus("sensors_duplicate.csv"), &SensorsOptions::default()).unwrap_err();
    assert!(
        e.to_string()
            .contains(":3: column `id`: duplicate sensor id (first on line 2)"),
        "{e}"
    );
    let e =
        read_sensors_csv(&corpus("sensors_bad_lat.csv"), &SensorsOptions::default()).unwrap_err();
    assert!(
        e.to_string()
            .contains(":3: column `lat/lon`: invalid position: \"146.779, -117.086\""),
        "{e}"
    );
}

#[test]
fn wide_corpus() {
    let wide = WideOptions::new(Modality::new("vw@30cm").unwrap());
    let (r, report) = read_wide_csv(&corpus("wide_ok.csv"), &wide, &known(&["s1", "s2"])).unwrap();
    assert_eq!((r.rows.len(), report.missing), (3, 1));
    assert_eq!(r.rows.iter().map(|x| x.t).max(), Some(1_420_070_400 + 3600));
    let e = read_wide_csv(&corpus("wide_unknown_column.csv"), &wide, &known(&["s1"])).unwrap_err();
    assert!(
        e.to_string().contains(":1: column `ghost`: unknown sensor"),
        "{e}"
    );
    let mut skip = known(&["s1"]);
    skip.on_error = OnError::Skip;
    let (r, report) = read_wide_csv(&corpus("wide_unknown_column.csv"), &wide, &skip).unwrap();
    assert_eq!((r.rows.len(), report.skipped), (1, 1));
}

#[test]
fn caf_impossible_date() {
    let e = read_caf_daily(&corpus("caf_bad_date.txt"), &IngestOptions::default()).unwrap_err();
    assert!(
        e.to_string().contains(
            "caf_bad_date.txt:3: column `Date`: invalid or impossible timestamp: \"04/31/2007\""
        ),
        "{e}"
    );
}

fn caf_sensors() -> Vec<gleaner_ingest::SensorInput> {
    let path = shared_data().join("caf/sensors/CAF_sensor_locations.csv");
    let (s, _) = read_sensors_csv(
        &path,
        &SensorsOptions {
            utm: Some((11, true)),
            ..Default::default()
        },
    )
    .unwrap();
    s
}

#[test]
fn caf_locations_from_utm_match_published_lat_lon() {
    let sensors = caf_sensors();
    assert_eq!(sensors.len(), 42);
    let path = shared_data().join("caf/sensors/CAF_sensor_locations.csv");
    let (by_ll, _) = read_sensors_csv(&path, &SensorsOptions::default()).unwrap();
    for (a, b) in sensors.iter().zip(&by_ll) {
        assert_eq!(a.sensor.id, b.sensor.id);
        assert!((a.sensor.position.lat() - b.sensor.position.lat()).abs() < 2e-5);
        assert!((a.sensor.position.lon() - b.sensor.position.lon()).abs() < 2e-5);
    }
}

#[test]
fn all_caf_daily_files_ingest() {
    let sensors = caf_sensors();
    let opts = IngestOptions {
        on_error: OnError::Fail,
        known_sensors: Some(sensors.iter().map(|s| s.sensor.id.to_string()).collect()),
        ..IngestOptions::default()
    };
    let mut files: Vec<_> = std::fs::read_dir(shared_data().join("caf/Daily"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    assert_eq!(files.len(), 42);
    let mut all = Readings::default();
    let mut missing = 0;
    for f in &files {
        let (r, report) = read_caf_daily(f, &opts).unwrap();
        assert_eq!(r.sensors.len(), 1, "{f:?}");
        assert_eq!(r.modalities.len(), 10, "{f:?}");
        assert_eq!(report.skipped, 0);
        missing += report.missing;
        all.append(r);
    }
    assert_eq!(all.sensors.len(), 42);
    let total = all.rows.len() as u64;
    let frac_missing = missing as f64 / (missing + total) as f64;
    assert!(
        (0.40..0.55).contains(&frac_missing),
        "missing fraction {frac_missing}"
    );
    // Physical ranges: VW in m3/m3, T in degC.
    for r in &all.rows {
        let m = &all.modalities[r.modality as usize].modality;
        match m.quantity() {
            "vw" => assert!((-0.1..=1.0).contains(&r.value), "{m} {}", r.value),
            "t" => assert!((-40.0..=60.0).contains(&r.value), "{m} {}", r.value),
            q => panic!("unexpected quantity {q}"),
        }
    }
}

#[test]
fn caf_hourly_wide_file_ingests() {
    let sensors = caf_sensors();
    let opts = IngestOptions {
        on_error: OnError::Fail,
        known_sensors: Some(sensors.iter().map(|s| s.sensor.id.to_string()).collect()),
        ..IngestOptions::default()
    };
    let path = shared_data().join("caf/derived/water_content_2015_Jan_April_32_sensors.csv");
    let wide = WideOptions::new(Modality::new("vw@30cm").unwrap());
    let (r, report) = read_wide_csv(&path, &wide, &opts).unwrap();
    assert_eq!(r.sensors.len(), 32);
    assert_eq!(report.missing, 0);
    // 2521 data lines from 2015-01-01 00:00 to 2015-04-22 09:00 (local clock read as UTC).
    assert_eq!(report.rows_read, 2521);
    assert_eq!(r.rows.iter().map(|x| x.t).min(), Some(1_420_070_400));
    assert_eq!(r.rows.iter().map(|x| x.t).max(), Some(1_429_693_200));
    assert_eq!(r.rows.len() as u64, 32 * report.rows_read);
}

#[test]
fn hubbard_brook_network_ingests() {
    use gleaner_ingest::{
        HubbardBrookMetadata, read_hubbard_brook_logger, read_hubbard_brook_sensors,
    };
    let dir = shared_data().join("hubbard_brook");
    let meta_path = dir.join("sensor_metadata.csv");
    let (sensors, _) = read_hubbard_brook_sensors(&meta_path).unwrap();
    assert_eq!(sensors.len(), 77);
    assert!(
        sensors
            .iter()
            .all(|s| (43.9..44.0).contains(&s.sensor.position.lat()))
    );
    let metadata = HubbardBrookMetadata::read(&meta_path).unwrap();
    let opts = IngestOptions {
        on_error: OnError::Fail,
        known_sensors: Some(sensors.iter().map(|s| s.sensor.id.to_string()).collect()),
        ..IngestOptions::default()
    };
    let (r, report) =
        read_hubbard_brook_logger(&dir.join("z6-19506.csv"), &metadata, &opts).unwrap();
    assert_eq!(report.rows_read, 16_264);
    assert_eq!(r.sensors.len(), 6, "six probes on this logger");
    let names: Vec<&str> = r.modalities.iter().map(|m| m.modality.as_str()).collect();
    for m in ["vw@15cm", "t@15cm", "matric@15cm", "ec@15cm", "ec_sat@15cm"] {
        assert!(names.contains(&m), "{m} missing from {names:?}");
    }
    let unit = |m: &str| {
        r.modalities
            .iter()
            .find(|x| x.modality.as_str() == m)
            .and_then(|x| x.unit.clone())
    };
    assert_eq!(unit("vw@15cm").as_deref(), Some("m3/m3"));
    assert_eq!(unit("matric@15cm").as_deref(), Some("kPa"));
    // 2023-07-25 17:00 at UTC-04:00 is 21:00 UTC.
    assert_eq!(r.rows.iter().map(|x| x.t).min(), Some(1_690_318_800));
    let vw = r
        .modalities
        .iter()
        .position(|x| x.modality.as_str().starts_with("vw@"))
        .unwrap() as u32;
    assert!(
        r.rows
            .iter()
            .filter(|x| x.modality == vw)
            .all(|x| (0.0..=0.8).contains(&x.value))
    );
}

/// Hubbard Brook's main soil-moisture depth is 50 cm (22 water-content probes; 15 cm has 12,
/// 30 cm two); ties go to the shallower depth; a file without `meas` has none.
#[test]
fn hubbard_brook_main_water_depth_counts_water_content_probes() {
    use gleaner_ingest::hubbard_brook_main_water_depth;
    let real = shared_data().join("hubbard_brook/sensor_metadata.csv");
    assert_eq!(hubbard_brook_main_water_depth(&real).unwrap(), Some(50));
    let dir = tempfile::tempdir().unwrap();
    let header = "siteID,lat,lon,logger,port,model,meas,depth_cm";
    let tie = dir.path().join("tie.csv");
    std::fs::write(
        &tie,
        format!(
            "{header}\nA,43.9,-71.7,z,1,T12,vwc,60\nA,43.9,-71.7,z,2,T12,vwc,20\n\
             A,43.9,-71.7,z,3,T21,matric,60\n"
        ),
    )
    .unwrap();
    assert_eq!(hubbard_brook_main_water_depth(&tie).unwrap(), Some(20));
    let none = dir.path().join("none.csv");
    std::fs::write(
        &none,
        "siteID,lat,lon,logger,port,depth_cm\nA,43.9,-71.7,z,1,15\n",
    )
    .unwrap();
    assert_eq!(hubbard_brook_main_water_depth(&none).unwrap(), None);
}

/// Line numbers count physical lines whatever the line ending: a bad value on line 4 of a file
/// with CRLF (or bare CR) line endings is reported at line 4, as with LF.
#[test]
fn crlf_files_report_the_right_line() {
    let dir = tempfile::tempdir().unwrap();
    for (name, eol) in [("lf.csv", "\n"), ("crlf.csv", "\r\n"), ("cr.csv", "\r")] {
        let text = [
            "sensor_id,timestamp,modality,value,unit",
            "s1,2014-01-01T00:00:00Z,vw@30cm,0.31,m3/m3",
            "s1,2014-01-02T00:00:00Z,vw@30cm,0.32,m3/m3",
            "s1,2014-01-03T00:00:00Z,vw@30cm,oops,m3/m3",
            "s1,2014-01-04T00:00:00Z,vw@30cm,0.33,m3/m3",
        ]
        .join(eol)
            + eol;
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        let err = read_long_csv(&path, &known(&["s1"])).unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains(&format!("{name}:4:")), "{name}: {msg}");
        assert!(msg.contains("oops"), "{name}: {msg}");
        let mut skip = known(&["s1"]);
        skip.on_error = OnError::Skip;
        let (readings, report) = read_long_csv(&path, &skip).unwrap();
        assert_eq!(readings.rows.len(), 3, "{name}");
        assert_eq!(report.skipped_rows[0].line, 4, "{name}");
        let mut lines: Vec<u32> = readings.rows.iter().map(|r| r.line).collect();
        lines.sort_unstable();
        assert_eq!(lines, vec![2, 3, 5], "{name}");
    }
}

mod arbitrary_bytes {
    //! Every reader on arbitrary bytes, and on valid files with random bytes spliced in:
    //! an error or a result, never a panic (the long runs are `gleaner-fuzz`).
    use super::*;
    use gleaner_field::Modality;
    use gleaner_ingest::{
        HubbardBrookMetadata, SensorsOptions, WideOptions, read_caf_daily,
        read_hubbard_brook_logger, read_hubbard_brook_sensors, read_long_csv, read_sensors_csv,
        read_wide_csv,
    };
    use proptest::prelude::*;

    fn every_reader(bytes: &[u8]) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("z9-1.csv");
        std::fs::write(&path, bytes).unwrap();
        let meta = dir.path().join("meta.csv");
        std::fs::write(
            &meta,
            "logger,port,lat,lon,depth_cm\nz9-1,1,43.9,-71.7,15\nz9-1,2,43.9,-71.7,50\n",
        )
        .unwrap();
        let skip = IngestOptions {
            on_error: OnError::Skip,
            ..IngestOptions::default()
        };
        for options in [&IngestOptions::default(), &skip] {
            let _ = read_long_csv(&path, options);
            let _ = read_caf_daily(&path, options);
            let wide = WideOptions::new(Modality::new("vw@30cm").unwrap());
            let _ = read_wide_csv(&path, &wide, options);
            let metadata = HubbardBrookMetadata::read(&meta).unwrap();
            let _ = read_hubbard_brook_logger(&path, &metadata, options);
        }
        let _ = read_sensors_csv(&path, &SensorsOptions::default());
        let utm = SensorsOptions {
            utm: Some((11, true)),
            on_error: OnError::Skip,
        };
        let _ = read_sensors_csv(&path, &utm);
        let _ = HubbardBrookMetadata::read(&path);
        let _ = read_hubbard_brook_sensors(&path);
    }

    const VALID: &[u8] = b"sensor_id,timestamp,modality,value,unit\n\
        n1,2014-01-01,vw@30cm,0.25,m3/m3\nn1,2014-01-02T06:00:00+02:00,t@30cm,3.2,degC\n";

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        #[test]
        fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..600)) {
            every_reader(&bytes);
        }

        #[test]
        fn spliced_bytes_never_panic(
            at in 0..VALID.len(),
            junk in prop::collection::vec(
                prop::sample::select(b",\t\n\r\"\0\xff9e-.@:NaTZ+".to_vec()), 1..40),
        ) {
            let mut bytes = VALID.to_vec();
            bytes.splice(at..at, junk);
            every_reader(&bytes);
        }
    }
}
