//! The reconstruction map's drawing time: the example field (85 cells, 141 sensors) as SVG
//! at the full page width, and that SVG rasterised at 300 dpi (2,102 px wide).
//!
//! ```text
//! cargo bench -p gleaner-render --bench reconstruction_map
//! ```

use criterion::{Criterion, criterion_group, criterion_main};
use gleaner_render::{
    FULL_WIDTH_MM, FigureOptions, example, png_width_px, reconstruction_map_svg, svg_to_png,
};

fn draw(c: &mut Criterion) {
    let doc = example::reconstruction_map();
    let opts = FigureOptions {
        width_mm: FULL_WIDTH_MM,
        ..FigureOptions::default()
    };
    c.bench_function("reconstruction_map/svg_85_cells_141_sensors", |b| {
        b.iter(|| reconstruction_map_svg(&doc, &opts).expect("a figure"))
    });
    let svg = reconstruction_map_svg(&doc, &opts).expect("a figure");
    let px = png_width_px(FULL_WIDTH_MM, 300.0);
    c.bench_function("reconstruction_map/png_2102_px", |b| {
        b.iter(|| svg_to_png(&svg, px).expect("a PNG"))
    });
}

criterion_group!(benches, draw);
criterion_main!(benches);
