//! Unit, snapshot and property tests of the writers.

use proptest::prelude::*;
use serde_json::Value;

use crate::flight::hold_s;
use crate::samples::{adaptive_mission, continuation, exploration_sortie, field};
use crate::*;
use gleaner_energy::{HOLD_STEP_S, flight_speed_mps};

/// Great-circle distance between two `[lon, lat]`, m (haversine, mean Earth radius).
fn dist_m(a: [f64; 2], b: [f64; 2]) -> f64 {
    let r = 6_371_008.8;
    let (p1, p2) = (a[1].to_radians(), b[1].to_radians());
    let dp = p2 - p1;
    let dl = (b[0] - a[0]).to_radians();
    let h = (dp / 2.0).sin().powi(2) + p1.cos() * p2.cos() * (dl / 2.0).sin().powi(2);
    2.0 * r * h.sqrt().min(1.0).asin()
}

/// Equal within 1e-12 relative (serde_json's float parsing is not always exact).
fn close(a: f64, b: f64) -> bool {
    a == b || (a - b).abs() <= 1e-12 * a.abs().max(b.abs())
}

/// (command, frame, params) of every WPL line after the header, params 1..7 as f64.
fn wpl_items(text: &str) -> Vec<(u16, u8, [f64; 7])> {
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("QGC WPL 110"));
    lines
        .enumerate()
        .map(|(k, line)| {
            let f: Vec<&str> = line.split('\t').collect();
            assert_eq!(f.len(), 12, "line {k}: {line}");
            assert_eq!(f[0].parse::<usize>().unwrap(), k);
            let p: Vec<f64> = f[4..11].iter().map(|x| x.parse().unwrap()).collect();
            (
                f[3].parse().unwrap(),
                f[2].parse().unwrap(),
                p.try_into().unwrap(),
            )
        })
        .collect()
}

/// (command, frame, params with null = NaN) of every .plan item.
fn plan_items(text: &str) -> (Value, Vec<(u16, u8, [f64; 7])>) {
    let v: Value = serde_json::from_str(text).unwrap();
    let items = v["mission"]["items"]
        .as_array()
        .unwrap()
        .iter()
        .map(|it| {
            let p: Vec<f64> = it["params"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap_or(f64::NAN))
                .collect();
            (
                it["command"].as_u64().unwrap() as u16,
                it["frame"].as_u64().unwrap() as u8,
                p.try_into().unwrap(),
            )
        })
        .collect();
    (v, items)
}

/// Checks the item list both files share against the mission.
fn check_items(m: &MissionDoc, items: &[(u16, u8, [f64; 7])]) {
    let p = &m.profile;
    assert_eq!(items.len(), m.stops.len() + 3);
    let (c, f, t) = items[0];
    assert_eq!((c, f), (MAV_CMD_NAV_TAKEOFF, MAV_FRAME_GLOBAL_RELATIVE_ALT));
    assert!(dist_m([t[5], t[4]], p.base_lon_lat) < 0.1);
    assert_eq!(t[6], gleaner_energy::flight_altitude_m(p.altitude_m));
    assert!(t[3].is_nan());
    let (c, f, s) = items[1];
    assert_eq!((c, f), (MAV_CMD_DO_CHANGE_SPEED, MAV_FRAME_MISSION));
    assert_eq!(
        [s[0], s[2], s[3], s[4], s[5], s[6]],
        [1.0, -1.0, 0.0, 0.0, 0.0, 0.0]
    );
    assert_eq!(s[1], flight_speed_mps(p.cruise_speed_mps));
    for (stop, &(c, f, w)) in m.stops.iter().zip(&items[2..]) {
        assert_eq!(
            (c, f),
            (MAV_CMD_NAV_WAYPOINT, MAV_FRAME_GLOBAL_RELATIVE_ALT)
        );
        let d = dist_m([w[5], w[4]], stop.centre_lon_lat);
        assert!(d < 0.1, "stop {}: {d} m from its centre", stop.order);
        assert!(
            w[0] >= stop.hover_s,
            "hold {} < hover {}",
            w[0],
            stop.hover_s
        );
        // Exact as a MAVLink float32 too.
        assert_eq!(f64::from(w[0] as f32), w[0]);
        // Rounded up to 0.25 s.
        assert!(
            w[0] < stop.hover_s + HOLD_STEP_S,
            "hold {} for {}",
            w[0],
            stop.hover_s
        );
        assert_eq!((w[1], w[2]), (0.0, 0.0));
        assert!(w[3].is_nan());
        assert_eq!(w[6], gleaner_energy::flight_altitude_m(p.altitude_m));
    }
    let (c, f, r) = items[items.len() - 1];
    assert_eq!(
        (c, f, r),
        (MAV_CMD_NAV_RETURN_TO_LAUNCH, MAV_FRAME_MISSION, [0.0; 7])
    );
}

fn check_files(m: &MissionDoc) {
    let w = wpl_items(&wpl(m).unwrap());
    let (home_c, home_f, home) = w[0];
    assert_eq!((home_c, home_f), (MAV_CMD_NAV_WAYPOINT, MAV_FRAME_GLOBAL));
    assert!(dist_m([home[5], home[4]], m.profile.base_lon_lat) < 0.1);
    assert!(close(home[6], m.profile.base_alt_m));
    check_items(m, &w[1..]);
    let (v, items) = plan_items(&qgc_plan(m).unwrap());
    check_items(m, &items);
    let mission = &v["mission"];
    let speed = flight_speed_mps(m.profile.cruise_speed_mps);
    assert_eq!(mission["cruiseSpeed"].as_f64().unwrap(), speed);
    assert_eq!(mission["hoverSpeed"].as_f64().unwrap(), speed);
    let home = mission["plannedHomePosition"].as_array().unwrap();
    assert!(close(home[2].as_f64().unwrap(), m.profile.base_alt_m));
    assert!(
        dist_m(
            [home[1].as_f64().unwrap(), home[0].as_f64().unwrap()],
            m.profile.base_lon_lat
        ) < 0.1
    );
}

#[test]
fn both_files_command_the_plan() {
    check_files(&adaptive_mission());
    check_files(&exploration_sortie());
}

#[test]
fn holds_round_up_to_a_quarter_second() {
    assert_eq!(hold_s(30.0), 30.0);
    assert_eq!(hold_s(34.27), 34.5);
    assert_eq!(hold_s(30.05), 30.25);
    assert_eq!(hold_s(30.25), 30.25);
    assert_eq!(hold_s(0.0), 0.0);
    assert_eq!(hold_s(1e-12), 0.25);
    for k in 0..10_000 {
        let h = f64::from(k) * 0.01;
        let x = hold_s(h);
        assert!(
            x >= h && f64::from(x as f32) == x && x < h + HOLD_STEP_S,
            "{h} -> {x}"
        );
    }
}

#[test]
fn plan_metadata_states_the_assumptions() {
    let m = adaptive_mission();
    let plan = qgc_plan_doc(&m).unwrap();
    assert_eq!(plan.gleaner, FlightMeta::of(&m));
    assert_eq!(plan.gleaner.mission_id, Some(7));
    assert_eq!(plan.gleaner.energy.total_j, m.energy.total_j);
    assert_eq!(plan.gleaner.cruise_speed_mps, 10.25);
    let text = qgc_plan(&m).unwrap();
    let v: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["gleaner"]["energy"]["budget_j"].as_f64(), Some(66_500.0));
    assert_eq!(v["geoFence"]["version"], 2);
    assert_eq!(v["rallyPoints"]["version"], 2);
    let notes = flight_notes(&m).unwrap();
    assert!(notes.contains("mission #7"), "{notes}");
    assert!(notes.contains("10.25 m/s"), "{notes}");
    assert!(notes.contains("commanded energy: "), "{notes}");
}

#[test]
fn geojson_has_every_cell_route_base_and_sensors() {
    let (f, m) = (field(), adaptive_mission());
    let fc = geojson_doc(&f, &m).unwrap();
    let kinds: Vec<&str> = fc
        .features
        .iter()
        .map(|x| x.properties.as_ref().unwrap()["kind"].as_str().unwrap())
        .collect();
    let count = |k: &str| kinds.iter().filter(|x| **x == k).count();
    assert_eq!(count("cell"), f.cells.len());
    assert_eq!(count("route"), 1);
    assert_eq!(count("stop"), m.stops.len());
    assert_eq!(count("base"), 1);
    assert_eq!(count("sensor"), f.sensors.len());
    let v: Value = serde_json::from_str(&geojson(&f, &m).unwrap()).unwrap();
    assert_eq!(v["type"], "FeatureCollection");
    assert!(v.get("crs").is_none());
    assert_eq!(v["gleaner"]["kind"], "adaptive");
    assert_eq!(v["gleaner"]["anomaly_form"], "raw");
    for feat in v["features"].as_array().unwrap() {
        if feat["properties"]["kind"] == "cell" {
            let ring: Vec<[f64; 2]> =
                serde_json::from_value(feat["geometry"]["coordinates"][0].clone()).unwrap();
            assert_eq!(ring.first(), ring.last());
            let area2: f64 = ring
                .windows(2)
                .map(|w| w[0][0] * w[1][1] - w[1][0] * w[0][1])
                .sum();
            assert!(area2 > 0.0, "clockwise ring {ring:?}");
            let cell = feat["properties"]["cell"].as_str().unwrap();
            let order = m.stops.iter().find(|s| s.cell == cell).map(|s| s.order);
            assert_eq!(
                feat["properties"]["visit_order"].as_u64(),
                order.map(u64::from)
            );
        }
        if feat["properties"]["kind"] == "route" {
            let line = feat["geometry"]["coordinates"].as_array().unwrap();
            assert_eq!(line.len(), m.stops.len() + 2);
        }
    }
}

#[test]
fn clockwise_rings_are_reversed() {
    let (mut f, m) = (field(), adaptive_mission());
    f.cells[0].ring_lon_lat.reverse();
    let v: Value = serde_json::from_str(&geojson(&f, &m).unwrap()).unwrap();
    let ring: Vec<[f64; 2]> =
        serde_json::from_value(v["features"][0]["geometry"]["coordinates"][0].clone()).unwrap();
    let area2: f64 = ring
        .windows(2)
        .map(|w| w[0][0] * w[1][1] - w[1][0] * w[0][1])
        .sum();
    assert!(area2 > 0.0);
}

/// Every flight-file writer refuses the mission with the same error kind.
fn refused(m: &MissionDoc, is: impl Fn(&ExportError) -> bool) {
    for (name, r) in [
        ("check", check_flyable(m).map(|()| String::new())),
        ("plan", qgc_plan(m)),
        ("wpl", wpl(m)),
        ("notes", flight_notes(m)),
    ] {
        match r {
            Err(e) => assert!(is(&e), "{name}: unexpected error {e}"),
            Ok(_) => panic!("{name}: written"),
        }
    }
}

#[test]
fn refuses_over_budget_and_non_finite_energy() {
    let mut m = adaptive_mission();
    m.energy.total_j = m.energy.budget_j + 0.01;
    refused(&m, |e| matches!(e, ExportError::OverBudget { .. }));
    m.energy.total_j = f64::NAN;
    refused(&m, |e| matches!(e, ExportError::OverBudget { .. }));
    m.energy.total_j = 1.0;
    m.energy.budget_j = f64::INFINITY;
    refused(&m, |e| matches!(e, ExportError::OverBudget { .. }));
    // At the budget exactly is feasible.
    m.energy.budget_j = 1.0;
    assert!(check_flyable(&m).is_ok());
    // The CAF mission at 5 m/s: ~87 kJ against 66.5 kJ.
    let mut m = adaptive_mission();
    m.energy.total_j = 87_000.0;
    let e = wpl(&m).unwrap_err();
    assert!(e.to_string().contains("87000 J exceeds"), "{e}");
}

/// The energy of what the files command, J, with a battery too large to refuse it.
fn commanded_j(m: &MissionDoc) -> f64 {
    let mut big = m.clone();
    big.energy.budget_j = 1e12;
    if let Some(model) = &mut big.energy_model {
        model.usable_budget_j = 1e12;
    }
    check_commanded(&big, "test", &commanded_flight(&big).unwrap()).unwrap()
}

/// A mission planned within the budget whose files would command more is refused by every
/// writer, naming the file and both energies; at the budget exactly it is written.
#[test]
fn refuses_files_that_command_more_than_the_budget() {
    let m = adaptive_mission();
    let commanded = commanded_j(&m);
    // The holds are rounded up (34.27 -> 34.5 s, 30.05 -> 30.25 s): more than the hovers.
    let hovers: f64 = m.stops.iter().map(|s| s.hover_s).sum();
    let holds: f64 = m.stops.iter().map(|s| hold_s(s.hover_s)).sum();
    assert!(holds - hovers > 0.4, "{hovers} {holds}");
    let mut tight = m.clone();
    tight.energy.total_j = commanded - 50.0;
    tight.energy.budget_j = commanded - 0.001;
    assert!(check_flyable(&tight).is_ok());
    for (file, r) in [(PLAN_FILE, qgc_plan(&tight)), (WPL_FILE, wpl(&tight))] {
        let e = r.unwrap_err();
        assert!(
            matches!(&e, ExportError::CommandedOverBudget { file: f, .. } if f == file),
            "{e}"
        );
        let text = e.to_string();
        assert!(
            text.starts_with(file) && text.contains("recomputed"),
            "{text}"
        );
    }
    assert!(flight_notes(&tight).is_err());
    // The model's own budget counts too.
    let mut tight = m.clone();
    if let Some(model) = &mut tight.energy_model {
        model.usable_budget_j = commanded - 0.001;
    }
    assert!(matches!(
        wpl(&tight),
        Err(ExportError::CommandedOverBudget { .. })
    ));
    // At the budget exactly: written.
    let mut exact = m.clone();
    exact.energy.budget_j = commanded;
    exact.energy.total_j = commanded;
    assert!(qgc_plan(&exact).is_ok() && wpl(&exact).is_ok());
    // Without an energy model nothing can be priced: refused.
    let mut none = m;
    none.energy_model = None;
    for r in [qgc_plan(&none), wpl(&none), flight_notes(&none)] {
        assert!(matches!(r, Err(ExportError::NoEnergyModel)));
    }
}

/// What the files command is the rounded plan: speed 10.25 m/s, holds on 0.25 s, positions
/// on 1e-7 degrees, read back identically from both files.
#[test]
fn files_read_back_as_commanded() {
    for m in [adaptive_mission(), exploration_sortie()] {
        let c = commanded_flight(&m).unwrap();
        assert_eq!(c.speed_mps, 10.25);
        assert_eq!(c.altitude_m, 30.0);
        for ((p, hold), s) in c.waypoints.iter().zip(&m.stops) {
            assert_eq!(*hold, hold_s(s.hover_s));
            assert_eq!(p.lat(), gleaner_energy::flight_degrees(s.centre_lon_lat[1]));
        }
        assert_eq!(parse_qgc_plan(&qgc_plan(&m).unwrap()).unwrap(), c);
        assert_eq!(parse_wpl(&wpl(&m).unwrap()).unwrap(), c);
    }
}

/// A continuation's files have no take-off: both read back as the same airborne flight from a
/// 0 s first waypoint where the aircraft is, priced without a climb and against the energy
/// left less the reserve; a file above that is refused, and there is no DJI form.
#[test]
fn a_continuation_flies_from_the_air() {
    let m = continuation();
    let c = commanded_flight(&m).unwrap();
    assert!(c.airborne);
    assert_eq!(c.waypoints.len(), m.stops.len() + 1);
    let start = m.continuation.unwrap().start_lon_lat;
    assert_eq!(c.waypoints[0].1, 0.0);
    assert_eq!(
        c.waypoints[0].0.lon(),
        gleaner_energy::flight_degrees(start[0])
    );
    assert_eq!(parse_qgc_plan(&qgc_plan(&m).unwrap()).unwrap(), c);
    let text = wpl(&m).unwrap();
    assert_eq!(parse_wpl(&text).unwrap(), c);
    assert!(
        wpl_items(&text)
            .iter()
            .all(|it| it.0 != flight::MAV_CMD_NAV_TAKEOFF)
    );
    // Priced as the energy model prices a continuation: from the aircraft through the stops.
    let e = m
        .energy_model
        .unwrap()
        .to_core()
        .energy(
            gleaner_field::LatLon::new(m.profile.base_lon_lat[1], m.profile.base_lon_lat[0])
                .unwrap(),
            &c,
        )
        .unwrap();
    assert_eq!(e.legs.len(), m.stops.len() + 1);
    assert_eq!(commanded_j(&m), e.total_j);
    let mut short = continuation();
    short.energy.budget_j = e.total_j - 1.0;
    short.energy.total_j = short.energy.budget_j - 1.0;
    for r in [qgc_plan(&short), wpl(&short)] {
        assert!(
            matches!(r, Err(ExportError::CommandedOverBudget { .. })),
            "{r:?}"
        );
    }
    assert!(wpml_kmz(&m, WpmlOptions::default()).is_err());
    // The geometry starts where the aircraft is.
    let g: Value = serde_json::from_str(&geojson(&field(), &m).unwrap()).unwrap();
    let route = g["features"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["id"] == "route")
        .unwrap();
    let first = &route["geometry"]["coordinates"][0];
    let lon_lat = [first[0].as_f64().unwrap(), first[1].as_f64().unwrap()];
    assert!(dist_m(lon_lat, start) < 0.01, "{lon_lat:?} {start:?}");
}

/// Broken files are errors naming the file and line, never panics.
#[test]
fn unreadable_files_are_errors() {
    let text = wpl(&adaptive_mission()).unwrap();
    for (broken, says) in [
        (String::new(), "QGC WPL 110"),
        ("QGC WPL 110\n".to_string(), "no home line"),
        (text.replace("\t178\t1\t", "\t178\t0\t"), "ground speed"),
        (text.replace("\t20\t", "\t21\t"), "unexpected command 21"),
        (
            text.replacen("\t30\t1\n", "\t31\t1\n", 2),
            "differs from take-off",
        ),
        (text.replace("nan", "x"), "is not a number"),
        (
            text.lines().take(4).collect::<Vec<_>>().join("\n"),
            "return to launch",
        ),
    ] {
        let e = parse_wpl(&broken).unwrap_err().to_string();
        assert!(e.contains(WPL_FILE) && e.contains(says), "{says}: {e}");
    }
    assert!(parse_qgc_plan("{").is_err());
    let plan = qgc_plan(&adaptive_mission()).unwrap();
    let e = parse_qgc_plan(&plan.replace("\"hoverSpeed\": 10.25", "\"hoverSpeed\": 5.0"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("hoverSpeed"), "{e}");
}

#[test]
fn refuses_bad_altitude_speed_and_hover() {
    for alt in [0.0, -1.0, 120.01, f64::NAN, f64::INFINITY] {
        let mut m = exploration_sortie();
        m.profile.altitude_m = alt;
        refused(&m, |e| matches!(e, ExportError::Altitude { .. }));
    }
    let mut m = exploration_sortie();
    m.profile.altitude_m = 120.0;
    assert!(check_flyable(&m).is_ok());
    for v in [0.0, -3.0, f64::NAN, f64::INFINITY] {
        let mut m = adaptive_mission();
        m.profile.cruise_speed_mps = v;
        refused(&m, |e| matches!(e, ExportError::CruiseSpeed { .. }));
    }
    for h in [-0.1, f64::NAN, f64::INFINITY, MAX_HOVER_S + 1.0] {
        let mut m = adaptive_mission();
        m.stops[1].hover_s = h;
        refused(&m, |e| matches!(e, ExportError::HoverTime { order: 2, .. }));
    }
    let mut m = adaptive_mission();
    m.profile.base_alt_m = f64::NAN;
    refused(&m, |e| matches!(e, ExportError::BaseAltitude { .. }));
}

#[test]
fn refuses_bad_positions_documents_and_empty_missions() {
    for (lon, lat) in [
        (0.0, 90.5),
        (180.5, 0.0),
        (f64::NAN, 0.0),
        (0.0, f64::NEG_INFINITY),
    ] {
        let mut m = adaptive_mission();
        m.stops[2].centre_lon_lat = [lon, lat];
        refused(&m, |e| matches!(e, ExportError::Coordinate { .. }));
        assert!(matches!(
            geojson(&field(), &m),
            Err(ExportError::Coordinate { .. })
        ));
        let mut m = adaptive_mission();
        m.profile.base_lon_lat = [lon, lat];
        refused(&m, |e| matches!(e, ExportError::Coordinate { .. }));
        let mut f = field();
        f.sensors[0].lon_lat = [lon, lat];
        assert!(matches!(
            geojson(&f, &adaptive_mission()),
            Err(ExportError::Coordinate { .. })
        ));
    }
    let mut m = adaptive_mission();
    m.stops.clear();
    refused(&m, |e| matches!(e, ExportError::NoStops));
    let mut m = adaptive_mission();
    m.version = 2;
    refused(&m, |e| matches!(e, ExportError::UnsupportedDocument { .. }));
    let mut m = adaptive_mission();
    m.format = FIELD_FORMAT.to_string();
    refused(&m, |e| matches!(e, ExportError::UnsupportedDocument { .. }));
}

#[test]
fn geojson_refuses_bad_rings_and_unknown_cells() {
    let m = adaptive_mission();
    let mut f = field();
    f.cells[0].ring_lon_lat.pop();
    assert!(matches!(geojson(&f, &m), Err(ExportError::Ring { .. })));
    let mut f = field();
    f.cells[1].ring_lon_lat.truncate(3);
    assert!(matches!(geojson(&f, &m), Err(ExportError::Ring { .. })));
    let mut f = field();
    let p = f.cells[2].ring_lon_lat[0];
    f.cells[2].ring_lon_lat = vec![p; 5];
    assert!(matches!(geojson(&f, &m), Err(ExportError::Ring { .. })));
    let mut f = field();
    f.cells.retain(|c| c.cell != "x0y0");
    assert!(matches!(
        geojson(&f, &m),
        Err(ExportError::UnknownCell { order: 2, .. })
    ));
    // A map is not a flight file: an over-budget mission still maps.
    let mut m = adaptive_mission();
    m.energy.total_j = 1e9;
    assert!(geojson(&field(), &m).is_ok());
}

#[test]
fn snapshots() {
    let f = field();
    for (name, m) in [
        ("adaptive", adaptive_mission()),
        ("exploration", exploration_sortie()),
    ] {
        insta::assert_snapshot!(format!("{name}.plan"), qgc_plan(&m).unwrap());
        insta::assert_snapshot!(format!("{name}.waypoints"), wpl(&m).unwrap());
        insta::assert_snapshot!(format!("{name}.geojson"), geojson(&f, &m).unwrap());
        insta::assert_snapshot!(format!("{name}.notes"), flight_notes(&m).unwrap());
    }
}

/// A flyable mission with `n` stops at arbitrary positions and hover times.
fn arb_mission() -> impl Strategy<Value = MissionDoc> {
    (
        (-179.99..179.99f64, -89.0..89.0f64),
        prop::collection::vec(((-0.02..0.02f64, -0.02..0.02f64), 0.0..3_600.0f64), 1..12),
        0.5..120.0f64,
        0.1..40.0f64,
        -400.0..5_000.0f64,
    )
        .prop_map(|((lon, lat), stops, alt, speed, base_alt)| {
            let mut m = adaptive_mission();
            // A battery for any of these flights: this test is about positions and holds.
            m.energy.budget_j = 1e12;
            if let Some(model) = &mut m.energy_model {
                model.usable_budget_j = 1e12;
            }
            m.profile.base_lon_lat = [lon, lat];
            m.profile.altitude_m = alt;
            m.profile.cruise_speed_mps = speed;
            m.profile.base_alt_m = base_alt;
            let template = m.stops[0].clone();
            m.stops = stops
                .into_iter()
                .enumerate()
                .map(|(k, ((de, dn), hover))| StopDoc {
                    order: k as u32 + 1,
                    cell: format!("x{k}y0"),
                    centre_lon_lat: [
                        (lon + de).clamp(-180.0, 180.0),
                        (lat + dn).clamp(-90.0, 90.0),
                    ],
                    hover_s: hover,
                    ..template.clone()
                })
                .collect();
            m
        })
}

/// Any f64, weighted towards the values that break writers.
fn any_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(f64::NAN),
        Just(f64::INFINITY),
        Just(f64::NEG_INFINITY),
        Just(0.0),
        Just(-0.0),
        Just(f64::MAX),
        Just(f64::MIN_POSITIVE),
        -1e3..1e3f64,
        any::<f64>(),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// Waypoints are within 0.1 m of their cell centres and holds are >= hover_s (< +0.1 s),
    /// in both files.
    #[test]
    fn waypoints_at_centres_and_holds_cover_hovers(m in arb_mission()) {
        check_files(&m);
    }

    /// Reading back any text never panics.
    #[test]
    fn reading_any_text_never_panics(text in ".{0,400}", cut in 0usize..2_000) {
        let _ = parse_wpl(&text);
        let _ = parse_qgc_plan(&text);
        let w = wpl(&adaptive_mission()).unwrap();
        // ASCII: any cut is a char boundary.
        let _ = parse_wpl(&w[..cut.min(w.len())]);
    }

    /// Both files read back exactly what the writer commands, for any flyable mission.
    #[test]
    fn files_read_back_what_is_commanded(m in arb_mission()) {
        let c = commanded_flight(&m).unwrap();
        prop_assert_eq!(parse_qgc_plan(&qgc_plan(&m).unwrap()).unwrap(), c.clone());
        prop_assert_eq!(parse_wpl(&wpl(&m).unwrap()).unwrap(), c);
    }

    /// No input panics: every writer returns a file or an error, and a file only for a mission
    /// that passes the checks.
    #[test]
    fn no_panics(
        alt in any_f64(), speed in any_f64(), hover in any_f64(), base_alt in any_f64(),
        lon in any_f64(), lat in any_f64(), total in any_f64(), budget in any_f64(),
    ) {
        let mut m = adaptive_mission();
        m.profile.altitude_m = alt;
        m.profile.cruise_speed_mps = speed;
        m.profile.base_alt_m = base_alt;
        m.stops[0].hover_s = hover;
        m.stops[1].centre_lon_lat = [lon, lat];
        m.energy.total_j = total;
        m.energy.budget_j = budget;
        let ok = check_flyable(&m).is_ok();
        // A file only for a mission that passes the checks; the three writers agree; a
        // checked mission is refused only for what its files command.
        let plan = qgc_plan(&m);
        prop_assert!(ok || plan.is_err());
        prop_assert_eq!(wpl(&m).is_ok(), plan.is_ok());
        prop_assert_eq!(flight_notes(&m).is_ok(), plan.is_ok());
        match plan {
            Ok(_) => check_files(&m),
            Err(e) if ok => prop_assert!(
                matches!(e, ExportError::CommandedOverBudget { .. } | ExportError::FileValue { .. }),
                "{e}"
            ),
            Err(_) => {}
        }
        let mut f = field();
        f.cells[0].ring_lon_lat[1] = [lon, lat];
        let _ = geojson(&f, &m);
    }
}

/// A two-sensor reconstruction: one read at the estimation time, one never read.
fn reconstruction_sample() -> gleaner_app::Reconstruction {
    use gleaner_app::{Estimator, Reconstruction, SensorEstimate};
    use gleaner_field::{LatLon, SensorId};
    use gleaner_kriging::{Covariance, FieldModel, IncrementModel, Variogram};
    let v = |nugget, partial, scale_s| Variogram {
        nugget,
        partial,
        scale_s,
    };
    Reconstruction {
        at: 1_393_632_000, // 2014-03-01
        modality: "vw@30cm".into(),
        model: FieldModel {
            covariance: Covariance::new(3.3e-3, 9.6e-4, 9_946.0, 9.75e6).unwrap(),
            means: vec![0.25, 0.30],
        },
        changes: IncrementModel::new(v(1e-5, 2e-4, 5e5), 97_369.0, v(2e-5, 3e-4, 4e5)).unwrap(),
        dynamic: None,
        estimator: Estimator::Changes,
        step_s: 86_400,
        sensors: vec![
            SensorEstimate {
                sensor: SensorId::new("CAF003").unwrap(),
                position: LatLon::new(46.778784, -117.086666).unwrap(),
                last_time: Some(1_393_632_000),
                carried: 0.312,
                kriged: 0.312,
                variance: 0.0,
                half90: 0.0,
            },
            SensorEstimate {
                sensor: SensorId::new("CAF007").unwrap(),
                position: LatLon::new(46.778623, -117.084989).unwrap(),
                last_time: None,
                carried: 0.30,
                kriged: 0.287,
                variance: 4e-4,
                half90: 0.0329,
            },
        ],
    }
}

#[test]
fn reconstruction_document() {
    let doc = crate::convert::reconstruction(&reconstruction_sample());
    assert_eq!(doc.format, RECONSTRUCTION_FORMAT);
    // [lon, lat], sd = √variance, never read = no time.
    assert_eq!(doc.sensors[0].lon_lat, [-117.086666, 46.778784]);
    assert!((doc.sensors[1].sd - 0.02).abs() < 1e-15);
    assert_eq!(doc.sensors[1].last_reading, None);
    let text = serde_json::to_string_pretty(&doc).unwrap();
    let back: docs::ReconstructionDoc = serde_json::from_str(&text).unwrap();
    assert_eq!(back, doc);
    insta::assert_snapshot!("reconstruction.json", text);
}

#[test]
fn reconstruction_map_document() {
    use gleaner_app::{MapCell, ReconstructionMap};
    use gleaner_field::{CellIndex, LatLon};
    let r = reconstruction_sample();
    let p = |lat, lon| LatLon::new(lat, lon).unwrap();
    let corners = [
        p(46.7787, -117.0868),
        p(46.7787, -117.0863),
        p(46.7791, -117.0863),
        p(46.7791, -117.0868),
    ];
    let map = ReconstructionMap {
        project: "caf".into(),
        unit: Some("m3/m3".into()),
        base: p(46.7782, -117.0875),
        cell_size_m: 40.0,
        cells: vec![MapCell {
            index: CellIndex { i: 2, j: 1 },
            corners,
            sensors: vec![0, 1],
            mean: 0.2995,
            sd: (2e-4f64).sqrt(),
        }],
        read: vec![true, false],
        read_within_s: 86_400,
        outline: vec![corners.iter().chain(&corners[..1]).copied().collect()],
        reconstruction: r,
    };
    let doc = crate::convert::reconstruction_map(&map);
    assert_eq!(doc.format, crate::RECONSTRUCTION_MAP_FORMAT);
    assert_eq!(doc.cells[0].cell, "x2y1");
    assert_eq!(doc.cells[0].sensors, ["CAF003", "CAF007"]);
    assert_eq!(doc.cells[0].ring_lon_lat.len(), 5);
    assert_eq!(doc.cells[0].ring_lon_lat[0], doc.cells[0].ring_lon_lat[4]);
    assert!(doc.sensors[0].read && !doc.sensors[1].read);
    assert!((doc.sensors[1].sd - 0.02).abs() < 1e-15);
    assert_eq!(doc.outline_lon_lat[0].len(), 5);
    let text = serde_json::to_string_pretty(&doc).unwrap();
    let back: docs::ReconstructionMapDoc = serde_json::from_str(&text).unwrap();
    assert_eq!(back, doc);
}
