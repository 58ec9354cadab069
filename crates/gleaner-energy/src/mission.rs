//! Mission energy: E_t, E_h, E_c, E_r of an ordered route from the base and back, its budget
//! feasibility, and the additive costs an orienteering planner needs (docs/method.md §3).

use gleaner_field::{CellId, Field, LocalPoint};

use crate::air::{Wind, WindLeg};
use crate::config::{CruiseSpeed, EnergyConfig, LinearEnergy, VerticalConfig};
use crate::error::{EnergyError, finite, non_negative};
use crate::link::{DataLogging, HoverConfig, LinkConfig, SensorBacklog};
use crate::propulsion::PowerModel;

/// Euclidean distance between two local points, metres: sqrt(Δe² + Δn²). Used for every
/// distance in this crate so that the planner costs and the breakdown agree to the last bit.
pub(crate) fn distance_m(a: &LocalPoint, b: &LocalPoint) -> f64 {
    let (de, dn) = (a.e - b.e, a.n - b.n);
    (de * de + dn * dn).sqrt()
}

/// Length of the polyline through `points` (a leg flown around obstacles: its start, turn
/// points, end), m: the sum of its segments' [`distance_m`], added from the end whose
/// (easting, northing) is smaller, so a polyline and its reverse have the same length to the
/// last bit (a planner's cost matrix stays exactly symmetric). Two points give their
/// straight-line distance exactly; fewer give 0.
pub fn path_length_m(points: &[LocalPoint]) -> f64 {
    let (Some(first), Some(last)) = (points.first(), points.last()) else {
        return 0.0;
    };
    let forward = first
        .e
        .total_cmp(&last.e)
        .then(first.n.total_cmp(&last.n))
        .is_le();
    let segment = |w: &[LocalPoint]| distance_m(&w[0], &w[1]);
    if forward {
        points.windows(2).map(segment).sum()
    } else {
        points.windows(2).rev().map(segment).sum()
    }
}

/// One stop of a route: where the UAV hovers and for how long.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellVisit {
    /// Cell centre in the local frame, metres.
    pub centre: LocalPoint,
    /// Hover time at the cell, seconds (see [`MissionEnergyModel::cell_service`]).
    pub hover_s: f64,
}

/// Collection at one cell: upload time, hover time and service energy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellService {
    /// Upload time t_comm, seconds.
    pub collection_s: f64,
    /// Hover time max(min_hover_s, overhead_s + t_comm), seconds.
    pub hover_s: f64,
    /// Hover energy P(0)·hover_s, J.
    pub hover_j: f64,
    /// Receiver energy P_rx·hover_s, J.
    pub comm_j: f64,
    /// Service energy hover_j + comm_j, J.
    pub energy_j: f64,
}

/// One flight leg at the cruise ground speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegEnergy {
    /// Leg length, metres.
    pub distance_m: f64,
    /// Flight time at the cruise ground speed, seconds.
    pub time_s: f64,
    /// Propulsion energy P(V_air)·distance/V (still air: P(V)·distance/V), J.
    pub energy_j: f64,
    /// Wind against the track, m/s (> 0 a head wind, < 0 a tail wind; distance-weighted
    /// mean over a polyline's segments; 0 in still air).
    pub headwind_mps: f64,
    /// Wind across the track, m/s (> 0 from the left, < 0 from the right; distance-weighted
    /// mean over a polyline's segments; 0 in still air).
    pub crosswind_mps: f64,
    /// Airspeed that holds the track at the ground speed, m/s (distance-weighted mean over a
    /// polyline's segments; the ground speed in still air).
    pub airspeed_mps: f64,
}

/// Energy spent at one visited cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellEnergy {
    /// Hover time, seconds.
    pub hover_s: f64,
    /// Hover energy P(0)·hover_s, J.
    pub hover_j: f64,
    /// Receiver energy P_rx·hover_s, J.
    pub comm_j: f64,
    /// hover_j + comm_j, J.
    pub service_j: f64,
}

/// The energy breakdown of one sortie B -> c_1 -> ... -> c_k -> B.
///
/// `total_j = travel_j + hover_j + comm_j + return_j`, and it also equals
/// `vertical_j + sum(legs[..].energy_j) + sum(cells[..].service_j)`.
#[derive(Debug, Clone, PartialEq)]
pub struct MissionEnergy {
    /// E_t: cruise from B through c_1..c_k, plus `vertical_j`, J.
    pub travel_j: f64,
    /// Climb and descent energy included in `travel_j` (0 unless configured), J.
    pub vertical_j: f64,
    /// E_h: hover energy over all cells, J.
    pub hover_j: f64,
    /// E_c: receiver energy over all cells, J.
    pub comm_j: f64,
    /// E_r: return leg c_k -> B, J.
    pub return_j: f64,
    /// E_t + E_h + E_c + E_r, J.
    pub total_j: f64,
    /// Usable budget B_usable, J.
    pub budget_j: f64,
    /// total_j / budget_j, dimensionless.
    pub utilisation: f64,
    /// budget_j − total_j (negative when infeasible), J.
    pub remaining_j: f64,
    /// total_j <= budget_j.
    pub feasible: bool,
    /// Cruise distance including the return leg, metres.
    pub distance_m: f64,
    /// Flight time: cruise, hover and (if configured) climb and descent, seconds.
    pub flight_time_s: f64,
    /// k + 1 legs: `legs[i]` arrives at cell i (from B when i = 0); `legs[k]` is the return
    /// leg. Empty for an empty route.
    pub legs: Vec<LegEnergy>,
    /// Per visited cell, in visiting order.
    pub cells: Vec<CellEnergy>,
}

/// A dense symmetric matrix of travel energies, J, stored row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct TravelCostMatrix {
    n: usize,
    costs: Vec<f64>,
}

impl TravelCostMatrix {
    /// Number of points (rows).
    pub fn len(&self) -> usize {
        self.n
    }

    /// True for a matrix over no points.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Travel energy from point `i` to point `j`, J. Panics if out of range (like slice
    /// indexing).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        assert!(
            i < self.n && j < self.n,
            "index ({i}, {j}) out of range for {} points",
            self.n
        );
        self.costs[i * self.n + j]
    }

    /// Row `i`: travel energies from point `i` to every point, J.
    pub fn row(&self, i: usize) -> &[f64] {
        &self.costs[i * self.n..(i + 1) * self.n]
    }

    /// All entries row-major (entry (i, j) at `i·n + j`), J.
    pub fn as_slice(&self) -> &[f64] {
        &self.costs
    }

    /// The row-major entries, J.
    pub fn into_vec(self) -> Vec<f64> {
        self.costs
    }
}

/// The validated, ready-to-use mission energy model built from an [`EnergyConfig`].
///
/// ```
/// use gleaner_energy::{CellVisit, EnergyConfig, MissionEnergyModel};
/// use gleaner_field::{CellId, Field, LocalPoint};
/// let model = MissionEnergyModel::new(&EnergyConfig::paper()).unwrap();
/// let route = [
///     CellVisit { centre: LocalPoint::new(300.0, 400.0), hover_s: 30.0 },
///     CellVisit { centre: LocalPoint::new(300.0, 0.0), hover_s: 30.0 },
/// ];
/// let e = model.breakdown(LocalPoint::new(0.0, 0.0), &route).unwrap();
/// // 900 m travelled at ~12.34 J/m, two 30 s hovers at 168.48 W + 0.5 W.
/// assert!((e.distance_m - 1200.0).abs() < 1e-9);
/// assert!((e.hover_j - 2.0 * 30.0 * model.hover_power_w()).abs() < 1e-9);
/// assert!(e.feasible && e.total_j < e.budget_j);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct MissionEnergyModel {
    power: PowerModel,
    cruise_speed_mps: f64,
    cruise_power_w: f64,
    energy_per_metre_j: f64,
    /// Hover power in still air P(0), W: the climb and descent.
    calm_hover_power_w: f64,
    /// Hover power at a stop in the model's wind P(|w|), W (P(0) in still air).
    hover_power_w: f64,
    /// The steady wind the legs and stops are priced in (calm by default).
    wind: Wind,
    /// True when every leg and stop is priced at the worst of the winds from calm up to
    /// `wind` (same direction; [`MissionEnergyModel::with_wind_up_to`]).
    up_to: bool,
    rx_power_w: f64,
    budget_j: f64,
    vertical_j: f64,
    vertical_s: f64,
    /// The linear model's energy per cell visited, J (`None`: the physical model).
    per_cell_j: Option<f64>,
    /// The linear model as configured (`None`: the physical model).
    linear: Option<LinearEnergy>,
    /// Climb and descent as configured (`None`: not modelled).
    vertical: Option<VerticalConfig>,
    link: LinkConfig,
    logging: DataLogging,
    hover: HoverConfig,
}

/// Winds sampled above calm by [`MissionEnergyModel::with_wind_up_to`] (the speeds
/// k/8 of the model's wind, k = 0..=8).
pub const UP_TO_SAMPLES: usize = 8;

impl MissionEnergyModel {
    /// Validates `config` and precomputes the cruise speed and powers.
    ///
    /// # Errors
    /// [`EnergyError::InvalidParameter`] naming the first invalid parameter.
    pub fn new(config: &EnergyConfig) -> Result<Self, EnergyError> {
        config.validate()?;
        let power = config.power.power_model()?;
        let cruise_speed_mps = match config.cruise {
            CruiseSpeed::MaxEndurance => power.max_endurance().speed_mps,
            CruiseSpeed::MaxRange => power.max_range().speed_mps,
            CruiseSpeed::Fixed(v) => v,
        };
        if cruise_speed_mps <= 0.0 {
            // Only reachable for a curve whose minimum power is in hover.
            return Err(EnergyError::InvalidParameter {
                name: "cruise speed (m/s)",
                value: cruise_speed_mps,
                expected: "a speed > 0 (this airframe's maximum-endurance speed is 0; set a fixed speed)",
            });
        }
        let cruise_power_w = power.power_w(cruise_speed_mps);
        let hover_power_w = power.hover_power_w();
        let (vertical_j, vertical_s) = match &config.vertical {
            None => (0.0, 0.0),
            Some(v) => {
                let h = config.link.altitude_m;
                let t = h / v.climb_speed_mps + h / v.descent_speed_mps;
                (hover_power_w * t + power.weight_n() * h, t)
            }
        };
        Ok(Self {
            power,
            cruise_speed_mps,
            cruise_power_w,
            energy_per_metre_j: config
                .linear
                .map_or(cruise_power_w / cruise_speed_mps, |l| l.j_per_m),
            per_cell_j: config.linear.map(|l| l.j_per_cell),
            linear: config.linear,
            vertical: config.vertical,
            calm_hover_power_w: hover_power_w,
            hover_power_w,
            wind: Wind::CALM,
            up_to: false,
            rx_power_w: config.rx_power_w,
            budget_j: config.battery.usable_j(),
            vertical_j,
            vertical_s,
            link: config.link,
            logging: config.logging,
            hover: config.hover,
        })
    }

    /// This model at another cruise speed `speed_mps` (m/s, > 0): the cruise power and the
    /// energy per metre recomputed as [`MissionEnergyModel::new`] computes them (the linear
    /// model keeps its energy per metre).
    ///
    /// # Errors
    /// [`EnergyError::InvalidParameter`] for a speed that is not finite and > 0.
    pub fn with_cruise_speed(&self, speed_mps: f64) -> Result<Self, EnergyError> {
        crate::error::positive("cruise speed (m/s)", speed_mps)?;
        let mut m = self.clone();
        m.cruise_speed_mps = speed_mps;
        m.cruise_power_w = m.power.power_w(speed_mps);
        m.energy_per_metre_j = self
            .linear
            .map_or(m.cruise_power_w / speed_mps, |l| l.j_per_m);
        Ok(m)
    }

    /// This model in a steady `wind` (the wind is replaced, not added): every leg then flies
    /// the airspeed and heading that hold its track at the cruise ground speed and costs
    /// P(V_air)·d/V (docs/method.md §3, wind), every stop hovers at P(|w|); take-off, climb
    /// and descent stay as in still air. [`Wind::CALM`] gives back the still-air model to
    /// the last bit. The linear model has no airspeed: its energies do not depend on the
    /// wind.
    pub fn with_wind(&self, wind: Wind) -> Self {
        let mut m = self.clone();
        m.wind = wind;
        m.up_to = false;
        m.hover_power_w = m.hover_power_at(wind);
        m
    }

    /// This model priced for any steady wind from calm up to `wind` (from `wind`'s
    /// direction): every leg costs the most it costs at [`UP_TO_SAMPLES`] + 1 speeds evenly
    /// spaced from 0 to `wind`'s, every stop hovers at the highest of their hover powers.
    /// A route it finds feasible stays feasible if the wind drops (hovering in a moderate wind
    /// takes less power than in still air, and a tail wind near the ground speed leaves the
    /// aircraft nearly hovering along its leg). Leg breakdowns keep `wind`'s head- and
    /// cross-wind components. [`Wind::CALM`] gives back the still-air model to the last bit.
    pub fn with_wind_up_to(&self, wind: Wind) -> Self {
        let mut m = self.with_wind(wind);
        if m.wind_applies() {
            m.up_to = true;
            m.hover_power_w = (0..=UP_TO_SAMPLES)
                .map(|k| m.hover_power_at(m.sample(k)))
                .fold(f64::NEG_INFINITY, f64::max);
        }
        m
    }

    /// True when the model prices the worst wind from calm up to its wind
    /// ([`MissionEnergyModel::with_wind_up_to`]).
    pub fn priced_up_to_wind(&self) -> bool {
        self.up_to
    }

    /// The `k`-th of the sampled winds from calm (k = 0) to the model's wind.
    fn sample(&self, k: usize) -> Wind {
        Wind {
            speed_mps: self.wind.speed_mps * k as f64 / UP_TO_SAMPLES as f64,
            from_deg: self.wind.from_deg,
        }
    }

    /// Hover power in `wind`, W: P(|w|), or exactly P(0) in calm air.
    fn hover_power_at(&self, wind: Wind) -> f64 {
        if wind.is_calm() {
            self.calm_hover_power_w
        } else {
            self.power.hover_power_in_wind_w(wind)
        }
    }

    /// The wind the model prices legs and stops in.
    pub fn wind(&self) -> Wind {
        self.wind
    }

    /// True when the wind changes any energy: a wind that is not calm over the physical
    /// model. Then a leg's cost depends on its direction (an asymmetric cost matrix).
    pub fn wind_applies(&self) -> bool {
        !self.wind.is_calm() && self.linear.is_none()
    }

    /// The linear model in place of the physical one, if configured.
    pub fn linear(&self) -> Option<LinearEnergy> {
        self.linear
    }

    /// Climb and descent rates, if their energy is modelled.
    pub fn vertical(&self) -> Option<VerticalConfig> {
        self.vertical
    }

    /// The propulsion power curve.
    pub fn power_model(&self) -> &PowerModel {
        &self.power
    }

    /// Cruise speed V, m/s.
    pub fn cruise_speed_mps(&self) -> f64 {
        self.cruise_speed_mps
    }

    /// Propulsion power at cruise speed P(V), W.
    pub fn cruise_power_w(&self) -> f64 {
        self.cruise_power_w
    }

    /// Travel energy per metre at cruise speed P(V)/V, J/m.
    pub fn energy_per_metre_j(&self) -> f64 {
        self.energy_per_metre_j
    }

    /// Hover power at a stop, W: P(|w|) in the model's wind, P(0) in still air.
    pub fn hover_power_w(&self) -> f64 {
        self.hover_power_w
    }

    /// Hover power in still air P(0), W (climb and descent are priced with it).
    pub fn calm_hover_power_w(&self) -> f64 {
        self.calm_hover_power_w
    }

    /// Receiver power P_rx, W.
    pub fn rx_power_w(&self) -> f64 {
        self.rx_power_w
    }

    /// Usable budget B_usable, J.
    pub fn usable_budget_j(&self) -> f64 {
        self.budget_j
    }

    /// Fixed energy of every non-empty sortie (climb and descent; 0 unless configured), J.
    /// A planner's budget for travel + service is `usable_budget_j() − sortie_fixed_j()`.
    pub fn sortie_fixed_j(&self) -> f64 {
        self.vertical_j
    }

    /// The radio link settings.
    pub fn link(&self) -> &LinkConfig {
        &self.link
    }

    /// The default sensor logging settings.
    pub fn logging(&self) -> &DataLogging {
        &self.logging
    }

    /// The hover-time rule.
    pub fn hover(&self) -> &HoverConfig {
        &self.hover
    }

    /// Travel energy from `from` to `to` (local frame, m) at the cruise ground speed,
    /// P(V)·distance/V in still air (the linear model: its energy per metre · distance), J.
    /// In wind ([`MissionEnergyModel::wind_applies`]) P(V_air)·distance/V with the airspeed
    /// that holds the track: it then depends on the direction.
    pub fn travel_energy_j(&self, from: LocalPoint, to: LocalPoint) -> f64 {
        if self.wind_applies() {
            return self.segment_in_wind(from, to).energy_j;
        }
        self.energy_per_metre_j * distance_m(&from, &to)
    }

    /// Travel energy (J) along the polyline `points` (local frame, m) flown in their order:
    /// in still air energy per metre times [`path_length_m`] (the same for both directions),
    /// in wind the sum of its segments' [`MissionEnergyModel::travel_energy_j`] from the
    /// first point. What a leg around no-fly zones costs in the breakdown, to the bit.
    pub fn polyline_energy_j(&self, points: &[LocalPoint]) -> f64 {
        if self.wind_applies() {
            return points
                .windows(2)
                .map(|w| self.segment_in_wind(w[0], w[1]).energy_j)
                .sum();
        }
        self.energy_per_metre_j * path_length_m(points)
    }

    /// One straight segment in the model's wind at the cruise ground speed (finite points:
    /// the callers check them; a non-finite one gives NaN energies, refused downstream).
    fn segment_in_wind(&self, from: LocalPoint, to: LocalPoint) -> WindLeg {
        let planned = self.segment_at(from, to, self.wind);
        if !self.up_to {
            return planned;
        }
        // The costliest of the sampled winds, with the planned wind's components.
        let mut worst = planned;
        for k in 0..UP_TO_SAMPLES {
            let leg = self.segment_at(from, to, self.sample(k));
            if leg.energy_j > worst.energy_j || leg.energy_j.is_nan() {
                worst = WindLeg {
                    headwind_mps: planned.headwind_mps,
                    crosswind_mps: planned.crosswind_mps,
                    ..leg
                };
            }
        }
        worst
    }

    fn segment_at(&self, from: LocalPoint, to: LocalPoint, wind: Wind) -> WindLeg {
        self.power
            .leg_in_wind(from, to, self.cruise_speed_mps, wind)
            .unwrap_or(WindLeg {
                distance_m: f64::NAN,
                ground_speed_mps: self.cruise_speed_mps,
                airspeed_mps: f64::NAN,
                track_deg: f64::NAN,
                heading_deg: f64::NAN,
                headwind_mps: f64::NAN,
                crosswind_mps: f64::NAN,
                time_s: f64::NAN,
                power_w: f64::NAN,
                energy_j: f64::NAN,
            })
    }

    /// The leg through `polyline` (start, turn points, end; local frame, m) as the breakdown
    /// prices it: distance [`path_length_m`], time distance / V, energy
    /// [`MissionEnergyModel::polyline_energy_j`], and the wind's distance-weighted mean
    /// components.
    fn leg(&self, polyline: &[LocalPoint]) -> LegEnergy {
        let distance_m = if polyline.len() == 2 {
            distance_m(&polyline[0], &polyline[1])
        } else {
            path_length_m(polyline)
        };
        let time_s = distance_m / self.cruise_speed_mps;
        if !self.wind_applies() {
            return LegEnergy {
                distance_m,
                time_s,
                energy_j: self.energy_per_metre_j * distance_m,
                headwind_mps: 0.0,
                crosswind_mps: 0.0,
                airspeed_mps: self.cruise_speed_mps,
            };
        }
        let (mut energy_j, mut head, mut cross, mut air, mut length) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for w in polyline.windows(2) {
            let s = self.segment_in_wind(w[0], w[1]);
            energy_j += s.energy_j;
            head += s.headwind_mps * s.distance_m;
            cross += s.crosswind_mps * s.distance_m;
            air += s.airspeed_mps * s.distance_m;
            length += s.distance_m;
        }
        let mean = |x: f64| if length > 0.0 { x / length } else { 0.0 };
        // A leg of zero length: the wind as it meets a hovering aircraft.
        let zero = length == 0.0;
        LegEnergy {
            distance_m,
            time_s,
            energy_j,
            headwind_mps: mean(head),
            crosswind_mps: mean(cross),
            airspeed_mps: if zero { self.wind.speed_mps } else { mean(air) },
        }
    }

    /// Service energy of hovering `hover_s` seconds at a cell, (P(0) + P_rx)·hover_s, J (the
    /// linear model: its energy per cell, whatever the hover time).
    pub fn service_energy_j(&self, hover_s: f64) -> f64 {
        match self.per_cell_j {
            Some(j) => j,
            None => (self.hover_power_w + self.rx_power_w) * hover_s,
        }
    }

    /// Collection at a cell whose sensors have `sensors` waiting: upload time, hover time and
    /// service energy.
    ///
    /// # Errors
    /// As [`LinkConfig::collection_time_s`].
    pub fn cell_service(&self, sensors: &[SensorBacklog]) -> Result<CellService, EnergyError> {
        let collection_s = self.link.collection_time_s(sensors)?;
        let hover_s = self.hover.hover_s(collection_s);
        let hover_j = self.hover_power_w * hover_s;
        let comm_j = self.rx_power_w * hover_s;
        Ok(CellService {
            collection_s,
            hover_s,
            hover_j,
            comm_j,
            energy_j: hover_j + comm_j,
        })
    }

    /// The backlog of every sensor of `cell` in `field`: horizontal offset from the cell centre
    /// and the data pending after `elapsed_s[sensor]` seconds since its last collection
    /// (indexed by sensor position in the field's input order; give never-collected sensors
    /// the time since deployment or history start), with the default [`DataLogging`].
    ///
    /// # Errors
    /// [`EnergyError::LengthMismatch`] if `elapsed_s` does not have one entry per sensor;
    /// [`EnergyError::InvalidParameter`] for a negative or non-finite elapsed time or a cell id
    /// outside the field.
    pub fn cell_backlog(
        &self,
        field: &Field,
        cell: CellId,
        elapsed_s: &[f64],
    ) -> Result<Vec<SensorBacklog>, EnergyError> {
        let points = field.sensor_points();
        if elapsed_s.len() != points.len() {
            return Err(EnergyError::LengthMismatch {
                what: "elapsed times vs field sensors",
                left: elapsed_s.len(),
                right: points.len(),
            });
        }
        let Some(c) = field.cells().get(cell.index()) else {
            return Err(EnergyError::InvalidParameter {
                name: "cell id",
                value: cell.index() as f64,
                expected: "an index below the field's cell count",
            });
        };
        c.sensors
            .iter()
            .map(|&s| {
                SensorBacklog::from_elapsed(
                    distance_m(&points[s], &c.centre),
                    elapsed_s[s],
                    &self.logging,
                )
            })
            .collect()
    }

    /// [`MissionEnergyModel::cell_service`] for every cell of `field`, in cell order, from the
    /// per-sensor times since last collection `elapsed_s` (seconds, see
    /// [`MissionEnergyModel::cell_backlog`]). The service energies are the node costs of an
    /// orienteering instance whose travel costs come from
    /// [`MissionEnergyModel::travel_cost_matrix`] (the base is (0, 0) in the field's frame).
    ///
    /// # Errors
    /// As [`MissionEnergyModel::cell_backlog`].
    pub fn field_services(
        &self,
        field: &Field,
        elapsed_s: &[f64],
    ) -> Result<Vec<CellService>, EnergyError> {
        (0..field.cells().len())
            .map(|i| {
                let backlog = self.cell_backlog(field, CellId(i as u32), elapsed_s)?;
                self.cell_service(&backlog)
            })
            .collect()
    }

    /// The matrix of travel energies between all pairs of `points`, J (entry (i, j): from
    /// `points[i]` to `points[j]`; for an orienteering cost matrix, put the base among the
    /// points). Symmetric in still air; in wind ([`MissionEnergyModel::wind_applies`]) each
    /// entry is [`MissionEnergyModel::travel_energy_j`] and depends on the direction.
    pub fn travel_cost_matrix(&self, points: &[LocalPoint]) -> TravelCostMatrix {
        let n = points.len();
        if self.wind_applies() {
            let mut costs = Vec::with_capacity(n * n);
            for a in points {
                costs.extend(points.iter().map(|b| self.travel_energy_j(*a, *b)));
            }
            return TravelCostMatrix { n, costs };
        }
        // Row by row (each pair computed twice, in the same operand order so the matrix is
        // exactly symmetric): sequential writes are faster than mirroring.
        let mut costs = Vec::with_capacity(n * n);
        for a in points {
            costs.extend(points.iter().map(|b| {
                let (de, dn) = ((a.e - b.e).abs(), (a.n - b.n).abs());
                self.energy_per_metre_j * (de * de + dn * dn).sqrt()
            }));
        }
        TravelCostMatrix { n, costs }
    }

    /// The energy breakdown of the sortie `base` -> `route[0]` -> ... -> `route[k-1]` -> `base`.
    /// An empty route flies nowhere and costs 0 J.
    ///
    /// # Errors
    /// [`EnergyError::InvalidParameter`] for a non-finite position or a negative / non-finite
    /// hover time.
    pub fn breakdown(
        &self,
        base: LocalPoint,
        route: &[CellVisit],
    ) -> Result<MissionEnergy, EnergyError> {
        self.breakdown_paths(base, route, &[])
    }

    /// [`MissionEnergyModel::breakdown`] of a route whose legs are polylines (flown around
    /// no-fly zones at the cruise altitude and speed, without stopping): `via[i]` holds the
    /// turn points (local frame, m) between the previous stop (the base for `i = 0`) and stop
    /// `i`, and `via[route.len()]` those of the return leg. A missing entry (or `via` empty) is
    /// a straight leg, so `breakdown_paths(base, route, &[])` is `breakdown(base, route)` to
    /// the last bit. Each leg's distance is [`path_length_m`] of its polyline (the same
    /// function a planner's cost matrix uses), its energy P(V)/V times that, its time that
    /// over V.
    ///
    /// # Errors
    /// As [`MissionEnergyModel::breakdown`], and for a non-finite turn point.
    pub fn breakdown_paths(
        &self,
        base: LocalPoint,
        route: &[CellVisit],
        via: &[Vec<LocalPoint>],
    ) -> Result<MissionEnergy, EnergyError> {
        let vertical = if route.is_empty() {
            (0.0, 0.0)
        } else {
            (self.vertical_j, self.vertical_s)
        };
        self.path(base, base, route, via, vertical, self.budget_j)
    }

    /// The energy breakdown of a *continuation*: the aircraft is already in the air at
    /// `start` (local frame, m, at the flight altitude), visits `route` in order (hovering
    /// `hover_s` at each), returns to `base` and descends there — no take-off and no climb —
    /// against the budget `budget_j` (J: the energy left less the reserve). `legs[0]` is the
    /// leg from `start`; with an empty route the one leg home. `vertical_j` is the descent
    /// alone (P(0)·h/v_descent, when climb and descent are modelled).
    ///
    /// # Errors
    /// As [`MissionEnergyModel::breakdown`]; a budget that is not finite.
    pub fn continuation(
        &self,
        start: LocalPoint,
        base: LocalPoint,
        route: &[CellVisit],
        budget_j: f64,
    ) -> Result<MissionEnergy, EnergyError> {
        self.continuation_paths(start, base, route, &[], budget_j)
    }

    /// [`MissionEnergyModel::continuation`] with legs that are polylines through `via`
    /// (turn points, local frame m; `via[i]` before stop `i`, `via[route.len()]` on the way
    /// home), as [`MissionEnergyModel::breakdown_paths`].
    ///
    /// # Errors
    /// As [`MissionEnergyModel::continuation`], and for a non-finite turn point.
    pub fn continuation_paths(
        &self,
        start: LocalPoint,
        base: LocalPoint,
        route: &[CellVisit],
        via: &[Vec<LocalPoint>],
        budget_j: f64,
    ) -> Result<MissionEnergy, EnergyError> {
        finite("start easting (m)", start.e)?;
        finite("start northing (m)", start.n)?;
        finite("remaining budget (J)", budget_j)?;
        self.path(start, base, route, via, self.descent(), budget_j)
    }

    /// Energy (J) and time (s) of the descent before landing: `P(0)·h/v_descent` and
    /// `h/v_descent` when climb and descent are modelled, else 0 — the fixed part of a
    /// continuation ([`MissionEnergyModel::continuation`]).
    pub fn descent(&self) -> (f64, f64) {
        match &self.vertical {
            None => (0.0, 0.0),
            Some(v) => {
                let t = self.link.altitude_m / v.descent_speed_mps;
                (self.calm_hover_power_w * t, t)
            }
        }
    }

    /// From `start` through `route` to `end` (legs polylines through `via`, as
    /// [`MissionEnergyModel::breakdown_paths`]), with `(vertical_j, vertical_s)` of climb and
    /// descent, against `budget_j`. With `start == end` and an empty route, no leg at all.
    fn path(
        &self,
        start: LocalPoint,
        end: LocalPoint,
        route: &[CellVisit],
        via: &[Vec<LocalPoint>],
        (vertical_j, vertical_s): (f64, f64),
        budget_j: f64,
    ) -> Result<MissionEnergy, EnergyError> {
        finite("base easting (m)", end.e)?;
        finite("base northing (m)", end.n)?;
        for v in route {
            finite("cell easting (m)", v.centre.e)?;
            finite("cell northing (m)", v.centre.n)?;
            non_negative("hover time (s)", v.hover_s)?;
        }
        for p in via.iter().flatten() {
            finite("turn point easting (m)", p.e)?;
            finite("turn point northing (m)", p.n)?;
        }
        let mut legs = Vec::with_capacity(route.len() + 1);
        let mut cells = Vec::with_capacity(route.len());
        let mut previous = start;
        let home = !route.is_empty() || start != end;
        let stops = route.iter().map(|v| v.centre).chain(home.then_some(end));
        let mut polyline = Vec::new();
        for (k, to) in stops.enumerate() {
            polyline.clear();
            polyline.push(previous);
            if let Some(turns) = via.get(k) {
                polyline.extend_from_slice(turns);
            }
            polyline.push(to);
            legs.push(self.leg(&polyline));
            previous = to;
        }
        for v in route {
            let (hover_j, comm_j) = match self.per_cell_j {
                Some(j) => (j, 0.0),
                None => (self.hover_power_w * v.hover_s, self.rx_power_w * v.hover_s),
            };
            cells.push(CellEnergy {
                hover_s: v.hover_s,
                hover_j,
                comm_j,
                service_j: hover_j + comm_j,
            });
        }
        let (outbound, return_j) = match legs.split_last() {
            Some((last, rest)) => (rest.iter().map(|l| l.energy_j).sum::<f64>(), last.energy_j),
            None => (0.0, 0.0),
        };
        let travel_j = vertical_j + outbound;
        let hover_j: f64 = cells.iter().map(|c| c.hover_j).sum();
        let comm_j: f64 = cells.iter().map(|c| c.comm_j).sum();
        let total_j = travel_j + hover_j + comm_j + return_j;
        let distance_m = legs.iter().map(|l| l.distance_m).sum::<f64>();
        let flight_time_s = legs.iter().map(|l| l.time_s).sum::<f64>()
            + cells.iter().map(|c| c.hover_s).sum::<f64>()
            + vertical_s;
        Ok(MissionEnergy {
            travel_j,
            vertical_j,
            hover_j,
            comm_j,
            return_j,
            total_j,
            budget_j,
            utilisation: total_j / budget_j,
            remaining_j: budget_j - total_j,
            feasible: total_j <= budget_j,
            distance_m,
            flight_time_s,
            legs,
            cells,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::VerticalConfig;
    use proptest::prelude::*;

    fn model() -> MissionEnergyModel {
        MissionEnergyModel::new(&EnergyConfig::paper()).unwrap()
    }

    fn visits(points: &[(f64, f64)], hover_s: f64) -> Vec<CellVisit> {
        points
            .iter()
            .map(|&(e, n)| CellVisit {
                centre: LocalPoint::new(e, n),
                hover_s,
            })
            .collect()
    }

    /// A continuation from the base without climb/descent modelled is the closed tour to
    /// the bit; with them it saves the climb; from elsewhere its first leg leaves `start`.
    #[test]
    fn a_continuation_is_the_tour_without_take_off() {
        let m = model();
        let route = visits(&[(300.0, 400.0), (300.0, 0.0)], 30.0);
        let base = LocalPoint::new(0.0, 0.0);
        let tour = m.breakdown(base, &route).unwrap();
        let cont = m
            .continuation(base, base, &route, m.usable_budget_j())
            .unwrap();
        assert_eq!(cont.total_j, tour.total_j);
        assert_eq!(cont.legs, tour.legs);
        let cfg = EnergyConfig {
            vertical: Some(VerticalConfig::default()),
            ..EnergyConfig::paper()
        };
        let v = MissionEnergyModel::new(&cfg).unwrap();
        let tour = v.breakdown(base, &route).unwrap();
        let cont = v.continuation(base, base, &route, 1e5).unwrap();
        let h = v.link().altitude_m;
        let descent = v.hover_power_w() * h / VerticalConfig::default().descent_speed_mps;
        assert!((cont.vertical_j - descent).abs() < 1e-9);
        assert!(cont.total_j < tour.total_j);
        assert_eq!(cont.budget_j, 1e5);
        // From (300, 400): the first leg is 0 m long, then 400 m, then 300 m home.
        let start = LocalPoint::new(300.0, 400.0);
        let c = m.continuation(start, base, &route, 10_000.0).unwrap();
        let d: Vec<f64> = c.legs.iter().map(|l| l.distance_m).collect();
        assert_eq!(d, vec![0.0, 400.0, 300.0]);
        // Nothing left to visit: the leg home.
        let home = m.continuation(start, base, &[], 10_000.0).unwrap();
        assert_eq!(home.legs.len(), 1);
        assert!((home.distance_m - 500.0).abs() < 1e-9);
        assert_eq!(home.feasible, home.total_j <= 10_000.0);
        assert!(m.continuation(start, base, &route, f64::NAN).is_err());
    }

    #[test]
    fn empty_route_costs_nothing() {
        let e = model().breakdown(LocalPoint::new(5.0, 5.0), &[]).unwrap();
        assert_eq!(e.total_j, 0.0);
        assert!(e.feasible && e.legs.is_empty() && e.cells.is_empty());
    }

    #[test]
    fn hand_checked_single_cell() {
        let m = model();
        let e = m
            .breakdown(LocalPoint::new(0.0, 0.0), &visits(&[(30.0, 40.0)], 30.0))
            .unwrap();
        let leg = 50.0 * m.cruise_power_w() / m.cruise_speed_mps();
        assert!((e.travel_j - leg).abs() < 1e-9 && (e.return_j - leg).abs() < 1e-9);
        assert!((e.hover_j - 30.0 * m.hover_power_w()).abs() < 1e-9);
        assert!((e.comm_j - 15.0).abs() < 1e-12);
        assert!((e.flight_time_s - (100.0 / m.cruise_speed_mps() + 30.0)).abs() < 1e-9);
        assert_eq!(e.legs.len(), 2);
    }

    #[test]
    fn comm_energy_is_small_at_defaults() {
        // Ten sensors spread over a 40 m cell, 30 days uncollected at default logging.
        let m = model();
        let backlog: Vec<SensorBacklog> = (0..10)
            .map(|i| {
                SensorBacklog::from_elapsed(2.8 * i as f64, 30.0 * 86_400.0, m.logging()).unwrap()
            })
            .collect();
        let s = m.cell_service(&backlog).unwrap();
        assert!(
            s.collection_s > 0.0 && s.collection_s < 5.0,
            "{}",
            s.collection_s
        );
        assert!((s.hover_s - (30.0 + s.collection_s)).abs() < 1e-12);
        assert!(
            s.comm_j < 0.01 * s.energy_j,
            "E_c {} of {}",
            s.comm_j,
            s.energy_j
        );
    }

    #[test]
    fn field_services_follow_sensor_backlogs() {
        use gleaner_field::{FieldConfig, LatLon, Sensor, SensorId};
        let base = LatLon::new(46.7785, -117.0870).unwrap();
        let sensors = vec![
            Sensor::new(
                SensorId::new("a").unwrap(),
                LatLon::new(46.7788, -117.0867).unwrap(),
            ),
            Sensor::new(
                SensorId::new("b").unwrap(),
                LatLon::new(46.7789, -117.0866).unwrap(),
            ),
            Sensor::new(
                SensorId::new("c").unwrap(),
                LatLon::new(46.7800, -117.0840).unwrap(),
            ),
        ];
        let field = Field::build(&sensors, base, &FieldConfig::with_cell_size(40.0)).unwrap();
        let m = model();
        let day = 86_400.0;
        let elapsed = [day, 10.0 * day, 0.0];
        let services = m.field_services(&field, &elapsed).unwrap();
        assert_eq!(services.len(), field.cells().len());
        for (i, cell) in field.cells().iter().enumerate() {
            let backlog = m.cell_backlog(&field, CellId(i as u32), &elapsed).unwrap();
            assert_eq!(backlog.len(), cell.sensors.len());
            for (b, &s) in backlog.iter().zip(&cell.sensors) {
                assert!(
                    (b.horizontal_offset_m - field.sensor_points()[s].distance(&cell.centre)).abs()
                        < 1e-9
                );
                assert!(
                    (b.pending_bytes - m.logging().pending_bytes(elapsed[s]).unwrap()).abs() < 1e-9
                );
            }
            assert_eq!(services[i], m.cell_service(&backlog).unwrap());
        }
        assert!(m.field_services(&field, &elapsed[..2]).is_err());
        assert!(m.cell_backlog(&field, CellId(99), &elapsed).is_err());
    }

    #[test]
    fn vertical_energy_is_fixed_per_sortie() {
        let cfg = EnergyConfig {
            vertical: Some(VerticalConfig::default()),
            ..EnergyConfig::paper()
        };
        let m = MissionEnergyModel::new(&cfg).unwrap();
        // 30 m at 2.5 m/s up and 1.5 m/s down: 32 s of hover power plus 20 N · 30 m.
        let expected = m.hover_power_w() * 32.0 + 600.0;
        assert!((m.sortie_fixed_j() - expected).abs() < 1e-9);
        let e = m
            .breakdown(LocalPoint::new(0.0, 0.0), &visits(&[(100.0, 0.0)], 30.0))
            .unwrap();
        assert!((e.vertical_j - expected).abs() < 1e-9);
        let plain = model()
            .breakdown(LocalPoint::new(0.0, 0.0), &visits(&[(100.0, 0.0)], 30.0))
            .unwrap();
        assert!((e.total_j - plain.total_j - expected).abs() < 1e-9);
    }

    #[test]
    fn matrix_is_symmetric_with_zero_diagonal() {
        let m = model();
        let pts = [
            LocalPoint::new(0.0, 0.0),
            LocalPoint::new(3.0, 4.0),
            LocalPoint::new(-10.0, 2.0),
        ];
        let c = m.travel_cost_matrix(&pts);
        assert_eq!(c.len(), 3);
        for i in 0..3 {
            assert_eq!(c.get(i, i), 0.0);
            for j in 0..3 {
                assert_eq!(c.get(i, j), c.get(j, i));
                assert_eq!(c.get(i, j), m.travel_energy_j(pts[i], pts[j]));
            }
        }
        assert_eq!(c.row(1)[0], c.get(1, 0));
    }

    #[test]
    fn invalid_route_input_is_rejected() {
        let m = model();
        assert!(m.breakdown(LocalPoint::new(f64::NAN, 0.0), &[]).is_err());
        assert!(
            m.breakdown(LocalPoint::new(0.0, 0.0), &visits(&[(1.0, 1.0)], -1.0))
                .is_err()
        );
    }

    fn arb_route() -> impl Strategy<Value = Vec<(f64, f64, f64)>> {
        prop::collection::vec(
            (-2000.0f64..2000.0, -2000.0f64..2000.0, 0.0f64..200.0),
            0..30,
        )
    }

    proptest! {
        #[test]
        fn breakdown_is_consistent(route in arb_route(), vertical in any::<bool>()) {
            let cfg = EnergyConfig {
                vertical: vertical.then(VerticalConfig::default),
                ..EnergyConfig::paper()
            };
            let m = MissionEnergyModel::new(&cfg).unwrap();
            let base = LocalPoint::new(0.0, 0.0);
            let visits: Vec<CellVisit> = route
                .iter()
                .map(|&(e, n, h)| CellVisit { centre: LocalPoint::new(e, n), hover_s: h })
                .collect();
            let b = m.breakdown(base, &visits).unwrap();
            let tol = 1e-9 * (1.0 + b.total_j);
            // Parts sum to total.
            prop_assert!((b.travel_j + b.hover_j + b.comm_j + b.return_j - b.total_j).abs() <= tol);
            // Same total from the additive planner costs.
            let mut stops = vec![base];
            stops.extend(visits.iter().map(|v| v.centre));
            stops.push(base);
            let travel: f64 = stops.windows(2).map(|w| m.travel_energy_j(w[0], w[1])).sum();
            let service: f64 = visits.iter().map(|v| m.service_energy_j(v.hover_s)).sum();
            let fixed = if visits.is_empty() { 0.0 } else { m.sortie_fixed_j() };
            prop_assert!((fixed + travel + service - b.total_j).abs() <= tol);
            let legs: f64 = b.legs.iter().map(|l| l.energy_j).sum();
            let cells: f64 = b.cells.iter().map(|c| c.service_j).sum();
            prop_assert!((b.vertical_j + legs + cells - b.total_j).abs() <= tol);
            // Feasibility rule.
            prop_assert_eq!(b.feasible, b.total_j <= m.usable_budget_j());
            prop_assert_eq!(b.feasible, b.remaining_j >= 0.0);
            prop_assert!((b.utilisation * b.budget_j - b.total_j).abs() <= tol);
        }

        #[test]
        fn energy_grows_with_added_cells(route in arb_route(), extra in (-2000.0f64..2000.0, -2000.0f64..2000.0, 0.0f64..200.0), at in 0usize..31) {
            // Inserting a stop anywhere never lowers the energy (triangle inequality, hover >= 0).
            let m = model();
            let base = LocalPoint::new(0.0, 0.0);
            let mut visits: Vec<CellVisit> = route
                .iter()
                .map(|&(e, n, h)| CellVisit { centre: LocalPoint::new(e, n), hover_s: h })
                .collect();
            let before = m.breakdown(base, &visits).unwrap().total_j;
            let pos = at.min(visits.len());
            visits.insert(pos, CellVisit { centre: LocalPoint::new(extra.0, extra.1), hover_s: extra.2 });
            let after = m.breakdown(base, &visits).unwrap().total_j;
            prop_assert!(after >= before - 1e-9 * (1.0 + before));
        }

        #[test]
        fn energy_monotone_in_route_length(scale in 0.1f64..10.0, route in arb_route()) {
            // Stretching the route about the base scales distance, so energy grows with length.
            let m = model();
            let base = LocalPoint::new(0.0, 0.0);
            let mk = |s: f64| -> Vec<CellVisit> {
                route.iter().map(|&(e, n, h)| CellVisit { centre: LocalPoint::new(s * e, s * n), hover_s: h }).collect()
            };
            let a = m.breakdown(base, &mk(1.0)).unwrap();
            let b = m.breakdown(base, &mk(scale)).unwrap();
            let tol = 1e-9 * (1.0 + a.total_j);
            if scale >= 1.0 {
                prop_assert!(b.distance_m >= a.distance_m - 1e-9 && b.total_j >= a.total_j - tol);
            } else {
                prop_assert!(b.distance_m <= a.distance_m + 1e-9 && b.total_j <= a.total_j + tol);
            }
        }
    }

    #[test]
    fn the_linear_model_charges_per_metre_and_per_cell() {
        let cfg = EnergyConfig {
            linear: Some(crate::LinearEnergy {
                j_per_m: 10.0,
                j_per_cell: 1_000.0,
            }),
            ..EnergyConfig::paper()
        };
        let m = MissionEnergyModel::new(&cfg).unwrap();
        let base = LocalPoint::new(0.0, 0.0);
        let visits = [
            CellVisit {
                centre: LocalPoint::new(300.0, 0.0),
                hover_s: 30.0,
            },
            CellVisit {
                centre: LocalPoint::new(300.0, 400.0),
                hover_s: 95.0,
            },
        ];
        let e = m.breakdown(base, &visits).unwrap();
        assert!(
            (e.total_j - (10.0 * 1_200.0 + 2_000.0)).abs() < 1e-9,
            "{e:?}"
        );
        assert!((m.service_energy_j(95.0) - 1_000.0).abs() < 1e-12);
        let bad = EnergyConfig {
            linear: Some(crate::LinearEnergy {
                j_per_m: -1.0,
                j_per_cell: 0.0,
            }),
            ..EnergyConfig::paper()
        };
        assert!(MissionEnergyModel::new(&bad).is_err());
    }
}
