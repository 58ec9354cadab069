//! Flight legs in a steady wind: the airspeed and heading that hold a leg's track at the
//! planned ground speed, the propulsion power at that airspeed (the same rotary-wing curve
//! P(V), V the airspeed), and the leg's energy with its head-, tail- and cross-wind parts.
//!
//! Frames and units: the local frame of the field (metres east `e`, north `n`); a wind is
//! given as meteorologists give it — its speed (m/s) and the direction it blows **from**
//! (degrees clockwise from north: 270 = a west wind, blowing towards the east). Headings and
//! tracks are degrees clockwise from north in [0, 360).
//!
//! For a leg along the unit vector `t` flown at ground speed `V_g` in a wind of velocity `w`
//! (the way the air moves), the aircraft must move through the air at `a = V_g·t − w`: its
//! airspeed is `|a|`, its heading the direction of `a`. The leg takes `d / V_g` seconds at
//! `P(|a|)` watts, so it costs `P(|a|) · d / V_g` joules. In still air `a = V_g·t` and this is
//! exactly the still-air model's `P(V_g)/V_g · d` (same operations, same bits: tested).
//! Hovering in a wind means holding `|w|` of airspeed: `P(|w|)`, `P(0)` in still air.

use gleaner_field::LocalPoint;

use crate::error::{EnergyError, finite, non_negative, positive};
use crate::propulsion::PowerModel;

/// A steady horizontal wind.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wind {
    /// Wind speed, m/s (>= 0).
    pub speed_mps: f64,
    /// Direction the wind blows from, degrees clockwise from north (meteorological).
    pub from_deg: f64,
}

impl Wind {
    /// Still air.
    pub const CALM: Wind = Wind {
        speed_mps: 0.0,
        from_deg: 0.0,
    };

    /// A wind of `speed_mps` (m/s, finite and >= 0) blowing from `from_deg` (degrees
    /// clockwise from north, finite; any value, taken modulo 360).
    ///
    /// # Errors
    /// [`EnergyError::InvalidParameter`] naming the value.
    pub fn new(speed_mps: f64, from_deg: f64) -> Result<Self, EnergyError> {
        non_negative("wind speed (m/s)", speed_mps)?;
        finite("wind direction (degrees from north)", from_deg)?;
        Ok(Self {
            speed_mps,
            from_deg,
        })
    }

    /// Whether the air is still (speed 0 m/s).
    pub fn is_calm(&self) -> bool {
        self.speed_mps == 0.0
    }

    /// The velocity of the air (where it moves to), m/s east and north.
    pub fn velocity_mps(&self) -> (f64, f64) {
        if self.is_calm() {
            return (0.0, 0.0);
        }
        let to = (self.from_deg + 180.0).to_radians();
        (self.speed_mps * to.sin(), self.speed_mps * to.cos())
    }
}

/// One leg flown in a wind at a planned ground speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindLeg {
    /// Leg length, m.
    pub distance_m: f64,
    /// Ground speed along the track, m/s.
    pub ground_speed_mps: f64,
    /// Airspeed that holds the track at that ground speed, m/s.
    pub airspeed_mps: f64,
    /// Track (direction of travel over the ground), degrees clockwise from north.
    pub track_deg: f64,
    /// Heading (direction the aircraft moves through the air), degrees clockwise from north.
    pub heading_deg: f64,
    /// Wind component against the track, m/s: > 0 a head wind, < 0 a tail wind.
    pub headwind_mps: f64,
    /// Wind component across the track, m/s: > 0 from the left (pushing right), < 0 from the
    /// right.
    pub crosswind_mps: f64,
    /// Flight time d / V_g, s.
    pub time_s: f64,
    /// Propulsion power at the airspeed, W.
    pub power_w: f64,
    /// Propulsion energy of the leg, J.
    pub energy_j: f64,
}

/// Degrees clockwise from north of the vector (`e`, `n`), in [0, 360).
fn bearing_deg(e: f64, n: f64) -> f64 {
    let b = e.atan2(n).to_degrees();
    if b < 0.0 { b + 360.0 } else { b }
}

impl PowerModel {
    /// The leg `from` -> `to` (local frame, m) flown at `ground_speed_mps` (m/s, > 0) along
    /// its track in `wind`. A leg of zero length has zero time and energy and the track and
    /// heading of the wind's own direction of travel (0 in still air).
    ///
    /// # Errors
    /// [`EnergyError::InvalidParameter`] for a non-finite position or a ground speed that is
    /// not finite and > 0.
    pub fn leg_in_wind(
        &self,
        from: LocalPoint,
        to: LocalPoint,
        ground_speed_mps: f64,
        wind: Wind,
    ) -> Result<WindLeg, EnergyError> {
        for x in [from.e, from.n, to.e, to.n] {
            finite("leg end (m)", x)?;
        }
        positive("ground speed (m/s)", ground_speed_mps)?;
        let (de, dn) = (to.e - from.e, to.n - from.n);
        let distance_m = (de * de + dn * dn).sqrt();
        let (te, tn) = if distance_m > 0.0 {
            (de / distance_m, dn / distance_m)
        } else {
            (0.0, 0.0)
        };
        let (we, wn) = wind.velocity_mps();
        // Along the track the wind moves the aircraft forward by w·t: the head wind is −w·t.
        let headwind_mps = -(we * te + wn * tn);
        // Across it: w·(tn, −te), the wind's component towards the track's right, > 0 for a
        // wind from the left.
        let crosswind_mps = we * tn - wn * te;
        let airspeed_mps = if wind.is_calm() {
            ground_speed_mps
        } else {
            let (ae, an) = (ground_speed_mps * te - we, ground_speed_mps * tn - wn);
            (ae * ae + an * an).sqrt()
        };
        let heading_deg = if wind.is_calm() {
            bearing_deg(te, tn)
        } else {
            bearing_deg(ground_speed_mps * te - we, ground_speed_mps * tn - wn)
        };
        let power_w = self.power_w(airspeed_mps);
        Ok(WindLeg {
            distance_m,
            ground_speed_mps,
            airspeed_mps,
            track_deg: bearing_deg(te, tn),
            heading_deg,
            headwind_mps,
            crosswind_mps,
            time_s: distance_m / ground_speed_mps,
            power_w,
            energy_j: power_w / ground_speed_mps * distance_m,
        })
    }

    /// Power to hover in `wind`: the airspeed is the wind speed, so P(|w|), W (P(0) in still
    /// air).
    pub fn hover_power_in_wind_w(&self, wind: Wind) -> f64 {
        self.power_w(wind.speed_mps)
    }
}
