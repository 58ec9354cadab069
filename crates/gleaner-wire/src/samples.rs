//! Small hand-built documents for tests, examples and documentation: a six-cell field at
//! roughly the position of the Cook Agronomy Farm (CAF), one adaptive mission over it and one
//! exploration sortie. Numbers are plausible, not computed by the planner.

use crate::{
    CellDoc, EnergyDoc, EnergyModelDoc, FIELD_FORMAT, FieldDoc, MISSION_FORMAT, MissionDoc,
    ProfileDoc, ScoresDoc, SensorDoc, StopDoc, VERSION,
};

/// Base station `[lon, lat]`, WGS84 degrees.
pub const BASE_LON_LAT: [f64; 2] = [-117.082_2, 46.782_5];
/// Base station altitude above mean sea level, m.
pub const BASE_ALT_M: f64 = 790.0;
/// Cell side, m.
pub const CELL_M: f64 = 40.0;

/// Metres per degree of latitude and of longitude at the base (spherical approximation,
/// good to well under a metre over this field).
fn metres_per_deg() -> (f64, f64) {
    let r = 6_371_008.8_f64;
    let k = r * std::f64::consts::PI / 180.0;
    (k, k * BASE_LON_LAT[1].to_radians().cos())
}

/// `[lon, lat]` of the point `east`, `north` metres from the base.
fn at(east: f64, north: f64) -> [f64; 2] {
    let (m_lat, m_lon) = metres_per_deg();
    [
        BASE_LON_LAT[0] + east / m_lon,
        BASE_LON_LAT[1] + north / m_lat,
    ]
}

/// Centre (east, north) of cell `x{i}y{j}`, metres from the base.
fn centre_m(i: i32, j: i32) -> (f64, f64) {
    (100.0 + CELL_M * f64::from(i), 60.0 + CELL_M * f64::from(j))
}

fn cell(i: i32, j: i32, sensors: usize, scores: Option<ScoresDoc>) -> CellDoc {
    let (e, n) = centre_m(i, j);
    let h = CELL_M / 2.0;
    let sw = at(e - h, n - h);
    CellDoc {
        cell: format!("x{i}y{j}"),
        centre_lon_lat: at(e, n),
        ring_lon_lat: vec![sw, at(e + h, n - h), at(e + h, n + h), at(e - h, n + h), sw],
        sensors,
        scores,
    }
}

fn scores(f: f64, r: f64, a: f64, u: f64) -> Option<ScoresDoc> {
    Some(ScoresDoc {
        f,
        r,
        a,
        u,
        s: f + a + u - r,
        computed_at_s: 1_400_000_000,
    })
}

/// The six-cell field `x0y0`..`x2y1` with scores on five cells and seven sensors.
#[must_use]
pub fn field() -> FieldDoc {
    let sensors = [
        (0, 0, 2),
        (1, 0, 1),
        (2, 0, 1),
        (0, 1, 1),
        (1, 1, 1),
        (2, 1, 1),
    ];
    let mut cells = vec![
        cell(0, 0, 2, scores(0.9, 0.2, 1.4, 0.5)),
        cell(1, 0, 1, scores(0.4, 0.7, 0.1, 0.2)),
        cell(2, 0, 1, None),
        cell(0, 1, 1, scores(0.3, 0.8, 0.2, 0.1)),
        cell(1, 1, 1, scores(0.8, 0.3, 0.6, 0.7)),
        cell(2, 1, 1, scores(1.0, 0.1, 2.2, 0.9)),
    ];
    cells.sort_by(|a, b| a.cell.cmp(&b.cell));
    let mut out = Vec::new();
    for (i, j, n) in sensors {
        let (e, nn) = centre_m(i, j);
        for k in 0..n {
            out.push(SensorDoc {
                id: format!("CAF{:03}", 10 * (i + 1) + j * 3 + k),
                lon_lat: at(e - 7.0 + 9.0 * f64::from(k), nn + 5.0),
            });
        }
    }
    out.sort_by(|a, b| a.id.cmp(&b.id));
    FieldDoc {
        format: FIELD_FORMAT.to_string(),
        version: VERSION,
        project: "caf-sample".to_string(),
        cell_size_m: CELL_M,
        base_lon_lat: BASE_LON_LAT,
        cells,
        sensors: out,
        zones: Vec::new(),
    }
}

/// The paper's energy model (what the writers price the files with).
fn paper_model() -> EnergyModelDoc {
    gleaner_energy::FlightEnergyModel {
        power: gleaner_energy::PowerParameters::default(),
        rx_power_w: 0.5,
        linear: None,
        vertical: None,
        usable_budget_j: 66_500.0,
        wind: gleaner_energy::Wind::CALM,
    }
    .into()
}

fn profile() -> ProfileDoc {
    ProfileDoc {
        base_lon_lat: BASE_LON_LAT,
        base_alt_m: BASE_ALT_M,
        altitude_m: 30.0,
        cruise_speed_mps: 10.25,
        wind_mps: 0.0,
        wind_from_deg: 0.0,
    }
}

fn stop(
    order: u32,
    i: i32,
    j: i32,
    s: f64,
    terms: Option<[f64; 4]>,
    leg_m: f64,
    hover_s: f64,
) -> StopDoc {
    let (e, n) = centre_m(i, j);
    StopDoc {
        order,
        cell: format!("x{i}y{j}"),
        centre_lon_lat: at(e, n),
        s,
        terms,
        leg_distance_m: leg_m,
        leg_energy_j: leg_m * 12.34,
        collection_s: hover_s - 30.0,
        hover_s,
        hover_j: hover_s * 168.48,
        comm_j: (hover_s - 30.0) * 0.5,
        via_lon_lat: Vec::new(),
    }
}

fn energy(stops: &[StopDoc], return_m: f64) -> EnergyDoc {
    let travel_j: f64 = stops.iter().map(|s| s.leg_energy_j).sum();
    let hover_j: f64 = stops.iter().map(|s| s.hover_j).sum();
    let comm_j: f64 = stops.iter().map(|s| s.comm_j).sum();
    let return_j = return_m * 12.34;
    let total_j = travel_j + hover_j + comm_j + return_j;
    let distance_m = stops.iter().map(|s| s.leg_distance_m).sum::<f64>() + return_m;
    EnergyDoc {
        travel_j,
        hover_j,
        comm_j,
        return_j,
        total_j,
        budget_j: 66_500.0,
        utilisation: total_j / 66_500.0,
        distance_m,
        flight_time_s: distance_m / 10.25 + stops.iter().map(|s| s.hover_s).sum::<f64>(),
    }
}

/// An adaptive mission (id 7) visiting `x2y1`, `x0y0`, `x1y1`; hover times 30, 34.27 and
/// 30.05 s (holds 30, 34.5 and 30.25 s: rounded up to 0.25 s).
#[must_use]
pub fn adaptive_mission() -> MissionDoc {
    let stops = vec![
        stop(1, 2, 1, 4.0, Some([1.0, 0.1, 2.2, 0.9]), 184.4, 30.0),
        stop(2, 0, 0, 2.6, Some([0.9, 0.2, 1.4, 0.5]), 89.4, 34.27),
        stop(3, 1, 1, 1.8, Some([0.8, 0.3, 0.6, 0.7]), 56.6, 30.05),
    ];
    let total_score = stops.iter().map(|s| s.s).sum();
    let energy = energy(&stops, 172.0);
    MissionDoc {
        format: MISSION_FORMAT.to_string(),
        version: VERSION,
        mission_id: Some(7),
        kind: "adaptive".to_string(),
        status: "planned".to_string(),
        planned_at: "2014-05-14T00:00:00Z".to_string(),
        planned_at_s: 1_400_025_600,
        flown_at: None,
        planner: "default".to_string(),
        seed: 42,
        weights: [1.0, 1.0, 1.0, 1.0],
        anomaly_form: "raw".to_string(),
        profile: profile(),
        stops,
        return_distance_m: 172.0,
        energy,
        total_score,
        candidates: Some(5),
        greedy_baseline: None,
        energy_model: Some(paper_model()),
        continuation: None,
        return_via_lon_lat: Vec::new(),
        zones: Vec::new(),
        unreachable: Vec::new(),
        wind: None,
    }
}

/// An exploration sortie (id 3, scores 0) visiting `x0y0`, `x1y0`, `x2y0`, `x2y1` with 30 s
/// hovers.
#[must_use]
pub fn exploration_sortie() -> MissionDoc {
    let stops = vec![
        stop(1, 0, 0, 0.0, None, 116.6, 30.0),
        stop(2, 1, 0, 0.0, None, 40.0, 30.0),
        stop(3, 2, 0, 0.0, None, 40.0, 30.0),
        stop(4, 2, 1, 0.0, None, 40.0, 30.0),
    ];
    let energy = energy(&stops, 184.4);
    MissionDoc {
        format: MISSION_FORMAT.to_string(),
        version: VERSION,
        mission_id: Some(3),
        kind: "exploration".to_string(),
        status: "planned".to_string(),
        planned_at: "2014-04-01T00:00:00Z".to_string(),
        planned_at_s: 1_396_310_400,
        flown_at: None,
        planner: "exploration".to_string(),
        seed: 0,
        weights: [1.0, 1.0, 1.0, 1.0],
        anomaly_form: "n/a".to_string(),
        profile: profile(),
        stops,
        return_distance_m: 184.4,
        energy,
        total_score: 0.0,
        candidates: None,
        greedy_baseline: None,
        energy_model: Some(paper_model()),
        return_via_lon_lat: Vec::new(),
        zones: Vec::new(),
        unreachable: Vec::new(),
        continuation: None,
        wind: None,
    }
}

/// A continuation of [`adaptive_mission`] re-planned in the air after its first stop: the
/// aircraft over `x2y1` with 40 kJ left (3.5 kJ reserve), the two remaining stops reversed.
#[must_use]
pub fn continuation() -> MissionDoc {
    let parent = adaptive_mission();
    let start = parent.stops[0].centre_lon_lat;
    let mut stops: Vec<StopDoc> = parent.stops[1..].iter().rev().cloned().collect();
    for (k, s) in stops.iter_mut().enumerate() {
        s.order = k as u32 + 1;
    }
    let mut energy = energy(&stops, 89.4);
    energy.budget_j = 36_500.0;
    energy.utilisation = energy.total_j / energy.budget_j;
    MissionDoc {
        status: "continuation".to_string(),
        planner: "replan".to_string(),
        total_score: stops.iter().map(|s| s.s).sum(),
        stops,
        return_distance_m: 89.4,
        energy,
        candidates: None,
        continuation: Some(crate::ContinuationDoc {
            parent_mission_id: 7,
            after_stop: 1,
            start_lon_lat: start,
            energy_left_j: 40_000.0,
            reserve_j: 3_500.0,
        }),
        ..parent
    }
}
