//! The bundled typeface (DejaVu Sans, from the `dejavu` crate) and text measurement.
//!
//! Figures name [`FONT_FAMILY`] and are laid out with the advance widths of the very faces
//! that [`crate::svg_to_png`] loads, so labels are placed where they will be drawn and never
//! depend on the fonts installed on the machine.

use std::sync::OnceLock;

use skrifa::instance::{LocationRef, Size};
use skrifa::{FontRef, MetadataProvider};

/// The font family every figure names (`font-family` of the root `<svg>`).
pub const FONT_FAMILY: &str = "DejaVu Sans";

/// The bundled faces: DejaVu Sans regular and bold (TrueType bytes).
pub(crate) fn faces() -> [&'static [u8]; 2] {
    [dejavu::sans::regular(), dejavu::sans::bold()]
}

/// Advance widths of one face, in em, for the characters figures use.
struct Metrics {
    /// Advance of the characters U+0000..U+2400 (em); NaN where the face has no glyph.
    advances: Vec<f32>,
    /// Advance used for characters outside the table or without a glyph (em).
    fallback: f32,
}

impl Metrics {
    fn load(data: &[u8]) -> Self {
        const TABLE: u32 = 0x2400;
        let fallback = 0.62;
        let Ok(font) = FontRef::new(data) else {
            return Self {
                advances: Vec::new(),
                fallback,
            };
        };
        let upem = f32::from(
            font.metrics(Size::unscaled(), LocationRef::default())
                .units_per_em,
        )
        .max(1.0);
        let charmap = font.charmap();
        let glyphs = font.glyph_metrics(Size::unscaled(), LocationRef::default());
        let advances = (0..TABLE)
            .map(|c| {
                charmap
                    .map(c)
                    .and_then(|g| glyphs.advance_width(g))
                    .map_or(f32::NAN, |a| a / upem)
            })
            .collect();
        Self { advances, fallback }
    }

    fn advance(&self, c: char) -> f64 {
        let a = self
            .advances
            .get(c as usize)
            .copied()
            .filter(|a| a.is_finite())
            .unwrap_or(self.fallback);
        f64::from(a)
    }
}

fn metrics(bold: bool) -> &'static Metrics {
    static REGULAR: OnceLock<Metrics> = OnceLock::new();
    static BOLD: OnceLock<Metrics> = OnceLock::new();
    let [regular, bold_face] = faces();
    if bold {
        BOLD.get_or_init(|| Metrics::load(bold_face))
    } else {
        REGULAR.get_or_init(|| Metrics::load(regular))
    }
}

/// Width of `text` set in the bundled face at `size` (any unit; the result is in the same
/// unit), without kerning. Used to lay labels out; kerning in DejaVu Sans changes widths by
/// a few per cent at most, which the layout's gaps absorb.
pub(crate) fn text_width(text: &str, size: f64, bold: bool) -> f64 {
    let m = metrics(bold);
    text.chars().map(|c| m.advance(c)).sum::<f64>() * size
}

/// Height of digits and capitals above the baseline, em (DejaVu Sans: 0.729).
pub(crate) const CAP_HEIGHT_EM: f64 = 0.729;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn widths_come_from_the_bundled_face() {
        // DejaVu Sans digits are 1303/2048 em wide.
        let w = text_width("0123456789", 10.0, false);
        assert!((w - 10.0 * 10.0 * 1303.0 / 2048.0).abs() < 1e-3, "{w}");
        assert!(text_width("S", 7.0, true) > text_width("S", 7.0, false));
        // Greek and the minus sign are in the face (not the fallback width).
        let m = metrics(false);
        for c in ['α', 'β', 'γ', 'δ', '−', '·', 'Σ', '°'] {
            assert!(m.advances[c as usize].is_finite(), "{c}");
        }
    }
}
