//! The map's coordinate ticks and axes.

use super::*;

/// One tick: its position along the axis (m in the local frame) and its label.
pub(crate) struct Tick {
    pub(crate) at_m: f64,
    pub(crate) label: String,
}

/// Ticks of one axis over [`lo_m`, `hi_m`] m: round metres, or round degrees converted.
/// `pt_per_m` is the map scale; labels are at least `min_gap` pt apart (measured along the
/// axis: their width for x, `font` for y).
fn axis_ticks(
    lo_m: f64,
    hi_m: f64,
    pt_per_m: f64,
    coords: Coordinates,
    deg: (f64, f64),
    font: f64,
    horizontal: bool,
) -> Vec<Tick> {
    // deg = (origin in degrees, m per degree) along this axis.
    let (unit_lo, unit_hi, m_per_unit, offset) = match coords {
        Coordinates::LocalMetres => (lo_m, hi_m, 1.0, 0.0),
        Coordinates::Degrees => (deg.0 + lo_m / deg.1, deg.0 + hi_m / deg.1, deg.1, deg.0),
    };
    let span = unit_hi - unit_lo;
    if !(span.is_finite() && span > 0.0) {
        return Vec::new();
    }
    let mut step = ticks::nice_step(span / 12.0);
    for _ in 0..40 {
        let values = ticks::multiples(unit_lo, unit_hi, step);
        let d = ticks::decimals(step);
        let labels: Vec<String> = values.iter().map(|&v| ticks::label(v, d)).collect();
        let spacing = step * m_per_unit * pt_per_m;
        let needed = if horizontal {
            labels
                .iter()
                .map(|l| text_width(l, font, false))
                .fold(0.0, f64::max)
                + 1.2 * font
        } else {
            2.0 * font
        };
        if spacing >= needed && values.len() <= 8 {
            return values
                .iter()
                .zip(labels)
                .map(|(&v, label)| Tick {
                    at_m: (v - offset) * m_per_unit,
                    label,
                })
                .collect();
        }
        step = ticks::nice_step(step * 1.5);
    }
    Vec::new()
}

/// The two axes' ticks for a map view.
pub(crate) struct Axes {
    pub(crate) x: Vec<Tick>,
    pub(crate) y: Vec<Tick>,
    pub(crate) x_title: String,
    pub(crate) y_title: String,
}

impl Axes {
    pub(crate) fn new(view: &MapView, p: &Projection, coords: Coordinates, font: f64) -> Self {
        let x = axis_ticks(
            view.e0,
            view.e1(),
            view.k,
            coords,
            (p.lon0, p.kx),
            font,
            true,
        );
        let y = axis_ticks(
            view.n0(),
            view.n1,
            view.k,
            coords,
            (p.lat0, p.ky),
            font,
            false,
        );
        let (x_long, y_long, x_short, y_short) = match coords {
            Coordinates::LocalMetres => (
                "metres east of base",
                "metres north of base",
                "east (m)",
                "north (m)",
            ),
            Coordinates::Degrees => ("longitude (°E)", "latitude (°N)", "lon (°)", "lat (°)"),
        };
        // The long title when it fits along the axis, else the short one (cut if need be).
        let pick = |long: &'static str, short: &'static str, len: f64| -> String {
            if text_width(long, font, false) <= len {
                long.to_string()
            } else {
                crate::svg::fit(short, font, false, len)
            }
        };
        let x_title = pick(x_long, x_short, view.w);
        let y_title = pick(y_long, y_short, view.h);
        Self {
            x,
            y,
            x_title,
            y_title,
        }
    }

    /// Widest y label, pt.
    pub(crate) fn y_label_width(&self, font: f64) -> f64 {
        self.y
            .iter()
            .map(|t| text_width(&t.label, font, false))
            .fold(0.0, f64::max)
    }
}

/// Tick length, pt.
pub(crate) const TICK: f64 = 2.5;

/// Draws the frame, ticks, tick labels and axis titles. The y title goes at `y_title_x`
/// (the left edge of its rotated line), the x title's baseline at `x_title_y`.
pub(crate) fn draw_axes(
    svg: &mut Svg,
    view: &MapView,
    axes: &Axes,
    font: f64,
    y_title_x: f64,
    x_title_y: f64,
) {
    svg.line(format_args!(
        r#"<g id="axes" stroke="{INK}" stroke-width="0.5">"#
    ));
    svg.line(format_args!(
        r#"<rect x="{}" y="{}" width="{}" height="{}" fill="none"/>"#,
        N(view.x),
        N(view.y),
        N(view.w),
        N(view.h)
    ));
    let bottom = view.y + view.h;
    for t in &axes.x {
        let (x, _) = view.pt((t.at_m, 0.0));
        svg.line(format_args!(
            r#"<line x1="{}" y1="{}" x2="{}" y2="{}"/>"#,
            N(x),
            N(bottom),
            N(x),
            N(bottom + TICK)
        ));
    }
    for t in &axes.y {
        let (_, y) = view.pt((0.0, t.at_m));
        svg.line(format_args!(
            r#"<line x1="{}" y1="{}" x2="{}" y2="{}"/>"#,
            N(view.x - TICK),
            N(y),
            N(view.x),
            N(y)
        ));
    }
    svg.line(format_args!("</g>"));
    svg.line(format_args!(r#"<g id="tick-labels" fill="{INK}">"#));
    let cap = CAP_HEIGHT_EM * font;
    for t in &axes.x {
        let (x, _) = view.pt((t.at_m, 0.0));
        svg.text(
            x,
            bottom + TICK + 1.0 + cap,
            font,
            Anchor::Middle,
            false,
            &t.label,
        );
    }
    for t in &axes.y {
        let (_, y) = view.pt((0.0, t.at_m));
        svg.text(
            view.x - TICK - 1.2,
            y + 0.5 * cap,
            font,
            Anchor::End,
            false,
            &t.label,
        );
    }
    svg.text(
        view.x + 0.5 * view.w,
        x_title_y,
        font,
        Anchor::Middle,
        false,
        &axes.x_title,
    );
    let (cx, cy) = (y_title_x + 0.93 * font, view.y + 0.5 * view.h);
    svg.vertical_title((cx, cy), font, "", &axes.y_title);
    svg.line(format_args!("</g>"));
}
