//! Reproduces every value of the shared energy test vectors (relative tolerance 1e-6).
//!
//! The vectors are read from `$GLEANER_TESTVECTORS_DIR/energy.json`, else from
//! `$GLEANER_DATA_DIR/../testvectors/energy.json`, else from the shared directory next to the
//! workspace (`../shared/testvectors`).

use std::path::PathBuf;

use gleaner_energy::{
    Airframe, Battery, CellVisit, CruiseSpeed, EnergyConfig, MissionEnergyModel, PowerModel,
    PowerSource,
};
use gleaner_field::LocalPoint;
use serde_json::Value;

const REL_TOL: f64 = 1e-6;

fn vectors() -> Value {
    let dir = std::env::var_os("GLEANER_TESTVECTORS_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            let data = std::env::var_os("GLEANER_DATA_DIR")
                .map(PathBuf::from)
                .unwrap_or_else(|| {
                    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data"))
                });
            data.join("../testvectors")
        });
    let path = dir.join("energy.json");
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("reading {}: {e}", path.display()));
    serde_json::from_str(&text).expect("energy.json is valid JSON")
}

fn num(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("missing number {key}"))
}

fn check(what: &str, got: f64, expected: f64) {
    let err = (got - expected).abs() / expected.abs().max(f64::MIN_POSITIVE);
    assert!(
        err <= REL_TOL,
        "{what}: got {got}, expected {expected} (relative error {err:e})"
    );
}

fn airframe(v: &Value) -> Airframe {
    let a = &v["airframe"];
    Airframe {
        weight_n: num(a, "W"),
        air_density_kg_m3: num(a, "rho"),
        rotor_radius_m: num(a, "R"),
        rotor_disc_area_m2: num(a, "A"),
        blade_angular_velocity_rad_s: num(a, "Omega"),
        tip_speed_mps: num(a, "U_tip"),
        rotor_solidity: num(a, "s"),
        fuselage_drag_ratio: num(a, "d0"),
        induced_power_correction: num(a, "k"),
        profile_drag_coefficient: num(a, "delta"),
    }
}

#[test]
fn airframe_matches_default() {
    assert_eq!(airframe(&vectors()), Airframe::default());
}

#[test]
fn power_model_values() {
    let v = vectors();
    let m = PowerModel::from_airframe(&airframe(&v)).unwrap();
    check("P0", m.blade_profile_power_w(), num(&v, "P0_W"));
    check("Pi", m.induced_power_w(), num(&v, "Pi_W"));
    check("v0", m.mean_induced_velocity_mps(), num(&v, "v0_mps"));
    check("hover power", m.hover_power_w(), num(&v, "hover_power_W"));
    let speeds = v["power_W_at"]
        .as_object()
        .expect("power_W_at is an object");
    assert!(!speeds.is_empty());
    for (speed, expected) in speeds {
        let speed: f64 = speed.parse().expect("speed key is a number");
        check(
            &format!("P({speed})"),
            m.power_w(speed),
            expected.as_f64().expect("number"),
        );
    }
    let e = m.max_endurance();
    check(
        "max-endurance speed",
        e.speed_mps,
        num(&v, "max_endurance_speed_mps"),
    );
    check(
        "power at max endurance",
        e.power_w,
        num(&v, "power_at_max_endurance_W"),
    );
    let r = m.max_range();
    check(
        "max-range speed",
        r.speed_mps,
        num(&v, "max_range_speed_mps"),
    );
    check(
        "energy per metre at max range",
        r.energy_per_metre_j,
        num(&v, "energy_per_metre_at_max_range_J"),
    );
}

#[test]
fn route_example_breakdown() {
    let v = vectors();
    let r = &v["route_example"];
    let size = num(r, "cell_size_m");
    let hover_s = num(r, "hover_s");
    let config = EnergyConfig {
        power: PowerSource::Airframe(airframe(&v)),
        cruise: CruiseSpeed::Fixed(num(r, "speed_mps")),
        battery: Battery::default(),
        rx_power_w: num(r, "P_rx_W"),
        ..EnergyConfig::paper()
    };
    let model = MissionEnergyModel::new(&config).unwrap();
    let route: Vec<CellVisit> = r["cells_grid_ij"]
        .as_array()
        .expect("cells_grid_ij is an array")
        .iter()
        .map(|ij| {
            let i = ij[0].as_f64().expect("grid i");
            let j = ij[1].as_f64().expect("grid j");
            CellVisit {
                centre: LocalPoint::new((i + 0.5) * size, (j + 0.5) * size),
                hover_s,
            }
        })
        .collect();
    assert_eq!(route.len(), 8);
    let e = model.breakdown(LocalPoint::new(0.0, 0.0), &route).unwrap();
    check("E_t", e.travel_j, num(r, "E_t_J"));
    check("E_h", e.hover_j, num(r, "E_h_J"));
    check("E_c", e.comm_j, num(r, "E_c_J"));
    check("E_r", e.return_j, num(r, "E_r_J"));
    check("total", e.total_j, num(r, "total_J"));
    check("usable budget", e.budget_j, num(r, "usable_budget_J"));
    assert_eq!(
        e.feasible,
        r["feasible"].as_bool().expect("feasible is a bool")
    );
    // The paper preset's budget is the same.
    check(
        "paper budget",
        MissionEnergyModel::new(&EnergyConfig::paper())
            .unwrap()
            .usable_budget_j(),
        num(r, "usable_budget_J"),
    );
}
