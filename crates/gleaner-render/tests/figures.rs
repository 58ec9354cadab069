//! Structural tests of the figures: they parse, hold one shape per cell, the arrows, the
//! legend, the title; text is big enough, inside the page and never overlaps other text;
//! PNGs decode at the asked size; bad numbers are errors, never panics.

use gleaner_render::usvg::{self, Node};
use gleaner_render::{
    Coordinates, FieldDoc, FigureOptions, MissionDoc, ReconstructionMapDoc, RenderError, example,
    exploration_map_svg, mission_figure_svg, parse_svg, reconstruction_map_svg, svg_to_png,
};
use resvg::tiny_skia::Pixmap;

/// Every text node with its text and bounding box (pt).
fn texts(tree: &usvg::Tree) -> Vec<(String, usvg::Rect)> {
    fn walk(g: &usvg::Group, out: &mut Vec<(String, usvg::Rect)>) {
        for n in g.children() {
            match n {
                Node::Group(g) => walk(g, out),
                Node::Text(t) => {
                    let s: String = t.chunks().iter().map(|c| c.text()).collect();
                    out.push((s, t.abs_bounding_box()));
                }
                _ => {}
            }
        }
    }
    let mut out = Vec::new();
    walk(tree.root(), &mut out);
    out
}

/// Ids of all nodes.
fn ids(tree: &usvg::Tree) -> Vec<String> {
    fn walk(g: &usvg::Group, out: &mut Vec<String>) {
        for n in g.children() {
            if !n.id().is_empty() {
                out.push(n.id().to_string());
            }
            if let Node::Group(g) = n {
                walk(g, out);
            }
        }
    }
    let mut out = Vec::new();
    walk(tree.root(), &mut out);
    out
}

fn overlap(a: &usvg::Rect, b: &usvg::Rect) -> bool {
    let tol = 0.05;
    a.left() + tol < b.right()
        && b.left() + tol < a.right()
        && a.top() + tol < b.bottom()
        && b.top() + tol < a.bottom()
}

/// The layout checks every figure must pass.
fn check_layout(name: &str, svg: &str, min_font_pt: f64) {
    let tree = parse_svg(svg).expect("parses");
    let size = tree.size();
    let all = texts(&tree);
    assert!(!all.is_empty());
    for (t, r) in &all {
        assert!(
            r.left() >= -0.01
                && r.top() >= -0.01
                && r.right() <= size.width() + 0.01
                && r.bottom() <= size.height() + 0.01,
            "{name}: text {t:?} at {r:?} leaves the {size:?} page"
        );
    }
    for (i, (ta, ra)) in all.iter().enumerate() {
        for (tb, rb) in &all[i + 1..] {
            assert!(
                !overlap(ra, rb),
                "{name}: texts {ta:?} {ra:?} and {tb:?} {rb:?} overlap"
            );
        }
    }
    // Every <text> is at least min_font_pt (subscripts in <tspan> excepted).
    for part in svg.split("<text ").skip(1) {
        let fs = part
            .split("font-size=\"")
            .nth(1)
            .and_then(|s| s.split('"').next())
            .and_then(|s| s.parse::<f64>().ok())
            .expect("every text states its size");
        assert!(
            fs >= min_font_pt,
            "{name}: text of {fs} pt: {}",
            &part[..part.len().min(120)]
        );
    }
}

fn count(svg: &str, needle: &str) -> usize {
    svg.matches(needle).count()
}

#[test]
fn mission_figure_has_every_element() {
    let (field, mission) = (example::field(), example::mission());
    let svg = mission_figure_svg(&field, &mission, &FigureOptions::default()).unwrap();
    let tree = parse_svg(&svg).unwrap();
    let ids = ids(&tree);
    let cells = ids.iter().filter(|id| id.starts_with("cell-")).count();
    assert_eq!(cells, field.cells.len(), "one shape per cell");
    for id in [
        "cells",
        "sensors",
        "route",
        "stops",
        "base",
        "axes",
        "colour-bar",
        "north-arrow",
        "scale-bar",
        "legend",
        "energy-table",
        "formula",
    ] {
        assert!(ids.iter().any(|i| i == id), "no #{id}");
    }
    // An arrowhead on each leg with room (the example's legs all have room).
    assert_eq!(count(&svg, r#"class="arrow""#), mission.stops.len() + 1 + 1);
    assert_eq!(count(&svg, r#"class="legend-entry""#), 5);
    // The return leg (casing and line) and its legend symbol (the same).
    assert_eq!(count(&svg, "stroke-dasharray"), 4);
    let all = texts(&tree);
    let has = |s: &str| all.iter().any(|(t, _)| t.contains(s));
    assert!(has("Mission 7"));
    assert!(has("2014-06-01 12:00 UTC"));
    assert!(has(
        "S = 0.4\u{b7}F + 0.3\u{b7}A + 0.2\u{b7}U \u{2212} 0.1\u{b7}R"
    ));
    for label in [
        "sensor",
        "stop, visiting order",
        "flight leg",
        "return leg",
        "base station",
    ] {
        assert!(has(label), "legend {label}");
    }
    for k in 1..=mission.stops.len() {
        assert!(all.iter().any(|(t, _)| *t == k.to_string()), "stop {k}");
    }
    for v in ["55.3", "66.5", "83.2", "30.4", "16.8", "1.2", "6.9"] {
        assert!(has(v), "energy {v}");
    }
    assert!(has("N") && has("100 m") && has("metres east of base"));
    check_layout("mission", &svg, 7.0);
    // 85 mm wide, as asked.
    assert!(svg.contains(r#"width="85mm""#));
}

#[test]
fn exploration_map_has_every_sortie() {
    let (field, sorties) = (example::field(), example::exploration());
    let svg = exploration_map_svg(&field, &sorties, &FigureOptions::default()).unwrap();
    let tree = parse_svg(&svg).unwrap();
    let ids = ids(&tree);
    assert_eq!(
        ids.iter().filter(|i| i.starts_with("cell-")).count(),
        field.cells.len()
    );
    for k in 1..=sorties.len() {
        assert!(ids.contains(&format!("sortie-{k}")));
    }
    let stops: usize = sorties.iter().map(|m| m.stops.len()).sum();
    assert_eq!(count(&svg, r#"class="stop""#), stops);
    let all = texts(&tree);
    for (k, m) in sorties.iter().enumerate() {
        let want = format!(
            "sortie {} (#{}): {} cells, {:.1} kJ",
            k + 1,
            k + 1,
            m.stops.len(),
            m.energy.total_j / 1000.0
        );
        assert!(all.iter().any(|(t, _)| t.starts_with(&want)), "{want}");
    }
    check_layout("exploration", &svg, 7.0);
}

#[test]
fn pngs_decode_at_the_asked_width() {
    let (field, mission) = (example::field(), example::mission());
    let svg = mission_figure_svg(&field, &mission, &FigureOptions::default()).unwrap();
    let tree = parse_svg(&svg).unwrap();
    for width in [200, 1004] {
        let png = svg_to_png(&svg, width).unwrap();
        let pix = Pixmap::decode_png(&png).unwrap();
        assert_eq!(pix.width(), width);
        let want = (f64::from(tree.size().height()) * f64::from(width)
            / f64::from(tree.size().width()))
        .round() as u32;
        assert_eq!(pix.height(), want);
        // Opaque white background, ink somewhere.
        assert_eq!(pix.pixel(0, 0).map(|p| p.alpha()), Some(255));
        assert!(pix.pixels().iter().any(|p| p.red() < 60 && p.green() < 60));
    }
    assert!(matches!(
        svg_to_png(&svg, 0),
        Err(RenderError::InvalidOption { .. })
    ));
    assert!(matches!(svg_to_png("<svg", 100), Err(RenderError::Svg(_))));
    assert!(matches!(
        svg_to_png("not svg", 100),
        Err(RenderError::Svg(_))
    ));
}

#[test]
fn outlined_text_needs_no_font() {
    let (field, mission) = (example::field(), example::mission());
    let svg = mission_figure_svg(&field, &mission, &FigureOptions::default()).unwrap();
    let out = gleaner_render::outline_text(&svg).unwrap();
    assert!(!out.contains("<text"));
    assert!(out.contains(r#"width="85.00mm""#), "{}", &out[..200]);
    let a = parse_svg(&svg).unwrap().size();
    let b = parse_svg(&out).unwrap().size();
    assert!((a.width() - b.width()).abs() < 0.01 && (a.height() - b.height()).abs() < 0.01);
    assert!(matches!(
        gleaner_render::outline_text("<svg"),
        Err(RenderError::Svg(_))
    ));
}

#[test]
fn output_is_deterministic() {
    let (field, mission) = (example::field(), example::mission());
    let opts = FigureOptions::default();
    let a = mission_figure_svg(&field, &mission, &opts).unwrap();
    let b = mission_figure_svg(&field, &mission, &opts).unwrap();
    assert_eq!(a, b);
    assert_eq!(svg_to_png(&a, 300).unwrap(), svg_to_png(&b, 300).unwrap());
    let sorties = example::exploration();
    assert_eq!(
        exploration_map_svg(&field, &sorties, &opts).unwrap(),
        exploration_map_svg(&field, &sorties, &opts).unwrap()
    );
}

fn expect_non_finite(field: &FieldDoc, mission: &MissionDoc, what: &str) {
    let opts = FigureOptions::default();
    match mission_figure_svg(field, mission, &opts) {
        Err(RenderError::NonFinite { what: w, .. }) => assert!(w.contains(what), "{w}"),
        other => panic!("{what}: expected NonFinite, got {other:?}"),
    }
    match exploration_map_svg(field, std::slice::from_ref(mission), &opts) {
        Err(RenderError::NonFinite { what: w, .. }) => assert!(w.contains(what), "{w}"),
        // The exploration map does not read the weights.
        Ok(_) if what.contains("weight") => {}
        other => panic!("{what}: expected NonFinite, got {other:?}"),
    }
}

#[test]
fn non_finite_numbers_are_errors() {
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let (f0, m0) = (example::field(), example::mission());
        let mut f = f0.clone();
        f.cells[3].ring_lon_lat[2][1] = bad;
        expect_non_finite(&f, &m0, "ring point 2 latitude");
        let mut f = f0.clone();
        f.cells[0].scores.as_mut().unwrap().s = bad;
        expect_non_finite(&f, &m0, "S");
        let mut f = f0.clone();
        f.sensors[1].lon_lat[0] = bad;
        expect_non_finite(&f, &m0, "sensor");
        let mut f = f0.clone();
        f.base_lon_lat[0] = bad;
        expect_non_finite(&f, &m0, "field base");
        let mut f = f0.clone();
        f.cell_size_m = bad;
        expect_non_finite(&f, &m0, "cell_size_m");
        let mut m = m0.clone();
        m.stops[2].centre_lon_lat[0] = bad;
        expect_non_finite(&f0, &m, "stop 3");
        let mut m = m0.clone();
        m.energy.return_j = bad;
        expect_non_finite(&f0, &m, "return_j");
        let mut m = m0.clone();
        m.weights[3] = bad;
        expect_non_finite(&f0, &m, "weight delta");
        let mut m = m0.clone();
        m.profile.base_lon_lat[1] = bad;
        expect_non_finite(&f0, &m, "base latitude");
    }
}

#[test]
fn impossible_inputs_and_options_are_errors() {
    let (field, mission) = (example::field(), example::mission());
    let mut f = field.clone();
    f.cells[0].ring_lon_lat[0][1] = 91.0;
    assert!(matches!(
        mission_figure_svg(&f, &mission, &FigureOptions::default()),
        Err(RenderError::OutOfRange { .. })
    ));
    let mut f = field.clone();
    f.cell_size_m = 0.0;
    assert!(matches!(
        mission_figure_svg(&f, &mission, &FigureOptions::default()),
        Err(RenderError::OutOfRange { .. })
    ));
    for opts in [
        FigureOptions {
            width_mm: f64::NAN,
            ..FigureOptions::default()
        },
        FigureOptions {
            width_mm: 0.0,
            ..FigureOptions::default()
        },
        FigureOptions {
            font_pt: 1.0,
            ..FigureOptions::default()
        },
        FigureOptions {
            font_pt: 20.0,
            width_mm: 40.0,
            ..FigureOptions::default()
        },
        FigureOptions {
            max_map_aspect: f64::INFINITY,
            ..FigureOptions::default()
        },
    ] {
        assert!(matches!(
            mission_figure_svg(&field, &mission, &opts),
            Err(RenderError::InvalidOption { .. })
        ));
        assert!(matches!(
            exploration_map_svg(&field, &[], &opts),
            Err(RenderError::InvalidOption { .. })
        ));
    }
}

/// Odd but valid inputs: every figure is made, parses and keeps its text apart.
#[test]
fn odd_inputs_still_make_clean_figures() {
    let (field, mission) = (example::field(), example::mission());
    let mut cases: Vec<(String, FieldDoc, MissionDoc, FigureOptions)> = Vec::new();
    let opts = FigureOptions::default();

    let mut empty = field.clone();
    empty.cells.clear();
    empty.sensors.clear();
    let mut no_stops = mission.clone();
    no_stops.stops.clear();
    cases.push((
        "empty".into(),
        empty.clone(),
        no_stops.clone(),
        opts.clone(),
    ));
    cases.push(("no stops".into(), field.clone(), no_stops, opts.clone()));
    cases.push((
        "stops, no cells".into(),
        empty,
        mission.clone(),
        opts.clone(),
    ));

    let mut unscored = field.clone();
    for c in unscored.cells.iter_mut().step_by(3) {
        c.scores = None;
    }
    cases.push((
        "some unscored".into(),
        unscored,
        mission.clone(),
        opts.clone(),
    ));

    let mut flat = field.clone();
    for c in &mut flat.cells {
        if let Some(s) = c.scores.as_mut() {
            s.s = 0.25;
        }
    }
    cases.push(("one S".into(), flat, mission.clone(), opts.clone()));

    let mut one = field.clone();
    one.cells.truncate(1);
    one.sensors.truncate(1);
    let mut one_stop = mission.clone();
    one_stop.stops.truncate(1);
    one_stop.stops[0].centre_lon_lat = one.cells[0].centre_lon_lat;
    cases.push(("one cell".into(), one, one_stop, opts.clone()));

    let mut tall = field.clone();
    for c in &mut tall.cells {
        for p in &mut c.ring_lon_lat {
            p.swap(0, 1);
            p[0] = -117.0875 + (p[0] - 46.7782) * 1.46;
            p[1] = 46.7782 + (p[1] + 117.0875) / 1.46;
        }
    }
    cases.push(("tall".into(), tall, mission.clone(), opts.clone()));

    let mut long = mission.clone();
    long.planner = "a planner with a very long name indeed, far too long for one line".into();
    long.kind = "<adaptive & \"odd\">".into();
    long.planned_at = "not a time".into();
    long.mission_id = None;
    cases.push(("long text".into(), field.clone(), long, opts.clone()));

    let mut many = mission.clone();
    let first = many.stops[0].clone();
    many.stops = (1..=80)
        .map(|k| {
            let mut s = first.clone();
            s.order = k;
            let c = &field.cells[k as usize % field.cells.len()];
            s.centre_lon_lat = c.centre_lon_lat;
            s
        })
        .collect();
    cases.push(("80 stops".into(), field.clone(), many, opts.clone()));

    let mut zero_budget = mission.clone();
    zero_budget.energy.budget_j = 0.0;
    cases.push((
        "zero budget".into(),
        field.clone(),
        zero_budget,
        opts.clone(),
    ));

    let mut odd_weights = mission.clone();
    odd_weights.weights = [1.0, -0.5, 0.0, -2.0];
    cases.push((
        "odd weights".into(),
        field.clone(),
        odd_weights,
        opts.clone(),
    ));

    let degrees = FigureOptions {
        coordinates: Coordinates::Degrees,
        ..FigureOptions::default()
    };
    cases.push(("degrees".into(), field.clone(), mission.clone(), degrees));
    let wide = FigureOptions {
        width_mm: 178.0,
        font_pt: 8.0,
        title: Some(String::new()),
        ..FigureOptions::default()
    };
    cases.push((
        "wide, no title".into(),
        field.clone(),
        mission.clone(),
        wide,
    ));

    // The same farm moved onto the antimeridian: the map must not tear.
    let shift = |p: &mut [f64; 2]| {
        p[0] += 179.9995 + 117.0875;
        if p[0] > 180.0 {
            p[0] -= 360.0;
        }
    };
    let (mut far, mut far_m) = (field.clone(), mission.clone());
    shift(&mut far.base_lon_lat);
    for c in &mut far.cells {
        c.ring_lon_lat.iter_mut().for_each(shift);
        shift(&mut c.centre_lon_lat);
    }
    far.sensors.iter_mut().for_each(|s| shift(&mut s.lon_lat));
    shift(&mut far_m.profile.base_lon_lat);
    far_m
        .stops
        .iter_mut()
        .for_each(|s| shift(&mut s.centre_lon_lat));
    assert!(far.cells.iter().any(|c| c.centre_lon_lat[0] < 0.0));
    cases.push(("antimeridian".into(), far, far_m, opts.clone()));

    for (name, f, m, o) in &cases {
        let svg = mission_figure_svg(f, m, o).unwrap_or_else(|e| panic!("{name}: {e}"));
        check_layout(name, &svg, 7.0);
        svg_to_png(&svg, 120).unwrap_or_else(|e| panic!("{name}: {e}"));
        let sorties = [m.clone(), m.clone()];
        let svg = exploration_map_svg(f, &sorties, o).unwrap_or_else(|e| panic!("{name}: {e}"));
        check_layout(&format!("{name}, exploration"), &svg, 7.0);
    }
}

#[test]
fn many_sorties_cycle_the_palette_with_dashes() {
    let field = example::field();
    let base = example::exploration();
    let sorties: Vec<MissionDoc> = (0..9).map(|k| base[k % base.len()].clone()).collect();
    let svg = exploration_map_svg(&field, &sorties, &FigureOptions::default()).unwrap();
    assert!(svg.contains(r#"id="sortie-9""#));
    assert!(svg.contains(r#"stroke-dasharray="4 1 1 1""#));
    check_layout("9 sorties", &svg, 7.0);
    let none = exploration_map_svg(&field, &[], &FigureOptions::default()).unwrap();
    check_layout("no sorties", &none, 7.0);
}

/// Numbers from a fixed generator, including NaN, infinities and huge values, in every
/// position: the result is a figure or an error, never a panic.
#[test]
fn arbitrary_numbers_never_panic() {
    let specials = [
        f64::NAN,
        f64::INFINITY,
        -1e308,
        1e308,
        0.0,
        -0.0,
        1e-300,
        179.9999,
        -90.0,
        500.0,
    ];
    let mut x: u64 = 0x2545_f491_4f6c_dd1d;
    let mut next = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    let opts = FigureOptions::default();
    for _ in 0..60 {
        let (mut f, mut m) = (example::field(), example::mission());
        for _ in 0..3 {
            let v = specials[(next() % specials.len() as u64) as usize];
            match next() % 9 {
                0 => f.base_lon_lat[(next() % 2) as usize] = v,
                1 => f.cells[(next() % 10) as usize].ring_lon_lat[1][0] = v,
                2 => f.cell_size_m = v,
                3 => m.stops[(next() % 8) as usize].centre_lon_lat[1] = v,
                4 => m.energy.budget_j = v,
                5 => m.weights[(next() % 4) as usize] = v,
                6 => m.total_score = v,
                7 => f.sensors[(next() % 10) as usize].lon_lat[0] = v,
                _ => m.profile.base_lon_lat[0] = v,
            }
        }
        if let Ok(svg) = mission_figure_svg(&f, &m, &opts) {
            parse_svg(&svg).unwrap();
        }
        if let Ok(svg) = exploration_map_svg(&f, std::slice::from_ref(&m), &opts) {
            parse_svg(&svg).unwrap();
        }
    }
}

/// The reconstruction map at the full page width: both panels, one shape per cell in each,
/// every sensor marked in each (read and estimated told apart), colour bars titled with the
/// unit, outline, legend, north arrow, scale bar, the title's modality, time and estimator.
#[test]
fn reconstruction_map_has_both_panels() {
    let doc = example::reconstruction_map();
    let opts = FigureOptions {
        width_mm: 178.0,
        ..FigureOptions::default()
    };
    let svg = reconstruction_map_svg(&doc, &opts).unwrap();
    let tree = parse_svg(&svg).unwrap();
    let ids = ids(&tree);
    for key in ["value", "sd"] {
        let cells = ids
            .iter()
            .filter(|id| id.starts_with(&format!("{key}-cell-")))
            .count();
        assert_eq!(cells, doc.cells.len(), "{key}: one shape per cell");
        for id in ["panel-", "-cells", "-outline", "-sensors", "-colour-bar"] {
            let want = if id.ends_with('-') {
                format!("{id}{key}")
            } else {
                format!("{key}{id}")
            };
            assert!(ids.contains(&want), "no #{want}");
        }
    }
    for id in ["north-arrow", "scale-bar", "legend", "axes"] {
        assert!(ids.iter().any(|i| i == id), "no #{id}");
    }
    let read = doc.sensors.iter().filter(|s| s.read).count();
    assert!(read > 0 && read < doc.sensors.len());
    assert_eq!(count(&svg, r#"class="sensor-read""#), 2 * read);
    assert_eq!(
        count(&svg, r#"class="sensor-estimated""#),
        2 * (doc.sensors.len() - read)
    );
    assert_eq!(count(&svg, r#"class="legend-entry""#), 3);
    let all = texts(&tree);
    let has = |s: &str| all.iter().any(|(t, _)| t.contains(s));
    assert!(has("Estimated VW at 30 cm"));
    assert!(has("2014-06-01 12:00 UTC"));
    assert!(has("kriging of changes"));
    assert!(has("VW (m\u{b3}/m\u{b3})"), "value bar title with its unit");
    assert!(has("sd (m\u{b3}/m\u{b3})"), "sd bar title with its unit");
    assert!(has("(a) Estimate") && has("(b) Uncertainty"));
    assert!(has("sensor read within 1 d before the time"));
    assert!(has("sensor estimated only") && has("field outline"));
    assert!(has(" m") && has("N"));
    check_layout("reconstruction map", &svg, 7.0);
    assert!(svg.contains(r#"width="178mm""#));
    // A narrower page still lays out cleanly; so does a field in degrees.
    for opts in [
        FigureOptions {
            width_mm: 130.0,
            ..FigureOptions::default()
        },
        FigureOptions {
            width_mm: 178.0,
            coordinates: Coordinates::Degrees,
            ..FigureOptions::default()
        },
    ] {
        let svg = reconstruction_map_svg(&doc, &opts).unwrap();
        check_layout(&format!("reconstruction map {opts:?}"), &svg, 7.0);
    }
}

/// The figure's bytes are fixed: the snapshot holds the SVG of the example.
#[test]
fn reconstruction_map_snapshot() {
    let opts = FigureOptions {
        width_mm: 178.0,
        ..FigureOptions::default()
    };
    let doc = example::reconstruction_map();
    let svg = reconstruction_map_svg(&doc, &opts).unwrap();
    assert_eq!(svg, reconstruction_map_svg(&doc, &opts).unwrap());
    insta::assert_snapshot!("reconstruction-map.svg", svg);
    // The PNG decodes at the asked width, opaque, with both colour maps' ends in it.
    let png = svg_to_png(&svg, 1200).unwrap();
    let pix = Pixmap::decode_png(&png).unwrap();
    assert_eq!(pix.width(), 1200);
    let size = parse_svg(&svg).unwrap().size();
    let want = (f64::from(size.height()) * 1200.0 / f64::from(size.width())).round() as u32;
    assert_eq!(pix.height(), want);
    // Opaque (but for the last row, which the page may cover only in part), not blank.
    let w = pix.width() as usize;
    let rows = pix.pixels().len() / w;
    assert!(
        pix.pixels()[..(rows - 1) * w]
            .iter()
            .all(|p| p.alpha() == 255)
    );
    let near = |r: u8, g: u8, b: u8| {
        pix.pixels().iter().any(|p| {
            (i32::from(p.red()) - i32::from(r)).abs() < 24
                && (i32::from(p.green()) - i32::from(g)).abs() < 24
                && (i32::from(p.blue()) - i32::from(b)).abs() < 24
        })
    };
    assert!(near(0x44, 0x01, 0x54), "viridis' dark end");
    assert!(near(0xfd, 0xe7, 0x25), "viridis' light end");
    assert!(near(0x3b, 0x0f, 0x70), "the uncertainty map's dark end");
    assert_eq!(png, svg_to_png(&svg, 1200).unwrap());
}

/// Bad numbers are errors naming them; odd inputs (no cells, one cell, every sd 0, a
/// constant field, no unit) still make clean figures; arbitrary numbers never panic.
#[test]
fn reconstruction_map_refuses_bad_numbers_and_survives_odd_inputs() {
    let opts = FigureOptions {
        width_mm: 178.0,
        ..FigureOptions::default()
    };
    let base = example::reconstruction_map();
    type Spoil = Box<dyn Fn(&mut ReconstructionMapDoc)>;
    let cases: Vec<(Spoil, &str)> = vec![
        (Box::new(|d| d.cells[3].mean = f64::NAN), "cell"),
        (Box::new(|d| d.cells[2].sd = -0.1), "sd"),
        (
            Box::new(|d| d.sensors[1].estimate = f64::INFINITY),
            "estimate",
        ),
        (Box::new(|d| d.sensors[0].lon_lat[1] = 95.0), "latitude"),
        (
            Box::new(|d| d.outline_lon_lat[0][2][0] = f64::NAN),
            "outline",
        ),
        (Box::new(|d| d.cell_size_m = 0.0), "cell_size_m"),
        (Box::new(|d| d.read_within_s = -1), "read_within_s"),
        (Box::new(|d| d.base_lon_lat[0] = 200.0), "base"),
    ];
    for (spoil, what) in cases {
        let mut d = base.clone();
        spoil(&mut d);
        let e = reconstruction_map_svg(&d, &opts).unwrap_err();
        assert!(e.to_string().contains(what), "{what}: {e}");
    }
    let mut one = base.clone();
    one.cells.truncate(1);
    one.sensors.truncate(1);
    let mut none = base.clone();
    none.cells.clear();
    none.sensors.clear();
    none.outline_lon_lat.clear();
    let mut flat = base.clone();
    flat.unit = None;
    flat.project.clear();
    for c in &mut flat.cells {
        c.mean = 0.25;
        c.sd = 0.0;
    }
    for (name, d) in [("one cell", one), ("no cells", none), ("flat", flat)] {
        let svg = reconstruction_map_svg(&d, &opts).unwrap();
        check_layout(name, &svg, 7.0);
    }
    let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut next = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    let specials = [
        f64::NAN,
        -1e308,
        1e308,
        0.0,
        -0.0,
        1e-300,
        179.9,
        -90.0,
        1e6,
    ];
    for _ in 0..40 {
        let mut d = base.clone();
        for _ in 0..3 {
            let v = specials[(next() % specials.len() as u64) as usize];
            let c = (next() % d.cells.len() as u64) as usize;
            let n = d.sensors.len();
            match next() % 5 {
                0 => d.cells[c].mean = v,
                1 => d.cells[c].sd = v,
                2 => d.cells[c].ring_lon_lat[1][0] = v,
                3 => d.sensors[c % n].estimate = v,
                _ => d.cell_size_m = v,
            }
        }
        if let Ok(svg) = reconstruction_map_svg(&d, &opts) {
            parse_svg(&svg).unwrap();
        }
    }
}
