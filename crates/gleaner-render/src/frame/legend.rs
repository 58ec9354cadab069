//! Route and stop marks and the legend grid with its symbols.

use super::*;

/// A legend symbol.
#[derive(Clone)]
pub(crate) enum Symbol {
    Sensor,
    /// A stop marker with a number, radius pt.
    Stop(f64),
    /// A route line with an arrowhead, colour, dash (0 = solid).
    Route(Rgb, u32),
    /// The return leg: dashed.
    Return(Rgb),
    /// The base, half-size pt.
    Base(f64),
    /// A filled square.
    Swatch(Rgb),
    /// A filled square and a route line over it (a sortie).
    Sortie(Rgb, Rgb, u32),
    /// A sensor read at the map's time: a dark disc, radius pt.
    SensorRead(f64),
    /// A sensor only estimated: a white diamond, half-size pt.
    SensorEstimated(f64),
    /// The field's outline: a dark line.
    Outline,
}

/// One legend entry.
pub(crate) struct Entry {
    pub(crate) symbol: Symbol,
    pub(crate) text: String,
}

/// Stroke dash pattern number `dash` (0 solid; the return leg has its own).
pub(crate) fn dash_attr(dash: u32) -> &'static str {
    match dash {
        0 => "",
        1 => r#" stroke-dasharray="4 1 1 1""#,
        _ => r#" stroke-dasharray="1 1""#,
    }
}

/// Dash pattern of return legs.
pub(crate) const RETURN_DASH: &str = "2.4 1.4";

/// An arrowhead pointing from (`x0`,`y0`) to (`x1`,`y1`), centred at `t` of the way along,
/// `len` pt long.
pub(crate) fn arrowhead(
    svg: &mut Svg,
    (x0, y0): (f64, f64),
    (x1, y1): (f64, f64),
    t: f64,
    len: f64,
    fill: &str,
) {
    let (dx, dy) = (x1 - x0, y1 - y0);
    let l = (dx * dx + dy * dy).sqrt();
    if !(l.is_finite() && l > 0.0) {
        return;
    }
    let (ux, uy) = (dx / l, dy / l);
    let (mx, my) = (x0 + dx * t, y0 + dy * t);
    let (hw, hl) = (0.42 * len, 0.5 * len);
    let tip = (mx + ux * hl, my + uy * hl);
    let back = (mx - ux * hl, my - uy * hl);
    let l1 = (back.0 - uy * hw, back.1 + ux * hw);
    let l2 = (back.0 + uy * hw, back.1 - ux * hw);
    let notch = (mx - ux * 0.25 * hl, my - uy * 0.25 * hl);
    svg.line(format_args!(
        r##"<path class="arrow" d="M{} {}L{} {}L{} {}L{} {}Z" fill="{fill}" stroke="#ffffff" stroke-width="0.35" stroke-linejoin="round"/>"##,
        N(tip.0),
        N(tip.1),
        N(l1.0),
        N(l1.1),
        N(notch.0),
        N(notch.1),
        N(l2.0),
        N(l2.1)
    ));
}

/// Width of a legend symbol's box, pt.
pub(crate) fn symbol_width(font: f64) -> f64 {
    2.3 * font
}

fn draw_symbol(svg: &mut Svg, s: &Symbol, x: f64, cy: f64, font: f64) {
    let w = symbol_width(font);
    let cx = x + 0.5 * w;
    match s {
        Symbol::Sensor => sensor_marker(svg, cx, cy),
        Symbol::Stop(r) => {
            stop_marker(svg, cx, cy, *r, "1", font, "#d62728");
        }
        Symbol::Route(c, dash) => {
            route_line(svg, &[(x, cy), (x + w, cy)], &c.hex(), dash_attr(*dash));
            arrowhead(svg, (x, cy), (x + w, cy), 0.55, 0.75 * font, &c.hex());
        }
        Symbol::Return(c) => {
            let dash = format!(r#" stroke-dasharray="{RETURN_DASH}""#);
            route_line(svg, &[(x, cy), (x + w, cy)], &c.hex(), &dash);
        }
        Symbol::Base(r) => base_marker(svg, cx, cy, *r),
        Symbol::Swatch(c) => {
            let h = 0.85 * font;
            svg.line(format_args!(
                r##"<rect x="{}" y="{}" width="{}" height="{}" fill="{}" stroke="#8c8c8c" stroke-width="0.3"/>"##,
                N(cx - 0.5 * h),
                N(cy - 0.5 * h),
                N(h),
                N(h),
                c.hex()
            ));
        }
        Symbol::Sortie(fill, line, dash) => {
            let h = 0.95 * font;
            svg.line(format_args!(
                r#"<rect x="{}" y="{}" width="{}" height="{}" fill="{}"/>"#,
                N(x + 0.15 * w),
                N(cy - 0.5 * h),
                N(0.7 * w),
                N(h),
                fill.hex()
            ));
            route_line(svg, &[(x, cy), (x + w, cy)], &line.hex(), dash_attr(*dash));
        }
        Symbol::SensorRead(r) => sensor_state_marker(svg, cx, cy, *r, true, ""),
        Symbol::SensorEstimated(r) => sensor_state_marker(svg, cx, cy, *r, false, ""),
        Symbol::Outline => {
            svg.line(format_args!(
                r#"<line x1="{}" y1="{}" x2="{}" y2="{}" stroke="{INK}" stroke-width="0.9"/>"#,
                N(x + 0.1 * w),
                N(cy),
                N(x + 0.9 * w),
                N(cy)
            ));
        }
    }
}

/// A polyline with a white casing under it so it reads on any fill.
pub(crate) fn route_line(svg: &mut Svg, pts: &[(f64, f64)], colour: &str, dash: &str) {
    if pts.len() < 2 {
        return;
    }
    let points: Vec<String> = pts
        .iter()
        .map(|&(x, y)| format!("{},{}", N(x), N(y)))
        .collect();
    let points = points.join(" ");
    svg.line(format_args!(
        r##"<polyline points="{points}" fill="none" stroke="#ffffff" stroke-width="2.3" stroke-linejoin="round" stroke-linecap="round"{dash}/>"##
    ));
    svg.line(format_args!(
        r#"<polyline points="{points}" fill="none" stroke="{colour}" stroke-width="1.1" stroke-linejoin="round"{dash}/>"#
    ));
}

/// A numbered stop: white disc, coloured ring, bold number.
pub(crate) fn stop_marker(
    svg: &mut Svg,
    x: f64,
    y: f64,
    r: f64,
    label: &str,
    font: f64,
    ring: &str,
) {
    svg.line(format_args!(
        r##"<circle cx="{}" cy="{}" r="{}" fill="#ffffff" stroke="{ring}" stroke-width="0.8"/>"##,
        N(x),
        N(y),
        N(r)
    ));
    let size = stop_font(font, label);
    svg.text_attrs(
        x,
        y + 0.5 * CAP_HEIGHT_EM * size,
        size,
        Anchor::Middle,
        true,
        &format!(r#"fill="{INK}""#),
        label,
    );
}

/// Text size of a stop number: the body size, smaller for three digits.
pub(crate) fn stop_font(font: f64, label: &str) -> f64 {
    if label.chars().count() >= 3 {
        0.8 * font
    } else {
        font
    }
}

/// Radius of the stop markers for stops numbered up to `last`, pt: room for the widest
/// number and for the digits' height.
pub(crate) fn stop_radius(font: f64, last: u32) -> f64 {
    let widest = "8".repeat(last.max(1).to_string().len());
    let size = stop_font(font, &widest);
    (0.5 * text_width(&widest, size, true) + 1.0).max(0.5 * CAP_HEIGHT_EM * size + 1.4)
}

/// Space between legend columns, em.
const LEGEND_COL_GAP: f64 = 0.9;

/// Height of one legend row, pt.
pub(crate) fn legend_row_height(font: f64) -> f64 {
    1.3 * font
}

/// The legend's columns: entries are listed down the columns in order (so related entries
/// stay together); as many columns as fit in `width` pt. Returns the rows and each column's
/// width, pt.
fn legend_columns(entries: &[Entry], width: f64, font: f64) -> (usize, Vec<f64>) {
    let item = |e: &Entry| symbol_width(font) + 0.4 * font + text_width(&e.text, font, false);
    let gap = LEGEND_COL_GAP * font;
    for cols in (1..=entries.len()).rev() {
        let rows = entries.len().div_ceil(cols);
        let widths: Vec<f64> = entries
            .chunks(rows)
            .map(|col| col.iter().map(item).fold(0.0, f64::max))
            .collect();
        let total = widths.iter().sum::<f64>() + gap * (widths.len() as f64 - 1.0);
        if total <= width || cols == 1 {
            return (rows, widths);
        }
    }
    (0, Vec::new())
}

/// Draws the legend from `top` at `x`, at most `width` pt wide, columns spread over the
/// width. Returns the height used, pt.
pub(crate) fn draw_legend(
    svg: &mut Svg,
    id: &str,
    entries: &[Entry],
    x: f64,
    top: f64,
    width: f64,
    font: f64,
) -> f64 {
    if entries.is_empty() {
        return 0.0;
    }
    let (rows, widths) = legend_columns(entries, width, font);
    let used: f64 = widths.iter().sum();
    // Spread the spare width between the columns.
    let gap = if widths.len() > 1 {
        ((width - used) / (widths.len() as f64 - 1.0)).min(3.0 * font)
    } else {
        0.0
    };
    let sw = symbol_width(font);
    let lh = legend_row_height(font);
    svg.line(format_args!(r#"<g id="{id}">"#));
    let mut col_x = x;
    for (c, col) in entries.chunks(rows.max(1)).enumerate() {
        let col_w = widths.get(c).copied().unwrap_or(width);
        for (row, e) in col.iter().enumerate() {
            let cy = top + (row as f64 + 0.5) * lh;
            svg.line(format_args!(r#"<g class="legend-entry">"#));
            draw_symbol(svg, &e.symbol, col_x, cy, font);
            let max_text = (x + width - col_x) - sw - 0.4 * font;
            let text = crate::svg::fit(&e.text, font, false, max_text);
            svg.text_attrs(
                col_x + sw + 0.4 * font,
                cy + 0.5 * CAP_HEIGHT_EM * font,
                font,
                Anchor::Start,
                false,
                &format!(r#"fill="{INK}""#),
                &text,
            );
            svg.line(format_args!("</g>"));
        }
        col_x += col_w + gap;
    }
    svg.line(format_args!("</g>"));
    rows as f64 * lh
}

/// Height [`draw_legend`] will use, pt.
pub(crate) fn legend_height(entries: &[Entry], width: f64, font: f64) -> f64 {
    if entries.is_empty() {
        return 0.0;
    }
    legend_columns(entries, width, font).0 as f64 * legend_row_height(font)
}

/// A sensor marker centred at (`x`, `y`), `r` pt: read = a dark disc with a thin white rim;
/// estimated only = a white diamond with a dark edge (told apart by shape as well as by
/// tone, so in grey too and on dark cells). A marker with a `title` (a sensor on the map,
/// not a legend symbol) carries the class `sensor-read` or `sensor-estimated`.
pub(crate) fn sensor_state_marker(svg: &mut Svg, x: f64, y: f64, r: f64, read: bool, title: &str) {
    let (title, class) = if title.is_empty() {
        (String::new(), "")
    } else if read {
        (
            format!("<title>{}</title>", esc(title)),
            r#" class="sensor-read""#,
        )
    } else {
        (
            format!("<title>{}</title>", esc(title)),
            r#" class="sensor-estimated""#,
        )
    };
    if read {
        svg.line(format_args!(
            r##"<circle{class} cx="{}" cy="{}" r="{}" fill="{INK}" stroke="#ffffff" stroke-width="0.35">{title}</circle>"##,
            N(x),
            N(y),
            N(r)
        ));
    } else {
        let d = 1.2 * r;
        svg.line(format_args!(
            r##"<path{class} d="M{} {}L{} {}L{} {}L{} {}Z" fill="#ffffff" stroke="{INK}" stroke-width="0.55" stroke-linejoin="round">{title}</path>"##,
            N(x),
            N(y - d),
            N(x + d),
            N(y),
            N(x),
            N(y + d),
            N(x - d),
            N(y)
        ));
    }
}
