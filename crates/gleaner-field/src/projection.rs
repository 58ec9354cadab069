//! WGS84 positions and the Transverse Mercator projection (Krüger series, 6th order in n, as
//! in Karney 2011), accurate to well under a millimetre within a few thousand km of the central
//! meridian — far more than a farm needs, and the same code serves UTM and the local frame.

use crate::FieldError;

/// WGS84 semi-major axis, metres.
const WGS84_A: f64 = 6_378_137.0;
/// WGS84 flattening (dimensionless).
const WGS84_F: f64 = 1.0 / 298.257_223_563;

/// A WGS84 position: latitude and longitude in degrees. Field order is `[lat, lon]`; GeoJSON
/// and other `[lon, lat]` wire formats convert explicitly.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LatLon {
    lat_deg: f64,
    lon_deg: f64,
}

impl LatLon {
    /// A position from latitude and longitude in degrees; rejects values outside
    /// [-90, 90] x [-180, 180] and non-finite values.
    pub fn new(lat_deg: f64, lon_deg: f64) -> Result<Self, FieldError> {
        if !(lat_deg.is_finite()
            && lon_deg.is_finite()
            && (-90.0..=90.0).contains(&lat_deg)
            && (-180.0..=180.0).contains(&lon_deg))
        {
            return Err(FieldError::InvalidLatLon {
                lat: lat_deg,
                lon: lon_deg,
            });
        }
        Ok(Self { lat_deg, lon_deg })
    }
    /// Latitude, degrees north.
    pub fn lat(&self) -> f64 {
        self.lat_deg
    }
    /// Longitude, degrees east.
    pub fn lon(&self) -> f64 {
        self.lon_deg
    }
}

/// A point in a projected plane: `e` metres east and `n` metres north of the frame's origin.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LocalPoint {
    /// Easting, metres.
    pub e: f64,
    /// Northing, metres.
    pub n: f64,
}

impl LocalPoint {
    /// A point `e` metres east and `n` metres north of the origin.
    pub const fn new(e: f64, n: f64) -> Self {
        Self { e, n }
    }
    /// Euclidean distance to `other`, metres.
    pub fn distance(&self, other: &LocalPoint) -> f64 {
        (self.e - other.e).hypot(self.n - other.n)
    }
}

/// The UTM zone (1..=60) whose central meridian is nearest `lon_deg` (no Norway/Svalbard
/// exceptions: they do not matter for a single farm's local frame).
pub fn utm_zone_for(lon_deg: f64) -> u8 {
    (((lon_deg + 180.0) / 6.0).floor() as i64).clamp(0, 59) as u8 + 1
}

/// A Transverse Mercator projection of the WGS84 ellipsoid: WGS84 degrees <-> metres.
///
/// NAD83 (CAF's EPSG:26911 datum) and WGS84 differ by about a metre at most, below the
/// accuracy of the published sensor positions, so NAD83 / UTM input uses [`Self::utm`] directly.
#[derive(Debug, Clone, PartialEq)]
pub struct TransverseMercator {
    lon0_rad: f64,
    k0: f64,
    false_e: f64,
    false_n: f64,
    /// Rectifying radius A, metres.
    big_a: f64,
    e: f64,
    alpha: [f64; 6],
    beta: [f64; 6],
}

impl TransverseMercator {
    fn with(lon0_deg: f64, k0: f64, false_e: f64, false_n: f64) -> Self {
        let f = WGS84_F;
        let n = f / (2.0 - f);
        let (n2, n3, n4, n5, n6) = (n * n, n.powi(3), n.powi(4), n.powi(5), n.powi(6));
        let big_a = WGS84_A / (1.0 + n) * (1.0 + n2 / 4.0 + n4 / 64.0 + n6 / 256.0);
        let alpha = [
            n / 2.0 - 2.0 * n2 / 3.0 + 5.0 * n3 / 16.0 + 41.0 * n4 / 180.0 - 127.0 * n5 / 288.0
                + 7891.0 * n6 / 37800.0,
            13.0 * n2 / 48.0 - 3.0 * n3 / 5.0 + 557.0 * n4 / 1440.0 + 281.0 * n5 / 630.0
                - 1983433.0 * n6 / 1935360.0,
            61.0 * n3 / 240.0 - 103.0 * n4 / 140.0
                + 15061.0 * n5 / 26880.0
                + 167603.0 * n6 / 181440.0,
            49561.0 * n4 / 161280.0 - 179.0 * n5 / 168.0 + 6601661.0 * n6 / 7257600.0,
            34729.0 * n5 / 80640.0 - 3418889.0 * n6 / 1995840.0,
            212378941.0 * n6 / 319334400.0,
        ];
        let beta = [
            n / 2.0 - 2.0 * n2 / 3.0 + 37.0 * n3 / 96.0 - n4 / 360.0 - 81.0 * n5 / 512.0
                + 96199.0 * n6 / 604800.0,
            n2 / 48.0 + n3 / 15.0 - 437.0 * n4 / 1440.0 + 46.0 * n5 / 105.0
                - 1118711.0 * n6 / 3870720.0,
            17.0 * n3 / 480.0 - 37.0 * n4 / 840.0 - 209.0 * n5 / 4480.0 + 5569.0 * n6 / 90720.0,
            4397.0 * n4 / 161280.0 - 11.0 * n5 / 504.0 - 830251.0 * n6 / 7257600.0,
            4583.0 * n5 / 161280.0 - 108847.0 * n6 / 3991680.0,
            20648693.0 * n6 / 638668800.0,
        ];
        let e = (f * (2.0 - f)).sqrt();
        Self {
            lon0_rad: lon0_deg.to_radians(),
            k0,
            false_e,
            false_n,
            big_a,
            e,
            alpha,
            beta,
        }
    }

    /// UTM zone `zone` (1..=60), northern hemisphere when `north`: scale 0.9996, false easting
    /// 500 000 m, false northing 0 m (north) or 10 000 000 m (south). EPSG:32611 / EPSG:26911
    /// are `utm(11, true)`.
    pub fn utm(zone: u8, north: bool) -> Result<Self, FieldError> {
        if !(1..=60).contains(&zone) {
            return Err(FieldError::InvalidUtmZone(zone));
        }
        let lon0 = -183.0 + 6.0 * f64::from(zone);
        Ok(Self::with(
            lon0,
            0.9996,
            500_000.0,
            if north { 0.0 } else { 10_000_000.0 },
        ))
    }

    /// The local east/north frame, metres, centred on `origin`: a Transverse Mercator with
    /// central meridian through `origin`, unit scale, and `origin` at (0, 0). Within 10 km of
    /// the origin, distances in this frame are true to better than 2 parts per million.
    pub fn local(origin: LatLon) -> Self {
        let mut tm = Self::with(origin.lon(), 1.0, 0.0, 0.0);
        let o = tm.forward(origin);
        tm.false_n = -o.n;
        tm
    }

    /// Projects a WGS84 position to (easting, northing) metres.
    pub fn forward(&self, p: LatLon) -> LocalPoint {
        let phi = p.lat().to_radians();
        let lam = p.lon().to_radians() - self.lon0_rad;
        let e = self.e;
        let sphi = phi.sin();
        let t = ((sphi).atanh() - e * (e * sphi).atanh()).sinh();
        let xi_p = t.atan2(lam.cos());
        let eta_p = (lam.sin() / (1.0 + t * t).sqrt()).atanh();
        let mut xi = xi_p;
        let mut eta = eta_p;
        for (j, a) in self.alpha.iter().enumerate() {
            let k = 2.0 * (j as f64 + 1.0);
            xi += a * (k * xi_p).sin() * (k * eta_p).cosh();
            eta += a * (k * xi_p).cos() * (k * eta_p).sinh();
        }
        LocalPoint {
            e: self.false_e + self.k0 * self.big_a * eta,
            n: self.false_n + self.k0 * self.big_a * xi,
        }
    }

    /// Unprojects (easting, northing) metres to WGS84.
    pub fn inverse(&self, p: LocalPoint) -> LatLon {
        let xi = (p.n - self.false_n) / (self.k0 * self.big_a);
        let eta = (p.e - self.false_e) / (self.k0 * self.big_a);
        let mut xi_p = xi;
        let mut eta_p = eta;
        for (j, b) in self.beta.iter().enumerate() {
            let k = 2.0 * (j as f64 + 1.0);
            xi_p -= b * (k * xi).sin() * (k * eta).cosh();
            eta_p -= b * (k * xi).cos() * (k * eta).sinh();
        }
        let tau_p = xi_p.sin() / (eta_p.sinh().powi(2) + xi_p.cos().powi(2)).sqrt();
        let lam = eta_p.sinh().atan2(xi_p.cos());
        // Newton iteration for tau = tan(phi) from the conformal tau' (Karney 2011, eq. 19-21).
        let e = self.e;
        let e2m = 1.0 - e * e;
        let mut tau = tau_p;
        for _ in 0..6 {
            let tau1 = (1.0 + tau * tau).sqrt();
            let sig = (e * (e * tau / tau1).atanh()).sinh();
            let taupa = (1.0 + sig * sig).sqrt() * tau - sig * tau1;
            let dtau = (tau_p - taupa) * (1.0 + e2m * tau * tau)
                / (e2m * tau1 * (1.0 + taupa * taupa).sqrt());
            tau += dtau;
            if dtau.abs() < 1e-14 * tau.abs().max(1.0) {
                break;
            }
        }
        let lat = tau.atan().to_degrees();
        let mut lon = (lam + self.lon0_rad).to_degrees();
        if lon > 180.0 {
            lon -= 360.0;
        } else if lon < -180.0 {
            lon += 360.0;
        }
        LatLon {
            lat_deg: lat,
            lon_deg: lon,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn caf_utm_matches_published_lat_lon() {
        // CAF003 from CAF_sensor_locations.csv (NAD83 / UTM 11N and its published lat/lon).
        let utm = TransverseMercator::utm(11, true).unwrap();
        let ll = utm.inverse(LocalPoint::new(493384.052, 5180585.318));
        assert!((ll.lat() - 46.778784).abs() < 2e-5, "{ll:?}");
        assert!((ll.lon() - -117.086666).abs() < 2e-5, "{ll:?}");
        let back = utm.forward(ll);
        assert!((back.e - 493384.052).abs() < 1e-6 && (back.n - 5180585.318).abs() < 1e-6);
    }

    #[test]
    fn utm_zone_of_pullman_is_11() {
        assert_eq!(utm_zone_for(-117.08), 11);
        assert_eq!(utm_zone_for(179.99), 60);
        assert_eq!(utm_zone_for(-180.0), 1);
    }

    #[test]
    fn local_frame_origin_is_zero_and_metric() {
        let o = LatLon::new(46.7788, -117.0867).unwrap();
        let tm = TransverseMercator::local(o);
        let p = tm.forward(o);
        assert!(p.e.abs() < 1e-9 && p.n.abs() < 1e-9);
        // One arc-second of latitude is about 30.9 m here.
        let q = tm.forward(LatLon::new(46.7788 + 1.0 / 3600.0, -117.0867).unwrap());
        assert!((q.n - 30.88).abs() < 0.05, "{q:?}");
    }

    proptest! {
        #[test]
        fn local_round_trip_within_1cm_over_10km(
            lat in -80.0f64..80.0, lon in -179.0f64..179.0,
            de in -10_000.0f64..10_000.0, dn in -10_000.0f64..10_000.0,
        ) {
            let tm = TransverseMercator::local(LatLon::new(lat, lon).unwrap());
            let p = LocalPoint::new(de, dn);
            let back = tm.forward(tm.inverse(p));
            prop_assert!(back.distance(&p) < 0.01, "{p:?} -> {back:?}");
        }

        #[test]
        fn utm_round_trip_within_1cm(lat in -80.0f64..84.0, dlon in -3.0f64..3.0) {
            let zone = 33u8;
            let lon = -183.0 + 6.0 * f64::from(zone) + dlon;
            let tm = TransverseMercator::utm(zone, lat >= 0.0).unwrap();
            let ll = LatLon::new(lat, lon).unwrap();
            let p = tm.forward(ll);
            let back = tm.forward(tm.inverse(p));
            prop_assert!(back.distance(&p) < 0.01);
        }
    }
}
