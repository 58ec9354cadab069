//! What both maps share: input checks, the local metric frame, the map's placement on the
//! page, cells, coordinate ticks, the north arrow, the scale bar, markers and the legend grid.

use gleaner_wire::{FieldDoc, MissionDoc};

use crate::colour::Rgb;
use crate::font::{CAP_HEIGHT_EM, text_width};
use crate::svg::{Anchor, N, Svg, esc, fit};
use crate::ticks;
use crate::{Coordinates, FigureOptions, RenderError};

mod axes;
mod legend;

pub(crate) use axes::{Axes, TICK, draw_axes};
pub(crate) use legend::{
    Entry, RETURN_DASH, Symbol, arrowhead, dash_attr, draw_legend, legend_height, route_line,
    sensor_state_marker, stop_marker, stop_radius,
};

/// Mean Earth radius, m (IUGG).
const EARTH_RADIUS_M: f64 = 6_371_008.8;

/// Points per millimetre.
pub(crate) const PT_PER_MM: f64 = 72.0 / 25.4;

/// Colour of text, frames and the base.
pub(crate) const INK: &str = "#1a1a1a";

/// Fails unless `v` is finite.
pub(crate) fn finite(what: impl FnOnce() -> String, v: f64) -> Result<f64, RenderError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(RenderError::NonFinite {
            what: what(),
            value: v,
        })
    }
}

/// Fails unless `p` is a finite WGS84 `[lon, lat]` in degrees.
pub(crate) fn lon_lat(what: impl Fn() -> String, p: [f64; 2]) -> Result<[f64; 2], RenderError> {
    let lon = finite(|| format!("{} longitude", what()), p[0])?;
    let lat = finite(|| format!("{} latitude", what()), p[1])?;
    if !(-180.0..=180.0).contains(&lon) {
        return Err(RenderError::OutOfRange {
            what: format!("{} longitude", what()),
            value: lon,
            expected: "[-180, 180] degrees",
        });
    }
    if !(-90.0..=90.0).contains(&lat) {
        return Err(RenderError::OutOfRange {
            what: format!("{} latitude", what()),
            value: lat,
            expected: "[-90, 90] degrees",
        });
    }
    Ok([lon, lat])
}

/// Checks the options every figure uses.
pub(crate) fn check_options(opts: &FigureOptions) -> Result<(), RenderError> {
    if !(opts.width_mm.is_finite() && (20.0..=1000.0).contains(&opts.width_mm)) {
        return Err(RenderError::InvalidOption {
            name: "width_mm",
            value: opts.width_mm,
            expected: "between 20 and 1000 mm",
        });
    }
    if !(opts.font_pt.is_finite() && (4.0..=24.0).contains(&opts.font_pt)) {
        return Err(RenderError::InvalidOption {
            name: "font_pt",
            value: opts.font_pt,
            expected: "between 4 and 24 pt",
        });
    }
    if !(opts.max_map_aspect.is_finite() && (0.2..=5.0).contains(&opts.max_map_aspect)) {
        return Err(RenderError::InvalidOption {
            name: "max_map_aspect",
            value: opts.max_map_aspect,
            expected: "between 0.2 and 5",
        });
    }
    if opts.width_mm * PT_PER_MM < 20.0 * opts.font_pt {
        return Err(RenderError::InvalidOption {
            name: "font_pt",
            value: opts.font_pt,
            expected: "at most width_mm * 72 / 25.4 / 20 (at least 20 characters across)",
        });
    }
    Ok(())
}

/// The local equirectangular frame: metres east and north of the origin (the field's base).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Projection {
    lon0: f64,
    lat0: f64,
    /// m per degree of longitude at the origin.
    kx: f64,
    /// m per degree of latitude.
    ky: f64,
}

impl Projection {
    pub(crate) fn new(origin: [f64; 2]) -> Result<Self, RenderError> {
        let [lon0, lat0] = lon_lat(|| "field base".into(), origin)?;
        if lat0.abs() > 85.0 {
            return Err(RenderError::OutOfRange {
                what: "field base latitude".into(),
                value: lat0,
                expected: "[-85, 85] degrees for a local map",
            });
        }
        let ky = EARTH_RADIUS_M * std::f64::consts::PI / 180.0;
        Ok(Self {
            lon0,
            lat0,
            kx: ky * lat0.to_radians().cos(),
            ky,
        })
    }

    /// `[lon, lat]` degrees to (east, north) m.
    pub(crate) fn local(&self, p: [f64; 2]) -> (f64, f64) {
        let mut dlon = p[0] - self.lon0;
        if dlon > 180.0 {
            dlon -= 360.0;
        } else if dlon < -180.0 {
            dlon += 360.0;
        }
        (dlon * self.kx, (p[1] - self.lat0) * self.ky)
    }
}

/// A cell projected, with its score.
pub(crate) struct CellShape {
    pub(crate) id: String,
    pub(crate) ring: Vec<(f64, f64)>,
    pub(crate) s: Option<f64>,
}

/// The field and missions in the local frame, m.
pub(crate) struct Scene {
    pub(crate) projection: Projection,
    pub(crate) cells: Vec<CellShape>,
    pub(crate) sensors: Vec<(f64, f64)>,
    /// Extent of everything drawn: (min east, max east, min north, max north), m.
    pub(crate) extent: (f64, f64, f64, f64),
}

impl Scene {
    /// Draws the map's layers below the routes on `view`: the cells filled with `fills` (one
    /// a cell), the zones over them, then the sensors.
    pub(crate) fn draw_ground(
        &self,
        svg: &mut Svg,
        view: &MapView,
        fills: &[Rgb],
        zones: &[ZoneShape],
    ) {
        draw_cells(svg, view, &self.cells, fills);
        draw_zones(svg, view, zones);
        draw_sensors(svg, view, &self.sensors);
    }

    /// Checks and projects the field; `extra` are further points to keep on the map.
    pub(crate) fn new(field: &FieldDoc, extra: &[(f64, f64)]) -> Result<Self, RenderError> {
        let projection = Projection::new(field.base_lon_lat)?;
        let cell_size_m = finite(|| "field cell_size_m".into(), field.cell_size_m)?;
        if cell_size_m <= 0.0 {
            return Err(RenderError::OutOfRange {
                what: "field cell_size_m".into(),
                value: cell_size_m,
                expected: "> 0 m",
            });
        }
        let mut cells = Vec::with_capacity(field.cells.len());
        for c in &field.cells {
            let mut ring = Vec::with_capacity(c.ring_lon_lat.len());
            for (k, p) in c.ring_lon_lat.iter().enumerate() {
                let p = lon_lat(|| format!("cell {} ring point {k}", c.cell), *p)?;
                ring.push(projection.local(p));
            }
            lon_lat(|| format!("cell {} centre", c.cell), c.centre_lon_lat)?;
            let s = match &c.scores {
                Some(sc) => {
                    for (name, v) in [("F", sc.f), ("R", sc.r), ("A", sc.a), ("U", sc.u)] {
                        finite(|| format!("cell {} {name}", c.cell), v)?;
                    }
                    Some(finite(|| format!("cell {} S", c.cell), sc.s)?)
                }
                None => None,
            };
            cells.push(CellShape {
                id: c.cell.clone(),
                ring,
                s,
            });
        }
        let mut sensors = Vec::with_capacity(field.sensors.len());
        for s in &field.sensors {
            sensors.push(projection.local(lon_lat(|| format!("sensor {}", s.id), s.lon_lat)?));
        }
        let mut ext = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        let mut grow = |(e, n): (f64, f64)| {
            ext = (ext.0.min(e), ext.1.max(e), ext.2.min(n), ext.3.max(n));
        };
        cells
            .iter()
            .flat_map(|c| c.ring.iter())
            .for_each(|&p| grow(p));
        sensors.iter().for_each(|&p| grow(p));
        extra.iter().for_each(|&p| grow(p));
        Ok(Self {
            projection,
            cells,
            sensors,
            extent: widened(ext, cell_size_m),
        })
    }
}

/// The extent `(e0, e1, n0, n1)` (m) with a span under a cell side `cell_size_m` (m), or under
/// 20 m, widened to it about its middle: a point or a line still gets an area.
pub(crate) fn widened(
    (e0, e1, n0, n1): (f64, f64, f64, f64),
    cell_size_m: f64,
) -> (f64, f64, f64, f64) {
    let min_span = cell_size_m.max(20.0);
    let widen = |lo: f64, hi: f64| {
        if hi - lo < min_span {
            let mid = 0.5 * (lo + hi);
            (mid - 0.5 * min_span, mid + 0.5 * min_span)
        } else {
            (lo, hi)
        }
    };
    let (e0, e1) = widen(e0, e1);
    let (n0, n1) = widen(n0, n1);
    (e0, e1, n0, n1)
}

/// A mission's base and stops in the local frame, m.
pub(crate) type Route = ((f64, f64), Vec<(f64, f64)>);

/// Checks a mission's numbers and returns its base and stops in the local frame.
pub(crate) fn mission_points(
    projection: &Projection,
    m: &MissionDoc,
    label: &str,
) -> Result<Route, RenderError> {
    let base = projection.local(lon_lat(|| format!("{label} base"), m.profile.base_lon_lat)?);
    let mut stops = Vec::with_capacity(m.stops.len());
    for s in &m.stops {
        stops.push(projection.local(lon_lat(
            || format!("{label} stop {} ({})", s.order, s.cell),
            s.centre_lon_lat,
        )?));
        finite(|| format!("{label} stop {} S", s.order), s.s)?;
    }
    let e = &m.energy;
    for (name, v) in [
        ("travel_j", e.travel_j),
        ("hover_j", e.hover_j),
        ("comm_j", e.comm_j),
        ("return_j", e.return_j),
        ("total_j", e.total_j),
        ("budget_j", e.budget_j),
        ("utilisation", e.utilisation),
    ] {
        finite(|| format!("{label} energy {name}"), v)?;
    }
    finite(|| format!("{label} total_score"), m.total_score)?;
    Ok((base, stops))
}

/// Where the map sits on the page: `x`, `y` top-left, pt; `k` pt per m; the extent in m.
#[derive(Debug, Clone, Copy)]
pub(crate) struct MapView {
    pub(crate) x: f64,
    pub(crate) y: f64,
    pub(crate) w: f64,
    pub(crate) h: f64,
    pub(crate) k: f64,
    pub(crate) e0: f64,
    pub(crate) n1: f64,
}

impl MapView {
    /// Places the extent (padded by `pad_pt` on every side) in a box of at most
    /// `max_w` x `max_h` pt at (`x`, `y`), north up, same scale on both axes.
    pub(crate) fn fit(
        extent: (f64, f64, f64, f64),
        x: f64,
        y: f64,
        max_w: f64,
        max_h: f64,
        pad_pt: f64,
    ) -> Self {
        let (e0, e1, n0, n1) = extent;
        let (sw, sh) = ((e1 - e0).max(1e-6), (n1 - n0).max(1e-6));
        let inner_w = (max_w - 2.0 * pad_pt).max(1.0);
        let inner_h = (max_h - 2.0 * pad_pt).max(1.0);
        let k = (inner_w / sw).min(inner_h / sh);
        let pad_m = pad_pt / k;
        Self {
            x,
            y,
            w: sw * k + 2.0 * pad_pt,
            h: sh * k + 2.0 * pad_pt,
            k,
            e0: e0 - pad_m,
            n1: n1 + pad_m,
        }
    }

    /// (east, north) m to page pt.
    pub(crate) fn pt(&self, (e, n): (f64, f64)) -> (f64, f64) {
        (
            self.x + (e - self.e0) * self.k,
            self.y + (self.n1 - n) * self.k,
        )
    }

    /// Appends to the SVG path data `d` the polyline through `points` ((east, north) m), in
    /// page pt: a move to the first point, a line to each next one (no closing `Z`).
    pub(crate) fn push_path(&self, d: &mut String, points: &[(f64, f64)]) {
        for (j, &p) in points.iter().enumerate() {
            let (x, y) = self.pt(p);
            d.push_str(&format!(
                "{}{} {}",
                if j == 0 { "M" } else { "L" },
                N(x),
                N(y)
            ));
        }
    }

    fn e1(&self) -> f64 {
        self.e0 + self.w / self.k
    }

    fn n0(&self) -> f64 {
        self.n1 - self.h / self.k
    }
}

/// The title (when not empty, one size up and bold) and subtitle lines above the map, each
/// fitted to `inner` pt, with their baselines from `top`.
pub(crate) struct Titles {
    lines: Vec<(String, f64, bool)>,
    baselines: Vec<f64>,
    /// Where the map may start, pt.
    pub(crate) map_top: f64,
}

impl Titles {
    pub(crate) fn new(title: &str, subtitle: &str, font: f64, inner: f64, top: f64) -> Self {
        let mut lines: Vec<(String, f64, bool)> = Vec::new();
        if !title.is_empty() {
            lines.push((fit(title, font + 1.0, true, inner), font + 1.0, true));
        }
        lines.push((fit(subtitle, font, false, inner), font, false));
        let mut y = top;
        let mut baselines = Vec::new();
        for (_, size, _) in &lines {
            baselines.push(y + 0.93 * size);
            y += 1.25 * size;
        }
        Self {
            lines,
            baselines,
            map_top: y + 0.35 * font,
        }
    }

    /// Draws the lines from `x`.
    pub(crate) fn draw(&self, svg: &mut Svg, x: f64) {
        for ((t, size, bold), baseline) in self.lines.iter().zip(&self.baselines) {
            svg.text_attrs(
                x,
                *baseline,
                *size,
                Anchor::Start,
                *bold,
                &format!(r#"fill="{INK}""#),
                t,
            );
        }
    }
}

/// The map placed between the y-axis labels (right of `margin`) and the right column at
/// `right` (less a gap), from `top`: fitted, then refitted with the measured y labels (at most
/// three passes). Returns the view, its axes and the baseline of the x-axis title below it.
pub(crate) fn fit_map(
    scene: &Scene,
    opts: &FigureOptions,
    margin: f64,
    right: f64,
    top: f64,
    pad: f64,
) -> (MapView, Axes, f64) {
    let font = opts.font_pt;
    let width = opts.width_mm * PT_PER_MM;
    let gap = 0.9 * font;
    let mut ylab_w = text_width("\u{2212}000", font, false);
    let mut passes = 0;
    loop {
        let left = margin + 1.25 * font + ylab_w + 1.2 + TICK;
        let avail_w = (right - gap - left).max(4.0 * font);
        let mut view = MapView::fit(
            scene.extent,
            left,
            top,
            avail_w,
            opts.max_map_aspect * width,
            pad,
        );
        view.x = left + 0.5 * (avail_w - view.w);
        let axes = Axes::new(&view, &scene.projection, opts.coordinates, font);
        let measured = axes.y_label_width(font);
        passes += 1;
        if measured <= ylab_w + 0.01 || passes >= 3 {
            let cap = CAP_HEIGHT_EM * font;
            let x_title_baseline = view.y + view.h + TICK + 1.0 + cap + 1.2 * font + 0.1 * font;
            return (view, axes, x_title_baseline);
        }
        ylab_w = measured;
    }
}

/// The route's points on the page (pt) and the marker radius at each (pt): base, stops,
/// base, through the turn points of legs flown around no-fly zones (`via[k]` before stop k,
/// `via[stops.len()]` on the return leg; local frame, m), which have radius 0.
pub(crate) fn route_points_via(
    view: &MapView,
    base: (f64, f64),
    stops: &[(f64, f64)],
    via: &[Vec<(f64, f64)>],
    base_r: f64,
    stop_r: f64,
) -> (Vec<(f64, f64)>, Vec<f64>) {
    let base_pt = view.pt(base);
    let mut pts = vec![base_pt];
    let mut radii = vec![base_r];
    for (k, &p) in stops.iter().enumerate() {
        for &t in via.get(k).into_iter().flatten() {
            pts.push(view.pt(t));
            radii.push(0.0);
        }
        pts.push(view.pt(p));
        radii.push(stop_r);
    }
    for &t in via.get(stops.len()).into_iter().flatten() {
        pts.push(view.pt(t));
        radii.push(0.0);
    }
    pts.push(base_pt);
    radii.push(base_r);
    (pts, radii)
}

/// The turn points of a mission's legs (one list per stop, then the return leg's), local
/// frame, m.
pub(crate) fn mission_via(
    projection: &Projection,
    m: &MissionDoc,
    label: &str,
) -> Result<Vec<Vec<(f64, f64)>>, RenderError> {
    let mut out = Vec::with_capacity(m.stops.len() + 1);
    for s in &m.stops {
        let mut leg = Vec::with_capacity(s.via_lon_lat.len());
        for (k, p) in s.via_lon_lat.iter().enumerate() {
            leg.push(projection.local(lon_lat(
                || format!("{label} stop {} turn point {k}", s.order),
                *p,
            )?));
        }
        out.push(leg);
    }
    let mut leg = Vec::with_capacity(m.return_via_lon_lat.len());
    for (k, p) in m.return_via_lon_lat.iter().enumerate() {
        leg.push(projection.local(lon_lat(|| format!("{label} return turn point {k}"), *p)?));
    }
    out.push(leg);
    Ok(out)
}

/// A zone projected into the local frame, m.
pub(crate) struct ZoneShape {
    /// A no-fly zone (else the geofence).
    pub(crate) no_fly: bool,
    /// Polygon rings (each polygon's exterior and holes, in order).
    pub(crate) polygons: Vec<Vec<Vec<(f64, f64)>>>,
    /// Lines; a single point for a point zone.
    pub(crate) lines: Vec<Vec<(f64, f64)>>,
    /// Its label for the tooltip.
    pub(crate) label: String,
}

/// Fill of a no-fly zone.
pub(crate) const NO_FLY: Rgb = Rgb(0x40, 0x40, 0x40);

/// The zones of the documents (`zones` of the mission, else of the field), projected.
pub(crate) fn zone_shapes(
    projection: &Projection,
    zones: &[gleaner_wire::ZoneDoc],
) -> Result<Vec<ZoneShape>, RenderError> {
    let mut out = Vec::with_capacity(zones.len());
    for (z, zone) in zones.iter().enumerate() {
        let what = |k: usize| format!("zone {z} position {k}");
        let mut polygons = Vec::new();
        let mut n = 0;
        for p in &zone.polygons_lon_lat {
            let mut rings = Vec::new();
            for r in p {
                let mut ring = Vec::with_capacity(r.len());
                for q in r {
                    ring.push(projection.local(lon_lat(|| what(n), *q)?));
                    n += 1;
                }
                rings.push(ring);
            }
            polygons.push(rings);
        }
        let mut lines = Vec::new();
        for l in &zone.lines_lon_lat {
            let mut line = Vec::with_capacity(l.len());
            for q in l {
                line.push(projection.local(lon_lat(|| what(n), *q)?));
                n += 1;
            }
            lines.push(line);
        }
        let name = zone
            .name
            .as_ref()
            .map_or_else(String::new, |n| format!(" {n}"));
        out.push(ZoneShape {
            no_fly: zone.kind != "geofence",
            polygons,
            lines,
            label: format!("{}{name} (buffer {} m)", zone.kind, zone.buffer_m),
        });
    }
    Ok(out)
}

/// Every point of the zones (to keep them on the map), m.
pub(crate) fn zone_points(zones: &[ZoneShape]) -> Vec<(f64, f64)> {
    zones
        .iter()
        .flat_map(|z| {
            z.polygons
                .iter()
                .flatten()
                .flatten()
                .chain(z.lines.iter().flatten())
                .copied()
        })
        .collect()
}

/// Draws the zones over the cells: no-fly zones filled dark and outlined, lines (power
/// lines) as thick dark strokes, points as dark discs; the geofence as a dashed outline.
pub(crate) fn draw_zones(svg: &mut Svg, view: &MapView, zones: &[ZoneShape]) {
    if zones.is_empty() {
        return;
    }
    svg.line(format_args!(r#"<g id="zones">"#));
    for (k, z) in zones.iter().enumerate() {
        let mut d = String::new();
        for ring in z.polygons.iter().flatten() {
            view.push_path(&mut d, ring);
            d.push('Z');
        }
        let (fill, stroke) = if z.no_fly {
            (
                format!(
                    r#"fill="{}" fill-opacity="0.55" fill-rule="evenodd""#,
                    NO_FLY.hex()
                ),
                format!(r#"stroke="{INK}" stroke-width="0.5""#),
            )
        } else {
            (
                r#"fill="none""#.to_string(),
                format!(r#"stroke="{INK}" stroke-width="0.8" stroke-dasharray="3 1.5""#),
            )
        };
        if !d.is_empty() {
            svg.line(format_args!(
                r#"<path id="zone-{k}" d="{d}" {fill} {stroke}><title>{}</title></path>"#,
                esc(&z.label)
            ));
        }
        for line in &z.lines {
            if let [p] = line[..] {
                let (x, y) = view.pt(p);
                svg.line(format_args!(
                    r#"<circle cx="{}" cy="{}" r="1.6" fill="{}"><title>{}</title></circle>"#,
                    N(x),
                    N(y),
                    NO_FLY.hex(),
                    esc(&z.label)
                ));
                continue;
            }
            let mut d = String::new();
            view.push_path(&mut d, line);
            svg.line(format_args!(
                r#"<path d="{d}" fill="none" stroke="{}" stroke-width="1.4"><title>{}</title></path>"#,
                NO_FLY.hex(),
                esc(&z.label)
            ));
        }
    }
    svg.line(format_args!("</g>"));
}

/// Draws the cells, filled, with hairline white borders; each `<path id="cell-N">` with a
/// `<title>` naming the cell.
pub(crate) fn draw_cells(svg: &mut Svg, view: &MapView, cells: &[CellShape], fills: &[Rgb]) {
    svg.line(format_args!(
        r##"<g id="cells" stroke="#ffffff" stroke-width="0.35" stroke-linejoin="round">"##
    ));
    for (k, (c, fill)) in cells.iter().zip(fills).enumerate() {
        if c.ring.len() < 3 {
            continue;
        }
        let mut d = String::new();
        view.push_path(&mut d, &c.ring);
        d.push('Z');
        let s =
            c.s.map_or_else(|| "not scored".to_string(), |s| format!("S = {s:.3}"));
        svg.line(format_args!(
            r#"<path id="cell-{k}" d="{d}" fill="{}"><title>{} {}</title></path>"#,
            fill.hex(),
            esc(&c.id),
            esc(&s)
        ));
    }
    svg.line(format_args!("</g>"));
}

/// Sensor dot radius, pt.
pub(crate) const SENSOR_R: f64 = 0.85;

/// One sensor marker at (`x`, `y`) pt.
pub(crate) fn sensor_marker(svg: &mut Svg, x: f64, y: f64) {
    svg.line(format_args!(
        r##"<circle cx="{}" cy="{}" r="{}" fill="{INK}" stroke="#ffffff" stroke-width="0.4"/>"##,
        N(x),
        N(y),
        N(SENSOR_R)
    ));
}

/// Draws the sensors.
pub(crate) fn draw_sensors(svg: &mut Svg, view: &MapView, sensors: &[(f64, f64)]) {
    svg.line(format_args!(r#"<g id="sensors">"#));
    for &p in sensors {
        let (x, y) = view.pt(p);
        sensor_marker(svg, x, y);
    }
    svg.line(format_args!("</g>"));
}

/// Half the size of the base marker, pt: a triangle 2·`BASE_R` wide.
pub(crate) fn base_r(font: f64) -> f64 {
    0.55 * font
}

/// The base station: a black triangle, point up, centred at (`x`, `y`).
pub(crate) fn base_marker(svg: &mut Svg, x: f64, y: f64, r: f64) {
    svg.line(format_args!(
        r##"<path d="M{} {}L{} {}L{} {}Z" fill="{INK}" stroke="#ffffff" stroke-width="0.6" stroke-linejoin="round"/>"##,
        N(x),
        N(y - r),
        N(x + r),
        N(y + 0.8 * r),
        N(x - r),
        N(y + 0.8 * r)
    ));
}

/// A north arrow (split arrowhead, "N" above) centred on `cx` from `top` down, `height` pt.
pub(crate) fn north_arrow(svg: &mut Svg, cx: f64, top: f64, height: f64, font: f64) {
    let cap = CAP_HEIGHT_EM * font;
    let tip = top + cap + 1.5;
    let (bottom, half) = (top + height, 0.3 * (height - cap));
    let notch = bottom - 0.3 * (bottom - tip);
    svg.line(format_args!(r#"<g id="north-arrow">"#));
    svg.text(cx, top + cap, font, Anchor::Middle, true, "N");
    svg.line(format_args!(
        r#"<path d="M{cx} {tip}L{r} {bottom}L{cx} {notch}Z" fill="{INK}" stroke="{INK}" stroke-width="0.4" stroke-linejoin="round"/>"#,
        cx = N(cx),
        tip = N(tip),
        r = N(cx - half),
        bottom = N(bottom),
        notch = N(notch)
    ));
    svg.line(format_args!(
        r##"<path d="M{cx} {tip}L{r} {bottom}L{cx} {notch}Z" fill="#ffffff" stroke="{INK}" stroke-width="0.4" stroke-linejoin="round"/>"##,
        cx = N(cx),
        tip = N(tip),
        r = N(cx + half),
        bottom = N(bottom),
        notch = N(notch)
    ));
    svg.line(format_args!("</g>"));
}

/// Height of [`north_arrow`] for a text size, pt.
pub(crate) fn north_arrow_height(font: f64) -> f64 {
    CAP_HEIGHT_EM * font + 1.5 + 1.7 * font
}

/// The scale bar's length: a round distance, m, at most `max_pt` long at `k` pt/m.
pub(crate) fn scale_length_m(k: f64, max_pt: f64) -> f64 {
    let max_m = max_pt / k;
    if !(max_m.is_finite() && max_m > 0.0) {
        return 1.0;
    }
    let mag = 10f64.powf(max_m.log10().floor());
    [5.0, 2.0, 1.0]
        .into_iter()
        .map(|m| m * mag)
        .find(|&v| v <= max_m)
        .unwrap_or(mag)
}

/// Label of a distance, m or km.
pub(crate) fn distance_label(m: f64) -> String {
    if m >= 1000.0 {
        format!(
            "{} km",
            ticks::label(m / 1000.0, ticks::decimals(m / 1000.0))
        )
    } else {
        format!("{} m", ticks::label(m, ticks::decimals(m)))
    }
}

/// A scale bar of `len_m` (two halves, black and white) centred on `cx`, its top at `top`;
/// the label below it. Returns the height used, pt.
pub(crate) fn scale_bar(svg: &mut Svg, cx: f64, top: f64, len_m: f64, k: f64, font: f64) -> f64 {
    let len = len_m * k;
    let (x0, h) = (cx - 0.5 * len, 0.32 * font);
    svg.line(format_args!(r#"<g id="scale-bar">"#));
    svg.line(format_args!(
        r#"<rect x="{}" y="{}" width="{}" height="{}" fill="{INK}" stroke="{INK}" stroke-width="0.4"/>"#,
        N(x0),
        N(top),
        N(0.5 * len),
        N(h)
    ));
    svg.line(format_args!(
        r##"<rect x="{}" y="{}" width="{}" height="{}" fill="#ffffff" stroke="{INK}" stroke-width="0.4"/>"##,
        N(x0 + 0.5 * len),
        N(top),
        N(0.5 * len),
        N(h)
    ));
    let cap = CAP_HEIGHT_EM * font;
    svg.text(
        cx,
        top + h + 1.5 + cap,
        font,
        Anchor::Middle,
        false,
        &distance_label(len_m),
    );
    svg.line(format_args!("</g>"));
    h + 1.5 + cap + 0.3 * font
}

/// Height of [`scale_bar`], pt.
pub(crate) fn scale_bar_height(font: f64) -> f64 {
    0.32 * font + 1.5 + CAP_HEIGHT_EM * font + 0.3 * font
}

/// Draws a route: the outbound legs solid, the return leg dashed, each leg with an arrowhead
/// in the free stretch between its end markers when there is room (and, but for the first
/// and the return leg, at least `min_free` pt of it). `radii` are the marker radii at each
/// point (pt) so arrows are never hidden under a marker.
pub(crate) fn draw_route(
    svg: &mut Svg,
    pts: &[(f64, f64)],
    radii: &[f64],
    colour: &str,
    dash: &str,
    arrow_len: f64,
    min_free: f64,
) {
    if pts.len() < 2 {
        return;
    }
    let n = pts.len();
    let ret = format!(r#" stroke-dasharray="{RETURN_DASH}""#);
    route_line(svg, &pts[..n - 1], colour, dash);
    route_line(svg, &pts[n - 2..], colour, &ret);
    for k in 0..n - 1 {
        let (a, b) = (pts[k], pts[k + 1]);
        let l = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
        let (ra, rb) = (
            radii.get(k).copied().unwrap_or(0.0),
            radii.get(k + 1).copied().unwrap_or(0.0),
        );
        let free = l - ra - rb;
        let first_or_last = k == 0 || k + 2 == n;
        if l > 0.0 && free >= arrow_len + 1.0 && (first_or_last || free >= min_free) {
            let t = (ra + 0.5 * free) / l;
            arrowhead(svg, a, b, t, arrow_len, colour);
        }
    }
}
