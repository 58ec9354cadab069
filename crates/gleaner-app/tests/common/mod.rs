//! Fixtures shared by the integration tests: the shared data directory and files cut from the
//! real CAF daily records.

use std::io::Write as _;
use std::path::{Path, PathBuf};

/// The shared data directory (`GLEANER_DATA_DIR`, default `../shared/data`).
/// The wall clock the tests' ingests run at (2020-01-01T00:00:00Z): after every reading they
/// ingest, since an ingest refuses readings dated after its clock.
pub const INGEST_CLOCK: i64 = 1_577_836_800;

pub fn shared_data() -> PathBuf {
    std::env::var_os("GLEANER_DATA_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"))
}

/// CAF's `MM/DD/YYYY` as (year, month, day).
pub fn ymd(date: &str) -> Option<(i32, u32, u32)> {
    let mut p = date.split('/');
    let m = p.next()?.parse().ok()?;
    let d = p.next()?.parse().ok()?;
    let y = p.next()?.parse().ok()?;
    Some((y, m, d))
}

/// Copies of the CAF daily files (into `out`, created) holding the rows of the given years.
pub fn caf_files(daily: &Path, out: &Path, years: std::ops::RangeInclusive<i32>) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let mut names: Vec<_> = std::fs::read_dir(daily)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    names.sort();
    std::fs::create_dir_all(out).unwrap();
    for path in names {
        let text = std::fs::read_to_string(&path).unwrap();
        let mut lines = text.lines();
        let mut kept = vec![lines.next().unwrap().to_string()];
        kept.extend(
            lines
                .filter(|l| {
                    l.split('\t')
                        .nth(1)
                        .and_then(ymd)
                        .is_some_and(|(y, _, _)| years.contains(&y))
                })
                .map(str::to_string),
        );
        let target = out.join(path.file_name().unwrap());
        std::fs::write(&target, kept.join("\n") + "\n").unwrap();
        files.push(target);
    }
    files
}

/// The sensors' real VW_30cm readings of January-February 2014 as a long CSV in `out`; returns
/// the file and its number of readings.
pub fn flight_file<'a>(
    daily: &Path,
    sensors: impl IntoIterator<Item = &'a String>,
    out: &Path,
) -> (PathBuf, usize) {
    let path = out.join("flight.csv");
    let mut f = std::fs::File::create(&path).unwrap();
    writeln!(f, "sensor_id,timestamp,modality,value,unit").unwrap();
    let mut n = 0;
    for sensor in sensors {
        let text = std::fs::read_to_string(daily.join(format!("{sensor}.txt"))).unwrap();
        for line in text.lines().skip(1) {
            let cols: Vec<&str> = line.split('\t').collect();
            let Some((y, m, d)) = ymd(cols[1]) else {
                continue;
            };
            if y == 2014 && m <= 2 && cols[2] != "NA" {
                writeln!(f, "{sensor},{y:04}-{m:02}-{d:02},vw@30cm,{},m3/m3", cols[2]).unwrap();
                n += 1;
            }
        }
    }
    (path, n)
}

/// Ingests `files` into `project` at [`INGEST_CLOCK`] with the default options.
#[allow(dead_code)] // not every test binary ingests this way
pub fn ingest_files<S: gleaner_app::Store>(
    project: &mut gleaner_app::Project<S>,
    files: Vec<PathBuf>,
) -> gleaner_app::IngestOutcome {
    gleaner_app::ingest(
        project,
        &gleaner_app::IngestRequest {
            files,
            ..Default::default()
        },
        INGEST_CLOCK,
        &gleaner_app::Silent,
    )
    .unwrap()
}
