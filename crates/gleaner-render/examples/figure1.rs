//! Renders the example mission figure, exploration map and reconstruction map into a
//! directory: SVG (text as text, DejaVu Sans), SVG with the text outlined (needs no font:
//! for PDF/LaTeX) and PNG.
//!
//! ```text
//! cargo run -p gleaner-render --example figure1 -- [OUT_DIR] [WIDTH_PX]
//! ```
//! OUT_DIR defaults to `target/figures`, WIDTH_PX to 1004 (85 mm at 300 dpi).

use std::path::PathBuf;

use gleaner_render::{
    FULL_WIDTH_MM, FigureOptions, example, exploration_map_svg, mission_figure_svg, outline_text,
    png_width_px, reconstruction_map_svg, svg_to_png,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let dir = PathBuf::from(args.next().unwrap_or_else(|| "target/figures".into()));
    let width_px: u32 = match args.next() {
        Some(w) => w.parse()?,
        None => 1004,
    };
    std::fs::create_dir_all(&dir)?;
    let field = example::field();
    let opts = FigureOptions::default();
    let figures = [
        (
            "figure1-example",
            mission_figure_svg(&field, &example::mission(), &opts)?,
        ),
        (
            "exploration-example",
            exploration_map_svg(&field, &example::exploration(), &opts)?,
        ),
        (
            "reconstruction-map-example",
            reconstruction_map_svg(
                &example::reconstruction_map(),
                &FigureOptions {
                    width_mm: FULL_WIDTH_MM,
                    ..FigureOptions::default()
                },
            )?,
        ),
    ];
    for (name, svg) in figures {
        // The full-width figure keeps the column figures' resolution.
        let width_px = if name.starts_with("reconstruction") {
            png_width_px(FULL_WIDTH_MM, f64::from(width_px) / (85.0 / 25.4))
        } else {
            width_px
        };
        let svg_path = dir.join(format!("{name}.svg"));
        let png_path = dir.join(format!("{name}.png"));
        let outlined_path = dir.join(format!("{name}-outlined.svg"));
        std::fs::write(&svg_path, &svg)?;
        std::fs::write(&outlined_path, outline_text(&svg)?)?;
        std::fs::write(&png_path, svg_to_png(&svg, width_px)?)?;
        for p in [svg_path, outlined_path, png_path] {
            println!("{}", p.display());
        }
    }
    Ok(())
}
