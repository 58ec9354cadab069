//! `gleaner reconstruct`: every sensor's estimated value and variance as a table.

use std::fmt::Write as _;

use gleaner_app::{Reconstruction, format_rfc3339};

/// The reconstruction as a text table (values in the modality's unit, sd its square root).
pub fn table(r: &Reconstruction) -> String {
    let mut out = String::new();
    let c = r.model.covariance;
    let _ = writeln!(
        out,
        "{} at {}: field model sill {:.3e}, nugget {:.3e}, range {:.0} m, time scale {:.1} d",
        r.modality,
        format_rfc3339(r.at),
        c.sill,
        c.nugget,
        c.range_m,
        c.time_scale_s / 86_400.0
    );
    let _ = writeln!(
        out,
        "{:<16} {:<21} {:>10} {:>10} {:>10}",
        "sensor", "last reading", "carried", "kriged", "sd"
    );
    for s in &r.sensors {
        let _ = writeln!(
            out,
            "{:<16} {:<21} {:>10.4} {:>10.4} {:>10.4}",
            s.sensor.as_str(),
            s.last_time.map_or("never".into(), format_rfc3339),
            s.carried,
            s.kriged,
            s.variance.sqrt()
        );
    }
    out
}
