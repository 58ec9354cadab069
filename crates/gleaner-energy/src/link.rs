//! Data collection at a cell: OFDMA link rates, pending data volume, collection and hover time
//! (docs/method.md §3).
//!
//! Channel model: log-distance path loss with a free-space reference gain at 1 m,
//! SNR_j (dB) = P_tx (dBm) + g0 (dB) − 10·alpha·log10(d_j / 1 m) − N (dBm), where the
//! UAV-sensor distance is d_j = sqrt(h² + o_j²) for flight altitude h and horizontal offset o_j
//! of sensor j from the cell centre (clamped below at the 1 m reference distance). The K_c
//! sensors of a cell share the bandwidth B_w equally (OFDMA):
//! r_j = (B_w/K_c)·log2(1 + SNR_j) bit/s, and the collection time is the slowest upload,
//! t_comm = max_j bytes_pending_j·8 / r_j.

use crate::error::{EnergyError, finite, non_negative, positive};

/// Radio link between the hovering UAV and the sensors of one cell.
///
/// Defaults: altitude 30 m; bandwidth 1 MHz; transmit power 10 dBm (10 mW, a typical LoRa /
/// 802.15.4 class node); noise power −110 dBm (thermal −174 dBm/Hz over 1 MHz = −114 dBm plus a
/// 4 dB receiver noise figure); reference channel gain −40 dB at 1 m (free-space
/// 20·log10(4π/λ) at 2.4 GHz, λ = 0.125 m); path-loss exponent 2 (line of sight from the air).
/// At these defaults a sensor directly below the UAV has an SNR of about 50.5 dB.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkConfig {
    /// Flight (hover) altitude above the sensors h, metres (default 30 m).
    pub altitude_m: f64,
    /// Total OFDMA bandwidth B_w shared by the cell's sensors, Hz (default 1e6 Hz).
    pub bandwidth_hz: f64,
    /// Sensor transmit power, dBm (default 10 dBm).
    pub tx_power_dbm: f64,
    /// Receiver noise power over the whole bandwidth, dBm (default −110 dBm).
    pub noise_power_dbm: f64,
    /// Channel power gain at the 1 m reference distance g0, dB (default −40 dB).
    pub reference_gain_db: f64,
    /// Path-loss exponent alpha, dimensionless (default 2).
    pub path_loss_exponent: f64,
}

impl Default for LinkConfig {
    fn default() -> Self {
        Self {
            altitude_m: 30.0,
            bandwidth_hz: 1e6,
            tx_power_dbm: 10.0,
            noise_power_dbm: -110.0,
            reference_gain_db: -40.0,
            path_loss_exponent: 2.0,
        }
    }
}

impl LinkConfig {
    /// Checks the parameters: altitude >= 0, bandwidth > 0, path-loss exponent > 0, all finite.
    ///
    /// # Errors
    /// [`EnergyError::InvalidParameter`] naming the first offending parameter.
    pub fn validate(&self) -> Result<(), EnergyError> {
        non_negative("altitude (m)", self.altitude_m)?;
        positive("bandwidth (Hz)", self.bandwidth_hz)?;
        finite("transmit power (dBm)", self.tx_power_dbm)?;
        finite("noise power (dBm)", self.noise_power_dbm)?;
        finite("reference channel gain (dB)", self.reference_gain_db)?;
        positive("path-loss exponent", self.path_loss_exponent)?;
        Ok(())
    }

    /// UAV-sensor distance sqrt(h² + offset²) for a sensor `horizontal_offset_m` metres from the
    /// cell centre, metres.
    pub fn distance_m(&self, horizontal_offset_m: f64) -> f64 {
        self.altitude_m.hypot(horizontal_offset_m)
    }

    /// Signal-to-noise ratio in dB for a sensor `horizontal_offset_m` metres from the cell
    /// centre (distance clamped below at 1 m).
    pub fn snr_db(&self, horizontal_offset_m: f64) -> f64 {
        let d = self.distance_m(horizontal_offset_m).max(1.0);
        self.tx_power_dbm + self.reference_gain_db
            - 10.0 * self.path_loss_exponent * d.log10()
            - self.noise_power_dbm
    }

    /// Upload rate of one of `sharing_sensors` sensors (K_c, at least 1) at
    /// `horizontal_offset_m` metres from the cell centre: (B_w/K_c)·log2(1 + SNR), bit/s.
    pub fn rate_bps(&self, horizontal_offset_m: f64, sharing_sensors: usize) -> f64 {
        let snr = 10f64.powf(self.snr_db(horizontal_offset_m) / 10.0);
        self.bandwidth_hz / sharing_sensors.max(1) as f64 * snr.ln_1p() / std::f64::consts::LN_2
    }

    /// Collection time t_comm = max over the cell's sensors of pending_bytes·8 / rate, seconds;
    /// 0 for a cell without sensors. All sensors in `sensors` share the bandwidth (K_c =
    /// `sensors.len()`).
    ///
    /// ```
    /// use gleaner_energy::{LinkConfig, SensorBacklog};
    /// let link = LinkConfig::default();
    /// let one = [SensorBacklog { horizontal_offset_m: 0.0, pending_bytes: 125_000.0 }];
    /// let t = link.collection_time_s(&one).unwrap();
    /// // 1 Mbit at about 16.8 bit/s/Hz over 1 MHz: about 0.06 s.
    /// assert!((t - 1e6 / link.rate_bps(0.0, 1)).abs() < 1e-12 && t < 0.1);
    /// ```
    ///
    /// # Errors
    /// [`EnergyError::InvalidParameter`] for a non-finite offset or a negative / non-finite
    /// pending volume.
    pub fn collection_time_s(&self, sensors: &[SensorBacklog]) -> Result<f64, EnergyError> {
        let k = sensors.len();
        let mut t: f64 = 0.0;
        for s in sensors {
            finite("sensor horizontal offset (m)", s.horizontal_offset_m)?;
            non_negative("pending data (bytes)", s.pending_bytes)?;
            if s.pending_bytes > 0.0 {
                t = t.max(s.pending_bytes * 8.0 / self.rate_bps(s.horizontal_offset_m, k));
            }
        }
        Ok(t)
    }
}

/// How a sensor logs data between collections (docs/method.md §1).
///
/// Defaults: one reading every 900 s (15 min), 64 bytes per reading (timestamp, a few channels
/// and framing), unbounded buffer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DataLogging {
    /// Interval between two readings, seconds (default 900 s).
    pub reading_interval_s: f64,
    /// Size of one reading on the air, bytes (default 64 bytes).
    pub bytes_per_reading: f64,
    /// Buffer capacity in readings; readings beyond it are lost (oldest first). `None` is
    /// unbounded (default).
    pub buffer_readings: Option<f64>,
}

impl Default for DataLogging {
    fn default() -> Self {
        Self {
            reading_interval_s: 900.0,
            bytes_per_reading: 64.0,
            buffer_readings: None,
        }
    }
}

impl DataLogging {
    /// Checks the parameters: interval > 0, bytes per reading >= 0, buffer >= 0, all finite.
    ///
    /// # Errors
    /// [`EnergyError::InvalidParameter`] naming the first offending parameter.
    pub fn validate(&self) -> Result<(), EnergyError> {
        positive("reading interval (s)", self.reading_interval_s)?;
        non_negative("bytes per reading", self.bytes_per_reading)?;
        if let Some(b) = self.buffer_readings {
            non_negative("buffer capacity (readings)", b)?;
        }
        Ok(())
    }

    /// Expected data waiting on a sensor `elapsed_s` seconds after its last collection, bytes:
    /// (elapsed / interval)·bytes_per_reading, capped at the buffer capacity. This is an
    /// expected volume (fractional readings), not a count of whole readings.
    ///
    /// ```
    /// use gleaner_energy::DataLogging;
    /// let log = DataLogging { reading_interval_s: 600.0, bytes_per_reading: 32.0, buffer_readings: Some(100.0) };
    /// assert_eq!(log.pending_bytes(6000.0).unwrap(), 320.0);
    /// assert_eq!(log.pending_bytes(1e9).unwrap(), 3200.0);
    /// ```
    ///
    /// # Errors
    /// [`EnergyError::InvalidParameter`] if `elapsed_s` is negative or not finite (a sensor
    /// never collected should be given the time since its deployment or the history start), or
    /// the logging parameters are invalid.
    pub fn pending_bytes(&self, elapsed_s: f64) -> Result<f64, EnergyError> {
        self.validate()?;
        non_negative("elapsed time since last collection (s)", elapsed_s)?;
        let mut readings = elapsed_s / self.reading_interval_s;
        if let Some(cap) = self.buffer_readings {
            readings = readings.min(cap);
        }
        Ok(readings * self.bytes_per_reading)
    }
}

/// The data one sensor has waiting when the UAV hovers over its cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorBacklog {
    /// Horizontal distance of the sensor from the cell centre, metres.
    pub horizontal_offset_m: f64,
    /// Data waiting to be uploaded, bytes.
    pub pending_bytes: f64,
}

impl SensorBacklog {
    /// The backlog of a sensor `horizontal_offset_m` metres from the cell centre, last collected
    /// `elapsed_s` seconds ago, logging as `logging` says.
    ///
    /// # Errors
    /// As [`DataLogging::pending_bytes`].
    pub fn from_elapsed(
        horizontal_offset_m: f64,
        elapsed_s: f64,
        logging: &DataLogging,
    ) -> Result<Self, EnergyError> {
        Ok(Self {
            horizontal_offset_m,
            pending_bytes: logging.pending_bytes(elapsed_s)?,
        })
    }
}

/// Hover-time rule: hover_s = max(min_hover_s, overhead_s + t_comm).
///
/// Defaults: overhead 30 s (descent to collection height, link set-up, stabilisation; the
/// paper's 30 s hover), minimum 0 s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HoverConfig {
    /// Fixed time spent at every cell on top of the upload, seconds (default 30 s).
    pub overhead_s: f64,
    /// Minimum hover time at a cell, seconds (default 0 s).
    pub min_hover_s: f64,
}

impl Default for HoverConfig {
    fn default() -> Self {
        Self {
            overhead_s: 30.0,
            min_hover_s: 0.0,
        }
    }
}

impl HoverConfig {
    /// Checks both times are finite and >= 0.
    ///
    /// # Errors
    /// [`EnergyError::InvalidParameter`] naming the offending time.
    pub fn validate(&self) -> Result<(), EnergyError> {
        non_negative("hover overhead (s)", self.overhead_s)?;
        non_negative("minimum hover time (s)", self.min_hover_s)?;
        Ok(())
    }

    /// Hover time for a collection that takes `collection_s` seconds:
    /// max(min_hover_s, overhead_s + collection_s), seconds.
    pub fn hover_s(&self, collection_s: f64) -> f64 {
        self.min_hover_s.max(self.overhead_s + collection_s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * (1.0 + b.abs())
    }

    /// Hand-computed in watts: P_tx = 10 dBm = 1e-2 W, g0 = -40 dB = 1e-4, N = -110 dBm =
    /// 1e-14 W. At 40 m offset d = sqrt(30² + 40²) = 50 m, so SNR = 1e-2·1e-4/50²/1e-14 = 40,000;
    /// directly below, d = 30 m and SNR = 1e-6/900/1e-14 = 111,111.1.
    #[test]
    fn snr_and_rate_hand_checked() {
        let link = LinkConfig::default();
        assert!(close(link.distance_m(40.0), 50.0, 1e-15));
        let snr_lin = 10f64.powf(link.snr_db(40.0) / 10.0);
        assert!(close(snr_lin, 40_000.0, 1e-12), "{snr_lin}");
        // 4 sensors share 1 MHz: 250 kHz · log2(40,001).
        let rate = link.rate_bps(40.0, 4);
        assert!(close(rate, 250_000.0 * 40_001f64.log2(), 1e-12));
        // Directly below at 30 m.
        let below = 10f64.powf(link.snr_db(0.0) / 10.0);
        assert!(close(below, 1e-2 * 1e-4 / 900.0 / 1e-14, 1e-12), "{below}");
    }

    #[test]
    fn collection_time_is_slowest_sensor() {
        let link = LinkConfig::default();
        let sensors = [
            SensorBacklog {
                horizontal_offset_m: 0.0,
                pending_bytes: 1000.0,
            },
            SensorBacklog {
                horizontal_offset_m: 40.0,
                pending_bytes: 1000.0,
            },
            SensorBacklog {
                horizontal_offset_m: 10.0,
                pending_bytes: 0.0,
            },
        ];
        let t = link.collection_time_s(&sensors).unwrap();
        assert!(close(t, 8000.0 / link.rate_bps(40.0, 3), 1e-12));
        assert_eq!(link.collection_time_s(&[]).unwrap(), 0.0);
    }

    #[test]
    fn pending_bytes_grow_and_cap() {
        let log = DataLogging::default();
        assert_eq!(log.pending_bytes(0.0).unwrap(), 0.0);
        // One day at 15 min, 64 B: 96 readings, 6144 bytes.
        assert!(close(log.pending_bytes(86_400.0).unwrap(), 6144.0, 1e-15));
        let capped = DataLogging {
            buffer_readings: Some(10.0),
            ..log
        };
        assert_eq!(capped.pending_bytes(86_400.0).unwrap(), 640.0);
        assert!(log.pending_bytes(-1.0).is_err());
        assert!(log.pending_bytes(f64::INFINITY).is_err());
    }

    #[test]
    fn hover_rule() {
        let h = HoverConfig::default();
        assert_eq!(h.hover_s(2.5), 32.5);
        let h = HoverConfig {
            overhead_s: 5.0,
            min_hover_s: 30.0,
        };
        assert_eq!(h.hover_s(2.5), 30.0);
        assert_eq!(h.hover_s(40.0), 45.0);
    }

    #[test]
    fn invalid_link_is_rejected() {
        let link = LinkConfig {
            bandwidth_hz: 0.0,
            ..LinkConfig::default()
        };
        assert!(
            link.validate()
                .unwrap_err()
                .to_string()
                .contains("bandwidth")
        );
        let bad = [SensorBacklog {
            horizontal_offset_m: f64::NAN,
            pending_bytes: 1.0,
        }];
        assert!(LinkConfig::default().collection_time_s(&bad).is_err());
    }
}
