//! SVG to PNG with resvg and the bundled font only.

use std::sync::{Arc, OnceLock};

use resvg::tiny_skia::{Pixmap, Transform};
use resvg::usvg::{self, fontdb};

use crate::RenderError;
use crate::font::{FONT_FAMILY, faces};

/// Largest PNG side, px (a 300 dpi page is about 3,500 px across).
pub const MAX_PNG_SIDE_PX: u32 = 16_384;

/// The font database with only the bundled faces; every generic family maps to them.
fn font_db() -> Arc<fontdb::Database> {
    static DB: OnceLock<Arc<fontdb::Database>> = OnceLock::new();
    DB.get_or_init(|| {
        let mut db = fontdb::Database::new();
        for face in faces() {
            db.load_font_source(fontdb::Source::Binary(Arc::new(face)));
        }
        db.set_sans_serif_family(FONT_FAMILY);
        db.set_serif_family(FONT_FAMILY);
        db.set_monospace_family(FONT_FAMILY);
        db.set_cursive_family(FONT_FAMILY);
        db.set_fantasy_family(FONT_FAMILY);
        Arc::new(db)
    })
    .clone()
}

/// Parses SVG text with the bundled font (no system fonts, no files, no network).
pub fn parse_svg(svg: &str) -> Result<usvg::Tree, RenderError> {
    let opts = usvg::Options {
        font_family: FONT_FAMILY.to_string(),
        fontdb: font_db(),
        resources_dir: None,
        ..usvg::Options::default()
    };
    usvg::Tree::from_str(svg, &opts).map_err(|e| RenderError::Svg(e.to_string()))
}

/// A figure of this crate with its text turned into outlines (paths) of the bundled font:
/// a self-contained vector file that looks the same in any SVG viewer or converter
/// (Inkscape, rsvg-convert to PDF for LaTeX) whatever fonts it has. The physical size is
/// kept, in mm.
///
/// Errors: SVG that does not parse.
pub fn outline_text(svg: &str) -> Result<String, RenderError> {
    let tree = parse_svg(svg)?;
    let opts = usvg::WriteOptions {
        coordinates_precision: 3,
        transforms_precision: 5,
        ..usvg::WriteOptions::default()
    };
    let out = tree.to_string(&opts);
    // usvg writes the size in CSS px (96 per inch); state it in mm as the figure did.
    let size = tree.size();
    let mm = |px: f32| format!("{:.2}mm", f64::from(px) * 25.4 / 96.0);
    let Some(end) = out.find('>') else {
        return Ok(out);
    };
    let (head, rest) = out.split_at(end);
    let head = replace_attr(head, "width", &mm(size.width()));
    let head = replace_attr(&head, "height", &mm(size.height()));
    Ok(head + rest)
}

/// `tag` with attribute `name`'s value set to `value` (unchanged if it has none).
fn replace_attr(tag: &str, name: &str, value: &str) -> String {
    let key = format!(" {name}=\"");
    if let Some(start) = tag.find(&key) {
        let from = start + key.len();
        if let Some(len) = tag[from..].find('"') {
            return format!("{}{value}{}", &tag[..from], &tag[from + len..]);
        }
    }
    tag.to_string()
}

/// Renders SVG text to a PNG `width_px` pixels wide (height from the SVG's aspect ratio),
/// with the bundled DejaVu Sans for all text. An 85 mm figure at 300 dpi is 1004 px wide.
///
/// Errors: SVG that does not parse, a width of 0, or a side over [`MAX_PNG_SIDE_PX`].
pub fn svg_to_png(svg: &str, width_px: u32) -> Result<Vec<u8>, RenderError> {
    if width_px == 0 || width_px > MAX_PNG_SIDE_PX {
        return Err(RenderError::InvalidOption {
            name: "width_px",
            value: f64::from(width_px),
            expected: "between 1 and 16384 px",
        });
    }
    let tree = parse_svg(svg)?;
    let size = tree.size();
    let scale = f64::from(width_px) / f64::from(size.width());
    let height = (f64::from(size.height()) * scale).round();
    if !(height.is_finite() && height >= 1.0 && height <= f64::from(MAX_PNG_SIDE_PX)) {
        return Err(RenderError::InvalidOption {
            name: "width_px",
            value: f64::from(width_px),
            expected: "a width giving a height between 1 and 16384 px",
        });
    }
    let mut pixmap = Pixmap::new(width_px, height as u32)
        .ok_or_else(|| RenderError::Png(format!("no {width_px} x {height} px image")))?;
    let scale = scale as f32;
    resvg::render(
        &tree,
        Transform::from_scale(scale, scale),
        &mut pixmap.as_mut(),
    );
    pixmap
        .encode_png()
        .map_err(|e| RenderError::Png(e.to_string()))
}
