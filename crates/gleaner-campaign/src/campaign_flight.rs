//! A campaign's flight days: each mission's wind — drawn from a distribution or read from a
//! file of observed daily winds — which is the forecast the mission is planned for, the wind
//! its sorties are flown in (the forecast plus a seeded error), each sortie's battery (a
//! seeded share of its rated capacity), and the simulated flight that re-plans in the air
//! ([`gleaner_app::replan`]) when the energy left cannot fly the rest of the route with the reserve.
//!
//! Every draw is a function of the conditions' seed and the mission time (and the sortie and
//! the leg), so every strategy, replicate and thread count meets the same weather on the same
//! day: each draw seeds its own ChaCha8 generator from a SplitMix64 hash of those keys and
//! samples `rand_distr`'s distributions (Weibull, normal, uniform) from it.
//!
//! The plan's margin is tied to the forecast error ([`FlightConditions::planning_margin_mps`]):
//! a mission is planned for the forecast speed plus the `q`-quantile of the error's component
//! along the wind (σ·Φ⁻¹(q)). In the air the day's wind is known from the first leg, so a
//! re-plan adds only a margin for the gusts still to come ([`FlightConditions::air_margin_mps`]).

use std::path::{Path, PathBuf};

use gleaner_energy::{CellVisit, Wind};
use gleaner_field::{CellIndex, UnixSeconds};
use gleaner_store::{MissionId, Store};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal, Weibull};
use statrs::distribution::{ContinuousCDF, Normal};

use crate::seed::splitmix;
use gleaner_app::Project;
use gleaner_app::wind::MAX_WIND_MPS;
use gleaner_app::{AppError, Result};
use gleaner_app::{ReplanRequest, replan};

/// Seconds in a day.
const DAY_S: i64 = 86_400;

/// Where a campaign's daily winds come from.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum WindSource {
    /// Still air every day (the forecast is 0 m/s).
    #[default]
    Still,
    /// A speed drawn from a Weibull distribution with this mean (m/s) and shape (k; about 2
    /// for surface winds, the Rayleigh case), from a direction drawn uniformly in [0, 360).
    Weibull {
        /// Mean speed, m/s.
        mean_mps: f64,
        /// Shape k (dimensionless).
        shape: f64,
    },
    /// Observed daily winds, read from a file ([`read_wind_csv`]).
    Observed {
        /// The file (named in errors).
        path: PathBuf,
        /// One row per day, ascending.
        days: Vec<DailyWind>,
    },
}

/// The Weibull shape used when `weibull:MEAN` gives none.
pub const DEFAULT_WEIBULL_SHAPE: f64 = 2.0;

/// The forecast error's standard deviation (m/s) when a daily wind is drawn or read and the
/// request gives none.
pub const DEFAULT_GUST_SD_MPS: f64 = 1.0;

/// The default [`FlightConditions::margin_quantile`]: the share of forecast errors along the
/// wind the plan's margin covers (chosen on CAF 2013; docs/method.md §3, wind).
pub const DEFAULT_MARGIN_QUANTILE: f64 = 0.95;

/// The quantile of the leg-by-leg gusts the in-air checks and re-plans cover
/// ([`FlightConditions::air_margin_mps`]): 97.5%, about two standard deviations.
pub const AIR_MARGIN_QUANTILE: f64 = 0.975;

/// Largest battery weakening a campaign may ask for (a sortie's battery holds at least half
/// its rated capacity).
pub const MAX_BATTERY_WEAKENING: f64 = 0.5;

/// One day of an observed-winds file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DailyWind {
    /// The day's midnight UTC, seconds.
    pub day: UnixSeconds,
    /// Mean wind speed at the flight altitude, m/s.
    pub speed_mps: f64,
    /// Direction it blows from, degrees clockwise from north.
    pub from_deg: f64,
    /// The file's line (1-based), for errors.
    pub line: usize,
}

/// The weather and batteries a campaign's flights meet (`simulate --wind`, `--wind-csv`,
/// `--gust`, `--leg-gust`, `--weak-battery`, `--margin-quantile`). The default is still air,
/// exact forecasts and full batteries: missions are flown exactly as planned.
#[derive(Debug, Clone, PartialEq)]
pub struct FlightConditions {
    /// Each mission's forecast wind.
    pub wind: WindSource,
    /// The forecast's error: the wind flown in is the forecast plus a vector whose east and
    /// north components are independent normal draws with this standard deviation, m/s
    /// (>= 0; 0: the forecast is exact).
    pub gust_sd_mps: f64,
    /// Each sortie's battery holds a share of its rated capacity drawn uniformly in
    /// [1 − this, 1] (in [0, [`MAX_BATTERY_WEAKENING`]]; 0: every battery is as rated).
    pub battery_weakening: f64,
    /// Seed of the draws.
    pub seed: u64,
    /// Gusts met leg by leg: each leg of a flown sortie (and the hover at its end) meets the
    /// day's wind plus a vector whose east and north components are independent normal
    /// draws with this standard deviation, m/s (>= 0; 0: every leg in the day's wind).
    pub leg_gust_sd_mps: f64,
    /// The plan's margin: the quantile q of the forecast error along the wind that the margin
    /// covers, in [0.5, 0.999] (the margin is σ·Φ⁻¹(q), σ = [`FlightConditions::gust_sd_mps`]);
    /// `None`: the project's `[flight] wind_margin_mps` as it is.
    pub margin_quantile: Option<f64>,
}

impl Default for FlightConditions {
    fn default() -> Self {
        Self {
            wind: WindSource::Still,
            gust_sd_mps: 0.0,
            battery_weakening: 0.0,
            seed: 0,
            leg_gust_sd_mps: 0.0,
            margin_quantile: Some(DEFAULT_MARGIN_QUANTILE),
        }
    }
}

/// One mission's wind: what it was planned for and what it was flown in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DayWind {
    /// The forecast (the plan adds `[flight] wind_margin_mps` to it).
    pub forecast: Wind,
    /// The wind the sorties are flown in.
    pub actual: Wind,
}

/// How one mission's sorties flew in the simulated flight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlightDay {
    /// The forecast it was planned for and the wind it was flown in.
    pub wind: DayWind,
    /// The weakest of its sorties' batteries, as a share of the rated capacity (1 with no
    /// sortie).
    pub battery_factor: f64,
    /// Sorties that re-planned in the air (or turned home early).
    pub replanned: usize,
    /// Planned stops the re-plans dropped.
    pub cells_dropped: usize,
    /// Readings brought back (newly stored).
    pub readings: u64,
    /// Energy flown, all sorties, J.
    pub energy_j: f64,
    /// Sorties whose flown energy exceeded what their battery could give above the reserve.
    pub over_budget: usize,
    /// The largest flown energy less the battery's usable energy over its sorties, J (< 0:
    /// energy to spare; −∞ with no sortie).
    pub max_excess_j: f64,
}

impl FlightDay {
    /// A mission day in `wind` before any sortie.
    pub fn new(wind: DayWind) -> Self {
        Self {
            wind,
            battery_factor: 1.0,
            replanned: 0,
            cells_dropped: 0,
            readings: 0,
            energy_j: 0.0,
            over_budget: 0,
            max_excess_j: f64::NEG_INFINITY,
        }
    }

    /// Adds a sortie flown with `energy_j` against `usable_j` (J) on a battery of
    /// `battery_factor`, which re-planned or not and dropped `dropped` stops.
    pub fn add(
        &mut self,
        (energy_j, usable_j): (f64, f64),
        battery_factor: f64,
        replanned: bool,
        dropped: usize,
    ) {
        self.energy_j += energy_j;
        self.battery_factor = self.battery_factor.min(battery_factor);
        self.replanned += usize::from(replanned);
        self.cells_dropped += dropped;
        self.over_budget += usize::from(energy_j > usable_j);
        self.max_excess_j = self.max_excess_j.max(energy_j - usable_j);
    }
}

/// The generator of draw `k` of stream `stream` at time `t` under `seed`: ChaCha8 seeded
/// with a SplitMix64 hash of the four keys.
fn rng(seed: u64, stream: u64, t: UnixSeconds, k: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(splitmix(
        seed ^ splitmix(stream ^ splitmix(t as u64 ^ splitmix(k))),
    ))
}

/// A uniform draw in [0, 1) of stream `stream`, time `t` and index `k` under `seed`.
fn uniform(seed: u64, stream: u64, t: UnixSeconds, k: u64) -> f64 {
    rng(seed, stream, t, k).random::<f64>()
}

/// The next two independent standard normal draws of `rng` (east, north).
fn normal_pair(rng: &mut ChaCha8Rng) -> (f64, f64) {
    let e: f64 = StandardNormal.sample(rng);
    let n: f64 = StandardNormal.sample(rng);
    (e, n)
}

/// Φ⁻¹(q): the standard normal quantile of `q` in (0, 1).
fn normal_quantile(q: f64) -> f64 {
    Normal::standard().inverse_cdf(q)
}

/// The wind whose air moves by (`e`, `n`) m/s (east, north), speed capped at
/// [`MAX_WIND_MPS`].
fn wind_of_velocity(e: f64, n: f64) -> Wind {
    let speed = e.hypot(n).min(MAX_WIND_MPS);
    // It blows from the opposite of where it moves to.
    let mut from = (-e).atan2(-n).to_degrees();
    if from < 0.0 {
        from += 360.0;
    }
    if speed == 0.0 || from >= 360.0 - 1e-9 {
        from = 0.0;
    }
    Wind {
        speed_mps: speed,
        from_deg: from.min(359.999_999),
    }
}

impl WindSource {
    /// Parses `still` or `weibull:MEAN[:SHAPE]` (mean speed in m/s, shape k [default 2]),
    /// as `simulate --wind` takes it.
    ///
    /// # Errors
    /// [`AppError::Invalid`] quoting the text, for a malformed value or one out of range
    /// (mean in [0, 20] m/s, shape in [1, 10]).
    pub fn parse(text: &str) -> Result<Self> {
        let t = text.trim();
        let bad = |why: &str| {
            AppError::Invalid(format!(
                "--wind {:?}: {why}; expected `still` or `weibull:MEAN[:SHAPE]`, the mean speed \
                 in m/s and the Weibull shape (default {DEFAULT_WEIBULL_SHAPE}), e.g. weibull:4",
                gleaner_ingest::shorten(text)
            ))
        };
        if t.eq_ignore_ascii_case("still") {
            return Ok(Self::Still);
        }
        let Some(rest) = t.strip_prefix("weibull:") else {
            return Err(bad("unknown wind model"));
        };
        let mut parts = rest.split(':');
        let mean_mps: f64 = parts
            .next()
            .and_then(|m| m.trim().parse().ok())
            .ok_or_else(|| bad("the mean is not a number"))?;
        let shape: f64 = match parts.next() {
            None => DEFAULT_WEIBULL_SHAPE,
            Some(k) => k
                .trim()
                .parse()
                .map_err(|_| bad("the shape is not a number"))?,
        };
        if parts.next().is_some() {
            return Err(bad("too many fields"));
        }
        if !(mean_mps.is_finite() && (0.0..=20.0).contains(&mean_mps)) {
            return Err(bad("the mean must be in [0, 20] m/s"));
        }
        if !(shape.is_finite() && (1.0..=10.0).contains(&shape)) {
            return Err(bad("the shape must be in [1, 10]"));
        }
        Ok(Self::Weibull { mean_mps, shape })
    }
}

impl WindSource {
    /// The source `simulate` names: the observed days of `csv` ([`read_wind_csv`]), else
    /// `text` ([`WindSource::parse`]), else still air.
    ///
    /// # Errors
    /// Those of [`read_wind_csv`] and [`WindSource::parse`].
    pub fn choose(text: Option<&str>, csv: Option<&Path>) -> Result<Self> {
        Ok(match (text, csv) {
            (_, Some(path)) => Self::Observed {
                path: path.to_path_buf(),
                days: read_wind_csv(path)?,
            },
            (Some(text), None) => Self::parse(text)?,
            (None, None) => Self::Still,
        })
    }

    /// The forecast error's standard deviation when none is given, m/s: 0 in still air, else
    /// [`DEFAULT_GUST_SD_MPS`].
    pub fn default_gust_sd_mps(&self) -> f64 {
        if *self == Self::Still {
            0.0
        } else {
            DEFAULT_GUST_SD_MPS
        }
    }
}

/// Parses a planning-margin quantile as `simulate --margin-quantile` takes it: a number in
/// [0.5, 0.999], or `settings` (`None`: the project's `[flight] wind_margin_mps`).
///
/// # Errors
/// [`AppError::Invalid`] quoting the text, for anything else.
pub fn parse_margin_quantile(text: &str) -> Result<Option<f64>> {
    let t = text.trim();
    if t.eq_ignore_ascii_case("settings") {
        return Ok(None);
    }
    match t.parse::<f64>() {
        Ok(q) if q.is_finite() && (0.5..=0.999).contains(&q) => Ok(Some(q)),
        _ => Err(AppError::Invalid(format!(
            "--margin-quantile {:?}: expected a number in [0.5, 0.999] (the share of forecast \
             errors along the wind the planning margin covers) or `settings` ([flight] \
             wind_margin_mps)",
            gleaner_ingest::shorten(text)
        ))),
    }
}

/// Reads a file of observed daily winds: a header line naming the columns `date`
/// (`YYYY-MM-DD` or `MM/DD/YYYY`), `speed_mps` (m/s, in [0, 40]) and `from_deg` (degrees
/// clockwise from north the wind blows from, in [0, 360]), in any order, other columns
/// ignored; one row per day. Blank lines are skipped; a UTF-8 BOM and CRLF are accepted.
///
/// # Errors
/// [`AppError::Invalid`] naming the file, the line and the field: a missing column, a row
/// with another number of fields than the header, a date, speed or direction that does not
/// parse or is out of range, a day given twice; an empty file. [`AppError::Io`] when the file
/// cannot be read.
pub fn read_wind_csv(path: &Path) -> Result<Vec<DailyWind>> {
    let table = gleaner_app::cell_csv::read_table(path, " `date,speed_mps,from_deg`")?;
    let bad =
        |line: usize, what: String| AppError::Invalid(format!("{}:{line}: {what}", path.display()));
    let header: Vec<String> = table
        .header
        .iter()
        .map(|c| c.to_ascii_lowercase())
        .collect();
    let column = |name: &str| {
        header.iter().position(|h| h == name).ok_or_else(|| {
            bad(
                1,
                format!("no column {name:?} in the header (expected date, speed_mps and from_deg)"),
            )
        })
    };
    let (c_date, c_speed, c_from) = (column("date")?, column("speed_mps")?, column("from_deg")?);
    let mut days: Vec<DailyWind> = Vec::new();
    for (line, fields) in &table.rows {
        let line = *line;
        let field = |c: usize| fields[c].as_str();
        let day = gleaner_ingest::time::parse_date(field(c_date)).ok_or_else(|| {
            bad(
                line,
                format!(
                    "date {:?}: expected YYYY-MM-DD or MM/DD/YYYY",
                    gleaner_ingest::shorten(field(c_date))
                ),
            )
        })?;
        let number = |c: usize, name: &str, range: (f64, f64), unit: &str| -> Result<f64> {
            let text = field(c);
            match text.parse::<f64>() {
                Ok(x) if x.is_finite() && (range.0..=range.1).contains(&x) => Ok(x),
                _ => Err(bad(
                    line,
                    format!(
                        "{name} {:?}: expected a number in [{}, {}] {unit}",
                        gleaner_ingest::shorten(text),
                        range.0,
                        range.1
                    ),
                )),
            }
        };
        let speed_mps = number(c_speed, "speed_mps", (0.0, MAX_WIND_MPS), "m/s")?;
        let from_deg = number(c_from, "from_deg", (0.0, 360.0), "degrees")?;
        days.push(DailyWind {
            day,
            speed_mps,
            from_deg: if from_deg == 360.0 { 0.0 } else { from_deg },
            line,
        });
    }
    if days.is_empty() {
        return Err(AppError::Invalid(format!(
            "{}: no rows after the header",
            path.display()
        )));
    }
    days.sort_by_key(|d| (d.day, d.line));
    if let Some(w) = days.windows(2).find(|w| w[0].day == w[1].day) {
        return Err(bad(
            w[1].line,
            format!(
                "date {}: given twice (first on line {})",
                &gleaner_app::format_rfc3339(w[1].day)[..10],
                w[0].line
            ),
        ));
    }
    Ok(days)
}

impl FlightConditions {
    /// Whether flights are flown exactly as planned: still air, exact forecasts, no gusts,
    /// full batteries.
    pub fn is_still(&self) -> bool {
        self.wind == WindSource::Still
            && self.gust_sd_mps == 0.0
            && self.leg_gust_sd_mps == 0.0
            && self.battery_weakening == 0.0
    }

    /// The margin a mission is planned with, m/s: added to its forecast speed (not to still
    /// air). With [`FlightConditions::margin_quantile`] q, σ·Φ⁻¹(q) (σ the forecast error's
    /// standard deviation, Φ the standard normal distribution function): the q-quantile of
    /// the error's component along the forecast wind, 0 for q = 0.5 or an exact forecast.
    /// Without one, or when flights are flown as planned, `settings_margin_mps` (`[flight]
    /// wind_margin_mps`) as it is.
    pub fn planning_margin_mps(&self, settings_margin_mps: f64) -> f64 {
        match self.margin_quantile {
            Some(q) if !self.is_still() => self.gust_sd_mps * normal_quantile(q).max(0.0),
            _ => settings_margin_mps,
        }
    }

    /// The forecast a mission of `day` is planned (and explored) for: `None` in still air
    /// (the project's `[flight]` settings), else the day's forecast.
    pub fn plan_wind(&self, day: &DayWind) -> Option<Wind> {
        match self.wind {
            WindSource::Still => None,
            _ => Some(day.forecast),
        }
    }

    /// The margin the aircraft adds in the air to the day's wind it has met, m/s, when it
    /// checks the rest of its route and when it re-plans: the [`AIR_MARGIN_QUANTILE`]
    /// quantile of the leg-by-leg gusts' component along the wind (σ_leg·Φ⁻¹(0.975) ≈
    /// 2 σ_leg); 0 without gusts (the day's wind is known once airborne).
    pub fn air_margin_mps(&self) -> f64 {
        self.leg_gust_sd_mps * normal_quantile(AIR_MARGIN_QUANTILE)
    }

    /// The winds sortie `sortie` (from 0) of the mission at `t` meets leg by leg: `day` plus
    /// the `legs` first gusts of its own seeded sequence (leg i of the route flown, the return
    /// last; the same leg index always meets the same gust), each speed capped at
    /// [`MAX_WIND_MPS`]. All `day` without leg gusts.
    pub fn leg_winds(&self, t: UnixSeconds, sortie: usize, day: Wind, legs: usize) -> Vec<Wind> {
        if self.leg_gust_sd_mps == 0.0 {
            return vec![day; legs];
        }
        let mut r = rng(self.seed, 5, t, sortie as u64);
        let (e, n) = day.velocity_mps();
        (0..legs)
            .map(|_| {
                let (ge, gn) = normal_pair(&mut r);
                wind_of_velocity(e + self.leg_gust_sd_mps * ge, n + self.leg_gust_sd_mps * gn)
            })
            .collect()
    }

    /// Checks the settings and that an observed-winds file covers every mission's day.
    ///
    /// # Errors
    /// [`AppError::Invalid`] naming the setting, or the file and the first day it lacks.
    pub fn check(&self, schedule: &[UnixSeconds]) -> Result<()> {
        if !(self.gust_sd_mps.is_finite() && (0.0..=10.0).contains(&self.gust_sd_mps)) {
            return Err(AppError::Invalid(format!(
                "--gust {}: the forecast error's standard deviation must be in [0, 10] m/s",
                gleaner_ingest::number(self.gust_sd_mps)
            )));
        }
        if !(self.leg_gust_sd_mps.is_finite() && (0.0..=10.0).contains(&self.leg_gust_sd_mps)) {
            return Err(AppError::Invalid(format!(
                "--leg-gust {}: the gusts' standard deviation must be in [0, 10] m/s",
                gleaner_ingest::number(self.leg_gust_sd_mps)
            )));
        }
        if let Some(q) = self.margin_quantile
            && !(q.is_finite() && (0.5..=0.999).contains(&q))
        {
            return Err(AppError::Invalid(format!(
                "--margin-quantile {}: the share of forecast errors the margin covers must be \
                 in [0.5, 0.999]",
                gleaner_ingest::number(q)
            )));
        }
        if !(self.battery_weakening.is_finite()
            && (0.0..=MAX_BATTERY_WEAKENING).contains(&self.battery_weakening))
        {
            return Err(AppError::Invalid(format!(
                "--weak-battery {}: the share a battery may lack must be in [0, \
                 {MAX_BATTERY_WEAKENING}]",
                gleaner_ingest::number(self.battery_weakening)
            )));
        }
        if let WindSource::Observed { path, days } = &self.wind {
            for &t in schedule {
                let day = t.div_euclid(DAY_S) * DAY_S;
                if days.binary_search_by_key(&day, |d| d.day).is_err() {
                    return Err(AppError::Invalid(format!(
                        "{}: no wind for {} (a mission day): give a row for every day of the \
                         campaign",
                        path.display(),
                        &gleaner_app::format_rfc3339(day)[..10]
                    )));
                }
            }
        }
        Ok(())
    }

    /// The wind of the mission at `t` (s): its forecast (drawn, read for its day, or still
    /// air) and the wind flown in (the forecast plus the error).
    ///
    /// # Errors
    /// [`AppError::Invalid`] when an observed-winds file has no row for the day.
    pub fn day(&self, t: UnixSeconds) -> Result<DayWind> {
        let forecast = match &self.wind {
            WindSource::Still => Wind::CALM,
            WindSource::Weibull { mean_mps, shape } => {
                let scale = mean_mps / statrs::function::gamma::gamma(1.0 + 1.0 / shape);
                let speed = match Weibull::new(scale, *shape) {
                    Ok(w) => w.sample(&mut rng(self.seed, 1, t, 0)).min(MAX_WIND_MPS),
                    // A mean of 0 m/s: still air every day.
                    Err(_) => 0.0,
                };
                let from = 360.0 * uniform(self.seed, 2, t, 0);
                Wind {
                    speed_mps: speed,
                    from_deg: if speed == 0.0 { 0.0 } else { from },
                }
            }
            WindSource::Observed { path, days } => {
                let day = t.div_euclid(DAY_S) * DAY_S;
                let d = days
                    .binary_search_by_key(&day, |d| d.day)
                    .map(|k| days[k])
                    .map_err(|_| {
                        AppError::Invalid(format!(
                            "{}: no wind for {}",
                            path.display(),
                            &gleaner_app::format_rfc3339(day)[..10]
                        ))
                    })?;
                Wind {
                    speed_mps: d.speed_mps,
                    from_deg: d.from_deg,
                }
            }
        };
        let actual = if self.gust_sd_mps > 0.0 {
            let (ze, zn) = normal_pair(&mut rng(self.seed, 3, t, 0));
            let (e, n) = forecast.velocity_mps();
            wind_of_velocity(e + self.gust_sd_mps * ze, n + self.gust_sd_mps * zn)
        } else {
            forecast
        };
        Ok(DayWind { forecast, actual })
    }

    /// The share of its rated capacity the battery of sortie `sortie` (from 0) of the mission
    /// at `t` holds, in [1 − [`FlightConditions::battery_weakening`], 1].
    pub fn battery_factor(&self, t: UnixSeconds, sortie: usize) -> f64 {
        if self.battery_weakening == 0.0 {
            return 1.0;
        }
        1.0 - self.battery_weakening * uniform(self.seed, 4, t, sortie as u64)
    }
}

/// How one sortie went in the simulated flight.
#[derive(Debug, Clone, PartialEq)]
pub struct SortieFlight {
    /// The cells visited, in the order flown.
    pub cells: Vec<CellIndex>,
    /// Whether it re-planned in the air (or turned home early).
    pub replanned: bool,
    /// Planned stops it did not visit.
    pub dropped: usize,
    /// Energy flown in the actual wind, J (climb, legs, hovers, return, descent).
    pub energy_j: f64,
    /// What its battery could give above the reserve, J: capacity × battery factor − reserve.
    pub usable_j: f64,
}

/// The weather one sortie meets in the air: the day's wind, the gusts leg by leg, and the
/// margin it adds to the day's wind when it checks the rest of its route and re-plans.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SortieWeather<'a> {
    /// The campaign's conditions (seed, gusts).
    pub conditions: &'a FlightConditions,
    /// The mission's time, s.
    pub t: UnixSeconds,
    /// The sortie, from 0.
    pub sortie: usize,
    /// The day's wind (the forecast plus its error).
    pub day: Wind,
}

impl FlightConditions {
    /// The weather sortie `sortie` (from 0) of the mission at `t` (s) meets in `day` wind.
    pub fn sortie(&self, t: UnixSeconds, sortie: usize, day: Wind) -> SortieWeather<'_> {
        SortieWeather {
            conditions: self,
            t,
            sortie,
            day,
        }
    }
}

/// `wind`'s speed plus `margin_mps` (m/s, may be < 0; the speed kept in [0, 40] m/s), from
/// the same direction.
fn plus(wind: Wind, margin_mps: f64) -> Wind {
    Wind {
        speed_mps: (wind.speed_mps + margin_mps).clamp(0.0, MAX_WIND_MPS),
        from_deg: wind.from_deg,
    }
}

/// Flies the stored mission `id` in `weather` on a battery holding `battery_factor` of its
/// rated capacity. Each leg (and the hover at its end) meets the day's wind plus that leg's
/// gust ([`FlightConditions::leg_winds`]). The aircraft learns the day's wind on its first
/// leg and reads the energy left from its battery: over each stop, done collecting, it prices
/// the rest of its route in the day's wind with [`FlightConditions::air_margin_mps`] added and
/// taken off (a stronger wind costs more on the legs, a weaker one more at the hovers: the
/// dearer of the two), and when the energy left less the reserve cannot fly it, it re-plans
/// from that stop with [`gleaner_app::replan`] (in the dearer wind; the remaining stops dropped and
/// reordered), once; when the re-planned route is still short, or no continuation exists, it
/// flies home from the stop it is over. Records nothing.
///
/// # Errors
/// An unknown mission, invalid `[energy]` settings, a project with a geofence or no-fly zones
/// (the continuation's legs are straight), a battery factor outside (0, 1].
pub fn fly_in_wind<S: Store>(
    project: &Project<S>,
    id: MissionId,
    weather: SortieWeather<'_>,
    battery_factor: f64,
    planner_iterations: u64,
) -> Result<SortieFlight> {
    if !(battery_factor > 0.0 && battery_factor <= 1.0) {
        return Err(AppError::Invalid(format!(
            "battery factor {}: must be in (0, 1]",
            gleaner_ingest::number(battery_factor)
        )));
    }
    let f = &project.settings().field;
    if f.geofence.is_some() || f.no_fly.is_some() {
        return Err(AppError::Invalid(
            "flights in a simulated wind re-plan with straight legs, and this project sets \
             [field] geofence or no_fly: simulate it in still air"
                .into(),
        ));
    }
    let mission = gleaner_app::mission(project, id)?;
    let profile = mission.mission.profile;
    let export = gleaner_app::export_energy_model(project, &mission)?;
    let model = gleaner_energy::FlightEnergyModel {
        wind: weather.day,
        ..export
    }
    .model(profile.cruise_speed_mps, profile.altitude_m)
    .map_err(|e| AppError::core("energy model", e))?
    // The air the flight meets, exactly: not the planner's worst case from calm up to it.
    .with_wind(weather.day);
    let margin_mps = weather.conditions.air_margin_mps();
    // What the aircraft prices the rest of its route in: the day's wind, or with gusts to
    // come the dearer of that wind plus and less the margin.
    let priced: Vec<(Wind, gleaner_energy::MissionEnergyModel)> = if margin_mps > 0.0 {
        [
            plus(weather.day, margin_mps),
            plus(weather.day, -margin_mps),
        ]
        .into_iter()
        .map(|w| (w, model.with_wind(w)))
        .collect()
    } else {
        vec![(weather.day, model.clone())]
    };
    let battery = project.settings().energy.to_core()?.battery;
    let capacity_j = battery.capacity_j * battery_factor;
    let reserve_j = battery.capacity_j * battery.reserve_fraction;
    let usable_j = capacity_j - reserve_j;
    let (_, field) = project.field()?;
    let frame = field.frame();
    let base = gleaner_energy::flight_point(frame, field.base());
    let visit = |s: &gleaner_store::StopRecord| {
        (
            s.cell,
            CellVisit {
                centre: frame.forward(s.centre),
                hover_s: s.hover_s,
            },
        )
    };
    let mut route: Vec<(CellIndex, CellVisit)> = mission.mission.stops.iter().map(visit).collect();
    let planned = route.len();
    // A re-plan never lengthens the route: planned + 1 legs at most.
    let winds = weather
        .conditions
        .leg_winds(weather.t, weather.sortie, weather.day, planned + 1);
    let visits = |r: &[(CellIndex, CellVisit)]| r.iter().map(|p| p.1).collect::<Vec<_>>();
    let core = |e| AppError::core("simulated flight", e);
    // Energy flown from take-off to over stop k (1-based), done collecting: the climb, k legs
    // and k hovers in their winds.
    let spent_j = |r: &[(CellIndex, CellVisit)], k: usize| -> Result<f64> {
        let s = model
            .sortie_in_winds(base, &visits(&r[..k]), &winds[..=k])
            .map_err(core)?;
        Ok(s.total_j - s.legs_j[k] - model.descent().0)
    };
    let mut replanned = false;
    // Over stop k (1-based), done collecting: can the rest be flown?
    let mut k = 1;
    while k < route.len() {
        let spent = spent_j(&route, k)?;
        let mut rest = (f64::NEG_INFINITY, weather.day);
        for (w, m) in &priced {
            let e = m
                .continuation(route[k - 1].1.centre, base, &visits(&route[k..]), usable_j)
                .map_err(core)?;
            if e.total_j > rest.0 {
                rest = (e.total_j, *w);
            }
        }
        if spent + rest.0 <= usable_j {
            k += 1;
            continue;
        }
        if replanned {
            route.truncate(k);
            break;
        }
        replanned = true;
        let left_j = (capacity_j - spent).min(battery.capacity_j);
        let continuation = if left_j > 0.0 {
            replan(
                project,
                &ReplanRequest {
                    mission: id,
                    after_stop: k,
                    energy_left_j: left_j,
                    seed: None,
                    iterations: Some(planner_iterations),
                    time_limit_s: Some(3_600.0),
                    wind: Some(rest.1),
                    wind_margin_mps: Some(0.0),
                },
            )
            .ok()
        } else {
            None
        };
        route.truncate(k);
        if let Some(c) = continuation {
            route.extend(c.mission.stops.iter().map(visit));
        }
        k += 1;
    }
    let flown = model
        .sortie_in_winds(base, &visits(&route), &winds[..=route.len()])
        .map_err(core)?;
    Ok(SortieFlight {
        dropped: planned - route.len(),
        cells: route.into_iter().map(|p| p.0).collect(),
        replanned,
        energy_j: flown.total_j,
        usable_j,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_margin_is_a_quantile_of_the_forecast_error() {
        let windy = FlightConditions {
            wind: WindSource::Weibull {
                mean_mps: 4.0,
                shape: 2.0,
            },
            gust_sd_mps: 1.5,
            ..FlightConditions::default()
        };
        // Φ⁻¹(0.95) ≈ 1.6449.
        let m = windy.planning_margin_mps(2.0);
        assert!((m - 1.5 * 1.644_853_626_951).abs() < 1e-6, "{m}");
        let q84 = FlightConditions {
            margin_quantile: Some(0.84),
            ..windy.clone()
        };
        // Φ⁻¹(0.84) ≈ 0.9945: about one standard deviation.
        assert!((q84.planning_margin_mps(2.0) - 1.5 * 0.994_457_883_209_753).abs() < 1e-6);
        let median = FlightConditions {
            margin_quantile: Some(0.5),
            ..windy.clone()
        };
        assert_eq!(median.planning_margin_mps(2.0), 0.0);
        let q975 = FlightConditions {
            margin_quantile: Some(0.975),
            ..windy.clone()
        };
        assert!((q975.planning_margin_mps(2.0) - 1.5 * 1.959_963_985).abs() < 1e-6);
        // Without a quantile, or flown as planned: the settings' margin.
        let settings = FlightConditions {
            margin_quantile: None,
            ..windy.clone()
        };
        assert_eq!(settings.planning_margin_mps(2.0), 2.0);
        assert_eq!(FlightConditions::default().planning_margin_mps(2.0), 2.0);
        // An exact forecast needs no margin.
        let exact = FlightConditions {
            gust_sd_mps: 0.0,
            ..windy.clone()
        };
        assert_eq!(exact.planning_margin_mps(2.0), 0.0);
        // In the air: nothing to add without gusts, about 2 σ of them with.
        assert_eq!(windy.air_margin_mps(), 0.0);
        let gusty = FlightConditions {
            leg_gust_sd_mps: 0.5,
            ..windy
        };
        assert!((gusty.air_margin_mps() - 0.5 * 1.959_963_985).abs() < 1e-6);
        assert!(!gusty.is_still());
        let only_gusts = FlightConditions {
            leg_gust_sd_mps: 0.5,
            ..FlightConditions::default()
        };
        assert!(!only_gusts.is_still());
    }

    #[test]
    fn parses_margin_quantiles() {
        assert_eq!(parse_margin_quantile("0.84").unwrap(), Some(0.84));
        assert_eq!(parse_margin_quantile(" 0.5 ").unwrap(), Some(0.5));
        assert_eq!(parse_margin_quantile("Settings").unwrap(), None);
        for bad in ["", "0.3", "1", "x", "NaN"] {
            let e = parse_margin_quantile(bad).unwrap_err().to_string();
            assert!(
                e.contains("--margin-quantile") && e.contains("0.999"),
                "{e}"
            );
        }
    }

    #[test]
    fn leg_gusts_have_their_spread_and_are_seeded() {
        let day = Wind::new(5.0, 250.0).unwrap();
        let calm = FlightConditions::default();
        assert_eq!(calm.leg_winds(0, 0, day, 4), vec![day; 4]);
        let c = FlightConditions {
            leg_gust_sd_mps: 1.2,
            seed: 9,
            ..FlightConditions::default()
        };
        let legs = c.leg_winds(7 * DAY_S, 1, day, 20_000);
        let (de, dn) = day.velocity_mps();
        let (mut sum_e, mut sq) = (0.0, 0.0);
        for w in &legs {
            let (e, n) = w.velocity_mps();
            sum_e += e - de;
            sq += (e - de).powi(2) + (n - dn).powi(2);
        }
        let n = legs.len() as f64;
        assert!((sum_e / n).abs() < 0.03, "mean {}", sum_e / n);
        let sd = (sq / (2.0 * n)).sqrt();
        assert!((sd - 1.2).abs() < 0.03, "sd {sd}");
        // The first legs are the same whatever the number asked for; another sortie, time or
        // seed meets other gusts.
        assert_eq!(c.leg_winds(7 * DAY_S, 1, day, 5)[..], legs[..5]);
        assert_ne!(c.leg_winds(7 * DAY_S, 2, day, 5)[..], legs[..5]);
        assert_ne!(c.leg_winds(8 * DAY_S, 1, day, 5)[..], legs[..5]);
        let other = FlightConditions { seed: 10, ..c };
        assert_ne!(other.leg_winds(7 * DAY_S, 1, day, 5)[..], legs[..5]);
    }

    #[test]
    fn parses_wind_models() {
        assert_eq!(WindSource::parse("still").unwrap(), WindSource::Still);
        assert_eq!(
            WindSource::parse("weibull:4").unwrap(),
            WindSource::Weibull {
                mean_mps: 4.0,
                shape: 2.0
            }
        );
        assert_eq!(
            WindSource::parse(" weibull:5.5:1.8 ").unwrap(),
            WindSource::Weibull {
                mean_mps: 5.5,
                shape: 1.8
            }
        );
        for bad in [
            "",
            "weibull",
            "weibull:",
            "weibull:x",
            "weibull:4:y",
            "weibull:4:2:1",
            "weibull:-1",
            "weibull:30",
            "weibull:4:0.5",
            "normal:4",
        ] {
            let e = WindSource::parse(bad).unwrap_err().to_string();
            assert!(
                e.contains("--wind") && e.contains("weibull:MEAN"),
                "{bad}: {e}"
            );
        }
    }

    #[test]
    fn weibull_draws_have_the_mean_and_are_seeded() {
        let c = FlightConditions {
            wind: WindSource::Weibull {
                mean_mps: 4.0,
                shape: 2.0,
            },
            seed: 7,
            ..FlightConditions::default()
        };
        let days: Vec<DayWind> = (0..20_000).map(|d| c.day(d * DAY_S).unwrap()).collect();
        let mean = days.iter().map(|d| d.forecast.speed_mps).sum::<f64>() / days.len() as f64;
        assert!((mean - 4.0).abs() < 0.05, "mean {mean}");
        // Rayleigh (k = 2): P(v > 6) = exp(−(6/λ)²), λ = 4/Γ(1.5).
        let above = days.iter().filter(|d| d.forecast.speed_mps > 6.0).count() as f64;
        let lambda = 4.0 / statrs::function::gamma::gamma(1.5);
        let want = (-(6.0f64 / lambda).powi(2)).exp();
        assert!((above / days.len() as f64 - want).abs() < 0.01);
        let north_half = days.iter().filter(|d| d.forecast.from_deg < 180.0).count() as f64;
        assert!((north_half / days.len() as f64 - 0.5).abs() < 0.02);
        // No forecast error: flown in the forecast.
        assert!(days.iter().all(|d| d.actual == d.forecast));
        // Same seed, same weather; another seed, another.
        assert_eq!(c.day(5 * DAY_S).unwrap(), days[5]);
        let other = FlightConditions { seed: 8, ..c };
        assert_ne!(other.day(5 * DAY_S).unwrap(), days[5]);
    }

    #[test]
    fn the_error_has_its_standard_deviation() {
        let c = FlightConditions {
            wind: WindSource::Weibull {
                mean_mps: 4.0,
                shape: 2.0,
            },
            gust_sd_mps: 1.5,
            battery_weakening: 0.2,
            seed: 3,
            ..FlightConditions::default()
        };
        let n = 20_000;
        let mut sq = 0.0;
        for d in 0..n {
            let w = c.day(d * DAY_S).unwrap();
            let (fe, f_n) = w.forecast.velocity_mps();
            let (ae, an) = w.actual.velocity_mps();
            sq += (ae - fe).powi(2) + (an - f_n).powi(2);
            let b = c.battery_factor(d * DAY_S, 1);
            assert!((0.8..=1.0).contains(&b));
        }
        let sd = (sq / (2.0 * n as f64)).sqrt();
        assert!((sd - 1.5).abs() < 0.03, "sd {sd}");
        assert_eq!(FlightConditions::default().battery_factor(0, 0), 1.0);
        assert!(FlightConditions::default().is_still());
        assert!(!c.is_still());
    }

    #[test]
    fn wind_of_velocity_inverts_velocity() {
        for (s, from) in [(3.0, 0.0), (5.0, 90.0), (2.0, 225.0), (7.5, 359.0)] {
            let w = Wind::new(s, from).unwrap();
            let (e, n) = w.velocity_mps();
            let back = wind_of_velocity(e, n);
            assert!((back.speed_mps - s).abs() < 1e-9);
            assert!(
                (back.from_deg - from).abs() < 1e-9,
                "{from} -> {}",
                back.from_deg
            );
        }
        assert_eq!(wind_of_velocity(0.0, 0.0), Wind::CALM);
        assert_eq!(wind_of_velocity(100.0, 0.0).speed_mps, MAX_WIND_MPS);
    }

    fn csv(text: &str) -> (tempfile::TempDir, PathBuf) {
        let tmp = tempfile::tempdir().unwrap();
        let p = tmp.path().join("winds.csv");
        std::fs::write(&p, text).unwrap();
        (tmp, p)
    }

    #[test]
    fn reads_observed_winds() {
        let (_t, p) = csv(
            "\u{feff}from_deg,date,speed_mps,gust\r\n270,2014-01-02,6.5,9\r\n\r\n0,2014-01-01,0,0\n360,01/03/2014,3,4\n",
        );
        let days = read_wind_csv(&p).unwrap();
        let d0 = gleaner_ingest::time::parse_date("2014-01-01").unwrap();
        assert_eq!(days.len(), 3);
        assert_eq!(
            (days[0].day, days[0].speed_mps, days[0].from_deg),
            (d0, 0.0, 0.0)
        );
        assert_eq!(
            (
                days[1].day,
                days[1].speed_mps,
                days[1].from_deg,
                days[1].line
            ),
            (d0 + DAY_S, 6.5, 270.0, 2)
        );
        assert_eq!((days[2].day, days[2].from_deg), (d0 + 2 * DAY_S, 0.0));
        let c = FlightConditions {
            wind: WindSource::Observed {
                path: p.clone(),
                days,
            },
            ..FlightConditions::default()
        };
        let w = c.day(d0 + DAY_S + 3_600).unwrap();
        assert_eq!((w.forecast.speed_mps, w.forecast.from_deg), (6.5, 270.0));
        assert!(c.check(&[d0, d0 + 2 * DAY_S]).is_ok());
        let e = c.check(&[d0, d0 + 3 * DAY_S]).unwrap_err().to_string();
        assert!(e.contains("winds.csv") && e.contains("2014-01-04"), "{e}");
    }

    #[test]
    fn observed_winds_errors_name_file_line_and_field() {
        let cases = [
            ("", "empty file"),
            (
                "date,speed_mps\n2014-01-01,3\n",
                ":1: no column \"from_deg\"",
            ),
            ("date,speed_mps,from_deg\n", "no rows"),
            (
                "date,speed_mps,from_deg\n2014-01-01,3\n",
                ":2: 2 fields, but the header has 3",
            ),
            (
                "date,speed_mps,from_deg\n2014-01-01,3,90\nJan 2,3,90\n",
                ":3: date \"Jan 2\"",
            ),
            (
                "date,speed_mps,from_deg\n2014-01-01,fast,90\n",
                ":2: speed_mps \"fast\"",
            ),
            (
                "date,speed_mps,from_deg\n2014-01-01,-1,90\n",
                ":2: speed_mps \"-1\"",
            ),
            (
                "date,speed_mps,from_deg\n2014-01-01,41,90\n",
                ":2: speed_mps \"41\"",
            ),
            (
                "date,speed_mps,from_deg\n2014-01-01,3,NaN\n",
                ":2: from_deg \"NaN\"",
            ),
            (
                "date,speed_mps,from_deg\n2014-01-01,3,361\n",
                ":2: from_deg \"361\"",
            ),
            (
                "date,speed_mps,from_deg\n2014-01-01,3,90\n2014-01-01,4,90\n",
                ":3: date 2014-01-01: given twice (first on line 2)",
            ),
        ];
        for (text, want) in cases {
            let (_t, p) = csv(text);
            let e = read_wind_csv(&p).unwrap_err().to_string();
            assert!(e.contains("winds.csv") && e.contains(want), "{text:?}: {e}");
        }
        let (_t, p) = csv("x");
        std::fs::write(&p, b"date,speed_mps,from_deg\n\xff\n").unwrap();
        let e = read_wind_csv(&p).unwrap_err().to_string();
        assert!(e.contains(":2: not valid UTF-8"), "{e}");
        let e = read_wind_csv(Path::new("/nonexistent/winds.csv"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("/nonexistent/winds.csv"), "{e}");
    }

    #[test]
    fn conditions_are_checked() {
        let bad_gust = FlightConditions {
            gust_sd_mps: -1.0,
            ..FlightConditions::default()
        };
        assert!(
            bad_gust
                .check(&[])
                .unwrap_err()
                .to_string()
                .contains("--gust")
        );
        let bad_battery = FlightConditions {
            battery_weakening: 0.7,
            ..FlightConditions::default()
        };
        assert!(
            bad_battery
                .check(&[])
                .unwrap_err()
                .to_string()
                .contains("--weak-battery")
        );
        let bad_leg = FlightConditions {
            leg_gust_sd_mps: f64::NAN,
            ..FlightConditions::default()
        };
        assert!(
            bad_leg
                .check(&[])
                .unwrap_err()
                .to_string()
                .contains("--leg-gust")
        );
        for q in [0.4, 1.0, f64::NAN] {
            let bad_q = FlightConditions {
                margin_quantile: Some(q),
                ..FlightConditions::default()
            };
            let e = bad_q.check(&[]).unwrap_err().to_string();
            assert!(e.contains("--margin-quantile"), "{e}");
        }
        assert!(FlightConditions::default().check(&[]).is_ok());
    }
}
