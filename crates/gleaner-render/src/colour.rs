//! Colours: the sequential maps for values (viridis) and uncertainty (reversed magma), both
//! perceptually uniform and readable in grey and by colour-blind readers, and the qualitative
//! palette for sorties (Okabe & Ito).

/// An sRGB colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Rgb(pub u8, pub u8, pub u8);

impl Rgb {
    /// The colour `0xrrggbb`.
    const fn from_hex(rgb: u32) -> Rgb {
        Rgb((rgb >> 16) as u8, (rgb >> 8) as u8, rgb as u8)
    }

    /// `#rrggbb`.
    pub(crate) fn hex(self) -> String {
        format!("#{:02x}{:02x}{:02x}", self.0, self.1, self.2)
    }

    /// This colour laid over white at opacity `alpha` (0..=1), as an opaque colour.
    pub(crate) fn tint(self, alpha: f64) -> Rgb {
        let a = alpha.clamp(0.0, 1.0);
        let mix = |c: u8| {
            (f64::from(c) * a + 255.0 * (1.0 - a))
                .round()
                .clamp(0.0, 255.0) as u8
        };
        Rgb(mix(self.0), mix(self.1), mix(self.2))
    }
}

/// A colour table written as `0xrrggbb` values, as colour maps are published.
const fn rgb_table<const N: usize>(hex: [u32; N]) -> [Rgb; N] {
    let mut out = [Rgb(0, 0, 0); N];
    let mut i = 0;
    while i < N {
        out[i] = Rgb::from_hex(hex[i]);
        i += 1;
    }
    out
}

/// Viridis sampled at 0, 0.1, ..., 1.
const VIRIDIS: [Rgb; 11] = rgb_table([
    0x440154, 0x482475, 0x414487, 0x355f8d, 0x2a788e, 0x21918c, 0x22a884, 0x44bf70, 0x7ad151,
    0xbddf26, 0xfde725,
]);

/// Magma (perceptually uniform, readable in grey and by colour-blind readers) at 1, 0.9,
/// ..., 0.2: light for small values, dark purple for large ones; its near-black end is left
/// out so dark markers stay visible on every cell.
const MAGMA_REVERSED: [Rgb; 9] = rgb_table([
    0xfcfdbf, 0xfecf92, 0xfe9f6d, 0xf7705c, 0xde4968, 0xb73779, 0x8c2981, 0x641a80, 0x3b0f70,
]);

/// A colour map through equally spaced anchors.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ColourMap(&'static [Rgb]);

/// Viridis: the figures' sequential map for values (S, an estimated field).
pub(crate) const VALUE_MAP: ColourMap = ColourMap(&VIRIDIS);

/// Reversed magma without its darkest part: the sequential map for uncertainty (light =
/// well known, dark = uncertain), distinct from [`VALUE_MAP`] at a glance.
pub(crate) const UNCERTAINTY_MAP: ColourMap = ColourMap(&MAGMA_REVERSED);

impl ColourMap {
    /// The colour of `t` in [0, 1] (clamped; NaN maps to 0).
    pub(crate) fn at(self, t: f64) -> Rgb {
        let anchors = self.0;
        let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
        let x = t * (anchors.len() - 1) as f64;
        let k = (x.floor() as usize).min(anchors.len() - 2);
        let u = x - k as f64;
        let (a, b) = (anchors[k], anchors[k + 1]);
        let mix = |p: u8, q: u8| {
            (f64::from(p) + (f64::from(q) - f64::from(p)) * u)
                .round()
                .clamp(0.0, 255.0) as u8
        };
        Rgb(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
    }

    /// The `<stop>`s of an SVG gradient equal to [`ColourMap::at`] over [0, 1].
    pub(crate) fn stops(self) -> String {
        let n = self.0.len() - 1;
        self.0
            .iter()
            .enumerate()
            .map(|(k, c)| {
                format!(
                    r#"<stop offset="{}" stop-color="{}"/>"#,
                    k as f64 / n as f64,
                    c.hex()
                )
            })
            .collect()
    }
}

/// The sequential colour of `t` in [0, 1] (clamped; NaN maps to 0).
pub(crate) fn sequential(t: f64) -> Rgb {
    VALUE_MAP.at(t)
}

/// The `<stop>`s of an SVG gradient equal to [`sequential`] over [0, 1].
pub(crate) fn ramp_stops() -> String {
    VALUE_MAP.stops()
}

/// Okabe & Ito's colour-blind-safe qualitative palette, without its yellow (too light for
/// lines on white) and black (the base and sensors are black).
const QUALITATIVE: [Rgb; 6] = [
    Rgb(0x00, 0x72, 0xb2), // blue
    Rgb(0xd5, 0x5e, 0x00), // vermillion
    Rgb(0x00, 0x9e, 0x73), // bluish green
    Rgb(0xcc, 0x79, 0xa7), // reddish purple
    Rgb(0xe6, 0x9f, 0x00), // orange
    Rgb(0x56, 0xb4, 0xe9), // sky blue
];

/// The colour of sortie `k` (from 0) and whether its route is drawn dashed-dotted to tell it
/// from the sortie with the same colour `QUALITATIVE.len()` earlier.
pub(crate) fn qualitative(k: usize) -> (Rgb, u32) {
    let n = QUALITATIVE.len();
    (QUALITATIVE[k % n], (k / n) as u32)
}

/// Fill of a cell without a score.
pub(crate) const NO_SCORE: Rgb = Rgb(0xd9, 0xd9, 0xd9);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sequential_hits_the_anchors_and_clamps() {
        assert_eq!(sequential(0.0), VIRIDIS[0]);
        assert_eq!(sequential(1.0), VIRIDIS[10]);
        assert_eq!(sequential(0.5), VIRIDIS[5]);
        assert_eq!(sequential(-3.0), VIRIDIS[0]);
        assert_eq!(sequential(f64::NAN), VIRIDIS[0]);
        assert_eq!(sequential(7.0).hex(), "#fde725");
    }

    #[test]
    fn the_uncertainty_map_runs_from_light_to_dark() {
        assert_eq!(UNCERTAINTY_MAP.at(0.0), MAGMA_REVERSED[0]);
        assert_eq!(UNCERTAINTY_MAP.at(1.0), MAGMA_REVERSED[8]);
        // Lightness falls monotonically along the map (a sequential scale in grey too).
        let luma =
            |c: Rgb| 0.2126 * f64::from(c.0) + 0.7152 * f64::from(c.1) + 0.0722 * f64::from(c.2);
        for k in 1..=100 {
            let (a, b) = (
                UNCERTAINTY_MAP.at(f64::from(k - 1) / 100.0),
                UNCERTAINTY_MAP.at(f64::from(k) / 100.0),
            );
            assert!(luma(b) <= luma(a) + 1e-9, "{k}");
        }
        assert_eq!(UNCERTAINTY_MAP.stops().matches("<stop").count(), 9);
    }

    #[test]
    fn tint_blends_with_white() {
        assert_eq!(Rgb(0, 0, 0).tint(0.0), Rgb(255, 255, 255));
        assert_eq!(Rgb(0, 0, 0).tint(1.0), Rgb(0, 0, 0));
        assert_eq!(Rgb(0, 100, 200).tint(0.5), Rgb(128, 178, 228));
    }

    #[test]
    fn palette_cycles_with_a_new_dash() {
        assert_eq!(qualitative(0), (QUALITATIVE[0], 0));
        assert_eq!(qualitative(6), (QUALITATIVE[0], 1));
    }
}
