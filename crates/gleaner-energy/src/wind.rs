//! A mission's energy in wind: the mission model's legs in a wind
//! ([`MissionEnergyModel::leg_in_wind`]), a sortie whose legs meet different winds
//! ([`MissionEnergyModel::sortie_in_winds`]), the costliest direction of a wind, and the
//! strongest wind a flight stands ([`strongest_wind`]). The wind itself ([`Wind`]) and a leg's
//! airspeed, heading and power in it ([`WindLeg`]) are the `air` module's, below the mission
//! model.
//!
//! Frames and units: the local frame of the field (metres east `e`, north `n`); wind speeds
//! m/s, directions degrees clockwise from north that the wind blows **from**; energies J.

use gleaner_field::LocalPoint;

pub use crate::air::{Wind, WindLeg};
use crate::error::{EnergyError, finite, non_negative};
use crate::mission::{CellVisit, MissionEnergyModel};

impl MissionEnergyModel {
    /// The leg `from` -> `to` (m) at this model's cruise ground speed in `wind` (see
    /// [`crate::PowerModel::leg_in_wind`]). With the linear model the energy stays its energy per
    /// metre times the distance, whatever the wind (it has no airspeed).
    ///
    /// # Errors
    /// As [`crate::PowerModel::leg_in_wind`].
    pub fn leg_in_wind(
        &self,
        from: LocalPoint,
        to: LocalPoint,
        wind: Wind,
    ) -> Result<WindLeg, EnergyError> {
        let mut leg = self
            .power_model()
            .leg_in_wind(from, to, self.cruise_speed_mps(), wind)?;
        if self.linear().is_some() {
            leg.energy_j = self.energy_per_metre_j() * leg.distance_m;
        }
        Ok(leg)
    }
}

/// A sortie flown in winds that change from leg to leg (a gusty day), J.
#[derive(Debug, Clone, PartialEq)]
pub struct GustySortie {
    /// Propulsion energy of each leg, J: `legs_j[i]` arrives at stop i, the last one is the
    /// return leg.
    pub legs_j: Vec<f64>,
    /// Service energy at each stop (hover in that stop's wind, receiver), J.
    pub services_j: Vec<f64>,
    /// Climb and descent, J (as in still air; 0 unless modelled or for an empty route).
    pub vertical_j: f64,
    /// Everything: `vertical_j + Σ legs_j + Σ services_j`, J.
    pub total_j: f64,
}

impl MissionEnergyModel {
    /// The sortie `base` → `route[0]` → … → `base` (local frame, m) when each leg meets its
    /// own wind: `winds[i]` is the wind of the leg arriving at stop i and of the hover there,
    /// `winds[route.len()]` that of the return leg (each leg as
    /// [`MissionEnergyModel::travel_energy_j`] in its wind, each stop as
    /// [`MissionEnergyModel::service_energy_j`] in its wind). With every wind equal to `w`
    /// it is `self.with_wind(w).breakdown(base, route)` (within rounding: the parts are
    /// summed in another order). An empty route costs 0 J.
    ///
    /// # Errors
    /// [`EnergyError::LengthMismatch`] unless `winds` has `route.len() + 1` entries (none for
    /// an empty route is also accepted); [`EnergyError::InvalidParameter`] for a non-finite
    /// position, a negative or non-finite hover time or wind speed, a non-finite direction.
    pub fn sortie_in_winds(
        &self,
        base: LocalPoint,
        route: &[CellVisit],
        winds: &[Wind],
    ) -> Result<GustySortie, EnergyError> {
        if route.is_empty() && winds.len() <= 1 {
            return Ok(GustySortie {
                legs_j: Vec::new(),
                services_j: Vec::new(),
                vertical_j: 0.0,
                total_j: 0.0,
            });
        }
        if winds.len() != route.len() + 1 {
            return Err(EnergyError::LengthMismatch {
                what: "winds (one per leg, the return included) and stops + 1",
                left: winds.len(),
                right: route.len() + 1,
            });
        }
        finite("base easting (m)", base.e)?;
        finite("base northing (m)", base.n)?;
        for w in winds {
            non_negative("wind speed (m/s)", w.speed_mps)?;
            finite("wind direction (degrees from north)", w.from_deg)?;
        }
        let mut legs_j = Vec::with_capacity(route.len() + 1);
        let mut services_j = Vec::with_capacity(route.len());
        let mut previous = base;
        for (v, w) in route.iter().zip(winds) {
            finite("cell easting (m)", v.centre.e)?;
            finite("cell northing (m)", v.centre.n)?;
            non_negative("hover time (s)", v.hover_s)?;
            let m = self.with_wind(*w);
            legs_j.push(m.travel_energy_j(previous, v.centre));
            services_j.push(m.service_energy_j(v.hover_s));
            previous = v.centre;
        }
        legs_j.push(
            self.with_wind(winds[route.len()])
                .travel_energy_j(previous, base),
        );
        let vertical_j = self.sortie_fixed_j();
        let total_j = vertical_j + legs_j.iter().sum::<f64>() + services_j.iter().sum::<f64>();
        Ok(GustySortie {
            legs_j,
            services_j,
            vertical_j,
            total_j,
        })
    }
}

/// Directions [`MissionEnergyModel::worst_energy_per_metre_j`] tries: every quarter degree.
const WORST_DIRECTIONS: usize = 1_440;

impl MissionEnergyModel {
    /// The most a metre of straight leg costs in this model's wind over every track
    /// direction (every quarter degree), J/m: the energy per metre of still air when the
    /// wind does not apply. Bounds what any route of a given length costs in this wind
    /// (up to the sampling between tried directions), so a planner that knows only lengths
    /// can plan within a budget scaled by [`MissionEnergyModel::energy_per_metre_j`] over
    /// this.
    pub fn worst_energy_per_metre_j(&self) -> f64 {
        if !self.wind_applies() {
            return self.energy_per_metre_j();
        }
        let origin = LocalPoint::new(0.0, 0.0);
        (0..WORST_DIRECTIONS)
            .map(|k| {
                let a = (k as f64 * 360.0 / WORST_DIRECTIONS as f64).to_radians();
                let to = LocalPoint::new(1_000.0 * a.sin(), 1_000.0 * a.cos());
                self.travel_energy_j(origin, to) / 1_000.0
            })
            .fold(self.energy_per_metre_j(), f64::max)
    }
}

/// Wind speeds tried by [`strongest_wind`] before bisecting, m/s: 0, 0.5, 1, … up to
/// [`STRONGEST_WIND_CAP_MPS`].
pub const STRONGEST_WIND_STEP_MPS: f64 = 0.5;
/// The strongest wind [`strongest_wind`] looks at, m/s (a multicopter does not fly above it).
pub const STRONGEST_WIND_CAP_MPS: f64 = 40.0;
/// Bisection steps of [`strongest_wind`]: the step of 0.5 m/s halved 40 times.
const STRONGEST_WIND_BISECTIONS: usize = 40;

/// The strongest wind from one direction at which a flight stays within its budget.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindTolerance {
    /// Wind speed, m/s: the flight is within budget at every speed tried up to it.
    pub speed_mps: f64,
    /// Direction the wind blows from, degrees clockwise from north.
    pub from_deg: f64,
    /// True when the flight is still within budget at [`STRONGEST_WIND_CAP_MPS`] (the speed
    /// is then the cap).
    pub capped: bool,
    /// Whether the flight is within budget in still air too. A route planned in a wind may
    /// not be: hovering in a moderate wind takes less power than hovering in still air
    /// (the power curve's bucket), so the planner can fit more hovering into the battery.
    pub still_air: bool,
}

/// The strongest wind from `from_deg` (degrees clockwise from north) at which `feasible`
/// holds, from still air upwards: [`strongest_wind_from`] starting at 0 m/s.
///
/// # Errors
/// The first error `feasible` returns.
pub fn strongest_wind<E>(
    from_deg: f64,
    feasible: impl FnMut(Wind) -> Result<bool, E>,
) -> Result<Option<WindTolerance>, E> {
    strongest_wind_from(from_deg, 0.0, feasible)
}

/// The strongest wind from `from_deg` (degrees clockwise from north) at which `feasible`
/// holds, scanning up from `start_mps` (m/s; the wind a flight was planned in): wind speeds
/// from `start_mps` upwards in steps of [`STRONGEST_WIND_STEP_MPS`] until the first at which
/// it fails, then bisection (40 halvings) between that speed and the last that held. `None`
/// when it fails at `start_mps`. A flight's energy need not grow with every wind speed (the
/// power curve has a bucket), so the scan finds the first failure above the start, not
/// merely some failure; and a flight planned in a wind may fail in still air while it
/// stands stronger winds (reported in [`WindTolerance::still_air`], not as `None`).
///
/// # Errors
/// The first error `feasible` returns.
pub fn strongest_wind_from<E>(
    from_deg: f64,
    start_mps: f64,
    mut feasible: impl FnMut(Wind) -> Result<bool, E>,
) -> Result<Option<WindTolerance>, E> {
    let start_mps = start_mps.clamp(0.0, STRONGEST_WIND_CAP_MPS);
    let at = |speed_mps: f64| Wind {
        speed_mps,
        from_deg,
    };
    if !feasible(at(start_mps))? {
        return Ok(None);
    }
    let still_air = start_mps == 0.0 || feasible(Wind::CALM)?;
    let mut lo = start_mps;
    while lo < STRONGEST_WIND_CAP_MPS {
        let hi = (lo + STRONGEST_WIND_STEP_MPS).min(STRONGEST_WIND_CAP_MPS);
        if feasible(at(hi))? {
            lo = hi;
            continue;
        }
        let mut hi = hi;
        for _ in 0..STRONGEST_WIND_BISECTIONS {
            let mid = 0.5 * (lo + hi);
            if feasible(at(mid))? {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        return Ok(Some(WindTolerance {
            speed_mps: lo,
            from_deg,
            capped: false,
            still_air,
        }));
    }
    Ok(Some(WindTolerance {
        speed_mps: STRONGEST_WIND_CAP_MPS,
        from_deg,
        capped: true,
        still_air,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::EnergyConfig;
    use proptest::prelude::*;

    fn model() -> MissionEnergyModel {
        MissionEnergyModel::new(&EnergyConfig::paper()).unwrap()
    }

    fn p(e: f64, n: f64) -> LocalPoint {
        LocalPoint::new(e, n)
    }

    #[test]
    fn still_air_is_the_still_air_model_exactly() {
        let m = model();
        let leg = m
            .leg_in_wind(p(0.0, 0.0), p(300.0, -400.0), Wind::CALM)
            .unwrap();
        assert_eq!(
            leg.energy_j,
            m.travel_energy_j(p(0.0, 0.0), p(300.0, -400.0))
        );
        assert_eq!(leg.airspeed_mps, m.cruise_speed_mps());
        assert_eq!((leg.headwind_mps, leg.crosswind_mps), (0.0, 0.0));
        assert_eq!(leg.heading_deg, leg.track_deg);
        assert_eq!(
            m.power_model().hover_power_in_wind_w(Wind::CALM),
            m.hover_power_w()
        );
        // A zero-length leg costs nothing.
        let z = m
            .leg_in_wind(p(5.0, 5.0), p(5.0, 5.0), Wind::new(6.0, 90.0).unwrap())
            .unwrap();
        assert_eq!((z.distance_m, z.time_s, z.energy_j), (0.0, 0.0, 0.0));
    }

    #[test]
    fn the_worst_direction_bounds_every_leg() {
        let m = model();
        assert_eq!(m.worst_energy_per_metre_j(), m.energy_per_metre_j());
        let w = m.with_wind(Wind::new(7.0, 200.0).unwrap());
        let worst = w.worst_energy_per_metre_j();
        assert!(worst > m.energy_per_metre_j());
        for k in 0..97 {
            let a = (k as f64 * 3.7_f64).to_radians();
            let to = p(500.0 * a.sin(), 500.0 * a.cos());
            let per_m = w.travel_energy_j(p(0.0, 0.0), to) / 500.0;
            assert!(per_m <= worst * (1.0 + 1e-6), "{k}: {per_m} > {worst}");
        }
        // The worst is a straight head or tail wind (the airspeed at an end of its range).
        let along = |deg: f64| {
            let a = deg.to_radians();
            w.travel_energy_j(p(0.0, 0.0), p(1000.0 * a.sin(), 1000.0 * a.cos())) / 1000.0
        };
        assert!((along(200.0).max(along(20.0)) - worst).abs() <= 1e-9 * worst);
    }

    #[test]
    fn a_gusty_sortie_needs_a_wind_per_leg() {
        let m = model();
        let route = [CellVisit {
            centre: p(100.0, 0.0),
            hover_s: 10.0,
        }];
        let e = m
            .sortie_in_winds(p(0.0, 0.0), &route, &[Wind::CALM])
            .unwrap_err();
        assert!(matches!(
            e,
            EnergyError::LengthMismatch {
                left: 1,
                right: 2,
                ..
            }
        ));
        let bad = Wind {
            speed_mps: f64::NAN,
            from_deg: 0.0,
        };
        assert!(
            m.sortie_in_winds(p(0.0, 0.0), &route, &[Wind::CALM, bad])
                .is_err()
        );
        assert_eq!(
            m.sortie_in_winds(p(0.0, 0.0), &[], &[]).unwrap().total_j,
            0.0
        );
        // A stronger head-wind gust on the way out costs more on that leg only.
        let east = Wind::new(5.0, 90.0).unwrap();
        let windy = m
            .sortie_in_winds(p(0.0, 0.0), &route, &[east, east])
            .unwrap();
        let gusty = m
            .sortie_in_winds(p(0.0, 0.0), &route, &[Wind::new(8.0, 90.0).unwrap(), east])
            .unwrap();
        assert!(gusty.legs_j[0] > windy.legs_j[0]);
        assert_eq!(gusty.legs_j[1], windy.legs_j[1]);
    }

    #[test]
    fn a_head_wind_on_a_northbound_leg_comes_from_the_north() {
        let m = model();
        let north = (p(0.0, 0.0), p(0.0, 1000.0));
        let head = m
            .leg_in_wind(north.0, north.1, Wind::new(5.0, 0.0).unwrap())
            .unwrap();
        assert!((head.headwind_mps - 5.0).abs() < 1e-12, "{head:?}");
        assert!(head.crosswind_mps.abs() < 1e-12);
        assert!((head.airspeed_mps - (m.cruise_speed_mps() + 5.0)).abs() < 1e-9);
        let tail = m
            .leg_in_wind(north.0, north.1, Wind::new(5.0, 180.0).unwrap())
            .unwrap();
        assert!((tail.headwind_mps + 5.0).abs() < 1e-12);
        assert!((tail.airspeed_mps - (m.cruise_speed_mps() - 5.0)).abs() < 1e-9);
        // Wind from the west (270): the aircraft heads a little west of north to hold it.
        let cross = m
            .leg_in_wind(north.0, north.1, Wind::new(5.0, 270.0).unwrap())
            .unwrap();
        assert!((cross.crosswind_mps - 5.0).abs() < 1e-12, "{cross:?}");
        assert!(
            cross.heading_deg > 270.0 && cross.heading_deg < 360.0,
            "{cross:?}"
        );
        let v = m.cruise_speed_mps();
        assert!((cross.airspeed_mps - (v * v + 25.0).sqrt()).abs() < 1e-9);
        assert!((cross.time_s - 1000.0 / v).abs() < 1e-9);
    }

    #[test]
    fn bad_inputs_are_errors() {
        let m = model();
        assert!(Wind::new(-1.0, 0.0).is_err());
        assert!(Wind::new(f64::NAN, 0.0).is_err());
        assert!(Wind::new(3.0, f64::INFINITY).is_err());
        let pm = m.power_model();
        assert!(
            pm.leg_in_wind(p(0.0, 0.0), p(1.0, 0.0), 0.0, Wind::CALM)
                .is_err()
        );
        assert!(
            pm.leg_in_wind(p(f64::NAN, 0.0), p(1.0, 0.0), 5.0, Wind::CALM)
                .is_err()
        );
    }

    fn visits(points: &[(f64, f64)], hover_s: f64) -> Vec<crate::CellVisit> {
        points
            .iter()
            .map(|&(e, n)| crate::CellVisit {
                centre: p(e, n),
                hover_s,
            })
            .collect()
    }

    /// In wind a tour costs more one way round than the other, the planner's directed costs
    /// add up to the breakdown, stops hover at P(|w|) and the climb is still air's.
    #[test]
    fn a_tour_in_wind_depends_on_its_direction() {
        let cfg = EnergyConfig {
            vertical: Some(crate::VerticalConfig::default()),
            ..EnergyConfig::paper()
        };
        let still = MissionEnergyModel::new(&cfg).unwrap();
        let m = still.with_wind(Wind::new(8.0, 270.0).unwrap());
        assert!(m.wind_applies() && !still.wind_applies());
        let base = p(0.0, 0.0);
        let route = visits(&[(600.0, 0.0), (0.0, 300.0), (-100.0, 100.0)], 30.0);
        let mut back = route.clone();
        back.reverse();
        let (a, b) = (
            m.breakdown(base, &route).unwrap(),
            m.breakdown(base, &back).unwrap(),
        );
        assert!(
            (a.total_j - b.total_j).abs() > 1.0,
            "{} {}",
            a.total_j,
            b.total_j
        );
        // East first: a tail wind on the first leg, a head wind on the way back west.
        assert!(
            (a.legs[0].headwind_mps + 8.0).abs() < 1e-9,
            "{:?}",
            a.legs[0]
        );
        assert!(a.legs[1].headwind_mps > 0.0 && a.legs[1].crosswind_mps.abs() > 0.0);
        let mut stops = vec![base];
        stops.extend(route.iter().map(|v| v.centre));
        stops.push(base);
        let travel: f64 = stops
            .windows(2)
            .map(|w| m.travel_energy_j(w[0], w[1]))
            .sum();
        let service: f64 = route.iter().map(|v| m.service_energy_j(v.hover_s)).sum();
        assert!((m.sortie_fixed_j() + travel + service - a.total_j).abs() < 1e-9 * a.total_j);
        let pw = m.power_model().power_w(8.0);
        assert_eq!(m.hover_power_w(), pw);
        assert!((a.hover_j - 90.0 * pw).abs() < 1e-9);
        assert_eq!(m.sortie_fixed_j(), still.sortie_fixed_j());
        assert_eq!(m.descent(), still.descent());
        // The matrix is the directed leg energies.
        let pts = [base, p(600.0, 0.0), p(0.0, 300.0)];
        let c = m.travel_cost_matrix(&pts);
        assert!((c.get(0, 1) - c.get(1, 0)).abs() > 1.0);
        assert_eq!(c.get(0, 1), m.travel_energy_j(pts[0], pts[1]));
        assert_eq!(c.get(2, 2), 0.0);
        // A polyline in wind: the sum of its segments as flown.
        let poly = [base, p(300.0, 200.0), p(600.0, 0.0)];
        let e = m.polyline_energy_j(&poly);
        let sum = m.travel_energy_j(poly[0], poly[1]) + m.travel_energy_j(poly[1], poly[2]);
        assert_eq!(e, sum);
        // The linear model has no airspeed: the wind changes nothing.
        let lin = MissionEnergyModel::new(&EnergyConfig {
            linear: Some(crate::LinearEnergy {
                j_per_m: 10.0,
                j_per_cell: 100.0,
            }),
            ..EnergyConfig::paper()
        })
        .unwrap();
        let windy = lin.with_wind(Wind::new(8.0, 270.0).unwrap());
        assert!(!windy.wind_applies());
        assert_eq!(
            windy.breakdown(base, &route).unwrap().total_j,
            lin.breakdown(base, &route).unwrap().total_j
        );
    }

    #[test]
    fn the_strongest_wind_is_where_the_route_stops_fitting() {
        let m = model();
        let base = p(0.0, 0.0);
        let route = visits(&[(900.0, 0.0), (900.0, 900.0), (0.0, 900.0)], 20.0);
        let fits = |w: Wind| -> Result<bool, EnergyError> {
            Ok(m.with_wind(w).breakdown(base, &route)?.feasible)
        };
        let t = strongest_wind(90.0, fits).unwrap().unwrap();
        assert!(!t.capped && t.from_deg == 90.0);
        assert!(
            t.speed_mps > 0.0 && t.speed_mps < STRONGEST_WIND_CAP_MPS,
            "{t:?}"
        );
        assert!(fits(Wind::new(t.speed_mps, 90.0).unwrap()).unwrap());
        assert!(!fits(Wind::new(t.speed_mps + 1e-6, 90.0).unwrap()).unwrap());
        // Every scanned speed below it fits.
        let mut w = 0.0;
        while w < t.speed_mps {
            assert!(fits(Wind::new(w, 90.0).unwrap()).unwrap(), "{w}");
            w += STRONGEST_WIND_STEP_MPS;
        }
        // A route over budget in still air stands no wind; one that fits anything is capped.
        let never = strongest_wind(0.0, |_| Ok::<_, EnergyError>(false)).unwrap();
        assert_eq!(never, None);
        let always = strongest_wind(0.0, |_| Ok::<_, EnergyError>(true))
            .unwrap()
            .unwrap();
        assert!(always.capped && always.speed_mps == STRONGEST_WIND_CAP_MPS);
        assert!(always.still_air && t.still_air);
    }

    /// A flight planned in a wind that is over budget in still air (more hovering fits in a
    /// moderate wind than in still air) still has the strongest wind it stands, scanned up
    /// from the wind it was planned in, and says that still air is over budget.
    #[test]
    fn a_route_over_budget_in_still_air_still_has_its_strongest_wind() {
        let m = model();
        let base = p(0.0, 0.0);
        let route = visits(&[(300.0, 0.0), (300.0, 300.0), (0.0, 300.0)], 60.0);
        let energy = |w: Wind| m.with_wind(w).breakdown(base, &route).unwrap().total_j;
        let calm = energy(Wind::CALM);
        let planned = Wind::new(8.0, 270.0).unwrap();
        assert!(energy(planned) < calm, "hovering in 8 m/s is cheaper");
        // A budget between the two: feasible in the planned wind, not in still air.
        let budget = 0.5 * (energy(planned) + calm);
        let fits = |w: Wind| -> Result<bool, EnergyError> { Ok(energy(w) <= budget) };
        assert_eq!(strongest_wind(270.0, fits).unwrap(), None);
        let t = strongest_wind_from(270.0, 8.0, fits).unwrap().unwrap();
        assert!(!t.still_air && !t.capped, "{t:?}");
        assert!(
            t.speed_mps > 8.0 && t.speed_mps < STRONGEST_WIND_CAP_MPS,
            "{t:?}"
        );
        assert!(fits(Wind::new(t.speed_mps, 270.0).unwrap()).unwrap());
        assert!(!fits(Wind::new(t.speed_mps + 1e-6, 270.0).unwrap()).unwrap());
        // Nothing from the start: none.
        assert_eq!(
            strongest_wind_from(270.0, 8.0, |_| Ok::<_, EnergyError>(false)).unwrap(),
            None
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// A model put in still air is the still-air model to the last bit: every leg, stop,
        /// polyline and matrix entry, with or without climb and descent.
        #[test]
        fn calm_wind_is_the_still_air_model_to_the_bit(
            stops in prop::collection::vec((-2e3f64..2e3, -2e3f64..2e3, 0.0f64..120.0), 0..12),
            turns in prop::collection::vec((-2e3f64..2e3, -2e3f64..2e3), 0..4),
            from in 0.0f64..360.0,
            vertical in any::<bool>(),
        ) {
            let cfg = EnergyConfig {
                vertical: vertical.then(crate::VerticalConfig::default),
                ..EnergyConfig::paper()
            };
            let still = MissionEnergyModel::new(&cfg).unwrap().for_flight().unwrap();
            let calm = still.with_wind(Wind { speed_mps: 0.0, from_deg: from });
            let route: Vec<crate::CellVisit> = stops
                .iter()
                .map(|&(e, n, h)| crate::CellVisit { centre: p(e, n), hover_s: h })
                .collect();
            let via: Vec<Vec<LocalPoint>> = (0..=route.len())
                .map(|k| if k % 2 == 0 { turns.iter().map(|&(e, n)| p(e, n)).collect() } else { Vec::new() })
                .collect();
            let base = p(0.0, 0.0);
            prop_assert_eq!(calm.breakdown(base, &route).unwrap(), still.breakdown(base, &route).unwrap());
            prop_assert_eq!(
                calm.breakdown_paths(base, &route, &via).unwrap(),
                still.breakdown_paths(base, &route, &via).unwrap()
            );
            prop_assert_eq!(
                calm.continuation(p(10.0, 20.0), base, &route, 5e4).unwrap(),
                still.continuation(p(10.0, 20.0), base, &route, 5e4).unwrap()
            );
            let pts: Vec<LocalPoint> = route.iter().map(|v| v.centre).collect();
            prop_assert_eq!(calm.travel_cost_matrix(&pts), still.travel_cost_matrix(&pts));
            let mut poly = vec![base];
            poly.extend(turns.iter().map(|&(e, n)| p(e, n)));
            prop_assert_eq!(calm.polyline_energy_j(&poly).to_bits(), still.polyline_energy_j(&poly).to_bits());
            prop_assert_eq!(calm.service_energy_j(31.25).to_bits(), still.service_energy_j(31.25).to_bits());
        }

        /// One wind on every leg of a gusty sortie is the steady-wind breakdown; a gust on
        /// one leg changes that leg and its stop only.
        #[test]
        fn a_sortie_in_one_wind_is_the_breakdown(
            stops in prop::collection::vec((-2e3f64..2e3, -2e3f64..2e3, 0.0f64..120.0), 0..12),
            speed in 0.0f64..15.0,
            from in 0.0f64..360.0,
            gust in 0.5f64..5.0,
            vertical in any::<bool>(),
        ) {
            let cfg = EnergyConfig {
                vertical: vertical.then(crate::VerticalConfig::default),
                ..EnergyConfig::paper()
            };
            let m = MissionEnergyModel::new(&cfg).unwrap();
            let w = Wind::new(speed, from).unwrap();
            let base = p(0.0, 0.0);
            let route: Vec<crate::CellVisit> = stops
                .iter()
                .map(|&(e, n, h)| crate::CellVisit { centre: p(e, n), hover_s: h })
                .collect();
            let winds = vec![w; route.len() + 1];
            let g = m.sortie_in_winds(base, &route, &winds).unwrap();
            let b = m.with_wind(w).breakdown(base, &route).unwrap();
            prop_assert!((g.total_j - b.total_j).abs() <= 1e-9 * (1.0 + b.total_j));
            for (leg, want) in g.legs_j.iter().zip(&b.legs) {
                prop_assert_eq!(leg.to_bits(), want.energy_j.to_bits());
            }
            for (svc, want) in g.services_j.iter().zip(&b.cells) {
                // (P + P_rx)·h against P·h + P_rx·h: the same to rounding.
                prop_assert!((svc - want.service_j).abs() <= 1e-12 * (1.0 + want.service_j));
            }
            prop_assert_eq!(g.vertical_j, b.vertical_j);
            if !route.is_empty() {
                let k = route.len() / 2;
                let mut gusty = winds.clone();
                gusty[k] = Wind::new(speed + gust, from).unwrap();
                let h = m.sortie_in_winds(base, &route, &gusty).unwrap();
                for i in 0..=route.len() {
                    if i != k {
                        prop_assert_eq!(h.legs_j[i].to_bits(), g.legs_j[i].to_bits());
                    }
                    if i != k && i < route.len() {
                        prop_assert_eq!(h.services_j[i].to_bits(), g.services_j[i].to_bits());
                    }
                }
            }
        }

        /// In any wind the breakdown's parts add up, and so do the planner's directed costs.
        #[test]
        fn a_breakdown_in_wind_adds_up(
            stops in prop::collection::vec((-2e3f64..2e3, -2e3f64..2e3, 0.0f64..120.0), 1..12),
            speed in 0.0f64..15.0,
            from in 0.0f64..360.0,
        ) {
            let m = model().with_wind(Wind::new(speed, from).unwrap());
            let base = p(0.0, 0.0);
            let route: Vec<crate::CellVisit> = stops
                .iter()
                .map(|&(e, n, h)| crate::CellVisit { centre: p(e, n), hover_s: h })
                .collect();
            let b = m.breakdown(base, &route).unwrap();
            let tol = 1e-9 * (1.0 + b.total_j);
            prop_assert!((b.travel_j + b.hover_j + b.comm_j + b.return_j - b.total_j).abs() <= tol);
            let mut pts = vec![base];
            pts.extend(route.iter().map(|v| v.centre));
            pts.push(base);
            let travel: f64 = pts.windows(2).map(|w| m.travel_energy_j(w[0], w[1])).sum();
            let service: f64 = route.iter().map(|v| m.service_energy_j(v.hover_s)).sum();
            prop_assert!((travel + service - b.total_j).abs() <= tol);
            for l in &b.legs {
                prop_assert!(l.headwind_mps.abs() <= speed + 1e-9 && l.crosswind_mps.abs() <= speed + 1e-9);
            }
        }

        /// Still air gives today's travel energy to the last bit, on any leg.
        #[test]
        fn still_air_equals_the_model(a in (-3e3f64..3e3, -3e3f64..3e3), b in (-3e3f64..3e3, -3e3f64..3e3)) {
            let m = model();
            let leg = m.leg_in_wind(p(a.0, a.1), p(b.0, b.1), Wind::CALM).unwrap();
            prop_assert_eq!(leg.energy_j, m.travel_energy_j(p(a.0, a.1), p(b.0, b.1)));
        }

        /// Energy per metre never falls as the head wind grows, on any track.
        #[test]
        fn head_wind_is_monotone(track in 0.0f64..360.0, w1 in 0.0f64..15.0, dw in 0.0f64..10.0) {
            let m = model();
            let t = track.to_radians();
            let to = p(1000.0 * t.sin(), 1000.0 * t.cos());
            let e = |w: f64| m.leg_in_wind(p(0.0, 0.0), to, Wind::new(w, track).unwrap()).unwrap();
            let (a, b) = (e(w1), e(w1 + dw));
            prop_assert!(b.energy_j >= a.energy_j * (1.0 - 1e-12), "{a:?} {b:?}");
            prop_assert!((a.headwind_mps - w1).abs() < 1e-9);
        }

        /// A cross wind from the left costs what the same wind from the right costs.
        #[test]
        fn cross_wind_is_symmetric(track in 0.0f64..360.0, w in 0.0f64..15.0) {
            let m = model();
            let t = track.to_radians();
            let to = p(800.0 * t.sin(), 800.0 * t.cos());
            let left = m.leg_in_wind(p(0.0, 0.0), to, Wind::new(w, track - 90.0).unwrap()).unwrap();
            let right = m.leg_in_wind(p(0.0, 0.0), to, Wind::new(w, track + 90.0).unwrap()).unwrap();
            prop_assert!((left.energy_j - right.energy_j).abs() <= 1e-9 * left.energy_j, "{left:?} {right:?}");
            prop_assert!((left.crosswind_mps + right.crosswind_mps).abs() < 1e-9);
            prop_assert!(left.headwind_mps.abs() < 1e-9 && right.headwind_mps.abs() < 1e-9);
            // Any cross wind costs at least still air: the airspeed is sqrt(V² + c²).
            let calm = m.leg_in_wind(p(0.0, 0.0), to, Wind::CALM).unwrap();
            prop_assert!(left.airspeed_mps >= calm.airspeed_mps - 1e-12);
        }
    }
}
