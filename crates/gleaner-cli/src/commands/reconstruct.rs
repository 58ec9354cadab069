//! `gleaner reconstruct`: every sensor's estimated value and variance as a table.

use std::fmt::Write as _;

use gleaner_app::{Estimator, Reconstruction, ReconstructionSeries, format_rfc3339};
use gleaner_kriging::Mean;

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
    let m = r.changes;
    let _ = writeln!(
        out,
        "model of changes: shared variogram {:.3e} + {:.3e}·(1 − exp(−h/{:.1} d)), range {:.0} m; \
         own {:.3e} + {:.3e}·(1 − exp(−h/{:.1} d))",
        m.shared.nugget,
        m.shared.partial,
        m.shared.scale_s / 86_400.0,
        m.range_m,
        m.own.nugget,
        m.own.partial,
        m.own.scale_s / 86_400.0
    );
    let _ = writeln!(
        out,
        "estimate (\"kriged\"): {}",
        match r.estimator {
            Estimator::Changes => "kriging of changes (last value + neighbours' known changes)",
            Estimator::Levels(Mean::Unknown) => "ordinary kriging of levels",
            Estimator::Levels(Mean::Known) => "simple kriging of levels",
            Estimator::Dynamic =>
                "dynamic field model (learned covariance of levels, AR(1) dynamics, Kalman filter)",
        }
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

/// A range reconstruction as CSV: `time,sensor,mean,sd,lo90,hi90` (RFC 3339 times; the
/// modality's unit), one row per time and sensor.
pub fn series_csv(r: &ReconstructionSeries) -> String {
    let mut out = String::from("time,sensor,mean,sd,lo90,hi90\n");
    let n = r.sensors.len();
    for (t, &time) in r.times.iter().enumerate() {
        let stamp = format_rfc3339(time);
        for (s, (id, _)) in r.sensors.iter().enumerate() {
            let k = t * n + s;
            let (lo, hi) = r.interval90(t, s);
            let _ = writeln!(
                out,
                "{stamp},{},{:.6},{:.6},{:.6},{:.6}",
                id.as_str(),
                r.mean[k],
                r.variance[k].sqrt(),
                lo,
                hi
            );
        }
    }
    out
}

/// What `--map` writes, by the file's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapFile {
    /// `.svg`: the figure as SVG text.
    Svg,
    /// `.png`: the figure rasterised at 300 dpi.
    Png,
}

impl MapFile {
    /// The kind of `path` (`.svg` or `.png`, in any case).
    pub fn of(path: &std::path::Path) -> anyhow::Result<Self> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("svg") => Ok(Self::Svg),
            Some("png") => Ok(Self::Png),
            _ => anyhow::bail!(
                "--map {}: the file must end in .svg or .png",
                path.display()
            ),
        }
    }
}

/// The map's PNG resolution, dots per inch.
pub const MAP_PNG_DPI: f64 = 300.0;

/// The reconstruction map as the file's bytes.
pub fn map_file(
    doc: &gleaner_wire::docs::ReconstructionMapDoc,
    kind: MapFile,
) -> anyhow::Result<Vec<u8>> {
    let opts = gleaner_render::FigureOptions {
        width_mm: gleaner_render::FULL_WIDTH_MM,
        ..Default::default()
    };
    let svg = gleaner_render::reconstruction_map_svg(doc, &opts)?;
    Ok(match kind {
        MapFile::Svg => svg.into_bytes(),
        MapFile::Png => gleaner_render::svg_to_png(
            &svg,
            gleaner_render::png_width_px(gleaner_render::FULL_WIDTH_MM, MAP_PNG_DPI),
        )?,
    })
}
