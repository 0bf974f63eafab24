//! The interactive layer of the HTML report: for each figure marked
//! [`Figure::interactive`], its series as JSON in a
//! `<script type="application/json" class="bp-data">` block, and one inline
//! script (`live.js`) that lets the reader zoom and pan the x axis and read
//! values under the cursor.
//!
//! The data are the figure's own, in axis space (`log10` on a log axis),
//! clipped to the initial view and thinned with the same M4 rule as the
//! drawing but for [`LIVE_COLUMNS`] columns (about four times the figure's
//! width, so a 4× zoom still shows every pixel column's extremes), numbers
//! to six significant digits. The static SVG is untouched: with scripts off
//! the report reads the same, without zoom.

use std::fmt::Write as _;

use super::draw::{PanelGeometry, Rendered, TICK_PX, X_TICK_BAND, Y_TICK_BAND};
use super::prepare::{prepare, Shape};
use super::spec::{Figure, MarkerStyle, Scale};
use crate::error::Result;

/// Columns the embedded series are thinned to.
pub(crate) const LIVE_COLUMNS: usize = 4000;

/// The script of the interactive layer.
pub(crate) const SCRIPT: &str = include_str!("live.js");

/// `v` rounded to six significant digits, as JSON (`null` when not finite).
fn num(out: &mut String, v: f64) {
    if !v.is_finite() {
        out.push_str("null");
        return;
    }
    if v == 0.0 {
        out.push('0');
        return;
    }
    let e = v.abs().log10().floor() as i32;
    let k = 5 - e;
    let r = if (-300..300).contains(&k) {
        let m = 10f64.powi(k);
        (v * m).round() / m
    } else {
        v
    };
    if (-4..7).contains(&e) {
        let _ = write!(out, "{r}");
    } else {
        let _ = write!(out, "{r:e}");
    }
}

/// A JSON string literal, safe inside an HTML `<script>` element.
fn string(out: &mut String, s: &str) {
    let json = serde_json::Value::String(s.to_string()).to_string();
    out.push_str(&json.replace("</", "<\\/"));
}

fn array(out: &mut String, vs: impl Iterator<Item = f64>) {
    out.push('[');
    for (i, v) in vs.enumerate() {
        if i > 0 {
            out.push(',');
        }
        num(out, v);
    }
    out.push(']');
}

/// The JSON spec of an interactive figure drawn as `rendered`, for the
/// figure element with HTML id `html_id`.
///
/// # Errors
/// As [`super::render_svg`] (the figure is prepared again at
/// [`LIVE_COLUMNS`]).
pub(crate) fn figure_json(fig: &Figure, html_id: &str, rendered: &Rendered) -> Result<String> {
    let p = prepare(fig, LIVE_COLUMNS)?;
    let mut o = String::with_capacity(64 * 1024);
    o.push_str("{\"figure\":");
    string(&mut o, html_id);
    let _ = write!(
        o,
        ",\"font\":{TICK_PX},\"bands\":[{X_TICK_BAND},{Y_TICK_BAND}],\"linked\":{}",
        linked(fig)
    );
    o.push_str(",\"panels\":[");
    for (k, ((panel, spec), PanelGeometry { plot })) in p
        .panels
        .iter()
        .zip(&fig.panels)
        .zip(&rendered.geometry)
        .enumerate()
    {
        if k > 0 {
            o.push(',');
        }
        let _ = write!(
            o,
            "{{\"plot\":[{},{},{},{}],\"x\":{{\"lo\":",
            plot[0], plot[1], plot[2], plot[3]
        );
        num(&mut o, panel.x.lo);
        o.push_str(",\"hi\":");
        num(&mut o, panel.x.hi);
        let _ = write!(o, ",\"log\":{},\"title\":", spec.x.scale == Scale::Log);
        string(&mut o, &panel.x.title);
        o.push_str("},\"y\":{\"lo\":");
        num(&mut o, panel.y.lo);
        o.push_str(",\"hi\":");
        num(&mut o, panel.y.hi);
        let _ = write!(
            o,
            ",\"log\":{},\"fixed\":{},\"title\":",
            spec.y.scale == Scale::Log,
            spec.y.range.is_some()
        );
        string(&mut o, &panel.y.title);
        o.push_str("},\"series\":[");
        let mut first = true;
        let mut by_index: Vec<_> = panel.series.iter().collect();
        by_index.sort_by_key(|s| s.index);
        for s in by_index {
            for shape in &s.shapes {
                let (kind, dash, segs): (&str, bool, Vec<&[(f64, f64)]>) = match shape {
                    Shape::Lines { segments, dashed } => (
                        "line",
                        *dashed,
                        segments.iter().map(Vec::as_slice).collect(),
                    ),
                    Shape::Points(pts) => ("points", false, vec![pts.as_slice()]),
                    // stems and error bars are not zoomed (no such figure
                    // is marked interactive); their points still read out
                    Shape::Stems { points, .. } => ("points", false, vec![points.as_slice()]),
                    Shape::Bars(_) => continue,
                };
                if !first {
                    o.push(',');
                }
                first = false;
                o.push_str("{\"name\":");
                string(&mut o, &s.name);
                let _ = write!(
                    o,
                    ",\"color\":\"{}\",\"w\":{},\"dash\":{dash},\"kind\":\"{kind}\",\"segs\":[",
                    s.color.hex(),
                    s.stroke_px
                );
                for (i, seg) in segs.iter().enumerate() {
                    if i > 0 {
                        o.push(',');
                    }
                    o.push('[');
                    array(&mut o, seg.iter().map(|p| p.0));
                    o.push(',');
                    array(&mut o, seg.iter().map(|p| p.1));
                    o.push(']');
                }
                o.push_str("]}");
            }
        }
        o.push(']');
        for (key, markers) in [("v", &panel.vlines), ("h", &panel.hlines)] {
            let _ = write!(o, ",\"{key}\":[");
            for (i, m) in markers.iter().enumerate() {
                if i > 0 {
                    o.push(',');
                }
                o.push('[');
                num(&mut o, m.at);
                o.push(',');
                string(&mut o, &m.label);
                let style = match m.style {
                    MarkerStyle::RedDashed => "red",
                    MarkerStyle::BlackDashed => "black",
                    MarkerStyle::GreySolid => "grey",
                };
                let _ = write!(o, ",\"{style}\"]");
            }
            o.push(']');
        }
        o.push('}');
    }
    o.push_str("]}");
    Ok(o)
}

/// Whether all panels share one x axis (same title, scale and range): then
/// zooming one zooms them all (stacked signals over time).
fn linked(fig: &Figure) -> bool {
    fig.panels.len() > 1
        && fig.panels.windows(2).all(|w| {
            w[0].x.title() == w[1].x.title()
                && w[0].x.scale == w[1].x.scale
                && w[0].x.range == w[1].x.range
        })
        && {
            // with no explicit range, the data must span the same x
            let span = |p: &super::spec::Panel| {
                p.series.iter().flat_map(|s| s.x.iter().copied()).fold(
                    (f64::INFINITY, f64::NEG_INFINITY),
                    |(a, b), v| {
                        if v.is_finite() {
                            (a.min(v), b.max(v))
                        } else {
                            (a, b)
                        }
                    },
                )
            };
            fig.panels[0].x.range.is_some()
                || fig.panels.windows(2).all(|w| span(&w[0]) == span(&w[1]))
        }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_keep_six_significant_digits() {
        let f = |v: f64| {
            let mut s = String::new();
            num(&mut s, v);
            s
        };
        assert_eq!(f(123.456789), "123.457");
        assert_eq!(f(-0.000123456789), "-0.000123457");
        assert_eq!(f(2.5e-25), "2.5e-25");
        assert_eq!(f(1234567890.0), "1.23457e9");
        assert_eq!(f(0.0), "0");
        assert_eq!(f(f64::NAN), "null");
    }

    #[test]
    fn strings_cannot_close_the_script_element() {
        let mut s = String::new();
        string(&mut s, "R</script><b>");
        assert!(!s.contains("</"), "{s}");
    }
}
