//! The wind a mission is planned for: the forecast (`[flight]` settings, or a request's own),
//! the margin added to it, the wind the legs are priced in, each leg as priced in it, and the
//! strongest wind a planned route stands (docs/method.md §3, wind).

use gleaner_energy::{
    CellVisit, LegEnergy, MissionEnergyModel, Wind, WindTolerance, strongest_wind_from,
};
use gleaner_field::LocalPoint;

use gleaner_scoring::settings::FlightSection;
use gleaner_scoring::{AppError, Result};

/// Strongest forecast wind a plan may be asked for, m/s (`[flight] wind_mps`'s range).
pub const MAX_WIND_MPS: f64 = 40.0;

/// A forecast wind `speed_mps` (m/s, in [0, 40]) from `from_deg` (degrees clockwise from
/// north, in [0, 360]), checked; `what` names the input in the error.
///
/// # Errors
/// [`AppError::Invalid`] naming `what`, the value and the range.
pub fn forecast(speed_mps: f64, from_deg: f64, what: &str) -> Result<Wind> {
    if !(speed_mps.is_finite() && (0.0..=MAX_WIND_MPS).contains(&speed_mps)) {
        return Err(AppError::Invalid(format!(
            "{what}: wind speed {} m/s: allowed [0, {MAX_WIND_MPS}] m/s",
            gleaner_ingest::number(speed_mps)
        )));
    }
    if !(from_deg.is_finite() && (0.0..=360.0).contains(&from_deg)) {
        return Err(AppError::Invalid(format!(
            "{what}: wind direction {} degrees: allowed [0, 360] degrees clockwise from north \
             (the direction the wind blows from)",
            gleaner_ingest::number(from_deg)
        )));
    }
    Wind::new(speed_mps, from_deg).map_err(|e| AppError::core("wind", e))
}

/// Parses `SPEED@FROM` (m/s @ degrees the wind blows from, clockwise from north), e.g.
/// `6@270` for a 6 m/s west wind, as `plan --wind` and `replan --wind` take it.
///
/// # Errors
/// [`AppError::Invalid`] quoting the text, for a malformed value or one out of range.
pub fn parse(text: &str) -> Result<Wind> {
    let bad = || {
        AppError::Invalid(format!(
            "--wind {:?}: expected SPEED@FROM, the speed in m/s and the direction the wind \
             blows from in degrees clockwise from north, e.g. 6@270 (a 6 m/s west wind)",
            gleaner_ingest::shorten(text)
        ))
    };
    let (speed, from) = text.trim().split_once('@').ok_or_else(bad)?;
    let speed: f64 = speed.trim().parse().map_err(|_| bad())?;
    let from: f64 = from.trim().parse().map_err(|_| bad())?;
    forecast(speed, from, &format!("--wind {}", text.trim()))
}

/// The wind of one plan: the forecast, the margin, and the wind its legs are priced in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanWind {
    /// The forecast (`[flight] wind_mps`, `wind_from_deg`, or the request's own).
    pub forecast: Wind,
    /// `[flight] wind_margin_mps`, m/s: added to a forecast above 0 m/s.
    pub margin_mps: f64,
    /// The wind the legs and hovers are priced in: the forecast's speed plus the margin
    /// from the forecast's direction; still air (from the forecast's direction) when the
    /// forecast is 0 m/s. Stored with the mission; its files are checked in it.
    pub planned: Wind,
}

impl PlanWind {
    /// The wind of a plan with the project's `[flight]` settings, or `given` in place of
    /// their forecast.
    ///
    /// # Errors
    /// [`AppError::Invalid`] for settings out of range (checked on load already).
    pub fn of(flight: &FlightSection, given: Option<Wind>) -> Result<Self> {
        let forecast = match given {
            Some(w) => forecast(w.speed_mps, w.from_deg, "wind")?,
            None => forecast(flight.wind_mps, flight.wind_from_deg, "[flight] wind_mps")?,
        };
        let margin_mps = flight.wind_margin_mps;
        if !(margin_mps.is_finite() && margin_mps >= 0.0) {
            return Err(AppError::Invalid(format!(
                "[flight] wind_margin_mps = {}: must be >= 0 m/s",
                gleaner_ingest::number(margin_mps)
            )));
        }
        let planned = if forecast.is_calm() {
            Wind {
                speed_mps: 0.0,
                from_deg: forecast.from_deg,
            }
        } else {
            Wind {
                speed_mps: forecast.speed_mps + margin_mps,
                from_deg: forecast.from_deg,
            }
        };
        Ok(Self {
            forecast,
            margin_mps,
            planned,
        })
    }
}

/// The wind of a planned route: the plan's wind, every leg's components (one per stop, the
/// leg arriving there, then the return leg) and the strongest wind it stands.
#[derive(Debug, Clone, PartialEq)]
pub struct RouteWind {
    /// The plan's wind.
    pub wind: PlanWind,
    /// Each leg as priced at [`PlanWind::planned`]: head- and cross-wind components, airspeed
    /// and energy (the plan's `MissionEnergy::legs`).
    pub legs: Vec<LegEnergy>,
    /// The strongest wind from the forecast's direction at which the route as its files
    /// command it stays within the budget (see [`strongest`]); `None` for an empty route.
    pub strongest: Option<WindTolerance>,
}

/// The strongest wind from `from_deg` (degrees from north) at which the sortie `base` →
/// `route` → `base` (legs through `via`, as [`MissionEnergyModel::breakdown_paths`]) stays
/// within the model's usable budget, scanned up from `planned_mps` (m/s, the wind it was
/// priced in): [`gleaner_energy::strongest_wind_from`] over the model in each trial wind
/// (whether still air is within budget too is [`WindTolerance::still_air`]). The planner
/// prices the values the files command, so this is the wind the exported route stands.
/// `None` when it is over budget in the planned wind.
///
/// # Errors
/// [`AppError::Core`] for invalid positions or hover times.
pub fn strongest(
    model: &MissionEnergyModel,
    base: LocalPoint,
    route: &[CellVisit],
    via: &[Vec<LocalPoint>],
    (from_deg, planned_mps): (f64, f64),
) -> Result<Option<WindTolerance>> {
    strongest_wind_from(from_deg, planned_mps, |w| {
        model
            .with_wind(w)
            .breakdown_paths(base, route, via)
            .map(|e| e.feasible)
    })
    .map_err(|e| AppError::core("strongest wind", e))
}

/// [`strongest`] of a continuation from `start` (in the air) against `budget_j` (J).
///
/// # Errors
/// As [`strongest`].
pub fn strongest_continuation(
    model: &MissionEnergyModel,
    (start, base): (LocalPoint, LocalPoint),
    route: &[CellVisit],
    budget_j: f64,
    (from_deg, planned_mps): (f64, f64),
) -> Result<Option<WindTolerance>> {
    strongest_wind_from(from_deg, planned_mps, |w| {
        model
            .with_wind(w)
            .continuation(start, base, route, budget_j)
            .map(|e| e.feasible)
    })
    .map_err(|e| AppError::core("strongest wind", e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_speed_at_direction() {
        let w = parse("6@270").unwrap();
        assert_eq!((w.speed_mps, w.from_deg), (6.0, 270.0));
        let w = parse(" 0.5 @ 0 ").unwrap();
        assert_eq!((w.speed_mps, w.from_deg), (0.5, 0.0));
        for bad in [
            "", "6", "6@", "@270", "x@1", "6@270@1", "-1@0", "41@0", "6@361", "nan@0",
        ] {
            let e = parse(bad).unwrap_err().to_string();
            assert!(e.contains("--wind"), "{bad}: {e}");
        }
        assert!(parse("6@400").unwrap_err().to_string().contains("[0, 360]"));
    }

    #[test]
    fn the_margin_is_added_to_a_forecast_only() {
        let f = FlightSection::default();
        let calm = PlanWind::of(&f, None).unwrap();
        assert!(calm.planned.is_calm());
        let w = PlanWind::of(&f, Some(Wind::new(6.0, 270.0).unwrap())).unwrap();
        assert_eq!(w.planned.speed_mps, 6.0 + f.wind_margin_mps);
        assert_eq!(w.planned.from_deg, 270.0);
        let set = FlightSection {
            wind_mps: 4.0,
            wind_from_deg: 90.0,
            wind_margin_mps: 1.5,
        };
        let w = PlanWind::of(&set, None).unwrap();
        assert_eq!((w.planned.speed_mps, w.planned.from_deg), (5.5, 90.0));
        assert!(PlanWind::of(&set, Some(Wind::new(50.0, 0.0).unwrap())).is_err());
    }
}
