//! A small built-in field and missions for examples, tests and documentation: 60 m cells
//! over about 0.8 x 0.5 km near Pullman, WA (the CAF site's latitude), scores from smooth
//! made-up fields, an eight-stop adaptive mission with the paper's headline energies
//! (55,309.8 J of 66,500 J), three exploration sorties covering every cell, and a
//! reconstruction of soil moisture over the field at one time.
//!
//! The numbers are illustrative, not model output: they exercise the figures.

use gleaner_wire::docs::{MapCellDoc, MapSensorDoc, ReconstructionMapDoc};
use gleaner_wire::{
    CellDoc, EnergyDoc, FIELD_FORMAT, FieldDoc, MISSION_FORMAT, MissionDoc, ProfileDoc,
    RECONSTRUCTION_MAP_FORMAT, ScoresDoc, SensorDoc, StopDoc, VERSION,
};

const BASE: [f64; 2] = [-117.0875, 46.7782];
const CELL_M: f64 = 60.0;
const M_PER_DEG_LAT: f64 = 6_371_008.8 * std::f64::consts::PI / 180.0;
const PLANNED_AT_S: i64 = 1_401_624_000;

fn to_lon_lat(e: f64, n: f64) -> [f64; 2] {
    let kx = M_PER_DEG_LAT * BASE[1].to_radians().cos();
    [BASE[0] + e / kx, BASE[1] + n / M_PER_DEG_LAT]
}

/// A deterministic number in [0, 1) from two integers.
fn hash01(a: i64, b: i64) -> f64 {
    let mut x = (a as u64)
        .wrapping_mul(0x9e37_79b9_7f4a_7c15)
        .wrapping_add((b as u64).wrapping_mul(0xc2b2_ae3d_27d4_eb4f));
    x ^= x >> 31;
    x = x.wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x ^= x >> 29;
    (x >> 11) as f64 / (1u64 << 53) as f64
}

/// The grid cells of the example field: (ix, iy) with the cell's south-west corner at
/// (20 + 60·ix, 30 + 60·iy) m from the base.
fn grid() -> Vec<(i64, i64)> {
    let mut out = Vec::new();
    for iy in 0..8 {
        for ix in 0..14 {
            // An irregular field: the corners are cut and a few cells have no sensor.
            let cut = (ix + iy < 2) || (ix > 10 && iy > 5) || (ix < 2 && iy > 6);
            if !cut && hash01(ix, iy) > 0.22 {
                out.push((ix, iy));
            }
        }
    }
    out
}

fn cell_id(ix: i64, iy: i64) -> String {
    format!("x{ix}y{iy}")
}

fn sw_corner(ix: i64, iy: i64) -> (f64, f64) {
    (20.0 + CELL_M * ix as f64, 30.0 + CELL_M * iy as f64)
}

fn centre(ix: i64, iy: i64) -> (f64, f64) {
    let (e, n) = sw_corner(ix, iy);
    (e + 0.5 * CELL_M, n + 0.5 * CELL_M)
}

fn scores(ix: i64, iy: i64) -> ScoresDoc {
    let (x, y) = (ix as f64, iy as f64);
    let f = 0.35 + 0.3 * (0.45 * x).sin().abs() + 0.2 * hash01(iy, ix);
    let a = 0.9 * (-((x - 9.0).powi(2) + (y - 5.0).powi(2)) / 6.0).exp()
        + 0.5 * (-((x - 3.0).powi(2) + (y - 2.0).powi(2)) / 4.0).exp();
    let u = 0.3 + 0.4 * hash01(ix + 7, iy + 3);
    let r = 0.2 + 0.6 * (0.3 * y).cos().abs() * hash01(ix + 1, iy + 11);
    let s = 0.4 * f + 0.3 * a + 0.2 * u - 0.1 * r;
    ScoresDoc {
        f,
        r,
        a,
        u,
        s,
        computed_at_s: PLANNED_AT_S,
    }
}

/// The example field: 60 m cells, one to three sensors each, all scored.
pub fn field() -> FieldDoc {
    let mut cells = Vec::new();
    let mut sensors = Vec::new();
    for (ix, iy) in grid() {
        let (e, n) = sw_corner(ix, iy);
        let ring = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (0.0, 0.0)]
            .iter()
            .map(|&(a, b)| to_lon_lat(e + a * CELL_M, n + b * CELL_M))
            .collect();
        let count = 1 + (hash01(ix + 3, iy + 5) * 2.2) as usize;
        for k in 0..count {
            let (u, v) = (hash01(ix * 7 + k as i64, iy), hash01(iy * 5 + k as i64, ix));
            sensors.push(SensorDoc {
                id: format!("S{:02}{:02}{k}", ix, iy),
                lon_lat: to_lon_lat(e + 8.0 + 44.0 * u, n + 8.0 + 44.0 * v),
            });
        }
        let (ce, cn) = centre(ix, iy);
        cells.push(CellDoc {
            cell: cell_id(ix, iy),
            centre_lon_lat: to_lon_lat(ce, cn),
            ring_lon_lat: ring,
            sensors: count,
            scores: Some(scores(ix, iy)),
        });
    }
    cells.sort_by(|a, b| a.cell.cmp(&b.cell));
    sensors.sort_by(|a, b| a.id.cmp(&b.id));
    FieldDoc {
        format: FIELD_FORMAT.into(),
        version: VERSION,
        project: "example farm".into(),
        cell_size_m: CELL_M,
        base_lon_lat: BASE,
        cells,
        sensors,
        zones: Vec::new(),
    }
}

fn profile() -> ProfileDoc {
    ProfileDoc {
        base_lon_lat: BASE,
        base_alt_m: 780.0,
        altitude_m: 30.0,
        cruise_speed_mps: 10.0,
        wind_mps: 0.0,
        wind_from_deg: 0.0,
    }
}

/// Stops visiting `cells` in the given order from the base, with legs measured.
fn stops(cells: &[(i64, i64)], exploration: bool) -> (Vec<StopDoc>, f64) {
    let mut prev = (0.0, 0.0);
    let mut out = Vec::new();
    for (k, &(ix, iy)) in cells.iter().enumerate() {
        let c = centre(ix, iy);
        let leg = ((c.0 - prev.0).powi(2) + (c.1 - prev.1).powi(2)).sqrt();
        let sc = scores(ix, iy);
        out.push(StopDoc {
            order: k as u32 + 1,
            cell: cell_id(ix, iy),
            centre_lon_lat: to_lon_lat(c.0, c.1),
            s: if exploration { 0.0 } else { sc.s },
            terms: (!exploration).then_some([sc.f, sc.r, sc.a, sc.u]),
            leg_distance_m: leg,
            leg_energy_j: 17.4 * leg,
            collection_s: 6.0,
            hover_s: 12.0,
            hover_j: 2100.0,
            comm_j: 155.0,
            via_lon_lat: Vec::new(),
        });
        prev = c;
    }
    let back = (prev.0.powi(2) + prev.1.powi(2)).sqrt();
    (out, back)
}

fn mission_doc(
    id: i64,
    kind: &str,
    cells: &[(i64, i64)],
    energy: [f64; 4],
    planned_at: (&str, i64),
) -> MissionDoc {
    let exploration = kind == "exploration";
    let (stops, back) = stops(cells, exploration);
    let total: f64 = energy.iter().sum();
    let budget = 66_500.0;
    let distance = stops.iter().map(|s| s.leg_distance_m).sum::<f64>() + back;
    MissionDoc {
        format: MISSION_FORMAT.into(),
        version: VERSION,
        mission_id: Some(id),
        kind: kind.into(),
        status: "planned".into(),
        planned_at: planned_at.0.into(),
        planned_at_s: planned_at.1,
        flown_at: None,
        planner: if exploration {
            "exploration"
        } else {
            "default"
        }
        .into(),
        seed: 1,
        weights: [0.4, 0.3, 0.2, 0.1],
        anomaly_form: if exploration { "n/a" } else { "raw" }.into(),
        profile: profile(),
        total_score: stops.iter().map(|s| s.s).sum(),
        stops,
        return_distance_m: back,
        energy: EnergyDoc {
            travel_j: energy[0],
            hover_j: energy[1],
            comm_j: energy[2],
            return_j: energy[3],
            total_j: total,
            budget_j: budget,
            utilisation: total / budget,
            distance_m: distance,
            flight_time_s: distance / 10.0 + 12.0 * cells.len() as f64,
        },
        candidates: None,
        greedy_baseline: None,
        energy_model: None,
        continuation: None,
        return_via_lon_lat: Vec::new(),
        zones: Vec::new(),
        unreachable: Vec::new(),
        wind: None,
    }
}

/// The example adaptive mission (#7): the eight cells with the highest S, nearest first,
/// with the paper's energies (total 55,309.8 J, budget 66,500 J, 83.2 %).
pub fn mission() -> MissionDoc {
    let mut ranked: Vec<(i64, i64)> = grid();
    ranked.sort_by(|a, b| scores(b.0, b.1).s.total_cmp(&scores(a.0, a.1).s));
    // The best cells, no two adjacent, so the example route spreads over the field.
    let mut picked: Vec<(i64, i64)> = Vec::new();
    for c in ranked {
        if picked.len() < 8
            && picked
                .iter()
                .all(|p| (p.0 - c.0).abs().max((p.1 - c.1).abs()) >= 2)
        {
            picked.push(c);
        }
    }
    let mut ranked = picked;
    let mut order = Vec::new();
    let mut at = (0.0, 0.0);
    while !ranked.is_empty() {
        let (k, _) = ranked
            .iter()
            .enumerate()
            .map(|(k, &(ix, iy))| {
                let c = centre(ix, iy);
                (k, (c.0 - at.0).powi(2) + (c.1 - at.1).powi(2))
            })
            .fold(
                (0, f64::INFINITY),
                |best, x| if x.1 < best.1 { x } else { best },
            );
        let next = ranked.remove(k);
        at = centre(next.0, next.1);
        order.push(next);
    }
    mission_doc(
        7,
        "adaptive",
        &order,
        [30_412.5, 16_800.0, 1_240.3, 6_857.0],
        ("2014-06-01T12:00:00Z", PLANNED_AT_S),
    )
}

/// The example exploration: three sorties (#1–#3) over bands of columns, each flown as a
/// serpentine, together visiting every cell once.
pub fn exploration() -> Vec<MissionDoc> {
    let cells = grid();
    let bands = [(0, 5), (5, 10), (10, 14)];
    bands
        .iter()
        .enumerate()
        .map(|(k, &(from, to))| {
            let mut order = Vec::new();
            for ix in from..to {
                let mut col: Vec<(i64, i64)> =
                    cells.iter().copied().filter(|c| c.0 == ix).collect();
                if (ix - from) % 2 == 1 {
                    col.reverse();
                }
                order.extend(col);
            }
            let n = order.len() as f64;
            let t = 1_401_580_800 + 3600 * k as i64;
            mission_doc(
                k as i64 + 1,
                "exploration",
                &order,
                [
                    9_000.0 + 1_150.0 * k as f64 + 310.0 * n,
                    2_100.0 * n * 0.4,
                    155.0 * n,
                    2_400.0 + 2_900.0 * k as f64,
                ],
                (&format!("2014-06-01T{:02}:00:00Z", k), t),
            )
        })
        .collect()
}

/// The boundary of the example field's cells as closed rings of `[lon, lat]`.
fn outline() -> Vec<Vec<[f64; 2]>> {
    use std::collections::{BTreeMap, HashSet};
    let cells: HashSet<(i64, i64)> = grid().into_iter().collect();
    let mut edges: BTreeMap<(i64, i64), Vec<(i64, i64)>> = BTreeMap::new();
    for &(i, j) in &cells {
        for (other, a, b) in [
            ((i, j - 1), (i, j), (i + 1, j)),
            ((i + 1, j), (i + 1, j), (i + 1, j + 1)),
            ((i, j + 1), (i + 1, j + 1), (i, j + 1)),
            ((i - 1, j), (i, j + 1), (i, j)),
        ] {
            if !cells.contains(&other) {
                edges.entry(a).or_default().push(b);
            }
        }
    }
    edges.values_mut().for_each(|e| e.sort_unstable());
    let corner = |(i, j): (i64, i64)| {
        let (e, n) = sw_corner(i, j);
        to_lon_lat(e, n)
    };
    let mut rings = Vec::new();
    while let Some((&start, _)) = edges.iter().find(|(_, e)| !e.is_empty()) {
        let mut ring = vec![corner(start)];
        let mut at = start;
        while let Some(next) = edges
            .get_mut(&at)
            .filter(|e| !e.is_empty())
            .map(|e| e.remove(0))
        {
            ring.push(corner(next));
            at = next;
            if at == start {
                break;
            }
        }
        rings.push(ring);
    }
    rings
}

/// The example reconstruction: volumetric water content at 30 cm (m³/m³) on 2014-06-01
/// at noon by kriging of changes, wetter to the north-east; sensors in about two cells of
/// three read within the day, the others estimated with a larger sd.
pub fn reconstruction_map() -> ReconstructionMapDoc {
    let field = field();
    let read = |id: &str| {
        let h: i64 = id.bytes().map(i64::from).sum();
        hash01(h, 17) > 0.33
    };
    let mut sensors = Vec::new();
    for s in &field.sensors {
        let (e, n) = {
            let kx = M_PER_DEG_LAT * BASE[1].to_radians().cos();
            (
                (s.lon_lat[0] - BASE[0]) * kx,
                (s.lon_lat[1] - BASE[1]) * M_PER_DEG_LAT,
            )
        };
        let estimate = 0.18 + 0.12 * (e / 900.0) + 0.05 * (n / 500.0) + 0.02 * (e / 130.0).sin();
        let is_read = read(&s.id);
        sensors.push(MapSensorDoc {
            sensor: s.id.clone(),
            lon_lat: s.lon_lat,
            estimate,
            sd: if is_read {
                0.002
            } else {
                0.008 + 0.012 * hash01(e as i64, n as i64)
            },
            last_reading: Some(
                if is_read {
                    "2014-06-01T00:00:00Z"
                } else {
                    "2014-05-20T00:00:00Z"
                }
                .into(),
            ),
            read: is_read,
        });
    }
    let cells = field
        .cells
        .iter()
        .map(|c| {
            let (ix, iy) = {
                let rest = c.cell.trim_start_matches('x');
                let (i, j) = rest.split_once('y').unwrap_or(("0", "0"));
                (i.parse::<i64>().unwrap_or(0), j.parse::<i64>().unwrap_or(0))
            };
            let prefix = format!("S{ix:02}{iy:02}");
            let mine: Vec<&MapSensorDoc> = sensors
                .iter()
                .filter(|s| s.sensor.starts_with(&prefix))
                .collect();
            let n = mine.len().max(1) as f64;
            MapCellDoc {
                cell: c.cell.clone(),
                ring_lon_lat: c.ring_lon_lat.clone(),
                sensors: mine.iter().map(|s| s.sensor.clone()).collect(),
                mean: mine.iter().map(|s| s.estimate).sum::<f64>() / n,
                sd: (mine.iter().map(|s| s.sd * s.sd).sum::<f64>() / n).sqrt(),
            }
        })
        .collect();
    ReconstructionMapDoc {
        format: RECONSTRUCTION_MAP_FORMAT.into(),
        version: VERSION,
        project: "example farm".into(),
        at: "2014-06-01T12:00:00Z".into(),
        modality: "vw@30cm".into(),
        unit: Some("m3/m3".into()),
        estimator: "changes".into(),
        base_lon_lat: BASE,
        cell_size_m: CELL_M,
        read_within_s: 86_400,
        cells,
        sensors,
        outline_lon_lat: outline(),
    }
}
