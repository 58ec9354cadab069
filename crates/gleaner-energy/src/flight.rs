//! What a flight file can command, and the energy of exactly that.
//!
//! A flight file cannot carry every value the planner computes: autopilots hold for a number
//! of seconds written with a few decimals, fly at a commanded speed, and store positions as
//! `int32` degrees × 10⁷. If the planner priced the unrounded values and the file wrote
//! rounded ones, the file would command more energy than was checked. So the values are put
//! on the files' grid *before* planning, and every writer recomputes the energy from the
//! values it wrote ([`FlightEnergyModel::energy`]):
//!
//! - hold times: rounded **up** to [`HOLD_STEP_S`] (0.25 s), so the aircraft hovers at least
//!   as long as the collection needs ([`flight_hold_s`]);
//! - the cruise ground speed: rounded to the nearest [`SPEED_STEP_MPS`] (0.25 m/s)
//!   ([`flight_speed_mps`]);
//! - the flight altitude above home: rounded to the nearest [`ALTITUDE_STEP_M`] (0.25 m;
//!   [`flight_altitude_m`], applied to the `[energy]` altitude before the model is built);
//! - positions: latitude and longitude rounded to [`COORDINATE_STEP_DEG`] (1e-7 degrees, at
//!   most 5.6 mm off; [`flight_position`]).
//!
//! Multiples of 0.25 are exact in binary, as `f64` and as the MAVLink `float32` the autopilot
//! receives, and print as short decimals, so the value in a file, the value parsed back from
//! it and the value on board are the same number. Every energy-relevant value then prints
//! with at most 15 significant digits, which any correctly rounding decimal parser (and
//! serde_json's fast path) reads back exactly.

use gleaner_field::{LatLon, LocalPoint, TransverseMercator};

use crate::config::{
    Battery, CruiseSpeed, EnergyConfig, LinearEnergy, PowerSource, VerticalConfig,
};
use crate::error::{EnergyError, non_negative, positive};
use crate::link::{DataLogging, HoverConfig, LinkConfig};
use crate::mission::{CellService, CellVisit, MissionEnergy, MissionEnergyModel};
use crate::propulsion::PowerParameters;
use crate::wind::Wind;

/// Resolution of a commanded hold time, s. Exact in binary (`f64` and `float32`).
pub const HOLD_STEP_S: f64 = 0.25;
/// Resolution of the commanded cruise ground speed, m/s. Exact in binary.
pub const SPEED_STEP_MPS: f64 = 0.25;
/// Resolution of a commanded latitude or longitude, degrees (MAVLink `int32` degE7).
pub const COORDINATE_STEP_DEG: f64 = 1e-7;
/// Resolution of the commanded flight altitude above home, m. Exact in binary.
pub const ALTITUDE_STEP_M: f64 = 0.25;

/// The hold a file commands for a hover of `hover_s` seconds: the smallest multiple of
/// [`HOLD_STEP_S`] that is >= `hover_s`, s. Exact arithmetic (×4, ceil, ÷4), so the result is
/// never below `hover_s`. Non-finite or negative input is returned unchanged (the writers and
/// the energy model refuse it), and so is a value too large to round.
pub fn flight_hold_s(hover_s: f64) -> f64 {
    if !(hover_s.is_finite() && hover_s >= 0.0) {
        return hover_s;
    }
    let hold = (hover_s / HOLD_STEP_S).ceil() * HOLD_STEP_S;
    if hold.is_finite() { hold } else { hover_s }
}

/// The cruise ground speed a file commands for a planned speed of `speed_mps` (m/s): the
/// nearest multiple of [`SPEED_STEP_MPS`], at least one step, m/s. Non-finite or non-positive
/// input is returned unchanged (refused downstream), and so is a value too large to round.
pub fn flight_speed_mps(speed_mps: f64) -> f64 {
    if !(speed_mps.is_finite() && speed_mps > 0.0) {
        return speed_mps;
    }
    let speed = ((speed_mps / SPEED_STEP_MPS).round() * SPEED_STEP_MPS).max(SPEED_STEP_MPS);
    if speed.is_finite() { speed } else { speed_mps }
}

/// The flight altitude above home a file commands for `altitude_m` (m): the nearest multiple
/// of [`ALTITUDE_STEP_M`], at least one step. Non-finite or non-positive input (refused
/// downstream) and values too large to round are returned unchanged.
pub fn flight_altitude_m(altitude_m: f64) -> f64 {
    if !(altitude_m.is_finite() && altitude_m > 0.0) {
        return altitude_m;
    }
    let alt = ((altitude_m / ALTITUDE_STEP_M).round() * ALTITUDE_STEP_M).max(ALTITUDE_STEP_M);
    if alt.is_finite() { alt } else { altitude_m }
}

/// A latitude or longitude as a file commands it: rounded to [`COORDINATE_STEP_DEG`],
/// degrees. `round(x·10⁷)/10⁷` is the `f64` nearest the decimal with 7 places, so printing it
/// with 7 decimals and parsing that back gives the same number.
pub fn flight_degrees(x: f64) -> f64 {
    (x * 1e7).round() / 1e7
}

/// A WGS84 position as a file commands it (both coordinates rounded by [`flight_degrees`]).
pub fn flight_position(p: LatLon) -> LatLon {
    // Rounding a valid position to 1e-7 degrees keeps it in [-90, 90] x [-180, 180].
    LatLon::new(flight_degrees(p.lat()), flight_degrees(p.lon())).unwrap_or(p)
}

/// Where a file's positions lie in the planner's local frame: `frame.forward` of the rounded
/// position, metres. The planner prices these points, the writers recompute with them.
pub fn flight_point(frame: &TransverseMercator, p: LatLon) -> LocalPoint {
    frame.forward(flight_position(p))
}

/// A flight as a file commands it, in the file's own values: home, altitude, speed and the
/// waypoints with their holds. The input of [`FlightEnergyModel::energy`].
#[derive(Debug, Clone, PartialEq)]
pub struct CommandedFlight {
    /// Home (take-off and return-to-launch position), WGS84.
    pub home: LatLon,
    /// Flight altitude above home, m.
    pub altitude_m: f64,
    /// Commanded cruise ground speed, m/s.
    pub speed_mps: f64,
    /// Waypoints in flying order: position (WGS84) and hold time (s).
    pub waypoints: Vec<(LatLon, f64)>,
    /// A continuation flown from the air (no take-off item): the aircraft is at the first
    /// waypoint at the flight altitude when the file starts; no take-off and no climb.
    pub airborne: bool,
}

/// The parameters that price a commanded flight: the power curve, the receiver power, the
/// optional linear and climb/descent models and the usable budget. Everything else the
/// energy of a flight depends on — speed, altitude, positions, holds — is read from the
/// flight itself. Plain data, so a document can carry it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlightEnergyModel {
    /// The level-flight power curve P(V) (P0 W, Pi W, v0 m/s, U_tip m/s, d0·rho·s·A kg/m, W N).
    pub power: PowerParameters,
    /// Receiver power while hovering, W.
    pub rx_power_w: f64,
    /// The linear model (J/m, J per cell) in place of the physical one, if used.
    pub linear: Option<LinearEnergy>,
    /// Climb and descent rates (m/s), if their energy is modelled.
    pub vertical: Option<VerticalConfig>,
    /// Usable battery energy, J.
    pub usable_budget_j: f64,
    /// The steady wind the flight was planned in (the forecast plus the planning margin;
    /// [`Wind::CALM`] for a still-air plan): the writers price the file in it.
    pub wind: Wind,
}

impl FlightEnergyModel {
    /// The mission energy model flying at `speed_mps` (m/s) and `altitude_m` (m above home)
    /// in [`FlightEnergyModel::wind`] with these parameters — built by
    /// [`MissionEnergyModel::new`] and [`MissionEnergyModel::with_wind`] themselves, so a
    /// route priced by the planner at the same speed, altitude and wind gets the same joules
    /// to the last bit.
    ///
    /// # Errors
    /// [`EnergyError::InvalidParameter`] for a parameter out of range (speed, altitude,
    /// power curve, budget).
    pub fn model(
        &self,
        speed_mps: f64,
        altitude_m: f64,
    ) -> Result<MissionEnergyModel, EnergyError> {
        positive("commanded speed (m/s)", speed_mps)?;
        positive("usable budget (J)", self.usable_budget_j)?;
        non_negative("receiver power (W)", self.rx_power_w)?;
        let config = EnergyConfig {
            power: PowerSource::Parameters(self.power),
            cruise: CruiseSpeed::Fixed(speed_mps),
            battery: Battery {
                capacity_j: self.usable_budget_j,
                reserve_fraction: 0.0,
            },
            link: LinkConfig {
                altitude_m,
                ..LinkConfig::default()
            },
            logging: DataLogging::default(),
            hover: HoverConfig::default(),
            rx_power_w: self.rx_power_w,
            vertical: self.vertical,
            linear: self.linear,
        };
        crate::wind::Wind::new(self.wind.speed_mps, self.wind.from_deg)?;
        Ok(MissionEnergyModel::new(&config)?.with_wind_up_to(self.wind))
    }

    /// The energy breakdown of `flight` as commanded: from its home through its waypoints and
    /// back, at its speed and altitude, hovering its holds; positions projected into
    /// `TransverseMercator::local(origin)` (the planner's frame: the project's base station).
    /// A waypoint holding exactly 0 s is a turn point of a detour around a no-fly zone (a
    /// stop always holds at least [`HOLD_STEP_S`]): it belongs to the leg to the next stop (or
    /// to the return leg), priced by [`MissionEnergyModel::breakdown_paths`] as the planner
    /// priced it; a flight of turn points only is priced as stops. An
    /// [`CommandedFlight::airborne`] flight starts at its first waypoint in the air
    /// ([`MissionEnergyModel::continuation_paths`]: no take-off, descent only). Compare
    /// `total_j` with the budget the flight was planned against (`usable_budget_j`, or for a
    /// continuation the energy left less the reserve).
    ///
    /// # Errors
    /// As [`FlightEnergyModel::model`]; negative or non-finite holds.
    pub fn energy(
        &self,
        origin: LatLon,
        flight: &CommandedFlight,
    ) -> Result<MissionEnergy, EnergyError> {
        let model = self.model(flight.speed_mps, flight.altitude_m)?;
        let frame = TransverseMercator::local(origin);
        let home = frame.forward(flight.home);
        // A continuation starts at its first waypoint, in the air.
        let (start, waypoints) = match (flight.airborne, flight.waypoints.split_first()) {
            (true, Some((first, rest))) => (Some(frame.forward(first.0)), rest),
            _ => (None, flight.waypoints.as_slice()),
        };
        let all_turns = waypoints.iter().all(|&(_, hold_s)| hold_s == 0.0);
        let mut visits: Vec<CellVisit> = Vec::with_capacity(waypoints.len());
        let mut via: Vec<Vec<LocalPoint>> = vec![Vec::new()];
        for &(p, hold_s) in waypoints {
            let centre = frame.forward(p);
            if hold_s == 0.0 && !all_turns {
                via.last_mut().expect("never empty").push(centre);
            } else {
                visits.push(CellVisit {
                    centre,
                    hover_s: hold_s,
                });
                via.push(Vec::new());
            }
        }
        match start {
            Some(start) => {
                model.continuation_paths(start, home, &visits, &via, self.usable_budget_j)
            }
            None => model.breakdown_paths(home, &visits, &via),
        }
    }
}

impl MissionEnergyModel {
    /// This model flying at the speed a file commands: the cruise speed rounded by
    /// [`flight_speed_mps`], with the cruise power and energy per metre recomputed there (the
    /// linear model keeps its energy per metre). Every planner input then prices what the
    /// files will command.
    ///
    /// # Errors
    /// Never for a model built by [`MissionEnergyModel::new`]; kept for a speed that rounds
    /// to an invalid value.
    pub fn for_flight(&self) -> Result<Self, EnergyError> {
        self.with_cruise_speed(flight_speed_mps(self.cruise_speed_mps()))
    }

    /// Collection at a cell as the files will command it: `s` with its hover time rounded up
    /// by [`flight_hold_s`] and its hover and receiver energies recomputed for it (J).
    pub fn flight_service(&self, s: CellService) -> CellService {
        let hover_s = flight_hold_s(s.hover_s);
        let hover_j = self.hover_power_w() * hover_s;
        let comm_j = self.rx_power_w() * hover_s;
        CellService {
            collection_s: s.collection_s,
            hover_s,
            hover_j,
            comm_j,
            energy_j: hover_j + comm_j,
        }
    }

    /// The parameters a writer needs to price what a file commands (see
    /// [`FlightEnergyModel`]).
    pub fn flight_energy_model(&self) -> FlightEnergyModel {
        FlightEnergyModel {
            power: *self.power_model().parameters(),
            rx_power_w: self.rx_power_w(),
            linear: self.linear(),
            vertical: self.vertical(),
            usable_budget_j: self.usable_budget_j(),
            wind: self.wind(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn model() -> MissionEnergyModel {
        MissionEnergyModel::new(&EnergyConfig::paper()).unwrap()
    }

    /// A flight with detours: zero-hold waypoints are turn points, priced along the
    /// polylines exactly as the planner's `breakdown_paths` priced them, and a polyline costs
    /// more than the straight leg.
    #[test]
    fn zero_hold_waypoints_are_turn_points_priced_as_planned() {
        let m = model().for_flight().unwrap();
        let origin = LatLon::new(46.78, -117.08).unwrap();
        let frame = TransverseMercator::local(origin);
        let at = |e: f64, n: f64| flight_position(frame.inverse(LocalPoint::new(e, n)));
        let local = |p: LatLon| frame.forward(p);
        let home = flight_position(origin);
        let (a, t1, b, t2) = (
            at(200.0, 0.0),
            at(250.0, 60.0),
            at(300.0, 0.0),
            at(150.0, -40.0),
        );
        let flight = CommandedFlight {
            home,
            altitude_m: m.link().altitude_m,
            speed_mps: m.cruise_speed_mps(),
            waypoints: vec![(a, 30.0), (t1, 0.0), (b, 30.5), (t2, 0.0)],
            airborne: false,
        };
        let commanded = m.flight_energy_model().energy(origin, &flight).unwrap();
        let visits = [
            CellVisit {
                centre: local(a),
                hover_s: 30.0,
            },
            CellVisit {
                centre: local(b),
                hover_s: 30.5,
            },
        ];
        let via = vec![Vec::new(), vec![local(t1)], vec![local(t2)]];
        let planned = m.breakdown_paths(local(home), &visits, &via).unwrap();
        assert_eq!(commanded.total_j.to_bits(), planned.total_j.to_bits());
        assert_eq!(commanded.legs.len(), 3);
        let straight = m.breakdown(local(home), &visits).unwrap();
        assert!(planned.total_j > straight.total_j);
        assert!(planned.legs[1].distance_m > straight.legs[1].distance_m);
        // Reversed polylines have the same length to the bit.
        let p = [local(a), local(t1), local(b)];
        let r = [local(b), local(t1), local(a)];
        assert_eq!(
            crate::path_length_m(&p).to_bits(),
            crate::path_length_m(&r).to_bits()
        );
        // A flight of turn points only is priced as stops.
        let only = CommandedFlight {
            waypoints: vec![(a, 0.0)],
            ..flight
        };
        assert!(
            m.flight_energy_model()
                .energy(origin, &only)
                .unwrap()
                .total_j
                > 0.0
        );
    }

    #[test]
    fn holds_round_up_to_the_step() {
        assert_eq!(flight_hold_s(30.0), 30.0);
        assert_eq!(flight_hold_s(30.0000001), 30.25);
        assert_eq!(flight_hold_s(30.26), 30.5);
        assert_eq!(flight_hold_s(0.0), 0.0);
        assert!(flight_hold_s(f64::NAN).is_nan());
        assert_eq!(flight_hold_s(-1.0), -1.0);
    }

    #[test]
    fn speeds_round_to_the_nearest_step() {
        assert_eq!(flight_speed_mps(10.211_691_346_479_384), 10.25);
        assert_eq!(flight_speed_mps(10.1), 10.0);
        assert_eq!(flight_speed_mps(0.01), 0.25);
        assert!(flight_speed_mps(f64::INFINITY).is_infinite());
        assert_eq!(flight_speed_mps(-3.0), -3.0);
        assert_eq!(flight_altitude_m(30.1), 30.0);
        assert_eq!(flight_altitude_m(0.01), 0.25);
        assert_eq!(flight_altitude_m(120.0), 120.0);
        assert_eq!(flight_altitude_m(0.0), 0.0);
    }

    #[test]
    fn the_flight_model_flies_the_rounded_speed() {
        let m = model().for_flight().unwrap();
        assert_eq!(m.cruise_speed_mps(), 10.25);
        let p = m.power_model().power_w(10.25);
        assert_eq!(m.cruise_power_w(), p);
        assert_eq!(m.energy_per_metre_j(), p / 10.25);
        // The parameters rebuild the same model: the same joules to the last bit.
        let f = m
            .flight_energy_model()
            .model(10.25, m.link().altitude_m)
            .unwrap();
        assert_eq!(f.energy_per_metre_j(), m.energy_per_metre_j());
        assert_eq!(f.hover_power_w(), m.hover_power_w());
        assert_eq!(f.usable_budget_j(), m.usable_budget_j());
        assert!(f.flight_energy_model().model(0.0, 30.0).is_err());
    }

    #[test]
    fn the_flight_service_hovers_the_hold() {
        let m = model();
        let s = m.cell_service(&[]).unwrap();
        let q = m.flight_service(CellService { hover_s: 30.1, ..s });
        assert_eq!(q.hover_s, 30.25);
        assert_eq!(q.energy_j, m.service_energy_j(30.25));
    }

    #[test]
    fn a_position_prints_and_parses_back_to_itself() {
        let p = flight_position(LatLon::new(46.781_234_567_89, -117.082_345_678_9).unwrap());
        let lat: f64 = format!("{:.7}", p.lat()).parse().unwrap();
        let lon: f64 = format!("{:.7}", p.lon()).parse().unwrap();
        assert_eq!((lat, lon), (p.lat(), p.lon()));
        assert_eq!(flight_position(p), p);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]
        #[test]
        fn rounding_is_exact_and_idempotent(h in 0.0f64..86_400.0, v in 0.1f64..40.0, lat in -80.0f64..80.0, lon in -179.0f64..179.0) {
            let hold = flight_hold_s(h);
            prop_assert!(hold >= h && hold - h < HOLD_STEP_S);
            prop_assert_eq!(f64::from(hold as f32), hold);
            prop_assert_eq!(flight_hold_s(hold), hold);
            let s = flight_speed_mps(v);
            prop_assert!((s - v).abs() <= SPEED_STEP_MPS / 2.0 || s == SPEED_STEP_MPS);
            prop_assert_eq!(f64::from(s as f32), s);
            prop_assert_eq!(flight_speed_mps(s), s);
            let p = flight_position(LatLon::new(lat, lon).unwrap());
            prop_assert_eq!(flight_position(p), p);
            prop_assert!((p.lat() - lat).abs() <= 0.5e-7 + 1e-15 && (p.lon() - lon).abs() <= 0.5e-7 + 1e-15);
            let text: f64 = format!("{:.7}", p.lat()).parse().unwrap();
            prop_assert_eq!(text, p.lat());
        }

        #[test]
        fn a_route_priced_up_to_a_wind_costs_at_least_its_cost_in_any_weaker_one(
            stops in proptest::collection::vec((-800.0f64..800.0, -800.0f64..800.0, 30.0f64..60.0), 1..10),
            wind in (0.5f64..14.0, 0.0f64..360.0),
            share in 0.0f64..1.0,
        ) {
            let still = MissionEnergyModel::new(&EnergyConfig::paper()).unwrap();
            let planned = Wind::new(wind.0, wind.1).unwrap();
            let up_to = still.with_wind_up_to(planned);
            prop_assert!(up_to.priced_up_to_wind());
            let visits: Vec<CellVisit> = stops.iter().map(|&(e, n, h)| CellVisit { centre: LocalPoint::new(e, n), hover_s: h }).collect();
            let base = LocalPoint::new(0.0, 0.0);
            let bound = up_to.breakdown(base, &visits).unwrap().total_j;
            // Calm, the planned wind, a sampled one and one between the samples.
            let samples = [0.0, 1.0, 3.0 / crate::mission::UP_TO_SAMPLES as f64, share];
            for f in samples {
                let w = Wind { speed_mps: planned.speed_mps * f, from_deg: planned.from_deg };
                let cost = still.with_wind(w).breakdown(base, &visits).unwrap().total_j;
                // Between samples the bound is the samples' worst: allow 2% there.
                let slack = if f == share { 0.02 * bound } else { 1e-9 * bound };
                prop_assert!(cost <= bound + slack, "{f}: {cost} > {bound}");
            }
            // Still air stays the still-air model to the bit.
            prop_assert_eq!(still.with_wind_up_to(Wind::CALM), still.clone());
        }

        #[test]
        fn a_commanded_flight_costs_what_the_planner_priced(
            stops in proptest::collection::vec((-800.0f64..800.0, -800.0f64..800.0, 30.0f64..60.0), 1..12),
            vertical in any::<bool>(),
            wind in (0.0f64..14.0, 0.0f64..360.0),
            calm in any::<bool>(),
        ) {
            let cfg = EnergyConfig { vertical: vertical.then(VerticalConfig::default), ..EnergyConfig::paper() };
            // In still air or in a wind: the writers price the file in the plan's wind.
            let wind = if calm { Wind::CALM } else { Wind::new(wind.0, wind.1).unwrap() };
            let m = MissionEnergyModel::new(&cfg).unwrap().for_flight().unwrap().with_wind_up_to(wind);
            let origin = LatLon::new(46.78, -117.08).unwrap();
            let frame = TransverseMercator::local(origin);
            let home = flight_position(origin);
            let points: Vec<LatLon> = stops.iter().map(|&(e, n, _)| flight_position(frame.inverse(LocalPoint::new(e, n)))).collect();
            let visits: Vec<CellVisit> = points.iter().zip(&stops).map(|(&p, &(_, _, h))| CellVisit { centre: frame.forward(p), hover_s: flight_hold_s(h) }).collect();
            let planned = m.breakdown(frame.forward(home), &visits).unwrap();
            let flight = CommandedFlight {
                home,
                altitude_m: m.link().altitude_m,
                speed_mps: m.cruise_speed_mps(),
                waypoints: points.iter().zip(&visits).map(|(&p, v)| (p, v.hover_s)).collect(),
                airborne: false,
            };
            let commanded = m.flight_energy_model().energy(origin, &flight).unwrap();
            prop_assert_eq!(commanded.total_j, planned.total_j);
        }
    }
}
