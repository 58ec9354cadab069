//! A small SVG text writer: escaping, fixed-precision numbers, text with measured widths.

use std::fmt::{self, Write as _};

use crate::font::{self, FONT_FAMILY};

/// Escapes text for XML content and attribute values.
pub(crate) fn esc(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            // Characters XML 1.0 forbids are dropped.
            c if (c as u32) < 0x20 && !matches!(c, '\t' | '\n' | '\r') => {}
            c => out.push(c),
        }
    }
    out
}

/// A coordinate or length in pt, two decimals (0.01 pt ≈ 3.5 µm on paper).
#[derive(Clone, Copy)]
pub(crate) struct N(pub f64);

impl fmt::Display for N {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = (self.0 * 100.0).round() / 100.0;
        // No "-0" and nothing non-finite in the output.
        let v = if v == 0.0 || !v.is_finite() { 0.0 } else { v };
        let s = format!("{v:.2}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        f.write_str(s)
    }
}

/// Horizontal anchoring of a text.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Anchor {
    Start,
    Middle,
    End,
}

impl Anchor {
    fn attr(self) -> &'static str {
        match self {
            Anchor::Start => "start",
            Anchor::Middle => "middle",
            Anchor::End => "end",
        }
    }
}

/// The document being written, in pt.
pub(crate) struct Svg {
    buf: String,
}

impl Svg {
    /// Opens a document `width_pt` x `height_pt`, printed at `width_mm`, with a white
    /// background.
    pub(crate) fn new(width_pt: f64, height_pt: f64, font_pt: f64, title: &str) -> Self {
        let mm = 25.4 / 72.0;
        let mut s = Self { buf: String::new() };
        s.raw(format_args!(
            r#"<svg xmlns="http://www.w3.org/2000/svg" version="1.1" width="{}mm" height="{}mm" viewBox="0 0 {} {}" font-family="{FONT_FAMILY}" font-size="{}">"#,
            N(width_pt * mm),
            N(height_pt * mm),
            N(width_pt),
            N(height_pt),
            N(font_pt)
        ));
        s.raw(format_args!("\n<title>{}</title>\n", esc(title)));
        s.raw(format_args!(
            r##"<rect id="background" width="{}" height="{}" fill="#ffffff"/>"##,
            N(width_pt),
            N(height_pt)
        ));
        s.raw(format_args!("\n"));
        s
    }

    /// Appends formatted text as is.
    pub(crate) fn raw(&mut self, args: fmt::Arguments<'_>) {
        // Writing to a String cannot fail.
        let _ = self.buf.write_fmt(args);
    }

    /// Appends a line of markup.
    pub(crate) fn line(&mut self, args: fmt::Arguments<'_>) {
        self.raw(args);
        self.buf.push('\n');
    }

    /// A text at (`x`, `y` = baseline) of `size` pt.
    pub(crate) fn text(&mut self, x: f64, y: f64, size: f64, anchor: Anchor, bold: bool, t: &str) {
        self.text_attrs(x, y, size, anchor, bold, "", t);
    }

    /// A title centred on (`x`, `y`) (pt) and turned a quarter turn anticlockwise (it reads
    /// bottom to top), of `size` (pt), with the extra attributes `extra` before its transform
    /// (e.g. `fill="#fff" `, or empty).
    pub(crate) fn vertical_title(&mut self, (x, y): (f64, f64), size: f64, extra: &str, t: &str) {
        self.text_attrs(
            x,
            y,
            size,
            Anchor::Middle,
            false,
            &format!(r#"{extra}transform="rotate(-90 {} {})""#, N(x), N(y)),
            t,
        );
    }

    /// A text with extra attributes (`extra` is inserted as is, e.g. `fill="#fff"`).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn text_attrs(
        &mut self,
        x: f64,
        y: f64,
        size: f64,
        anchor: Anchor,
        bold: bool,
        extra: &str,
        t: &str,
    ) {
        let weight = if bold { r#" font-weight="bold""# } else { "" };
        let anchor_attr = if anchor == Anchor::Start {
            String::new()
        } else {
            format!(r#" text-anchor="{}""#, anchor.attr())
        };
        self.line(format_args!(
            r#"<text x="{}" y="{}" font-size="{}"{anchor_attr}{weight}{}{extra}>{}</text>"#,
            N(x),
            N(y),
            N(size),
            if extra.is_empty() { "" } else { " " },
            esc(t)
        ));
    }

    /// Closes the document.
    pub(crate) fn finish(mut self) -> String {
        self.buf.push_str("</svg>\n");
        self.buf
    }
}

/// A symbol or subscripted label, `E_t` style: text before `_` normal, one character after
/// it a subscript. Returns the markup (already escaped) and its width at `size`.
pub(crate) fn subscripted(label: &str, size: f64, bold: bool) -> (String, f64) {
    match label.split_once('_') {
        Some((main, sub)) if !sub.is_empty() => {
            let sub_size = size * 0.72;
            let markup = format!(
                r#"{}<tspan font-size="{}" baseline-shift="sub">{}</tspan>"#,
                esc(main),
                N(sub_size),
                esc(sub)
            );
            let w = font::text_width(main, size, bold) + font::text_width(sub, sub_size, bold);
            (markup, w)
        }
        _ => (esc(label), font::text_width(label, size, bold)),
    }
}

/// Shortens `text` with an ellipsis until it is at most `max_w` wide at `size`.
pub(crate) fn fit(text: &str, size: f64, bold: bool, max_w: f64) -> String {
    if font::text_width(text, size, bold) <= max_w {
        return text.to_string();
    }
    let mut chars: Vec<char> = text.chars().collect();
    while !chars.is_empty() {
        chars.pop();
        let candidate: String = chars.iter().collect::<String>().trim_end().to_string() + "…";
        if font::text_width(&candidate, size, bold) <= max_w {
            return candidate;
        }
    }
    String::new()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_short_and_never_negative_zero() {
        assert_eq!(N(1.0).to_string(), "1");
        assert_eq!(N(1.256).to_string(), "1.26");
        assert_eq!(N(-0.001).to_string(), "0");
        assert_eq!(N(f64::NAN).to_string(), "0");
        assert_eq!(N(-12.5).to_string(), "-12.5");
    }

    #[test]
    fn text_is_escaped() {
        assert_eq!(esc("a<b & \"c\"\u{1}"), "a&lt;b &amp; &quot;c&quot;");
    }

    #[test]
    fn fit_shortens_with_an_ellipsis() {
        let long = "a very long title that will not fit in a narrow space";
        let short = fit(long, 7.0, false, 60.0);
        assert!(short.ends_with('…'));
        assert!(font::text_width(&short, 7.0, false) <= 60.0);
        assert_eq!(fit("ok", 7.0, false, 60.0), "ok");
    }
}
