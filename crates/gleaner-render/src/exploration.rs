//! The exploration overview: every sortie on one map, one colour each.

use std::collections::HashMap;

use gleaner_wire::{FieldDoc, MissionDoc};

use crate::colour::{self, Rgb};
use crate::figure::display_time;
use crate::font::text_width;
use crate::frame::{self, Entry, PT_PER_MM, Scene, Symbol, base_r};
use crate::svg::Svg;
use crate::{FigureOptions, RenderError};

/// Fill of cells no sortie visits.
const NOT_VISITED: Rgb = Rgb(0xee, 0xee, 0xee);

/// Opacity of a sortie's colour in the cells it visits (over white).
const CELL_TINT: f64 = 0.38;

/// The exploration sorties on one map as an SVG document, `opts.width_mm` wide.
///
/// Each sortie has a colour from a colour-blind-safe qualitative palette (after six, the
/// colours repeat with a dash pattern): the cells it visits are tinted with it and its route
/// is drawn in it, from the base through its stops (small dots, an arrowhead on each leg
/// with room) and back (dashed). The legend gives each sortie's mission id, cells and energy
/// in kJ with its share of the budget; the title the number of sorties and cells and the
/// total energy. Ticks, north arrow and scale bar as in [`crate::mission_figure_svg`].
///
/// A cell visited by two sorties takes the first one's colour. Errors: non-finite or
/// impossible numbers in the inputs, unusable options.
pub fn exploration_map_svg(
    field: &FieldDoc,
    sorties: &[MissionDoc],
    opts: &FigureOptions,
) -> Result<String, RenderError> {
    frame::check_options(opts)?;
    let projection = frame::Projection::new(field.base_lon_lat)?;
    let mut routes = Vec::with_capacity(sorties.len());
    let mut extra = Vec::new();
    for (k, m) in sorties.iter().enumerate() {
        let (base, stops) = frame::mission_points(&projection, m, &format!("sortie {}", k + 1))?;
        let via = frame::mission_via(&projection, m, &format!("sortie {}", k + 1))?;
        extra.push(base);
        extra.extend(stops.iter().copied());
        extra.extend(via.iter().flatten().copied());
        routes.push((base, stops, via));
    }
    let zones = frame::zone_shapes(&projection, &field.zones)?;
    extra.extend(frame::zone_points(&zones));
    let scene = Scene::new(field, &extra)?;

    let font = opts.font_pt;
    let width = opts.width_mm * PT_PER_MM;
    let margin = 0.6 * font;
    let inner = width - 2.0 * margin;

    // Which sortie visits which cell (the first one wins).
    let mut visited_by: HashMap<&str, usize> = HashMap::new();
    for (k, m) in sorties.iter().enumerate() {
        for s in &m.stops {
            visited_by.entry(s.cell.as_str()).or_insert(k);
        }
    }
    let fills: Vec<Rgb> = scene
        .cells
        .iter()
        .map(|c| match visited_by.get(c.id.as_str()) {
            Some(&k) => colour::qualitative(k).0.tint(CELL_TINT),
            None => NOT_VISITED,
        })
        .collect();

    let (title, subtitle) = titles_text(field, sorties, opts);

    // Right column: north arrow and scale bar.
    let rc_w = (text_width("500 m", font, false) + 2.0).max(2.0 * font);
    let rc_x = width - margin - rc_w;
    let na_h = frame::north_arrow_height(font);
    let sb_h = frame::scale_bar_height(font);

    let titles = frame::Titles::new(&title, &subtitle, font, inner, margin);
    let map_top = titles.map_top;
    let pad = 0.6 * font + 1.5;
    let (view, axes, x_title_baseline) = frame::fit_map(&scene, opts, margin, rc_x, map_top, pad);
    let row_h = view.h.max(na_h + 0.8 * font + sb_h);
    let below_map = (x_title_baseline + 0.45 * font).max(map_top + row_h);

    // Legend: one entry per sortie, then the shared symbols.
    let entries = sortie_entries(sorties);
    let shared = shared_entries(&fills, font);
    let legend_top = below_map + 0.5 * font;
    let sorties_h = frame::legend_height(&entries, inner, font);
    let shared_top = legend_top + sorties_h + if entries.is_empty() { 0.0 } else { 0.3 * font };
    let shared_h = frame::legend_height(&shared, inner, font);
    let height = shared_top + shared_h + margin;

    let mut svg = Svg::new(width, height, font, &title);
    titles.draw(&mut svg, margin);
    scene.draw_ground(&mut svg, &view, &fills, &zones);
    let br = base_r(font);
    let dot_r = 0.28 * font;
    for (k, (base, stops, via)) in routes.iter().enumerate() {
        let (c, dash) = colour::qualitative(k);
        let (pts, radii) = frame::route_points_via(&view, *base, stops, via, br, dot_r);
        svg.line(format_args!(r#"<g id="sortie-{}" class="sortie">"#, k + 1));
        if !stops.is_empty() {
            frame::draw_route(
                &mut svg,
                &pts,
                &radii,
                &c.hex(),
                frame::dash_attr(dash),
                0.7 * font,
                3.0 * font,
            );
        }
        for &(x, y) in &pts[1..pts.len() - 1] {
            svg.line(format_args!(
                r##"<circle class="stop" cx="{}" cy="{}" r="{}" fill="{}" stroke="#ffffff" stroke-width="0.4"/>"##,
                crate::svg::N(x),
                crate::svg::N(y),
                crate::svg::N(dot_r),
                c.hex()
            ));
        }
        svg.line(format_args!("</g>"));
    }
    svg.line(format_args!(r#"<g id="base">"#));
    for (k, (base, _, _)) in routes.iter().enumerate() {
        // One marker per distinct base.
        if routes[..k].iter().any(|(b, _, _)| b == base) {
            continue;
        }
        let (x, y) = view.pt(*base);
        frame::base_marker(&mut svg, x, y, br);
    }
    if routes.is_empty() {
        let (x, y) = view.pt((0.0, 0.0));
        frame::base_marker(&mut svg, x, y, br);
    }
    svg.line(format_args!("</g>"));
    frame::draw_axes(&mut svg, &view, &axes, font, margin, x_title_baseline);

    let cx = rc_x + 0.5 * rc_w;
    frame::north_arrow(&mut svg, cx, map_top, na_h, font);
    let len_m = frame::scale_length_m(view.k, rc_w - 1.0);
    frame::scale_bar(&mut svg, cx, map_top + row_h - sb_h, len_m, view.k, font);

    frame::draw_legend(
        &mut svg,
        "legend-sorties",
        &entries,
        margin,
        legend_top,
        inner,
        font,
    );
    frame::draw_legend(&mut svg, "legend", &shared, margin, shared_top, inner, font);
    Ok(svg.finish())
}

/// The symbols every sortie shares: sensor, return leg, base, and unvisited cells when the
/// map has them.
fn shared_entries(fills: &[Rgb], font: f64) -> Vec<Entry> {
    let mut shared = vec![
        Entry {
            symbol: Symbol::Sensor,
            text: "sensor".into(),
        },
        Entry {
            symbol: Symbol::Return(Rgb(0x55, 0x55, 0x55)),
            text: "return leg".into(),
        },
        Entry {
            symbol: Symbol::Base(base_r(font)),
            text: "base station".into(),
        },
    ];
    if fills.contains(&NOT_VISITED) {
        shared.push(Entry {
            symbol: Symbol::Swatch(NOT_VISITED),
            text: "cell not visited".into(),
        });
    }
    shared
}

/// The map's title (the options', else the project and the sortie count) and subtitle.
fn titles_text(field: &FieldDoc, sorties: &[MissionDoc], opts: &FigureOptions) -> (String, String) {
    let total_cells: usize = sorties.iter().map(|m| m.stops.len()).sum();
    let total_kj: f64 = sorties.iter().map(|m| m.energy.total_j).sum::<f64>() / 1000.0;
    let title = match &opts.title {
        Some(t) => t.clone(),
        None => format!(
            "Exploration of {} \u{b7} {} sorties",
            if field.project.is_empty() {
                "the field"
            } else {
                &field.project
            },
            sorties.len()
        ),
    };
    let first_time = sorties
        .iter()
        .min_by_key(|m| m.planned_at_s)
        .map(|m| display_time(&m.planned_at));
    let subtitle = format!(
        "{} of {} cells visited \u{b7} {:.1} kJ in all{}",
        total_cells,
        field.cells.len(),
        total_kj,
        first_time.map_or(String::new(), |t| format!(" \u{b7} from {t}"))
    );

    (title, subtitle)
}

/// One legend entry per sortie: its colours, id, cells, energy and share of the budget.
fn sortie_entries(sorties: &[MissionDoc]) -> Vec<Entry> {
    sorties
        .iter()
        .enumerate()
        .map(|(k, m)| {
            let (c, dash) = colour::qualitative(k);
            let id = m.mission_id.map_or(String::new(), |id| format!(" (#{id})"));
            let pct = if m.energy.budget_j > 0.0 {
                format!(", {:.0} %", 100.0 * m.energy.total_j / m.energy.budget_j)
            } else {
                String::new()
            };
            Entry {
                symbol: Symbol::Sortie(c.tint(CELL_TINT), c, dash),
                text: format!(
                    "sortie {}{id}: {} cells, {:.1} kJ{pct}",
                    k + 1,
                    m.stops.len(),
                    m.energy.total_j / 1000.0
                ),
            }
        })
        .collect()
}
