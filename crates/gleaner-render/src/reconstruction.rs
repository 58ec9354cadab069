//! The reconstruction map: an estimated field and its uncertainty at one time, two panels
//! side by side.

use gleaner_wire::docs::ReconstructionMapDoc;

use crate::colour::{ColourMap, Rgb, UNCERTAINTY_MAP, VALUE_MAP};
use crate::figure::{ColourScale, colour_tick, display_time};
use crate::font::{CAP_HEIGHT_EM, text_width};
use crate::frame::{
    self, Axes, Entry, INK, MapView, PT_PER_MM, Projection, Symbol, TICK, finite, lon_lat,
};
use crate::svg::{Anchor, N, Svg, esc, fit};
use crate::{FigureOptions, RenderError};

/// A unit as printed: `m3/m3` as m³/m³, `degC` as °C; others as they are.
pub(crate) fn pretty_unit(unit: &str) -> String {
    match unit.trim() {
        "m3/m3" | "m^3/m^3" => "m\u{b3}/m\u{b3}".into(),
        "degC" | "deg C" | "C" => "\u{b0}C".into(),
        "degF" => "\u{b0}F".into(),
        u => u.replace("m3", "m\u{b3}").replace("m2", "m\u{b2}"),
    }
}

/// A modality as printed: `vw@30cm` as "VW at 30 cm", `t@0.5m` as "T at 0.5 m".
pub(crate) fn pretty_modality(modality: &str) -> String {
    let (quantity, depth) = match modality.split_once('@') {
        Some((q, d)) => (q, Some(d)),
        None => (modality, None),
    };
    let q = quantity.to_uppercase();
    match depth {
        Some(d) => {
            let split = d.find(|c: char| c.is_ascii_alphabetic()).unwrap_or(d.len());
            let (num, unit) = d.split_at(split);
            if unit.is_empty() {
                format!("{q} at {num}")
            } else {
                format!("{q} at {num} {unit}")
            }
        }
        None => q,
    }
}

/// An estimator's name as printed.
pub(crate) fn estimator_text(name: &str) -> String {
    match name {
        "changes" => "kriging of changes".into(),
        "levels" => "ordinary kriging of levels".into(),
        "simple" => "simple kriging of levels".into(),
        "dynamic" => "dynamic field model".into(),
        other => other.into(),
    }
}

/// A duration, s, as printed: whole days or hours when it is one.
fn duration_text(s: i64) -> String {
    match s {
        0 => "0 s".into(),
        s if s % 86_400 == 0 => format!("{} d", s / 86_400),
        s if s % 3_600 == 0 => format!("{} h", s / 3_600),
        s if s % 60 == 0 => format!("{} min", s / 60),
        s => format!("{s} s"),
    }
}

/// A cell of the map in the local frame.
struct Shape {
    id: String,
    ring: Vec<(f64, f64)>,
    mean: f64,
    sd: f64,
}

/// A sensor in the local frame.
struct Point {
    id: String,
    at: (f64, f64),
    estimate: f64,
    sd: f64,
    read: bool,
}

/// Radius of a sensor marker at text size `font`, pt.
fn marker_r(font: f64) -> f64 {
    0.25 * font
}

/// One panel's content: which values, which colours, the bar's title.
struct Panel<'a> {
    /// `value` or `sd`: ids of its groups and cells.
    key: &'static str,
    header: String,
    bar_title: String,
    map: ColourMap,
    scale: Option<ColourScale>,
    value: &'a dyn Fn(&Shape) -> f64,
    unit: &'a str,
}

/// The map of a reconstruction as an SVG document, `opts.width_mm` wide (178 mm, the full
/// page width, suits its two panels).
///
/// Left, the estimated field: every cell filled by the mean of its sensors' estimates on
/// viridis; right, its uncertainty: every cell filled by the root mean of its sensors'
/// posterior variances (a posterior standard deviation) on reversed magma, from 0. Each
/// panel has a colour bar titled with the quantity and its unit. On both, every sensor is
/// marked — a dark disc if it was read at the time (its latest reading at most
/// `read_within_s` before it), a white diamond if it is only estimated — and
/// the field's outline is drawn over the cells. Ticks are metres from the base station or
/// degrees ([`crate::Coordinates`]); the legend row holds the symbols, a scale bar in metres
/// and a north arrow; the title names the modality, the time (UTC) and the estimator.
///
/// Errors: a NaN or infinite number, a negative sd or cell size, an impossible position,
/// or unusable options.
pub fn reconstruction_map_svg(
    doc: &ReconstructionMapDoc,
    opts: &FigureOptions,
) -> Result<String, RenderError> {
    frame::check_options(opts)?;
    let projection = Projection::new(doc.base_lon_lat)?;
    let cell_size_m = finite(|| "cell_size_m".into(), doc.cell_size_m)?;
    let (cells, sensors, outline) = projected(doc, &projection, cell_size_m)?;

    let extent = extent_of(&cells, &sensors, &outline, cell_size_m);

    let font = opts.font_pt;
    let cap = CAP_HEIGHT_EM * font;
    let width = opts.width_mm * PT_PER_MM;
    let margin = 0.6 * font;
    let inner = width - 2.0 * margin;

    // Text.
    let short = doc
        .modality
        .split('@')
        .next()
        .unwrap_or_default()
        .to_uppercase();
    let unit = doc.unit.as_deref().map(pretty_unit).unwrap_or_default();
    let with_unit = |label: &str| {
        if unit.is_empty() {
            label.to_string()
        } else {
            format!("{label} ({unit})")
        }
    };
    let (title, subtitle) = titles_text(doc, opts, (&sensors, cells.len(), cell_size_m));

    // Colour scales: the estimate over its range, the sd from 0.
    let means: Vec<f64> = cells.iter().map(|c| c.mean).collect();
    let value_scale = ColourScale::new(&means);
    let max_sd = cells.iter().map(|c| c.sd).fold(0.0, f64::max);
    let sd_scale = (!cells.is_empty()).then(|| ColourScale {
        lo: 0.0,
        hi: if max_sd > 0.0 { max_sd } else { 1e-3 },
        ticks: Vec::new(),
    });
    let value_of = |c: &Shape| c.mean;
    let sd_of = |c: &Shape| c.sd;
    let mut panels = [
        Panel {
            key: "value",
            header: format!("(a) Estimate: {}", with_unit(&short)),
            bar_title: with_unit(&short),
            map: VALUE_MAP,
            scale: value_scale,
            value: &value_of,
            unit: &unit,
        },
        Panel {
            key: "sd",
            header: format!("(b) Uncertainty: {}", with_unit("posterior sd")),
            bar_title: with_unit("sd"),
            map: UNCERTAINTY_MAP,
            scale: sd_scale,
            value: &sd_of,
            unit: &unit,
        },
    ];

    // Horizontal layout: two slots, each [y title | y labels | map | gap | colour bar].
    let gap_between = 1.6 * font;
    let slot_w = (inner - gap_between) / 2.0;
    let bar_w = 0.9 * font;
    let bar_gap = 0.9 * font;
    let column_w = |p: &Panel| {
        let labels = p.scale.as_ref().map_or(0.0, |s| s.label_width(font));
        bar_w + TICK + 1.2 + labels + 0.5 * font + 1.25 * font
    };
    let columns = [column_w(&panels[0]), column_w(&panels[1])];
    let widest_column = columns[0].max(columns[1]);
    let titles = frame::Titles::new(&title, &subtitle, font, inner, margin);
    let header_baseline = titles.map_top + cap;
    let map_top = header_baseline + 0.9 * font;
    let pad = marker_r(font) + 1.5;
    let y_area = |ylab_w: f64| 1.25 * font + ylab_w + 1.2 + TICK;
    let avail_w = |ylab_w: f64| (slot_w - y_area(ylab_w) - bar_gap - widest_column).max(4.0 * font);
    let (view, ylab_w) = fit_view((extent, &projection), opts, (map_top, pad), avail_w);
    let used_w = y_area(ylab_w) + view.w + bar_gap + widest_column;
    let offset = 0.5 * (slot_w - used_w).max(0.0);
    let slot_x = |k: usize| margin + k as f64 * (slot_w + gap_between);
    let x_title_baseline = view.y + view.h + TICK + 1.0 + cap + 1.2 * font + 0.1 * font;

    // The legend row: symbols left, scale bar and north arrow right.
    let entries = legend_entries(doc, font);
    let na_h = frame::north_arrow_height(font);
    let na_w = 2.0 * font;
    let scale_max = (0.22 * inner).max(text_width("500 m", font, false) + 2.0);
    let len_m = frame::scale_length_m(view.k, scale_max);
    let scale_w = (len_m * view.k).max(text_width(&frame::distance_label(len_m), font, false));
    let right_w = scale_w + 1.5 * font + na_w;
    let legend_w = (inner - right_w - 2.0 * font).max(10.0 * font);
    let row_top = x_title_baseline + 0.9 * font;
    let legend_h = frame::legend_height(&entries, legend_w, font);
    let row_h = legend_h.max(na_h);
    let height = row_top + row_h + margin;

    // Draw.
    let mut svg = Svg::new(width, height, font, &title);
    titles.draw(&mut svg, margin);
    let layout = PanelLayout {
        header_baseline,
        slot_w,
        offset,
        bar_w,
        bar_gap,
        x_title_baseline,
        y_area: y_area(ylab_w),
        font,
    };
    let content = Content {
        cells: &cells,
        sensors: &sensors,
        outline: &outline,
        projection: &projection,
        opts,
    };
    for (k, panel) in panels.iter_mut().enumerate() {
        draw_panel(
            &mut svg,
            panel,
            &content,
            &layout,
            (slot_x(k) + offset, view),
        );
    }
    frame::draw_legend(
        &mut svg, "legend", &entries, margin, row_top, legend_w, font,
    );
    let na_cx = width - margin - 0.5 * na_w;
    frame::north_arrow(&mut svg, na_cx, row_top, na_h, font);
    let sb_cx = width - margin - na_w - 1.5 * font - 0.5 * scale_w;
    frame::scale_bar(
        &mut svg,
        sb_cx,
        row_top + 0.5 * (na_h - frame::scale_bar_height(font)),
        len_m,
        view.k,
        font,
    );
    Ok(svg.finish())
}

/// The map's placement in its slot at `map_top` (pt), `avail_w(y labels' width)` wide:
/// fitted, then refitted with the measured y labels (at most three passes). Returns it and
/// the y labels' width, pt.
fn fit_view(
    (extent, projection): ((f64, f64, f64, f64), &Projection),
    opts: &FigureOptions,
    (map_top, pad): (f64, f64),
    avail_w: impl Fn(f64) -> f64,
) -> (MapView, f64) {
    let font = opts.font_pt;
    let mut ylab_w = text_width("\u{2212}000", font, false);
    let mut view;
    let mut passes = 0;
    loop {
        let avail_w = avail_w(ylab_w);
        view = MapView::fit(
            extent,
            0.0,
            map_top,
            avail_w,
            opts.max_map_aspect * avail_w,
            pad,
        );
        let axes = Axes::new(&view, projection, opts.coordinates, font);
        let measured = axes.y_label_width(font);
        passes += 1;
        if measured <= ylab_w + 0.01 || passes >= 3 {
            break;
        }
        ylab_w = measured;
    }
    (view, ylab_w)
}

/// The map's title (the options', else the modality, time and estimator) and subtitle (the
/// project, the sensors read and estimated, the cells).
fn titles_text(
    doc: &ReconstructionMapDoc,
    opts: &FigureOptions,
    (sensors, cells, cell_size_m): (&[Point], usize, f64),
) -> (String, String) {
    let quantity = pretty_modality(&doc.modality);
    let title = match &opts.title {
        Some(t) => t.clone(),
        None => format!(
            "Estimated {quantity} \u{b7} {} \u{b7} {}",
            display_time(&doc.at),
            estimator_text(&doc.estimator)
        ),
    };
    let read = sensors.iter().filter(|s| s.read).count();
    let subtitle = format!(
        "{}{} sensors: {} read within {} before the time, {} estimated only \u{b7} {} cells of {} m, each the mean of its sensors",
        if doc.project.is_empty() {
            String::new()
        } else {
            format!("{} \u{b7} ", doc.project)
        },
        sensors.len(),
        read,
        duration_text(doc.read_within_s),
        sensors.len() - read,
        cells,
        ticks_label(cell_size_m)
    );

    (title, subtitle)
}

/// The cells, sensors and outline rings in the local frame, m.
type Projected = (Vec<Shape>, Vec<Point>, Vec<Vec<(f64, f64)>>);

/// The document's cells, sensors and outline in the local frame (m), checked: finite, sds
/// and the cell size positive, positions possible.
fn projected(
    doc: &ReconstructionMapDoc,
    projection: &Projection,
    cell_size_m: f64,
) -> Result<Projected, RenderError> {
    if cell_size_m <= 0.0 {
        return Err(RenderError::OutOfRange {
            what: "cell_size_m".into(),
            value: cell_size_m,
            expected: "> 0 m",
        });
    }
    if doc.read_within_s < 0 {
        return Err(RenderError::OutOfRange {
            what: "read_within_s".into(),
            value: doc.read_within_s as f64,
            expected: ">= 0 s",
        });
    }
    let non_negative = |what: String, v: f64| -> Result<f64, RenderError> {
        let v = finite(|| what.clone(), v)?;
        if v < 0.0 {
            return Err(RenderError::OutOfRange {
                what,
                value: v,
                expected: ">= 0",
            });
        }
        Ok(v)
    };
    let mut cells = Vec::with_capacity(doc.cells.len());
    for c in &doc.cells {
        let mut ring = Vec::with_capacity(c.ring_lon_lat.len());
        for (k, p) in c.ring_lon_lat.iter().enumerate() {
            ring.push(projection.local(lon_lat(|| format!("cell {} ring point {k}", c.cell), *p)?));
        }
        cells.push(Shape {
            id: c.cell.clone(),
            ring,
            mean: finite(|| format!("cell {} mean", c.cell), c.mean)?,
            sd: non_negative(format!("cell {} sd", c.cell), c.sd)?,
        });
    }
    let mut sensors = Vec::with_capacity(doc.sensors.len());
    for s in &doc.sensors {
        sensors.push(Point {
            id: s.sensor.clone(),
            at: projection.local(lon_lat(|| format!("sensor {}", s.sensor), s.lon_lat)?),
            estimate: finite(|| format!("sensor {} estimate", s.sensor), s.estimate)?,
            sd: non_negative(format!("sensor {} sd", s.sensor), s.sd)?,
            read: s.read,
        });
    }
    let mut outline = Vec::with_capacity(doc.outline_lon_lat.len());
    for (r, ring) in doc.outline_lon_lat.iter().enumerate() {
        let mut pts = Vec::with_capacity(ring.len());
        for (k, p) in ring.iter().enumerate() {
            pts.push(projection.local(lon_lat(|| format!("outline ring {r} point {k}"), *p)?));
        }
        outline.push(pts);
    }
    Ok((cells, sensors, outline))
}

/// The map's extent (e0, e1, n0, n1, m) over the cells, sensors and outline; a span under a
/// cell side (or 20 m) widened to it about its middle, so a point still gets an area.
fn extent_of(
    cells: &[Shape],
    sensors: &[Point],
    outline: &[Vec<(f64, f64)>],
    cell_size_m: f64,
) -> (f64, f64, f64, f64) {
    let mut ext: Option<(f64, f64, f64, f64)> = None;
    let mut grow = |(e, n): (f64, f64)| {
        ext = Some(match ext {
            None => (e, e, n, n),
            Some(x) => (x.0.min(e), x.1.max(e), x.2.min(n), x.3.max(n)),
        });
    };
    cells
        .iter()
        .flat_map(|c| c.ring.iter())
        .for_each(|&p| grow(p));
    sensors.iter().for_each(|s| grow(s.at));
    outline.iter().flatten().for_each(|&p| grow(p));
    frame::widened(ext.unwrap_or((0.0, 0.0, 0.0, 0.0)), cell_size_m)
}

/// The legend's symbols: sensors read, sensors estimated, the field's outline.
fn legend_entries(doc: &ReconstructionMapDoc, font: f64) -> Vec<Entry> {
    vec![
        Entry {
            symbol: Symbol::SensorRead(marker_r(font)),
            text: format!(
                "sensor read within {} before the time",
                duration_text(doc.read_within_s)
            ),
        },
        Entry {
            symbol: Symbol::SensorEstimated(marker_r(font)),
            text: "sensor estimated only".into(),
        },
        Entry {
            symbol: Symbol::Outline,
            text: "field outline".into(),
        },
    ]
}

/// Where the panels go: their slot, header, colour bar and axis titles, pt.
struct PanelLayout {
    header_baseline: f64,
    slot_w: f64,
    offset: f64,
    bar_w: f64,
    bar_gap: f64,
    x_title_baseline: f64,
    /// Width of the y title and labels left of the map.
    y_area: f64,
    font: f64,
}

/// What every panel draws.
struct Content<'a> {
    cells: &'a [Shape],
    sensors: &'a [Point],
    outline: &'a [Vec<(f64, f64)>],
    projection: &'a Projection,
    opts: &'a FigureOptions,
}

/// One panel at `x0` (pt): its header, cells, outline, sensors, axes and colour bar; `view`
/// the map's placement (moved to the panel).
fn draw_panel(
    svg: &mut Svg,
    panel: &mut Panel<'_>,
    content: &Content<'_>,
    layout: &PanelLayout,
    (x0, view): (f64, MapView),
) {
    let font = layout.font;
    let r = marker_r(font);
    let mut v = view;
    v.x = x0 + layout.y_area;
    svg.line(format_args!(r#"<g id="panel-{}">"#, panel.key));
    svg.text_attrs(
        x0,
        layout.header_baseline,
        font,
        Anchor::Start,
        true,
        &format!(r#"fill="{INK}""#),
        &fit(&panel.header, font, true, layout.slot_w - layout.offset),
    );
    // Cells.
    svg.line(format_args!(
        r##"<g id="{}-cells" stroke="#ffffff" stroke-width="0.35" stroke-linejoin="round">"##,
        panel.key
    ));
    for (j, c) in content.cells.iter().enumerate() {
        if c.ring.len() < 3 {
            continue;
        }
        let value = (panel.value)(c);
        let fill: Rgb = match &panel.scale {
            Some(s) => panel.map.at(s.t(value)),
            None => crate::colour::NO_SCORE,
        };
        let mut d = String::new();
        v.push_path(&mut d, &c.ring);
        d.push('Z');
        svg.line(format_args!(
            r#"<path id="{}-cell-{j}" class="cell" d="{d}" fill="{}"><title>{} {}</title></path>"#,
            panel.key,
            fill.hex(),
            esc(&c.id),
            esc(format!("{} {}", value_text(value), panel.unit).trim_end())
        ));
    }
    svg.line(format_args!("</g>"));
    // Outline.
    if !content.outline.is_empty() {
        let mut d = String::new();
        for ring in content.outline {
            v.push_path(&mut d, ring);
        }
        svg.line(format_args!(
            r#"<path id="{}-outline" d="{d}" fill="none" stroke="{INK}" stroke-width="0.9" stroke-linejoin="round"/>"#,
            panel.key
        ));
    }
    // Sensors: the estimated ones first, the read ones over them.
    svg.line(format_args!(r#"<g id="{}-sensors">"#, panel.key));
    for read in [false, true] {
        for s in content.sensors.iter().filter(|s| s.read == read) {
            let (x, y) = v.pt(s.at);
            let value = if panel.key == "sd" { s.sd } else { s.estimate };
            let title = format!("{} {} {}", s.id, value_text(value), panel.unit);
            frame::sensor_state_marker(svg, x, y, r, s.read, title.trim_end());
        }
    }
    svg.line(format_args!("</g>"));
    let axes_k = Axes::new(&v, content.projection, content.opts.coordinates, font);
    frame::draw_axes(svg, &v, &axes_k, font, x0, layout.x_title_baseline);
    // Colour bar: gradient, frame, ticks, labels, the rotated title.
    if let Some(scale) = panel.scale.as_mut() {
        colour_bar(
            svg,
            (panel.key, &panel.map, &panel.bar_title),
            scale,
            &v,
            layout,
        );
    }
    svg.line(format_args!("</g>"));
}

/// A panel's colour bar right of its map `v`: gradient, frame, ticks, labels, the rotated
/// title.
fn colour_bar(
    svg: &mut Svg,
    (key, map, bar_title): (&str, &ColourMap, &str),
    scale: &mut ColourScale,
    v: &MapView,
    layout: &PanelLayout,
) {
    let (font, bar_w, bar_gap) = (layout.font, layout.bar_w, layout.bar_gap);
    let cap = CAP_HEIGHT_EM * font;
    let bx = v.x + v.w + bar_gap;
    let (top, len) = (v.y, v.h);
    scale.set_ticks(len, 1.5 * font);
    svg.line(format_args!(r#"<g id="{}-colour-bar">"#, key));
    svg.line(format_args!(
        r#"<defs><linearGradient id="{}-ramp" x1="0" y1="1" x2="0" y2="0">{}</linearGradient></defs>"#,
        key,
        map.stops()
    ));
    svg.line(format_args!(
        r#"<rect x="{}" y="{}" width="{}" height="{}" fill="url(#{}-ramp)" stroke="{INK}" stroke-width="0.4"/>"#,
        N(bx),
        N(top),
        N(bar_w),
        N(len),
        key
    ));
    let mut label_w: f64 = 0.0;
    for (value, label) in &scale.ticks {
        let ty = top + len - scale.t(*value) * len;
        colour_tick(svg, bx + bar_w, ty, (font, cap), label);
        label_w = label_w.max(text_width(label, font, false));
    }
    // Rotated a quarter turn: its glyphs lie left of its baseline at `cx`.
    let cx = bx + bar_w + TICK + 1.2 + label_w + 0.5 * font + 0.93 * font;
    let cy = top + 0.5 * len;
    svg.vertical_title(
        (cx, cy),
        font,
        &format!(r#"fill="{INK}" "#),
        &fit(bar_title, font, false, len),
    );
    svg.line(format_args!("</g>"));
}

/// A value in a tooltip: four significant decimals.
fn value_text(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e5).contains(&a) {
        format!("{v:.3e}")
    } else {
        format!("{v:.4}")
    }
}

/// A length in m as printed (no trailing zeros).
fn ticks_label(m: f64) -> String {
    let s = format!("{m:.2}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_printed_for_readers() {
        assert_eq!(pretty_modality("vw@30cm"), "VW at 30 cm");
        assert_eq!(pretty_modality("vwc-a@0.15m"), "VWC-A at 0.15 m");
        assert_eq!(pretty_modality("t"), "T");
        assert_eq!(pretty_unit("m3/m3"), "m\u{b3}/m\u{b3}");
        assert_eq!(pretty_unit("degC"), "\u{b0}C");
        assert_eq!(pretty_unit("kPa"), "kPa");
        assert_eq!(estimator_text("changes"), "kriging of changes");
        assert_eq!(estimator_text("other"), "other");
        assert_eq!(duration_text(86_400), "1 d");
        assert_eq!(duration_text(21_600), "6 h");
        assert_eq!(duration_text(90), "90 s");
        assert_eq!(ticks_label(40.0), "40");
        assert_eq!(value_text(0.28731), "0.2873");
        assert_eq!(value_text(1.5e-5), "1.500e-5");
    }
}
