//! Charts for campaign reports: lines of a metric against time or budget, one per strategy,
//! and means with 95% intervals per strategy.

use crate::RenderError;
use crate::colour::qualitative;
use crate::font::text_width;
use crate::svg::{Anchor, Svg};
use crate::ticks::{decimals, label, multiples, nice_step};

/// One line of a [`LineChart`].
#[derive(Debug, Clone, PartialEq)]
pub struct Line {
    /// Legend entry.
    pub name: String,
    /// Points (x, y) in the axes' units; non-finite y values break the line.
    pub points: Vec<(f64, f64)>,
}

/// What the x axis shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum XAxis {
    /// Plain numbers.
    Number,
    /// Seconds since the Unix epoch, labelled as dates (YYYY-MM-DD, UTC).
    Date,
}

/// A chart of lines.
#[derive(Debug, Clone, PartialEq)]
pub struct LineChart {
    /// Title above the plot.
    pub title: String,
    /// x axis label.
    pub x_label: String,
    /// y axis label.
    pub y_label: String,
    /// How x values are labelled.
    pub x_axis: XAxis,
    /// The lines.
    pub lines: Vec<Line>,
}

/// One row of an [`IntervalChart`].
#[derive(Debug, Clone, PartialEq)]
pub struct IntervalRow {
    /// Label (strategy).
    pub name: String,
    /// Mean.
    pub mean: f64,
    /// Lower end of the interval.
    pub low: f64,
    /// Upper end of the interval.
    pub high: f64,
}

/// Means with intervals, one horizontal row each.
#[derive(Debug, Clone, PartialEq)]
pub struct IntervalChart {
    /// Title.
    pub title: String,
    /// Label of the value axis.
    pub x_label: String,
    /// The rows, top to bottom.
    pub rows: Vec<IntervalRow>,
}

const W: f64 = 480.0;
const FONT: f64 = 9.0;

fn date_label(t: f64) -> String {
    let days = (t / 86_400.0).floor() as i64;
    // Civil date from days since 1970-01-01 (proleptic Gregorian).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let y = yoe + era * 400;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = if m <= 2 { y + 1 } else { y };
    format!("{y:04}-{m:02}-{d:02}")
}

fn range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return None;
    }
    if hi - lo < 1e-12 * lo.abs().max(1e-12) {
        let pad = lo.abs().max(1.0) * 0.05;
        return Some((lo - pad, hi + pad));
    }
    Some((lo, hi))
}

fn check(what: &str, v: f64) -> Result<(), RenderError> {
    if v.is_finite() || v.is_nan() {
        Ok(())
    } else {
        Err(RenderError::NonFinite {
            what: what.to_string(),
            value: v,
        })
    }
}

/// The SVG of a line chart (deterministic; 480 x 300 pt plus the legend).
pub fn line_chart_svg(chart: &LineChart) -> Result<String, RenderError> {
    for l in &chart.lines {
        for &(x, y) in &l.points {
            check(&format!("{} x", l.name), x)?;
            check(&format!("{} y", l.name), y)?;
        }
    }
    let pts = || chart.lines.iter().flat_map(|l| l.points.iter());
    let (x0, x1) = range(pts().map(|p| p.0)).unwrap_or((0.0, 1.0));
    let (y0, y1) = range(pts().map(|p| p.1)).unwrap_or((0.0, 1.0));
    let ystep = nice_step((y1 - y0) / 5.0);
    let (y0, y1) = ((y0 / ystep).floor() * ystep, (y1 / ystep).ceil() * ystep);
    let legend_rows = chart.lines.len().div_ceil(3);
    let (left, right, top, plot_h) = (62.0, 14.0, 28.0, 220.0);
    let bottom_axis = top + plot_h;
    let h = bottom_axis + 40.0 + 14.0 * legend_rows as f64;
    let pw = W - left - right;
    let sx = |x: f64| left + (x - x0) / (x1 - x0) * pw;
    let sy = |y: f64| bottom_axis - (y - y0) / (y1 - y0) * plot_h;
    let mut s = Svg::new(W, h, FONT, &chart.title);
    s.text(W / 2.0, 16.0, 10.0, Anchor::Middle, true, &chart.title);
    s.line(format_args!(
        r##"<rect x="{left}" y="{top}" width="{pw:.2}" height="{plot_h}" fill="none" stroke="#444444" stroke-width="0.6"/>"##
    ));
    let yd = decimals(ystep);
    for v in multiples(y0, y1, ystep) {
        let y = sy(v);
        s.line(format_args!(
            r##"<line x1="{left}" y1="{y:.2}" x2="{:.2}" y2="{y:.2}" stroke="#dddddd" stroke-width="0.4"/>"##,
            left + pw
        ));
        s.text(left - 4.0, y + 3.0, FONT, Anchor::End, false, &label(v, yd));
    }
    let span = x1 - x0;
    let (xstep, xfmt): (f64, Box<dyn Fn(f64) -> String>) = match chart.x_axis {
        XAxis::Number => {
            let st = nice_step(span / 6.0);
            let d = decimals(st);
            (st, Box::new(move |v| label(v, d)))
        }
        XAxis::Date => {
            let day = 86_400.0;
            let st = (nice_step(span / day / 5.0) * day).max(day);
            (st, Box::new(date_label))
        }
    };
    for v in multiples(x0, x1, xstep) {
        let x = sx(v);
        s.line(format_args!(
            r##"<line x1="{x:.2}" y1="{bottom_axis}" x2="{x:.2}" y2="{:.2}" stroke="#444444" stroke-width="0.6"/>"##,
            bottom_axis + 3.0
        ));
        s.text(x, bottom_axis + 13.0, FONT, Anchor::Middle, false, &xfmt(v));
    }
    s.text(
        left + pw / 2.0,
        bottom_axis + 27.0,
        FONT,
        Anchor::Middle,
        false,
        &chart.x_label,
    );
    s.text_attrs(
        14.0,
        top + plot_h / 2.0,
        FONT,
        Anchor::Middle,
        false,
        &format!(r#"transform="rotate(-90 14 {:.2})""#, top + plot_h / 2.0),
        &chart.y_label,
    );
    for (k, l) in chart.lines.iter().enumerate() {
        let (colour, dash) = qualitative(k);
        // Solid, dashed, then dotted: each pass through the palette its own pattern, so a
        // 13th line does not look like the 7th.
        let dash_attr = match dash {
            0 => "",
            1 => r#" stroke-dasharray="4 2""#,
            _ => r#" stroke-dasharray="1 2""#,
        };
        let mut d = String::new();
        let mut pen_up = true;
        for &(x, y) in &l.points {
            if !y.is_finite() {
                pen_up = true;
                continue;
            }
            d.push_str(&format!(
                "{}{:.2},{:.2} ",
                if pen_up { "M" } else { "L" },
                sx(x),
                sy(y)
            ));
            pen_up = false;
        }
        s.line(format_args!(
            r#"<path d="{}" fill="none" stroke="{}" stroke-width="1"{dash_attr}/>"#,
            d.trim_end(),
            colour.hex()
        ));
        let (row, col) = (k / 3, k % 3);
        let lx = left + col as f64 * (pw / 3.0);
        let ly = bottom_axis + 44.0 + row as f64 * 14.0;
        s.line(format_args!(
            r#"<line x1="{lx:.2}" y1="{:.2}" x2="{:.2}" y2="{:.2}" stroke="{}" stroke-width="2"{dash_attr}/>"#,
            ly - 3.0,
            lx + 16.0,
            ly - 3.0,
            colour.hex()
        ));
        s.text(lx + 20.0, ly, FONT, Anchor::Start, false, &l.name);
    }
    Ok(s.finish())
}

/// The SVG of means with 95% intervals, one row per entry (deterministic).
pub fn interval_chart_svg(chart: &IntervalChart) -> Result<String, RenderError> {
    for r in &chart.rows {
        for (what, v) in [("mean", r.mean), ("low", r.low), ("high", r.high)] {
            check(&format!("{} {what}", r.name), v)?;
        }
    }
    let label_w = chart
        .rows
        .iter()
        .map(|r| text_width(&r.name, FONT, false))
        .fold(40.0f64, f64::max)
        + 10.0;
    let (left, right, top, row_h) = (label_w, 16.0, 28.0, 16.0);
    let plot_h = row_h * chart.rows.len().max(1) as f64;
    let bottom_axis = top + plot_h;
    let h = bottom_axis + 34.0;
    let pw = W - left - right;
    let (x0, x1) = range(
        chart
            .rows
            .iter()
            .flat_map(|r| [r.low, r.high, r.mean].into_iter()),
    )
    .unwrap_or((0.0, 1.0));
    let step = nice_step((x1 - x0) / 5.0);
    let (x0, x1) = ((x0 / step).floor() * step, (x1 / step).ceil() * step);
    let sx = |x: f64| left + (x - x0) / (x1 - x0) * pw;
    let mut s = Svg::new(W, h, FONT, &chart.title);
    s.text(W / 2.0, 16.0, 10.0, Anchor::Middle, true, &chart.title);
    let d = decimals(step);
    for v in multiples(x0, x1, step) {
        let x = sx(v);
        s.line(format_args!(
            r##"<line x1="{x:.2}" y1="{top}" x2="{x:.2}" y2="{bottom_axis}" stroke="#dddddd" stroke-width="0.4"/>"##
        ));
        s.text(
            x,
            bottom_axis + 12.0,
            FONT,
            Anchor::Middle,
            false,
            &label(v, d),
        );
    }
    s.text(
        left + pw / 2.0,
        bottom_axis + 26.0,
        FONT,
        Anchor::Middle,
        false,
        &chart.x_label,
    );
    for (k, r) in chart.rows.iter().enumerate() {
        let y = top + row_h * (k as f64 + 0.5);
        s.text(left - 6.0, y + 3.0, FONT, Anchor::End, false, &r.name);
        if !(r.mean.is_finite() && r.low.is_finite() && r.high.is_finite()) {
            continue;
        }
        s.line(format_args!(
            r##"<line x1="{:.2}" y1="{y:.2}" x2="{:.2}" y2="{y:.2}" stroke="#444444" stroke-width="1.2"/>"##,
            sx(r.low),
            sx(r.high)
        ));
        s.line(format_args!(
            r##"<circle cx="{:.2}" cy="{y:.2}" r="2.6" fill="#1f77b4"/>"##,
            sx(r.mean)
        ));
    }
    Ok(s.finish())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_are_civil_dates() {
        assert_eq!(date_label(0.0), "1970-01-01");
        assert_eq!(date_label(1_388_534_400.0), "2014-01-01");
        assert_eq!(date_label(951_782_400.0), "2000-02-29");
    }

    #[test]
    fn charts_parse_and_rasterise() {
        let chart = LineChart {
            title: "RMSE".into(),
            x_label: "mission".into(),
            y_label: "m3/m3".into(),
            x_axis: XAxis::Date,
            lines: vec![
                Line {
                    name: "gleaner".into(),
                    points: vec![(1.388e9, 0.01), (1.3881e9, f64::NAN), (1.389e9, 0.02)],
                },
                Line {
                    name: "paper".into(),
                    points: vec![(1.388e9, 0.015), (1.389e9, 0.03)],
                },
            ],
        };
        let svg = line_chart_svg(&chart).unwrap();
        assert!(svg.contains("gleaner") && svg.contains("2014-"));
        assert!(crate::svg_to_png(&svg, 300).is_ok());
        let iv = interval_chart_svg(&IntervalChart {
            title: "RMSE".into(),
            x_label: "m3/m3".into(),
            rows: vec![IntervalRow {
                name: "gleaner".into(),
                mean: 0.02,
                low: 0.01,
                high: 0.03,
            }],
        })
        .unwrap();
        assert!(crate::svg_to_png(&iv, 300).is_ok());
        let bad = LineChart {
            lines: vec![Line {
                name: "x".into(),
                points: vec![(0.0, f64::INFINITY)],
            }],
            ..chart
        };
        assert!(line_chart_svg(&bad).is_err());
    }

    #[test]
    fn thirteen_lines_get_thirteen_styles() {
        let chart = LineChart {
            title: "RMSE".into(),
            x_label: "mission".into(),
            y_label: "m3/m3".into(),
            x_axis: XAxis::Date,
            lines: (0..13)
                .map(|k| Line {
                    name: format!("s{k}"),
                    points: vec![(0.0, k as f64), (1.0, k as f64)],
                })
                .collect(),
        };
        let svg = line_chart_svg(&chart).unwrap();
        // Six solid (path and legend line each), six dashed, one dotted.
        assert_eq!(svg.matches(r#"stroke-dasharray="4 2""#).count(), 12);
        assert_eq!(svg.matches(r#"stroke-dasharray="1 2""#).count(), 2);
    }
}
