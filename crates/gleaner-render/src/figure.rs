//! The mission figure (the paper's Figure 1).

use gleaner_wire::{FieldDoc, MissionDoc};

use crate::colour::{self, NO_SCORE, Rgb};
use crate::font::{CAP_HEIGHT_EM, text_width};
use crate::frame::{self, Entry, INK, PT_PER_MM, Scene, Symbol, TICK, base_r, finite};
use crate::svg::{Anchor, N, Svg, fit, subscripted};
use crate::ticks;
use crate::{FigureOptions, RenderError};

/// Colour of the route.
pub(crate) const ROUTE: Rgb = Rgb(0xd6, 0x27, 0x28);

/// `2014-06-01T12:00:00Z` as `2014-06-01 12:00 UTC`; other text as it is.
pub(crate) fn display_time(rfc3339: &str) -> String {
    let b = rfc3339.as_bytes();
    let utc = rfc3339.ends_with('Z') || rfc3339.ends_with("+00:00");
    match (rfc3339.get(..10), rfc3339.get(11..16)) {
        (Some(date), Some(time)) if utc && b.get(10) == Some(&b'T') && b.get(13) == Some(&b':') => {
            format!("{date} {time} UTC")
        }
        _ => rfc3339.to_string(),
    }
}

/// A weight as printed in the formula: up to three decimals, no trailing zeros.
fn weight(w: f64) -> String {
    let s = format!("{:.3}", w.abs());
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s.is_empty() { "0".into() } else { s.into() }
}

/// `S = α·F + β·A + γ·U − δ·R` with the numbers.
pub(crate) fn formula(w: [f64; 4]) -> String {
    let mut out = String::from("S =");
    let terms = [
        (w[0], 'F', 1.0),
        (w[1], 'A', 1.0),
        (w[2], 'U', 1.0),
        (w[3], 'R', -1.0),
    ];
    for (k, (wt, name, sign)) in terms.into_iter().enumerate() {
        let v = wt * sign;
        let op = match (k, v < 0.0) {
            (0, false) => " ",
            (0, true) => " \u{2212}",
            (_, false) => " + ",
            (_, true) => " \u{2212} ",
        };
        out.push_str(op);
        out.push_str(&weight(v));
        out.push('\u{b7}');
        out.push(name);
    }
    out
}

/// A colour scale (of S, or of an estimated field): domain and ticks.
pub(crate) struct ColourScale {
    pub(crate) lo: f64,
    pub(crate) hi: f64,
    pub(crate) ticks: Vec<(f64, String)>,
}

impl ColourScale {
    /// The scale spanning `values` (widened around a single value); None without a finite
    /// one.
    pub(crate) fn new(values: &[f64]) -> Option<Self> {
        let (lo, hi) = values
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        if !(lo.is_finite() && hi.is_finite()) {
            return None;
        }
        let (lo, hi) = if hi - lo < 1e-9 * (1.0 + lo.abs()) {
            let half = (0.1 * lo.abs()).max(0.05);
            (lo - half, hi + half)
        } else {
            (lo, hi)
        };
        Some(Self {
            lo,
            hi,
            ticks: Vec::new(),
        })
    }

    /// Ticks at least `min_gap` pt apart on a bar `len` pt long.
    pub(crate) fn set_ticks(&mut self, len: f64, min_gap: f64) {
        let span = self.hi - self.lo;
        let mut step = ticks::nice_step(span / 10.0);
        for _ in 0..40 {
            let values = ticks::multiples(self.lo, self.hi, step);
            if step / span * len >= min_gap && values.len() <= 7 {
                let d = ticks::decimals(step);
                self.ticks = values.iter().map(|&v| (v, ticks::label(v, d))).collect();
                return;
            }
            step = ticks::nice_step(step * 1.5);
        }
        self.ticks.clear();
    }

    /// Where `v` lies on the scale, 0 at `lo`, 1 at `hi`.
    pub(crate) fn t(&self, v: f64) -> f64 {
        (v - self.lo) / (self.hi - self.lo)
    }

    /// The widest tick label this scale can have, pt.
    pub(crate) fn label_width(&self, font: f64) -> f64 {
        // Any tick set's labels are at most as wide as these.
        let d = ticks::decimals(ticks::nice_step((self.hi - self.lo) / 10.0));
        [self.lo, self.hi, -self.hi.abs().max(self.lo.abs())]
            .iter()
            .map(|&v| text_width(&ticks::label(v, d), font, false))
            .chain(self.ticks.iter().map(|(_, l)| text_width(l, font, false)))
            .fold(0.0, f64::max)
    }
}

/// The energy table's cells: header, kJ row, % row.
struct EnergyTable {
    heads: [&'static str; 6],
    kj: [String; 6],
    pct: [String; 6],
}

impl EnergyTable {
    fn new(m: &MissionDoc) -> Self {
        let e = &m.energy;
        let values = [
            e.travel_j, e.hover_j, e.comm_j, e.return_j, e.total_j, e.budget_j,
        ];
        let kj = values.map(|v| format!("{:.1}", v / 1000.0).replace('-', "\u{2212}"));
        let pct = values.map(|v| {
            if e.budget_j > 0.0 {
                format!("{:.1}", 100.0 * v / e.budget_j).replace('-', "\u{2212}")
            } else {
                "\u{2013}".into()
            }
        });
        Self {
            heads: ["E_t", "E_h", "E_c", "E_r", "total", "budget"],
            kj,
            pct,
        }
    }

    const ROW_KJ: &'static str = "energy (kJ)";
    const ROW_PCT: &'static str = "% of budget";

    /// Column widths (label column first) for the wide form, pt.
    fn widths(&self, font: f64) -> (f64, [f64; 6]) {
        let label =
            text_width(Self::ROW_KJ, font, false).max(text_width(Self::ROW_PCT, font, false));
        let mut cols = [0.0; 6];
        for (k, c) in cols.iter_mut().enumerate() {
            *c = subscripted(self.heads[k], font, true)
                .1
                .max(text_width(&self.kj[k], font, false))
                .max(text_width(&self.pct[k], font, false));
        }
        (label, cols)
    }

    fn height(font: f64) -> f64 {
        3.0 * 1.3 * font + 0.8 * font
    }

    /// Draws the table from `top`, `width` wide at `x`. Returns the height used.
    fn draw(&self, svg: &mut Svg, x: f64, top: f64, width: f64, font: f64) -> f64 {
        let (label_w, cols) = self.widths(font);
        let gap =
            ((width - label_w - cols.iter().sum::<f64>()) / 6.0).clamp(0.4 * font, 2.5 * font);
        let total_w = label_w + cols.iter().sum::<f64>() + 6.0 * gap;
        let lh = 1.3 * font;
        let cap = CAP_HEIGHT_EM * font;
        svg.line(format_args!(r#"<g id="energy-table" fill="{INK}">"#));
        let rule = |svg: &mut Svg, y: f64, w: f64| {
            svg.line(format_args!(
                r#"<line x1="{}" y1="{}" x2="{}" y2="{}" stroke="{INK}" stroke-width="{}"/>"#,
                N(x),
                N(y),
                N(x + total_w),
                N(y),
                N(w)
            ));
        };
        rule(svg, top, 0.6);
        let mut right = x + label_w;
        let mut rights = [0.0; 6];
        for (k, c) in cols.iter().enumerate() {
            right += gap + c;
            rights[k] = right;
        }
        let y1 = top + 0.3 * font + 0.5 * lh + 0.5 * cap;
        for (k, h) in self.heads.iter().enumerate() {
            let (markup, _) = subscripted(h, font, true);
            svg.line(format_args!(
                r#"<text x="{}" y="{}" font-size="{}" text-anchor="end" font-weight="bold">{markup}</text>"#,
                N(rights[k]),
                N(y1),
                N(font)
            ));
        }
        let mid = top + 0.3 * font + lh + 0.1 * font;
        rule(svg, mid, 0.35);
        let y2 = mid + 0.2 * font + 0.5 * lh + 0.5 * cap;
        let y3 = y2 + lh;
        svg.text(x, y2, font, Anchor::Start, false, Self::ROW_KJ);
        svg.text(x, y3, font, Anchor::Start, false, Self::ROW_PCT);
        for (k, &r) in rights.iter().enumerate() {
            svg.text(r, y2, font, Anchor::End, k == 4, &self.kj[k]);
            svg.text(r, y3, font, Anchor::End, k == 4, &self.pct[k]);
        }
        let bottom = y3 + (lh - 0.5 * lh - 0.5 * cap) + 0.1 * font;
        rule(svg, bottom, 0.6);
        svg.line(format_args!("</g>"));
        bottom - top
    }
}

/// The mission figure (the paper's Figure 1) as an SVG document, `opts.width_mm` wide.
///
/// Cells are coloured by their latest S (viridis; grey where not scored) with a colour bar
/// and the formula `S = α·F + β·A + γ·U − δ·R` with the mission's weights; sensors are dots;
/// the route runs from the base through the stops (numbered in visiting order, an arrowhead
/// on each leg) and back (dashed). Ticks are metres from the field's base or degrees
/// ([`crate::Coordinates`]); a north arrow and scale bar sit beside the colour bar; the
/// legend names every symbol; the table gives E_t, E_h, E_c, E_r, the total and the budget
/// in kJ and as % of the budget. The title names the mission id, kind and time t.
///
/// Errors: a NaN or infinite number or an impossible position anywhere in the inputs, or
/// unusable options. Cells are matched to nothing: the figure draws what the documents say.
pub fn mission_figure_svg(
    field: &FieldDoc,
    mission: &MissionDoc,
    opts: &FigureOptions,
) -> Result<String, RenderError> {
    frame::check_options(opts)?;
    let projection = frame::Projection::new(field.base_lon_lat)?;
    let (base, stops) = frame::mission_points(&projection, mission, "mission")?;
    let via = frame::mission_via(&projection, mission, "mission")?;
    let zones = frame::zone_shapes(
        &projection,
        if mission.zones.is_empty() {
            &field.zones
        } else {
            &mission.zones
        },
    )?;
    for (k, w) in mission.weights.iter().enumerate() {
        finite(
            || format!("mission weight {}", ["alpha", "beta", "gamma", "delta"][k]),
            *w,
        )?;
    }
    let mut extra = vec![base];
    extra.extend(stops.iter().copied());
    extra.extend(via.iter().flatten().copied());
    extra.extend(frame::zone_points(&zones));
    let scene = Scene::new(field, &extra)?;

    let font = opts.font_pt;
    let cap = CAP_HEIGHT_EM * font;
    let width = opts.width_mm * PT_PER_MM;
    let margin = 0.6 * font;
    let inner = width - 2.0 * margin;

    // Title and subtitle.
    let (title, subtitle) = titles_text(mission, opts);

    // Colour scale.
    let scored: Vec<f64> = scene.cells.iter().filter_map(|c| c.s).collect();
    let mut scale = ColourScale::new(&scored);
    let fills: Vec<Rgb> = scene
        .cells
        .iter()
        .map(|c| match (c.s, &scale) {
            (Some(s), Some(sc)) => colour::sequential(sc.t(s)),
            _ => NO_SCORE,
        })
        .collect();

    // Right column: colour bar, north arrow, scale bar.
    let bar_w = 0.9 * font;
    let cbar_label_w = scale.as_ref().map_or(0.0, |s| s.label_width(font));
    let rc_w = (bar_w + TICK + 1.2 + cbar_label_w)
        .max(text_width("500 m", font, false) + 2.0)
        .max(2.0 * font);
    let rc_x = width - margin - rc_w;
    let na_h = frame::north_arrow_height(font);
    let sb_h = frame::scale_bar_height(font);
    let s_label_h = 1.4 * font;
    let rc_min_h = s_label_h
        + if scale.is_some() { 4.0 * font } else { 0.0 }
        + 0.8 * font
        + na_h
        + 0.8 * font
        + sb_h;

    // Vertical layout above the map.
    let titles = frame::Titles::new(&title, &subtitle, font, inner, margin);
    let map_top = titles.map_top;

    // The map: fit, then refit with the measured y labels.
    let last = mission.stops.iter().map(|s| s.order).max().unwrap_or(1);
    let stop_r = frame::stop_radius(font, last);
    let pad = stop_r + 1.5;
    let (view, axes, x_title_baseline) = frame::fit_map(&scene, opts, margin, rc_x, map_top, pad);
    let row_h = view.h.max(rc_min_h);
    let below_map = (x_title_baseline + 0.45 * font).max(map_top + row_h);

    // Below: formula, legend, energy table.
    let formula_text = formula(mission.weights);
    let formula_baseline = below_map + 0.5 * font + cap;
    let legend_top = formula_baseline + 0.9 * font;
    let entries = legend_entries(&scene, &zones, font);
    let legend_h = frame::legend_height(&entries, inner, font);
    let table_top = legend_top + legend_h + 0.5 * font;
    let height = table_top + EnergyTable::height(font) + margin;

    // Draw.
    let mut svg = Svg::new(width, height, font, &title);
    titles.draw(&mut svg, margin);
    scene.draw_ground(&mut svg, &view, &fills, &zones);

    // Route.
    let br = base_r(font);
    let (pts, radii) = frame::route_points_via(&view, base, &stops, &via, br, stop_r);
    let base_pt = pts[0];
    svg.line(format_args!(r#"<g id="route">"#));
    if !stops.is_empty() {
        frame::draw_route(&mut svg, &pts, &radii, &ROUTE.hex(), "", 0.85 * font, 0.0);
    }
    svg.line(format_args!("</g>"));
    draw_stops(&mut svg, &view, mission, &stops, (stop_r, font));
    svg.line(format_args!(r#"<g id="base">"#));
    frame::base_marker(&mut svg, base_pt.0, base_pt.1, br);
    svg.line(format_args!("</g>"));
    frame::draw_axes(&mut svg, &view, &axes, font, margin, x_title_baseline);

    // Right column.
    let rc_bottom = map_top + row_h;
    let sb_top = rc_bottom - sb_h;
    let na_top = sb_top - 0.8 * font - na_h;
    let cx = rc_x + 0.5 * rc_w;
    if let Some(sc) = scale.as_mut() {
        s_colour_bar(&mut svg, sc, (rc_x, map_top, na_top), bar_w, font);
    }
    frame::north_arrow(&mut svg, cx, na_top, na_h, font);
    let len_m = frame::scale_length_m(view.k, rc_w - 1.0);
    frame::scale_bar(&mut svg, cx, sb_top, len_m, view.k, font);

    // Formula, legend, table.
    svg.text_attrs(
        margin,
        formula_baseline,
        font,
        Anchor::Start,
        false,
        &format!(r#"id="formula" fill="{INK}""#),
        &fit(&format!("Utility {formula_text}"), font, false, inner),
    );
    frame::draw_legend(
        &mut svg, "legend", &entries, margin, legend_top, inner, font,
    );
    EnergyTable::new(mission).draw(&mut svg, margin, table_top, inner, font);
    Ok(svg.finish())
}

/// The stops' numbered markers, in visiting order.
fn draw_stops(
    svg: &mut Svg,
    view: &frame::MapView,
    mission: &MissionDoc,
    stops: &[(f64, f64)],
    (stop_r, font): (f64, f64),
) {
    svg.line(format_args!(r#"<g id="stops">"#));
    for (s, &p) in mission.stops.iter().zip(stops) {
        let (x, y) = view.pt(p);
        frame::stop_marker(svg, x, y, stop_r, &s.order.to_string(), font, &ROUTE.hex());
    }
    svg.line(format_args!("</g>"));
}

/// The figure's title (the options', else the mission, its kind and time) and subtitle.
fn titles_text(mission: &MissionDoc, opts: &FigureOptions) -> (String, String) {
    let title = match &opts.title {
        Some(t) => t.clone(),
        None => {
            let who = match mission.mission_id {
                Some(id) => format!("Mission {id}"),
                None => "Mission (dry run)".to_string(),
            };
            format!(
                "{who} \u{b7} {} \u{b7} {}",
                mission.kind,
                display_time(&mission.planned_at)
            )
        }
    };
    let subtitle = format!(
        "{} cells visited \u{b7} total S = {:.2} \u{b7} planner: {}",
        mission.stops.len(),
        mission.total_score,
        mission.planner
    );

    (title, subtitle)
}

/// The legend's symbols: sensor, stop, legs, base, and unscored cells, no-fly zones and the
/// geofence when the map has them.
fn legend_entries(scene: &Scene, zones: &[frame::ZoneShape], font: f64) -> Vec<Entry> {
    let mut entries = vec![
        Entry {
            symbol: Symbol::Sensor,
            text: "sensor".into(),
        },
        Entry {
            symbol: Symbol::Stop(frame::stop_radius(font, 1)),
            text: "stop, visiting order".into(),
        },
        Entry {
            symbol: Symbol::Route(ROUTE, 0),
            text: "flight leg".into(),
        },
        Entry {
            symbol: Symbol::Return(ROUTE),
            text: "return leg".into(),
        },
        Entry {
            symbol: Symbol::Base(base_r(font)),
            text: "base station".into(),
        },
    ];
    if scene.cells.iter().any(|c| c.s.is_none()) {
        entries.push(Entry {
            symbol: Symbol::Swatch(NO_SCORE),
            text: "cell not scored".into(),
        });
    }
    if zones.iter().any(|z| z.no_fly) {
        entries.push(Entry {
            symbol: Symbol::Swatch(frame::NO_FLY),
            text: "no-fly zone".into(),
        });
    }
    if zones.iter().any(|z| !z.no_fly) {
        entries.push(Entry {
            symbol: Symbol::Outline,
            text: "geofence".into(),
        });
    }
    entries
}

/// The colour bar of S at the right column's `x`, from below its label at `map_top` down to
/// above the north arrow at `na_top` (pt): gradient, frame, ticks, labels.
/// One tick of a vertical colour bar whose right edge is at `x` (mm): a tick mark at height
/// `ty` (mm) and its label right of it; `font` is the label's size and `cap` its cap height
/// (mm).
pub(crate) fn colour_tick(svg: &mut Svg, x: f64, ty: f64, (font, cap): (f64, f64), label: &str) {
    svg.line(format_args!(
        r#"<line class="colour-tick" x1="{}" y1="{}" x2="{}" y2="{}" stroke="{INK}" stroke-width="0.4"/>"#,
        N(x),
        N(ty),
        N(x + TICK),
        N(ty)
    ));
    svg.text_attrs(
        x + TICK + 1.2,
        ty + 0.5 * cap,
        font,
        Anchor::Start,
        false,
        &format!(r#"fill="{INK}""#),
        label,
    );
}

fn s_colour_bar(
    svg: &mut Svg,
    sc: &mut ColourScale,
    (rc_x, map_top, na_top): (f64, f64, f64),
    bar_w: f64,
    font: f64,
) {
    let cap = CAP_HEIGHT_EM * font;
    let s_label_h = 1.4 * font;
    let bar_top = map_top + s_label_h;
    let bar_bottom = na_top - 0.8 * font;
    let len = (bar_bottom - bar_top).max(1.0);
    sc.set_ticks(len, 1.5 * font);
    let bx = rc_x;
    svg.line(format_args!(r#"<g id="colour-bar">"#));
    svg.text_attrs(
        bx + 0.5 * bar_w,
        map_top + cap,
        font,
        Anchor::Middle,
        true,
        &format!(r#"fill="{INK}""#),
        "S",
    );
    // The bar: a vertical gradient through the colour map's anchors, top = high S.
    svg.line(format_args!(
        r#"<defs><linearGradient id="s-ramp" x1="0" y1="1" x2="0" y2="0">{}</linearGradient></defs>"#,
        colour::ramp_stops()
    ));
    svg.line(format_args!(
        r#"<rect x="{}" y="{}" width="{}" height="{}" fill="url(#s-ramp)"/>"#,
        N(bx),
        N(bar_top),
        N(bar_w),
        N(len)
    ));
    svg.line(format_args!(
        r#"<rect x="{}" y="{}" width="{}" height="{}" fill="none" stroke="{INK}" stroke-width="0.4"/>"#,
        N(bx),
        N(bar_top),
        N(bar_w),
        N(len)
    ));
    for (v, label) in &sc.ticks {
        let ty = bar_bottom - sc.t(*v) * len;
        colour_tick(svg, bx + bar_w, ty, (font, cap), label);
    }
    svg.line(format_args!("</g>"));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formula_prints_the_weights() {
        assert_eq!(
            formula([0.4, 0.3, 0.2, 0.1]),
            "S = 0.4\u{b7}F + 0.3\u{b7}A + 0.2\u{b7}U \u{2212} 0.1\u{b7}R"
        );
        assert_eq!(
            formula([1.0, 0.25, 0.0, -0.5]),
            "S = 1\u{b7}F + 0.25\u{b7}A + 0\u{b7}U + 0.5\u{b7}R"
        );
        assert!(formula([-1.0, 0.0, 0.0, 0.0]).starts_with("S = \u{2212}1"));
    }

    #[test]
    fn times_are_shown_in_utc() {
        assert_eq!(display_time("2014-06-01T12:00:00Z"), "2014-06-01 12:00 UTC");
        assert_eq!(
            display_time("2014-06-01T12:00:00+00:00"),
            "2014-06-01 12:00 UTC"
        );
        assert_eq!(display_time("yesterday"), "yesterday");
        assert_eq!(display_time("é"), "é");
    }
}
