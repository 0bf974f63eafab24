//! From a [`Figure`] to what is actually drawn: validated, in axis space
//! (`log10` on log axes), clipped to the visible range and thinned to about
//! what the pixels can show. Pure functions, no drawing library.
//!
//! # Display decimation
//!
//! A line series whose x values never decrease and that has more than four
//! visible points per pixel column is thinned with the M4 rule: in every pixel
//! column the first, last, lowest and highest points are kept, in their
//! original order. The polyline drawn through them covers exactly the same
//! pixels as the full one (the vertical extent of every column and the joins
//! between columns are kept), so peaks are never lost; a 30 000-lag
//! correlation becomes at most `4 * width` points. Point and stem series are
//! thinned to the lowest and highest point per column the same way. Only the
//! drawing is thinned: the data in the [`Figure`] (and any export made from
//! it) is untouched.

use super::spec::{Axis, Figure, MarkerStyle, Panel, Rgb, Scale, Series, SeriesStyle};
use super::ticks::{self, Ticks};
use crate::error::{Error, Result};

/// A figure ready to draw.
#[derive(Debug, Clone)]
pub(crate) struct Prepared {
    pub title: String,
    pub panels: Vec<PreparedPanel>,
    pub warnings: Vec<String>,
}

/// One axis after fitting: range and ticks in axis space.
#[derive(Debug, Clone)]
pub(crate) struct Frame {
    pub lo: f64,
    pub hi: f64,
    pub ticks: Ticks,
    pub title: String,
}

/// A reference line in axis space.
#[derive(Debug, Clone)]
pub(crate) struct PreparedMarker {
    pub at: f64,
    pub label: String,
    pub style: MarkerStyle,
}

/// What a prepared series draws.
#[derive(Debug, Clone)]
pub(crate) enum Shape {
    /// Polylines (gaps where data was missing or clipped).
    Lines {
        segments: Vec<Vec<(f64, f64)>>,
        dashed: bool,
    },
    /// Circles.
    Points(Vec<(f64, f64)>),
    /// Vertical lines from `base` to each point, with circles.
    Stems { base: f64, points: Vec<(f64, f64)> },
    /// `(x, y, bar_low, bar_high)`; the bar ends are already clipped.
    Bars(Vec<(f64, f64, f64, f64)>),
}

/// The little picture in front of a legend entry.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum LegendSample {
    Line,
    Dashed,
    Point,
}

/// A series ready to draw.
#[derive(Debug, Clone)]
pub(crate) struct PreparedSeries {
    /// Position in the panel's declared series (legend order).
    pub index: usize,
    pub name: String,
    pub color: Rgb,
    pub stroke_px: f64,
    pub shapes: Vec<Shape>,
    /// What the legend shows for it.
    pub legend: LegendSample,
}

/// A panel ready to draw.
#[derive(Debug, Clone)]
pub(crate) struct PreparedPanel {
    pub title: String,
    pub x: Frame,
    pub y: Frame,
    pub series: Vec<PreparedSeries>,
    pub vlines: Vec<PreparedMarker>,
    pub hlines: Vec<PreparedMarker>,
    pub legend: bool,
}

fn report_err(what: String, reason: impl Into<String>) -> Error {
    Error::Report {
        what,
        reason: reason.into(),
    }
}

/// Whether `id` can be a file stem: ASCII letters, digits, `_`, `-`, not empty,
/// not starting with `-`.
pub(crate) fn valid_id(id: &str) -> bool {
    !id.is_empty()
        && !id.starts_with('-')
        && id
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-')
}

/// Maps a data value to axis space; `None` when it cannot be drawn.
fn to_axis(scale: Scale, v: f64) -> Option<f64> {
    match scale {
        _ if !v.is_finite() => None,
        Scale::Linear => Some(v),
        Scale::Log if v > 0.0 => Some(v.log10()),
        Scale::Log => None,
    }
}

/// Prepares `fig` for drawing on a canvas `columns` pixels wide.
///
/// # Errors
///
/// [`Error::Report`] when the figure is malformed: bad id, no panels, a series
/// whose `x` and `y` (or error bars) differ in length, negative or non-finite
/// error bars, an explicit range that is not finite and increasing (or not
/// positive on a log axis), a panel with nothing drawable and no range.
pub(crate) fn prepare(fig: &Figure, columns: usize) -> Result<Prepared> {
    if !valid_id(&fig.id) {
        return Err(report_err(
            format!("figure '{}'", fig.id),
            "id must be non-empty ASCII letters, digits, '_' or '-' (it names the file)",
        ));
    }
    if fig.panels.is_empty() {
        return Err(report_err(format!("figure '{}'", fig.id), "has no panels"));
    }
    if fig.width_px < 200
        || fig.panel_height_px < 120
        || fig.width_px > 8000
        || fig.panel_height_px > 8000
    {
        return Err(report_err(
            format!("figure '{}'", fig.id),
            format!(
                "size {} x {} px per panel is outside 200..=8000 x 120..=8000",
                fig.width_px, fig.panel_height_px
            ),
        ));
    }
    let mut warnings = Vec::new();
    let mut panels = Vec::with_capacity(fig.panels.len());
    for (i, panel) in fig.panels.iter().enumerate() {
        let what = if fig.panels.len() == 1 {
            format!("figure '{}'", fig.id)
        } else {
            format!("figure '{}' panel {}", fig.id, i + 1)
        };
        panels.push(prepare_panel(panel, &what, columns, &mut warnings)?);
    }
    Ok(Prepared {
        title: fig.title.clone(),
        panels,
        warnings,
    })
}

/// One series in axis space, with `None` where a point cannot be drawn.
struct AxisSeries {
    pts: Vec<Option<(f64, f64)>>,
    /// Error bar ends in axis space (`None` = that end cannot be drawn).
    bars: Vec<(Option<f64>, Option<f64>)>,
}

fn check_range(axis: &Axis, what: &str, which: &str) -> Result<Option<(f64, f64)>> {
    let Some((lo, hi)) = axis.range else {
        return Ok(None);
    };
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Err(report_err(
            format!("{what} {which} axis"),
            format!("range ({lo}, {hi}) must be finite with low < high"),
        ));
    }
    if axis.scale == Scale::Log && lo <= 0.0 {
        return Err(report_err(
            format!("{what} {which} axis"),
            format!("log axis range ({lo}, {hi}) must be positive"),
        ));
    }
    match axis.scale {
        Scale::Linear => Ok(Some((lo, hi))),
        Scale::Log => Ok(Some((lo.log10(), hi.log10()))),
    }
}

fn to_axis_series(
    s: &Series,
    panel: &Panel,
    what: &str,
    warnings: &mut Vec<String>,
) -> Result<AxisSeries> {
    let sw = format!("{what} series '{}'", s.name);
    if s.x.len() != s.y.len() {
        return Err(report_err(
            sw,
            format!("x has {} values but y has {}", s.x.len(), s.y.len()),
        ));
    }
    let mut bars = Vec::new();
    if let SeriesStyle::ErrorBars { minus, plus, .. } = &s.style {
        for (name, e) in [("minus", minus), ("plus", plus)] {
            if e.len() != s.y.len() {
                return Err(report_err(
                    sw,
                    format!(
                        "error bars '{name}' have {} values but y has {}",
                        e.len(),
                        s.y.len()
                    ),
                ));
            }
            if let Some(i) = e.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
                return Err(report_err(
                    sw,
                    format!("error bar '{name}'[{i}] = {} must be finite and >= 0", e[i]),
                ));
            }
        }
        bars = s
            .y
            .iter()
            .zip(minus.iter().zip(plus))
            .map(|(&y, (&m, &p))| (to_axis(panel.y.scale, y - m), to_axis(panel.y.scale, y + p)))
            .collect();
    }
    let mut non_finite = 0usize;
    let mut non_positive = [0usize; 2];
    let pts =
        s.x.iter()
            .zip(&s.y)
            .map(|(&x, &y)| {
                if !(x.is_finite() && y.is_finite()) {
                    non_finite += 1;
                    return None;
                }
                let tx = to_axis(panel.x.scale, x);
                let ty = to_axis(panel.y.scale, y);
                if tx.is_none() {
                    non_positive[0] += 1;
                }
                if ty.is_none() {
                    non_positive[1] += 1;
                }
                Some((tx?, ty?))
            })
            .collect();
    if non_finite > 0 {
        warnings.push(format!(
            "{sw}: {non_finite} of {} points are NaN or infinite and are not drawn",
            s.x.len()
        ));
    }
    for (axis, n) in ["x", "y"].iter().zip(non_positive) {
        if n > 0 {
            warnings.push(format!(
                "{sw}: {n} of {} points have {axis} <= 0 and are not drawn on the log {axis} axis",
                s.x.len()
            ));
        }
    }
    if let SeriesStyle::ErrorBars { .. } = &s.style {
        let cut = bars.iter().filter(|(lo, _)| lo.is_none()).count();
        if cut > 0 && panel.y.scale == Scale::Log {
            warnings.push(format!(
                "{sw}: {cut} error bars reach y <= 0 and are cut at the bottom of the log axis"
            ));
        }
    }
    Ok(AxisSeries { pts, bars })
}

/// Extent of the finite values, or `None`.
fn extent(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    values.fold(None, |acc, v| match acc {
        None => Some((v, v)),
        Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
    })
}

/// Widens a range by `frac` of its span on both sides; a zero span becomes
/// ±`half_width`-ish around the value.
fn pad(lo: f64, hi: f64, frac: f64, scale: Scale) -> (f64, f64) {
    if hi > lo {
        let d = (hi - lo) * frac;
        return (lo - d, hi + d);
    }
    match scale {
        Scale::Log => (lo - 0.5, hi + 0.5),
        Scale::Linear => {
            let d = if lo == 0.0 { 1.0 } else { lo.abs() * 0.1 };
            (lo - d, hi + d)
        }
    }
}

fn prepare_panel(
    panel: &Panel,
    what: &str,
    columns: usize,
    warnings: &mut Vec<String>,
) -> Result<PreparedPanel> {
    let x_range = check_range(&panel.x, what, "x")?;
    let y_range = check_range(&panel.y, what, "y")?;
    let data: Vec<AxisSeries> = panel
        .series
        .iter()
        .map(|s| to_axis_series(s, panel, what, warnings))
        .collect::<Result<_>>()?;

    // points (and error bars) at the ends of the axis get a margin, so they
    // do not sit on the frame; pure line plots run edge to edge
    let point_like = panel
        .series
        .iter()
        .any(|s| !matches!(s.style, SeriesStyle::Line | SeriesStyle::DashedLine));
    let (x_lo, x_hi) = match x_range {
        Some(r) => r,
        None => {
            let e = extent(
                data.iter()
                    .flat_map(|d| d.pts.iter().flatten().map(|p| p.0)),
            );
            let Some((lo, hi)) = e else {
                return Err(report_err(
                    what.to_string(),
                    "has no drawable data and no x range (every series is empty, NaN, or <= 0 on a log axis)",
                ));
            };
            pad(lo, hi, if point_like { 0.04 } else { 0.0 }, panel.x.scale)
        }
    };
    let (y_lo, y_hi) = match y_range {
        Some(r) => r,
        None => {
            let in_x = |x: f64| x >= x_lo && x <= x_hi;
            let mut vals: Vec<f64> = Vec::new();
            for (s, d) in panel.series.iter().zip(&data) {
                vals.extend(d.pts.iter().flatten().filter(|p| in_x(p.0)).map(|p| p.1));
                for (p, (lo, hi)) in d.pts.iter().zip(&d.bars) {
                    if let Some(p) = p {
                        if in_x(p.0) {
                            vals.extend(lo.iter().chain(hi.iter()));
                        }
                    }
                }
                if matches!(s.style, SeriesStyle::Stem) && panel.y.scale == Scale::Linear {
                    vals.push(0.0);
                }
            }
            let Some((lo, hi)) = extent(vals.into_iter()) else {
                return Err(report_err(
                    what.to_string(),
                    "has no drawable data inside the x range and no y range",
                ));
            };
            pad(lo, hi, 0.05, panel.y.scale)
        }
    };

    let x = Frame {
        lo: x_lo,
        hi: x_hi,
        ticks: axis_ticks(panel.x.scale, x_lo, x_hi, 8),
        title: panel.x.title(),
    };
    let y = Frame {
        lo: y_lo,
        hi: y_hi,
        ticks: axis_ticks(panel.y.scale, y_lo, y_hi, 6),
        title: panel.y.title(),
    };
    let rect = Rect {
        x0: x_lo,
        x1: x_hi,
        y0: y_lo,
        y1: y_hi,
    };

    let any_highlight = panel.series.iter().any(|s| s.highlight);
    let mut palette_i = 0usize;
    let mut series = Vec::with_capacity(panel.series.len());
    let mut order: Vec<usize> = (0..panel.series.len()).collect();
    // highlighted series on top; stable otherwise
    order.sort_by_key(|&i| panel.series[i].highlight);
    let colors: Vec<Rgb> = panel
        .series
        .iter()
        .map(|s| {
            s.color.unwrap_or_else(|| {
                let c = Rgb::palette(palette_i);
                palette_i += 1;
                c
            })
        })
        .collect();
    for i in order {
        let s = &panel.series[i];
        let d = &data[i];
        let stroke_px = if s.highlight {
            3.0
        } else if any_highlight {
            1.0
        } else {
            1.5
        };
        let mut shapes = Vec::new();
        let monotonic = d
            .pts
            .iter()
            .flatten()
            .zip(d.pts.iter().flatten().skip(1))
            .all(|(a, b)| b.0 >= a.0);
        let line = |dashed: bool| {
            let mut segments = Vec::new();
            for run in d.pts.split(|p| p.is_none()) {
                let run: Vec<(f64, f64)> = run.iter().flatten().copied().collect();
                let run = if monotonic {
                    m4(&run, x_lo, x_hi, columns)
                } else {
                    run
                };
                segments.extend(clip_polyline(&run, &rect));
            }
            Shape::Lines { segments, dashed }
        };
        let visible_points = || {
            let pts: Vec<(f64, f64)> = d
                .pts
                .iter()
                .flatten()
                .copied()
                .filter(|p| rect.contains(*p))
                .collect();
            if monotonic {
                min_max_per_column(&pts, x_lo, x_hi, columns)
            } else {
                pts
            }
        };
        match &s.style {
            SeriesStyle::Line => shapes.push(line(false)),
            SeriesStyle::DashedLine => shapes.push(line(true)),
            SeriesStyle::Points => shapes.push(Shape::Points(visible_points())),
            SeriesStyle::LinePoints => {
                shapes.push(line(false));
                shapes.push(Shape::Points(visible_points()));
            }
            SeriesStyle::Stem => {
                let base = match panel.y.scale {
                    Scale::Linear => 0.0f64.clamp(y_lo, y_hi),
                    Scale::Log => y_lo,
                };
                shapes.push(Shape::Stems {
                    base,
                    points: visible_points(),
                });
            }
            SeriesStyle::ErrorBars { line: joined, .. } => {
                if *joined {
                    shapes.push(line(false));
                }
                let bars = d
                    .pts
                    .iter()
                    .zip(&d.bars)
                    .filter_map(|(p, (lo, hi))| {
                        let (x, y) = (*p)?;
                        if !(x >= x_lo && x <= x_hi) {
                            return None;
                        }
                        let lo = lo.unwrap_or(y_lo).clamp(y_lo, y_hi);
                        let hi = hi.unwrap_or(y_hi).clamp(y_lo, y_hi);
                        Some((x, y, lo, hi))
                    })
                    .collect();
                shapes.push(Shape::Bars(bars));
            }
        }
        series.push(PreparedSeries {
            index: i,
            name: s.name.clone(),
            color: colors[i],
            stroke_px,
            shapes,
            legend: match s.style {
                SeriesStyle::Line | SeriesStyle::LinePoints => LegendSample::Line,
                SeriesStyle::DashedLine => LegendSample::Dashed,
                _ => LegendSample::Point,
            },
        });
    }

    // vertical markers' labels are thinned at drawing time, in pixels
    let markers = |ms: &[super::spec::Marker], scale: Scale, lo: f64, hi: f64, thin: bool| {
        let mut out: Vec<PreparedMarker> = ms
            .iter()
            .filter_map(|m| {
                let at = to_axis(scale, m.at)?;
                (at >= lo && at <= hi).then(|| PreparedMarker {
                    at,
                    label: m.label.clone(),
                    style: m.style,
                })
            })
            .collect();
        if thin {
            thin_labels(&mut out, hi - lo);
        }
        out
    };
    Ok(PreparedPanel {
        title: panel.title.clone(),
        vlines: markers(&panel.vlines, panel.x.scale, x_lo, x_hi, false),
        hlines: markers(&panel.hlines, panel.y.scale, y_lo, y_hi, true),
        x,
        y,
        series,
        legend: panel.shows_legend(),
    })
}

/// Blanks marker labels that would overprint the previous label: labels
/// closer than 6 % of the axis span (about 50 px) to a kept one are dropped.
/// The lines themselves are all drawn.
fn thin_labels(markers: &mut [PreparedMarker], span: f64) {
    let mut order: Vec<usize> = (0..markers.len()).collect();
    order.sort_by(|&a, &b| markers[a].at.total_cmp(&markers[b].at));
    let mut last: Option<f64> = None;
    for i in order {
        if markers[i].label.is_empty() {
            continue;
        }
        match last {
            Some(l) if markers[i].at - l < 0.06 * span => markers[i].label.clear(),
            _ => last = Some(markers[i].at),
        }
    }
}

fn axis_ticks(scale: Scale, lo: f64, hi: f64, target: usize) -> Ticks {
    match scale {
        Scale::Linear => ticks::linear(lo, hi, target),
        Scale::Log => ticks::log(lo, hi, target),
    }
}

/// The visible rectangle in axis space.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Rect {
    pub x0: f64,
    pub x1: f64,
    pub y0: f64,
    pub y1: f64,
}

impl Rect {
    fn contains(&self, p: (f64, f64)) -> bool {
        p.0 >= self.x0 && p.0 <= self.x1 && p.1 >= self.y0 && p.1 <= self.y1
    }

    /// Liang–Barsky: the part of segment `a`–`b` inside the rectangle.
    fn clip(&self, a: (f64, f64), b: (f64, f64)) -> Option<((f64, f64), (f64, f64))> {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let mut t0 = 0.0f64;
        let mut t1 = 1.0f64;
        for (p, q) in [
            (-dx, a.0 - self.x0),
            (dx, self.x1 - a.0),
            (-dy, a.1 - self.y0),
            (dy, self.y1 - a.1),
        ] {
            if p == 0.0 {
                if q < 0.0 {
                    return None;
                }
            } else {
                let r = q / p;
                if p < 0.0 {
                    t0 = t0.max(r);
                } else {
                    t1 = t1.min(r);
                }
            }
        }
        (t0 <= t1).then_some((
            (a.0 + t0 * dx, a.1 + t0 * dy),
            (a.0 + t1 * dx, a.1 + t1 * dy),
        ))
    }
}

/// Splits a polyline into the pieces inside `rect`.
pub(crate) fn clip_polyline(pts: &[(f64, f64)], rect: &Rect) -> Vec<Vec<(f64, f64)>> {
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    if pts.len() == 1 {
        if rect.contains(pts[0]) {
            out.push(vec![pts[0]]);
        }
        return out;
    }
    let mut cur: Vec<(f64, f64)> = Vec::new();
    for w in pts.windows(2) {
        match rect.clip(w[0], w[1]) {
            Some((a, b)) => {
                if cur.last() != Some(&a) {
                    if cur.len() > 1 {
                        out.push(std::mem::take(&mut cur));
                    }
                    cur.clear();
                    cur.push(a);
                }
                cur.push(b);
            }
            None => {
                if cur.len() > 1 {
                    out.push(std::mem::take(&mut cur));
                }
                cur.clear();
            }
        }
    }
    if cur.len() > 1 {
        out.push(cur);
    }
    out
}

/// Column of `x` among `columns` equal columns over `[lo, hi]`; points left
/// of the range fall in column `-1`, right of it in `columns`.
fn column(x: f64, lo: f64, hi: f64, columns: usize) -> i64 {
    if x < lo {
        -1
    } else if x > hi {
        columns as i64
    } else {
        (((x - lo) / (hi - lo) * columns as f64) as i64).min(columns as i64 - 1)
    }
}

/// M4 decimation of a polyline with non-decreasing x (see the module doc):
/// keeps first, lowest, highest and last point of every pixel column, in
/// order. Everything left (right) of the range collapses to its last (first)
/// point, so the line still runs to the edge. Returns the input when it is
/// already small.
pub(crate) fn m4(pts: &[(f64, f64)], lo: f64, hi: f64, columns: usize) -> Vec<(f64, f64)> {
    let columns = columns.max(1);
    if pts.len() <= 4 * columns {
        return pts.to_vec();
    }
    let mut out = Vec::with_capacity(4 * columns + 4);
    let mut start = 0;
    while start < pts.len() {
        let c = column(pts[start].0, lo, hi, columns);
        let mut end = start + 1;
        while end < pts.len() && column(pts[end].0, lo, hi, columns) == c {
            end += 1;
        }
        let run = &pts[start..end];
        if c < 0 {
            out.push(run[run.len() - 1]);
        } else if c >= columns as i64 {
            out.push(run[0]);
            break;
        } else {
            let (mut imin, mut imax) = (0, 0);
            for (i, p) in run.iter().enumerate() {
                if p.1 < run[imin].1 {
                    imin = i;
                }
                if p.1 > run[imax].1 {
                    imax = i;
                }
            }
            let mut keep = [0, imin, imax, run.len() - 1];
            keep.sort_unstable();
            let mut last = usize::MAX;
            for k in keep {
                if k != last {
                    out.push(run[k]);
                    last = k;
                }
            }
        }
        start = end;
    }
    out
}

/// Keeps the lowest and highest point of every pixel column (points must have
/// non-decreasing x and lie inside the range). Returns the input when small.
pub(crate) fn min_max_per_column(
    pts: &[(f64, f64)],
    lo: f64,
    hi: f64,
    columns: usize,
) -> Vec<(f64, f64)> {
    let columns = columns.max(1);
    if pts.len() <= 2 * columns {
        return pts.to_vec();
    }
    let mut out = Vec::with_capacity(2 * columns);
    let mut start = 0;
    while start < pts.len() {
        let c = column(pts[start].0, lo, hi, columns);
        let mut end = start + 1;
        while end < pts.len() && column(pts[end].0, lo, hi, columns) == c {
            end += 1;
        }
        let run = &pts[start..end];
        let imin = (0..run.len())
            .min_by(|&a, &b| run[a].1.total_cmp(&run[b].1))
            .unwrap_or(0);
        let imax = (0..run.len())
            .max_by(|&a, &b| run[a].1.total_cmp(&run[b].1))
            .unwrap_or(0);
        out.push(run[imin.min(imax)]);
        if imin != imax {
            out.push(run[imin.max(imax)]);
        }
        start = end;
    }
    out
}

#[cfg(test)]
#[path = "prepare_tests.rs"]
mod tests;
