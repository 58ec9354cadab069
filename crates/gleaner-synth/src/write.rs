//! CSV writers for the project's generic formats. Each takes any `std::io::Write`; wrap files
//! in a `BufWriter` (the readings writer already writes in large blocks).

use std::io::{self, Write};

use rayon::prelude::*;

use crate::SynthFarm;
use gleaner_field::time::format_rfc3339 as rfc3339;

/// Header of the sensors CSV.
pub const SENSORS_HEADER: &str = "id,lat,lon,elevation_m";
/// Header of the long readings CSV.
pub const READINGS_HEADER: &str = "sensor_id,timestamp,modality,value,unit";
/// Header of the ground-truth events CSV.
pub const GROUND_TRUTH_HEADER: &str =
    "event_id,kind,start,end,centre_lat,centre_lon,radius_m,affected_sensor_ids";
/// Header of the faults CSV.
pub const FAULTS_HEADER: &str = "sensor_id,kind,modality,start,end";

/// Appends `v` with exactly `decimals` decimal places (rounded half away from zero), no
/// exponent, no `-0`. Non-finite values are written as `NaN`, `inf` or `-inf`.
pub fn push_fixed(buf: &mut Vec<u8>, v: f64, decimals: u32) {
    if !v.is_finite() {
        buf.extend_from_slice(if v.is_nan() {
            b"NaN"
        } else if v > 0.0 {
            b"inf"
        } else {
            b"-inf"
        });
        return;
    }
    let decimals = decimals.min(9);
    let scale = 10u64.pow(decimals);
    let scaled = (v.abs() * scale as f64).round();
    if scaled >= 1.0e18 {
        // Too large for the integer path; rare enough to take the slow one.
        let _ = write!(buf, "{:.*}", decimals as usize, v);
        return;
    }
    let scaled = scaled as u64;
    if v < 0.0 && scaled != 0 {
        buf.push(b'-');
    }
    push_u64(buf, scaled / scale);
    if decimals > 0 {
        buf.push(b'.');
        let frac = scaled % scale;
        let mut digits = [b'0'; 9];
        let mut f = frac;
        for k in (0..decimals as usize).rev() {
            digits[k] = b'0' + (f % 10) as u8;
            f /= 10;
        }
        buf.extend_from_slice(&digits[..decimals as usize]);
    }
}

fn push_u64(buf: &mut Vec<u8>, mut n: u64) {
    let mut digits = [0u8; 20];
    let mut i = digits.len();
    loop {
        i -= 1;
        digits[i] = b'0' + (n % 10) as u8;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    buf.extend_from_slice(&digits[i..]);
}

/// Writes `id,lat,lon,elevation_m`: WGS84 degrees with 7 decimals (about 1 cm), elevation in
/// metres with 2 decimals (empty when unknown).
pub fn write_sensors_csv(farm: &SynthFarm, out: &mut impl Write) -> io::Result<()> {
    let mut buf = Vec::with_capacity(64 * farm.sensors().len() + 64);
    buf.extend_from_slice(SENSORS_HEADER.as_bytes());
    buf.push(b'\n');
    for s in farm.sensors() {
        buf.extend_from_slice(s.id.as_str().as_bytes());
        buf.push(b',');
        push_fixed(&mut buf, s.position.lat(), 7);
        buf.push(b',');
        push_fixed(&mut buf, s.position.lon(), 7);
        buf.push(b',');
        if let Some(e) = s.elevation_m {
            push_fixed(&mut buf, e, 2);
        }
        buf.push(b'\n');
    }
    out.write_all(&buf)
}

/// Sensors formatted per parallel task.
const SENSORS_PER_TASK: usize = 32;
/// Tasks formatted before their bytes are written (bounds memory to a few tens of MB).
const TASKS_PER_WAVE: usize = 32;

/// Writes the long readings table `sensor_id,timestamp,modality,value,unit`, one row per
/// present reading, ordered by sensor, then time, then modality (missing readings are absent
/// rows). Timestamps are RFC 3339 UTC (`2014-01-01T00:00:00Z`); values have the modality's
/// decimals (4); units are `m3/m3` and `degC`.
///
/// Formatting runs in parallel, writing in order, so the bytes do not depend on the number
/// of threads.
pub fn write_readings_csv(farm: &SynthFarm, out: &mut impl Write) -> io::Result<()> {
    out.write_all(READINGS_HEADER.as_bytes())?;
    out.write_all(b"\n")?;
    let stamps: Vec<Vec<u8>> = farm
        .times()
        .iter()
        .map(|&t| {
            let mut s = b",".to_vec();
            s.extend_from_slice(rfc3339(t).as_bytes());
            s.push(b',');
            s
        })
        .collect();
    let mods: Vec<(Vec<u8>, Vec<u8>, u32)> = farm
        .modalities()
        .iter()
        .map(|m| {
            (
                format!("{},", m.modality).into_bytes(),
                format!(",{}\n", m.unit).into_bytes(),
                m.decimals,
            )
        })
        .collect();
    let n = farm.sensors().len();
    let steps = farm.times().len();
    let tasks: Vec<(usize, usize)> = (0..n)
        .step_by(SENSORS_PER_TASK)
        .map(|a| (a, (a + SENSORS_PER_TASK).min(n)))
        .collect();
    for wave in tasks.chunks(TASKS_PER_WAVE) {
        let buffers: Vec<Vec<u8>> = wave
            .par_iter()
            .map(|&(a, b)| {
                let mut buf = Vec::with_capacity((b - a) * steps * mods.len() * 52);
                for s in a..b {
                    let id = farm.sensors()[s].id.as_str().as_bytes();
                    let series: Vec<&[f32]> = (0..mods.len()).map(|m| farm.series(s, m)).collect();
                    for (t, stamp) in stamps.iter().enumerate() {
                        for (m, (name, unit, decimals)) in mods.iter().enumerate() {
                            let v = series[m][t];
                            if v.is_nan() {
                                continue;
                            }
                            buf.extend_from_slice(id);
                            buf.extend_from_slice(stamp);
                            buf.extend_from_slice(name);
                            push_fixed(&mut buf, f64::from(v), *decimals);
                            buf.extend_from_slice(unit);
                        }
                    }
                }
                buf
            })
            .collect();
        for b in &buffers {
            out.write_all(b)?;
        }
    }
    Ok(())
}

/// Writes the events' ground truth: `event_id,kind,start,end,centre_lat,centre_lon,radius_m,
/// affected_sensor_ids` with RFC 3339 times (end exclusive), WGS84 degrees (7 decimals),
/// radius in metres and the affected sensors' ids separated by `;`.
pub fn write_ground_truth_csv(farm: &SynthFarm, out: &mut impl Write) -> io::Result<()> {
    let mut buf = Vec::new();
    buf.extend_from_slice(GROUND_TRUTH_HEADER.as_bytes());
    buf.push(b'\n');
    for e in farm.events() {
        buf.extend_from_slice(e.id.as_bytes());
        buf.push(b',');
        buf.extend_from_slice(e.kind.as_str().as_bytes());
        buf.push(b',');
        buf.extend_from_slice(rfc3339(e.start).as_bytes());
        buf.push(b',');
        buf.extend_from_slice(rfc3339(e.end).as_bytes());
        buf.push(b',');
        push_fixed(&mut buf, e.centre.lat(), 7);
        buf.push(b',');
        push_fixed(&mut buf, e.centre.lon(), 7);
        buf.push(b',');
        push_fixed(&mut buf, e.radius_m, 1);
        buf.push(b',');
        for (k, &s) in e.affected.iter().enumerate() {
            if k > 0 {
                buf.push(b';');
            }
            buf.extend_from_slice(farm.sensors()[s].id.as_str().as_bytes());
        }
        buf.push(b'\n');
    }
    out.write_all(&buf)
}

/// Writes the random faults: `sensor_id,kind,modality,start,end` (modality empty for a
/// dropout, which silences the whole station; end exclusive; RFC 3339 times).
pub fn write_faults_csv(farm: &SynthFarm, out: &mut impl Write) -> io::Result<()> {
    let mut buf = Vec::new();
    buf.extend_from_slice(FAULTS_HEADER.as_bytes());
    buf.push(b'\n');
    for f in farm.faults() {
        buf.extend_from_slice(farm.sensors()[f.sensor].id.as_str().as_bytes());
        buf.push(b',');
        buf.extend_from_slice(f.kind.as_str().as_bytes());
        buf.push(b',');
        if let Some(m) = f.modality {
            buf.extend_from_slice(farm.modalities()[m].modality.as_str().as_bytes());
        }
        buf.push(b',');
        buf.extend_from_slice(rfc3339(f.start).as_bytes());
        buf.push(b',');
        buf.extend_from_slice(rfc3339(f.end).as_bytes());
        buf.push(b'\n');
    }
    out.write_all(&buf)
}

/// The four files of a farm in its directory.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FarmFiles {
    /// `sensors.csv`: `id,lat,lon,elevation_m`.
    pub sensors: std::path::PathBuf,
    /// `readings.csv`: the long readings format.
    pub readings: std::path::PathBuf,
    /// `ground_truth.csv`: the localised events.
    pub ground_truth: std::path::PathBuf,
    /// `faults.csv`: injected sensor faults.
    pub faults: std::path::PathBuf,
}

impl FarmFiles {
    /// The files' names inside `dir`.
    pub fn in_dir(dir: &std::path::Path) -> Self {
        Self {
            sensors: dir.join("sensors.csv"),
            readings: dir.join("readings.csv"),
            ground_truth: dir.join("ground_truth.csv"),
            faults: dir.join("faults.csv"),
        }
    }
}

/// A farm's file that could not be written: `{path}: cannot {create|write}: {OS message}`.
#[derive(Debug, thiserror::Error)]
#[error("{}: cannot {what}: {source}", path.display())]
pub struct WriteError {
    /// The file or directory.
    pub path: std::path::PathBuf,
    /// `create` or `write`.
    pub what: &'static str,
    /// The OS error.
    pub source: io::Error,
}

/// Creates `dir` (if missing) and writes the farm's four files into it ([`FarmFiles`]), each
/// through a 1 MiB buffer.
pub fn write_farm_files(farm: &SynthFarm, dir: &std::path::Path) -> Result<FarmFiles, WriteError> {
    let fail = |path: &std::path::Path, what: &'static str| {
        let path = path.to_path_buf();
        move |source| WriteError { path, what, source }
    };
    std::fs::create_dir_all(dir).map_err(fail(dir, "create"))?;
    let files = FarmFiles::in_dir(dir);
    let write = |path: &std::path::Path,
                 f: &dyn Fn(&mut io::BufWriter<std::fs::File>) -> io::Result<()>| {
        let file = std::fs::File::create(path).map_err(fail(path, "create"))?;
        let mut w = io::BufWriter::with_capacity(1 << 20, file);
        f(&mut w)
            .and_then(|()| w.flush())
            .map_err(fail(path, "write"))
    };
    write(&files.sensors, &|w| write_sensors_csv(farm, w))?;
    write(&files.readings, &|w| write_readings_csv(farm, w))?;
    write(&files.ground_truth, &|w| write_ground_truth_csv(farm, w))?;
    write(&files.faults, &|w| write_faults_csv(farm, w))?;
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(v: f64, decimals: u32, expected: &str) {
        let mut buf = Vec::new();
        push_fixed(&mut buf, v, decimals);
        assert_eq!(
            String::from_utf8(buf).unwrap(),
            expected,
            "{v} with {decimals}"
        );
    }

    #[test]
    fn fixed_formatting() {
        check(0.0, 4, "0.0000");
        check(0.23456, 4, "0.2346");
        check(-0.00001, 4, "0.0000");
        check(-12.5, 2, "-12.50");
        check(46.7807123456, 7, "46.7807123");
        check(-117.082, 7, "-117.0820000");
        check(785.0, 0, "785");
        check(f64::NAN, 3, "NaN");
        check(1.0e30, 1, &format!("{:.1}", 1.0e30));
        check(f64::from(0.3105f32), 4, "0.3105");
    }

    proptest::proptest! {
        #[test]
        fn fixed_matches_std_formatting(v in -1000.0f64..1000.0, d in 0u32..7) {
            let mut buf = Vec::new();
            push_fixed(&mut buf, v, d);
            let ours: f64 = String::from_utf8(buf).unwrap().parse().unwrap();
            proptest::prop_assert!((ours - v).abs() <= 0.5 * 10f64.powi(-(d as i32)) + 1e-9);
        }
    }
}
