//! Drawing a prepared figure with `plotters`, onto SVG or an RGB bitmap.
//!
//! One drawing routine serves both backends. Log axes are drawn as linear
//! axes over `log10` of the data with our own ticks and `10ⁿ` labels (see
//! [`super::ticks`]), so every panel has the same coordinate type and the
//! tick choice is ours rather than the library's.
//!
//! Text is measured (and, for PNG, rasterised) with the embedded DejaVu Sans
//! font through `ab_glyph`; no system font library is involved. The SVG keeps
//! text as `<text>` elements, with a font stack that starts with DejaVu Sans
//! and ends in the viewer's `sans-serif`.

use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::prepare::{
    prepare, Frame, LegendSample, Prepared, PreparedMarker, PreparedPanel, Shape,
};
use super::spec::{Figure, MarkerStyle, Rgb};
use super::text::{self, CrispText, FONT_TTF, PLOTTERS_SIZE_PER_EM};
use crate::error::{Error, Result};

/// Font family name written into the SVG and under which the embedded font
/// is registered with `plotters`.
const FAMILY: &str = "DejaVu Sans, Bitstream Vera Sans, Verdana, sans-serif";

/// Registers the embedded font once per process (the SVG text is measured
/// with it) and checks that our own text layout can parse it.
fn ensure_font() -> Result<()> {
    static REGISTERED: OnceLock<std::result::Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            plotters::style::register_font(FAMILY, FontStyle::Normal, FONT_TTF)
                .map_err(|_| "the embedded DejaVu Sans font could not be parsed".to_string())?;
            text::font()
                .map(|_| ())
                .ok_or_else(|| "the embedded DejaVu Sans font could not be parsed".to_string())
        })
        .clone()
        .map_err(|reason| Error::Report {
            what: "font".into(),
            reason,
        })
}

/// Text sizes, px of an em at scale 1 (the SVG's `font-size`). A 900 px
/// figure printed 17 cm wide puts a 16 px tick label at 8.5 pt, above the
/// 7–8 pt journals ask of figure text.
pub(crate) const TICK_PX: f64 = 16.0;
const AXIS_TITLE_PX: f64 = 17.0;
const FIGURE_TITLE_PX: f64 = 20.0;
const PANEL_TITLE_PX: f64 = 16.0;
const LEGEND_PX: f64 = 15.0;
const MARKER_PX: f64 = 14.0;

/// Panel layout, px at scale 1: strips above the plot for the panel title
/// and the legend (so a legend never covers data), the axis label areas and
/// the margins around the plot.
const PANEL_TITLE_STRIP: f64 = 26.0;
const LEGEND_ROW: f64 = 24.0;
const LEGEND_SAMPLE: f64 = 26.0;
const LEGEND_GAP: f64 = 6.0;
const LEGEND_SPACING: f64 = 22.0;
const MARGIN_TOP: f64 = 10.0;
const MARGIN_RIGHT: f64 = 26.0;
const MARGIN_LEFT: f64 = 8.0;
const MARGIN_BOTTOM: f64 = 4.0;
const X_LABEL_AREA: f64 = 60.0;
const Y_LABEL_AREA: f64 = 106.0;
/// Tick label bands beside the plot that the interactive layer redraws:
/// the x tick labels lie within this height under the plot, the y tick
/// labels within this width left of it (the axis titles are further out).
pub(crate) const X_TICK_BAND: f64 = 32.0;
pub(crate) const Y_TICK_BAND: f64 = 78.0;

/// Where one panel's plot lies in the image (SVG user units), for the
/// interactive layer of the HTML report.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PanelGeometry {
    /// Left, top, right, bottom of the plot area, px.
    pub plot: [i32; 4],
}

/// An SVG image of a figure and the notes made while drawing it.
#[derive(Debug, Clone, PartialEq)]
pub struct Rendered {
    /// The SVG document (UTF-8, starts with `<svg`, has a `viewBox`).
    pub svg: String,
    /// What was left out of the drawing and why (NaN points, non-positive
    /// values on a log axis, error bars cut at a log axis). The report lists
    /// these under "Drawing notes".
    pub warnings: Vec<String>,
    /// Each panel's plot area, for the interactive layer.
    pub(crate) geometry: Vec<PanelGeometry>,
}

/// Height of the figure title strip, px at scale 1.
const TITLE_PX: f64 = 38.0;

fn size(fig: &Figure, p: &Prepared, scale: u32) -> (u32, u32) {
    let title = if p.title.is_empty() { 0.0 } else { TITLE_PX };
    let h = title + (fig.panel_height_px as usize * p.panels.len()) as f64;
    (fig.width_px * scale, (h * scale as f64).round() as u32)
}

/// Draws `fig` as an SVG document.
///
/// Long line series are thinned for display (see the module docs of
/// `report::prepare`: M4 per pixel column); the figure's data is not changed.
///
/// # Errors
///
/// [`Error::Report`] when the figure is malformed (see [`Figure`]'s field
/// docs: bad id, length mismatch, bad range, nothing drawable) or drawing
/// fails.
pub fn render_svg(fig: &Figure) -> Result<Rendered> {
    ensure_font()?;
    let p = prepare(fig, fig.width_px as usize)?;
    let (w, h) = size(fig, &p, 1);
    let mut svg = String::new();
    let geometry;
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        geometry = draw(&root, &p, 1.0, false).map_err(|e| draw_err(fig, e))?;
        root.present().map_err(|e| draw_err(fig, e))?;
    }
    Ok(Rendered {
        svg,
        warnings: p.warnings,
        geometry,
    })
}

/// Draws `fig` as a PNG image (8-bit RGB), `scale` times the figure's pixel
/// size (2 gives crisp text on high-density screens and in print).
///
/// # Errors
///
/// As [`render_svg`], and [`Error::Report`] when `scale` is not 1..=4.
pub fn render_png(fig: &Figure, scale: u32) -> Result<Vec<u8>> {
    if !(1..=4).contains(&scale) {
        return Err(Error::Report {
            what: format!("figure '{}'", fig.id),
            reason: format!("PNG scale {scale} is not in 1..=4"),
        });
    }
    ensure_font()?;
    let p = prepare(fig, (fig.width_px * scale) as usize)?;
    let (w, h) = size(fig, &p, scale);
    let mut rgb = vec![0u8; w as usize * h as usize * 3];
    {
        let root = CrispText {
            inner: BitMapBackend::with_buffer(&mut rgb, (w, h)),
        }
        .into_drawing_area();
        draw(&root, &p, scale as f64, true).map_err(|e| draw_err(fig, e))?;
        root.present().map_err(|e| draw_err(fig, e))?;
    }
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let png_err = |e: png::EncodingError| Error::Report {
            what: format!("figure '{}'", fig.id),
            reason: format!("PNG encoding failed: {e}"),
        };
        let mut writer = enc.write_header().map_err(png_err)?;
        writer.write_image_data(&rgb).map_err(png_err)?;
        writer.finish().map_err(png_err)?;
    }
    Ok(out)
}

fn draw_err<E: std::fmt::Display>(fig: &Figure, e: E) -> Error {
    Error::Report {
        what: format!("figure '{}'", fig.id),
        reason: format!("drawing failed: {e}"),
    }
}

fn rgb(c: Rgb) -> RGBColor {
    RGBColor(c.0, c.1, c.2)
}

/// A text style whose em is `em_px` pixels (`plotters` sizes text by
/// 1.24 em, see [`PLOTTERS_SIZE_PER_EM`]).
fn font(em_px: f64) -> TextStyle<'static> {
    TextStyle::from((FAMILY, em_px * PLOTTERS_SIZE_PER_EM)).color(&BLACK)
}

type DrawResult<DB, T = ()> =
    std::result::Result<T, DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

/// `bitmap`: the target rasterises thick polylines itself (see `draw_panel`).
fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    p: &Prepared,
    s: f64,
    bitmap: bool,
) -> DrawResult<DB, Vec<PanelGeometry>> {
    root.fill(&WHITE)?;
    let body = if p.title.is_empty() {
        root.clone()
    } else {
        let (top, rest) = root.split_vertically((TITLE_PX * s) as u32);
        let (w, h) = top.dim_in_pixel();
        let (title, em) = fit_text(&p.title, FIGURE_TITLE_PX * s, f64::from(w) - 24.0 * s, s);
        top.draw(&Text::new(
            title,
            ((w / 2) as i32, (h / 2) as i32 + (3.0 * s) as i32),
            font(em).pos(Pos::new(HPos::Center, VPos::Center)),
        ))?;
        rest
    };
    let areas = body.split_evenly((p.panels.len(), 1));
    let mut geometry = Vec::with_capacity(p.panels.len());
    for (area, panel) in areas.iter().zip(&p.panels) {
        geometry.push(draw_panel(area, panel, s, bitmap)?);
    }
    Ok(geometry)
}

/// A title that fits `max_px`: drawn smaller down to 13 px, then cut in the
/// middle with an ellipsis (a long file path keeps its start and its name).
fn fit_text(text: &str, em: f64, max_px: f64, s: f64) -> (String, f64) {
    let w = text::text_width(text, em);
    if w <= max_px {
        return (text.to_string(), em);
    }
    let small = (em * max_px / w).max(13.0 * s).min(em);
    if text::text_width(text, small) <= max_px {
        return (text.to_string(), small);
    }
    let chars: Vec<char> = text.chars().collect();
    let mut keep = chars.len();
    while keep > 2 {
        keep -= 1;
        let head: String = chars[..keep / 2].iter().collect();
        let tail: String = chars[chars.len() - (keep - keep / 2)..].iter().collect();
        let t = format!("{head}…{tail}");
        if text::text_width(&t, small) <= max_px {
            return (t, small);
        }
    }
    ("…".into(), small)
}

/// One legend entry laid out: which series, and its width in px.
struct LegendEntry<'a> {
    series: &'a super::prepare::PreparedSeries,
    width: f64,
}

/// The legend entries of a panel in rows that fit `avail` px, in declared
/// order; empty when the panel shows no legend.
fn legend_rows<'a>(p: &'a PreparedPanel, avail: f64, s: f64) -> Vec<Vec<LegendEntry<'a>>> {
    if !p.legend {
        return Vec::new();
    }
    let mut named: Vec<&super::prepare::PreparedSeries> =
        p.series.iter().filter(|x| !x.name.is_empty()).collect();
    named.sort_by_key(|x| x.index);
    let mut rows: Vec<Vec<LegendEntry<'a>>> = Vec::new();
    let mut used = 0.0;
    for series in named {
        let width =
            (LEGEND_SAMPLE + LEGEND_GAP) * s + text::text_width(&series.name, LEGEND_PX * s);
        let start_new = rows.is_empty() || used + width > avail;
        if start_new {
            rows.push(Vec::new());
            used = 0.0;
        }
        used += width + LEGEND_SPACING * s;
        rows.last_mut()
            .expect("a row was pushed")
            .push(LegendEntry { series, width });
    }
    rows
}

/// Draws the legend rows in the strip `area`, starting at `x0` (the left
/// edge of the plot).
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    rows: &[Vec<LegendEntry<'_>>],
    x0: f64,
    s: f64,
) -> DrawResult<DB> {
    for (r, row) in rows.iter().enumerate() {
        let y = ((r as f64 + 0.5) * LEGEND_ROW * s).round() as i32;
        let mut x = x0;
        for e in row {
            let color = rgb(e.series.color);
            let style = color.stroke_width(((e.series.stroke_px * s).round() as u32).max(1));
            let (a, b) = (x.round() as i32, (x + LEGEND_SAMPLE * s).round() as i32);
            match e.series.legend {
                LegendSample::Line => area.draw(&PathElement::new(vec![(a, y), (b, y)], style))?,
                LegendSample::Dashed => {
                    let dash = (6.0 * s) as i32;
                    let gap = (4.0 * s) as i32;
                    let mut u = a;
                    while u < b {
                        area.draw(&PathElement::new(
                            vec![(u, y), ((u + dash).min(b), y)],
                            style,
                        ))?;
                        u += dash + gap;
                    }
                }
                LegendSample::Point => area.draw(&Circle::new(
                    ((a + b) / 2, y),
                    (3.5 * s).round() as i32,
                    color.filled(),
                ))?,
            }
            area.draw(&Text::new(
                e.series.name.clone(),
                (((LEGEND_SAMPLE + LEGEND_GAP) * s + x).round() as i32, y),
                font(LEGEND_PX * s).pos(Pos::new(HPos::Left, VPos::Center)),
            ))?;
            x += e.width + LEGEND_SPACING * s;
        }
    }
    Ok(())
}

/// A linear coordinate over axis space with our own tick positions.
struct AxisCoord {
    lo: f64,
    hi: f64,
    major: Vec<f64>,
    minor: Vec<f64>,
}

impl plotters::coord::ranged1d::Ranged for AxisCoord {
    type FormatOption = plotters::coord::ranged1d::DefaultFormatting;
    type ValueType = f64;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let frac = (v - self.lo) / (self.hi - self.lo);
        limit.0 + ((limit.1 - limit.0) as f64 * frac + 1e-3).floor() as i32
    }

    fn key_points<Hint: plotters::coord::ranged1d::KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.minor.clone()
        } else {
            self.major.clone()
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.lo..self.hi
    }
}

/// Tick label for axis-space position `v` (the label of the nearest major tick).
fn label_at(frame: &Frame, v: f64) -> String {
    let tol = (frame.hi - frame.lo).abs() * 1e-9;
    frame
        .ticks
        .major
        .iter()
        .find(|(t, _)| (t - v).abs() <= tol)
        .map(|(_, l)| l.clone())
        .unwrap_or_default()
}

/// Draws one panel.
///
/// On a bitmap, `plotters` turns a thick polyline into one polygon whose
/// joins spike far out at the sharp reversals of decimated data (and at
/// repeated pixels), so there every thick line is drawn as separate
/// two-point strokes, skipping those of zero pixel length. SVG polylines are
/// joined by the viewer and drawn whole.
fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    p: &PreparedPanel,
    s: f64,
    bitmap: bool,
) -> DrawResult<DB, PanelGeometry> {
    let (w, _) = area.dim_in_pixel();
    let plot_x0 = (MARGIN_LEFT + Y_LABEL_AREA) * s;
    let plot_x1 = f64::from(w) - MARGIN_RIGHT * s;
    let mut rest = area.clone();
    if !p.title.is_empty() {
        let (top, below) = rest.split_vertically((PANEL_TITLE_STRIP * s) as u32);
        let (_, h) = top.dim_in_pixel();
        let (title, em) = fit_text(&p.title, PANEL_TITLE_PX * s, plot_x1 - plot_x0, s);
        top.draw(&Text::new(
            title,
            (((plot_x0 + plot_x1) / 2.0) as i32, (h as f64 * 0.6) as i32),
            font(em).pos(Pos::new(HPos::Center, VPos::Center)),
        ))?;
        rest = below;
    }
    let rows = legend_rows(p, plot_x1 - plot_x0, s);
    if !rows.is_empty() {
        let (strip, below) =
            rest.split_vertically((rows.len() as f64 * LEGEND_ROW * s + 4.0 * s) as u32);
        draw_legend(&strip, &rows, plot_x0, s)?;
        rest = below;
    }
    let x_key: Vec<f64> = p.x.ticks.major.iter().map(|t| t.0).collect();
    let y_key: Vec<f64> = p.y.ticks.major.iter().map(|t| t.0).collect();
    let mut builder = ChartBuilder::on(&rest);
    builder
        .margin_top((MARGIN_TOP * s) as u32)
        .margin_right((MARGIN_RIGHT * s) as u32)
        .margin_left((MARGIN_LEFT * s) as u32)
        .margin_bottom((MARGIN_BOTTOM * s) as u32)
        .x_label_area_size((X_LABEL_AREA * s) as u32)
        .y_label_area_size((Y_LABEL_AREA * s) as u32);
    let mut chart = builder.build_cartesian_2d(
        AxisCoord {
            lo: p.x.lo,
            hi: p.x.hi,
            major: x_key,
            minor: p.x.ticks.minor.clone(),
        },
        AxisCoord {
            lo: p.y.lo,
            hi: p.y.hi,
            major: y_key,
            minor: p.y.ticks.minor.clone(),
        },
    )?;
    let x_fmt = |v: &f64| label_at(&p.x, *v);
    let y_fmt = |v: &f64| label_at(&p.y, *v);
    chart
        .configure_mesh()
        .x_desc(p.x.title.as_str())
        .y_desc(p.y.title.as_str())
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .x_labels(100)
        .y_labels(100)
        .max_light_lines(100)
        .label_style(font(TICK_PX * s))
        .axis_desc_style(font(AXIS_TITLE_PX * s))
        .bold_line_style(RGBColor(215, 215, 215).stroke_width((1.0 * s) as u32))
        .light_line_style(RGBColor(238, 238, 238).stroke_width((1.0 * s) as u32))
        .axis_style(BLACK.stroke_width((1.0 * s).max(1.0) as u32))
        .set_all_tick_mark_size((5.0 * s) as u32)
        .draw()?;
    let (xr, yr) = chart.plotting_area().get_pixel_range();
    let geometry = PanelGeometry {
        plot: [xr.start, yr.start, xr.end, yr.end],
    };

    // frame around the plotting area
    chart.draw_series(std::iter::once(Rectangle::new(
        [(p.x.lo, p.y.lo), (p.x.hi, p.y.hi)],
        BLACK.stroke_width((1.0 * s).max(1.0) as u32),
    )))?;

    // A vertical marker's label is kept when it starts after the previous
    // kept label and either fits before the next marker line or leads a
    // crowd of lines (the first of 1.1 Hz harmonics on a 0–500 Hz axis):
    // the rest of a crowd stays unlabelled.
    let mut order: Vec<&PreparedMarker> = p.vlines.iter().collect();
    order.sort_by(|a, b| a.at.total_cmp(&b.at));
    let px: Vec<f64> = order
        .iter()
        .map(|m| f64::from(chart.backend_coord(&(m.at, p.y.hi)).0))
        .collect();
    let mut last_right = f64::NEG_INFINITY;
    for (i, m) in order.iter().enumerate() {
        let mut m = (*m).clone();
        if !m.label.is_empty() {
            let w = text::text_width(&m.label, MARKER_PX * s) + 8.0 * s;
            let next = px.get(i + 1).copied().unwrap_or(f64::from(xr.end));
            let room_right = next - px[i] >= w || i + 1 == px.len();
            let leads = i == 0 || px[i] - px[i - 1] >= w;
            if !(room_right || leads) || px[i] < last_right {
                m.label.clear();
            } else {
                last_right = px[i] + w;
            }
        }
        draw_marker(&mut chart, &m, [(m.at, p.y.lo), (m.at, p.y.hi)], s, xr.end)?;
    }
    for m in &p.hlines {
        draw_marker(&mut chart, m, [(p.x.lo, m.at), (p.x.hi, m.at)], s, xr.end)?;
    }

    for series in &p.series {
        let color = rgb(series.color);
        let width = ((series.stroke_px * s).round() as u32).max(1);
        let line_style = color.stroke_width(width);
        let r = (3.0 * s).round() as i32;
        for shape in &series.shapes {
            match shape {
                Shape::Lines { segments, dashed } => {
                    for seg in segments {
                        if *dashed {
                            chart.draw_series(DashedLineSeries::new(
                                seg.iter().copied(),
                                (7.0 * s) as u32,
                                (4.0 * s) as u32,
                                line_style,
                            ))?;
                        } else if bitmap && width > 1 {
                            let strokes =
                                pixel_strokes(&chart, seg.windows(2).map(|w| (w[0], w[1])));
                            chart.draw_series(
                                strokes
                                    .into_iter()
                                    .map(|(a, b)| PathElement::new(vec![a, b], line_style)),
                            )?;
                        } else {
                            chart.draw_series(LineSeries::new(seg.iter().copied(), line_style))?;
                        }
                    }
                }
                Shape::Points(pts) => {
                    chart.draw_series(pts.iter().map(|&pt| Circle::new(pt, r, color.filled())))?;
                }
                Shape::Stems { base, points } => {
                    let strokes =
                        pixel_strokes(&chart, points.iter().map(|&(x, y)| ((x, *base), (x, y))));
                    chart.draw_series(
                        strokes
                            .into_iter()
                            .map(|(a, b)| PathElement::new(vec![a, b], line_style)),
                    )?;
                    chart
                        .draw_series(points.iter().map(|&pt| Circle::new(pt, r, color.filled())))?;
                }
                Shape::Bars(bars) => {
                    let cap = (4.0 * s).round() as i32;
                    let strokes = pixel_strokes(
                        &chart,
                        bars.iter().map(|&(x, _, lo, hi)| ((x, lo), (x, hi))),
                    );
                    chart.draw_series(
                        strokes
                            .into_iter()
                            .map(|(a, b)| PathElement::new(vec![a, b], line_style)),
                    )?;
                    for &(x, _, lo, hi) in bars {
                        chart.draw_series([lo, hi].into_iter().map(|yb| {
                            EmptyElement::at((x, yb))
                                + PathElement::new(
                                    vec![(-cap, 0), (cap, 0)],
                                    color.stroke_width(width),
                                )
                        }))?;
                    }
                    chart.draw_series(
                        bars.iter()
                            .map(|&(x, y, _, _)| Circle::new((x, y), r, color.filled())),
                    )?;
                }
            }
        }
    }

    Ok(geometry)
}

/// The strokes whose ends fall on different pixels (a zero-length thick
/// stroke has no direction and rasterises to garbage).
fn pixel_strokes<DB: DrawingBackend>(
    chart: &ChartContext<'_, DB, Cartesian2d<AxisCoord, AxisCoord>>,
    strokes: impl Iterator<Item = ((f64, f64), (f64, f64))>,
) -> Vec<((f64, f64), (f64, f64))> {
    strokes
        .filter(|(a, b)| chart.backend_coord(a) != chart.backend_coord(b))
        .collect()
}

/// Draws a marker line and its label: a vertical line's label to the
/// right of its top end, or to the left when it would run past the plot's
/// right edge `right_px`; a horizontal line's above its right end.
fn draw_marker<DB: DrawingBackend, X, Y>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, Y>>,
    m: &PreparedMarker,
    ends: [(f64, f64); 2],
    s: f64,
    right_px: i32,
) -> DrawResult<DB>
where
    X: plotters::coord::ranged1d::Ranged<ValueType = f64>,
    Y: plotters::coord::ranged1d::Ranged<ValueType = f64>,
{
    let (color, dashed) = match m.style {
        MarkerStyle::RedDashed => (rgb(Rgb::RED), true),
        MarkerStyle::BlackDashed => (BLACK, true),
        MarkerStyle::GreySolid => (RGBColor(150, 150, 150), false),
    };
    let style = color.stroke_width(((1.5 * s).round() as u32).max(1));
    if dashed {
        chart.draw_series(DashedLineSeries::new(
            ends,
            (8.0 * s) as u32,
            (5.0 * s) as u32,
            style,
        ))?;
    } else {
        chart.draw_series(LineSeries::new(ends, style))?;
    }
    if !m.label.is_empty() {
        let vertical = ends[0].0 == ends[1].0;
        let width = text::text_width(&m.label, MARKER_PX * s);
        let x_px = chart.backend_coord(&ends[1]).0;
        let (anchor, offset, pos) =
            if vertical && f64::from(x_px) + 4.0 * s + width > f64::from(right_px) {
                // top end, text left of the line (it would leave the plot)
                (
                    ends[1],
                    ((-4.0 * s) as i32, (3.0 * s) as i32),
                    Pos::new(HPos::Right, VPos::Top),
                )
            } else if vertical {
                // top end, text right of the line
                (
                    ends[1],
                    ((4.0 * s) as i32, (3.0 * s) as i32),
                    Pos::new(HPos::Left, VPos::Top),
                )
            } else {
                // right end, text above the line
                (
                    ends[1],
                    ((-4.0 * s) as i32, (-3.0 * s) as i32),
                    Pos::new(HPos::Right, VPos::Bottom),
                )
            };
        chart.draw_series(std::iter::once(
            EmptyElement::at(anchor)
                + Text::new(
                    m.label.clone(),
                    offset,
                    font(MARKER_PX * s).color(&color).pos(pos),
                ),
        ))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::{Axis, Panel, Series};

    /// Text elements of an SVG: (text, x, y, font-size).
    fn texts(svg: &str) -> Vec<(String, f64, f64, f64)> {
        let doc = roxmltree::Document::parse(svg).unwrap();
        doc.descendants()
            .filter(|n| n.has_tag_name("text"))
            .map(|n| {
                let num = |a: &str| n.attribute(a).and_then(|v| v.parse().ok()).unwrap_or(0.0);
                (
                    n.text().unwrap_or("").trim().to_string(),
                    num("x"),
                    num("y"),
                    num("font-size"),
                )
            })
            .collect()
    }

    /// Regression: legends were drawn inside the plot, over the data (the
    /// demo's Figs. 11, 12, 23, 25). They sit in a strip above the plot.
    #[test]
    fn legends_are_above_the_plot_not_on_the_data() {
        let x: Vec<f64> = (0..100).map(f64::from).collect();
        let fig = Figure::new("l", "Legend").with_panel(
            Panel::new(Axis::linear("x", "s"), Axis::linear("y", "N"))
                .with_series(Series::line("rising", x.clone(), x.clone()))
                .with_series(Series::line("flat at the top", x.clone(), vec![99.0; 100]))
                .titled("(a) panel"),
        );
        let r = render_svg(&fig).unwrap();
        let top = f64::from(r.geometry[0].plot[1]);
        let t = texts(&r.svg);
        for name in ["rising", "flat at the top"] {
            let (_, _, y, _) = t.iter().find(|x| x.0 == name).expect(name);
            assert!(*y < top, "legend '{name}' at y = {y}, plot starts at {top}");
        }
        // and under the panel title
        let (_, _, y_title, _) = t.iter().find(|x| x.0 == "(a) panel").unwrap();
        let (_, _, y_legend, _) = t.iter().find(|x| x.0 == "rising").unwrap();
        assert!(y_title < y_legend);
    }

    /// Regression: tick labels were 10.5 px (13 / 1.24), small in print.
    /// At 900 px printed 17 cm wide, 16 px is 8.5 pt; no text is below 14 px.
    #[test]
    fn text_is_legible_at_print_size() {
        let x: Vec<f64> = (0..100).map(f64::from).collect();
        let fig = Figure::new("t", "Ticks").with_panel(
            Panel::new(Axis::linear("Frequency", "Hz"), Axis::log("PSD", "N²/Hz"))
                .with_series(Series::line(
                    "p",
                    x.clone(),
                    x.iter().map(|v| 1.0 + v * v).collect(),
                ))
                .with_vlines(crate::report::Marker::harmonics(20.0, 3, "f_c")),
        );
        let t = texts(&render_svg(&fig).unwrap().svg);
        let tick = t.iter().find(|x| x.0 == "20").expect("a tick label 20");
        assert!((tick.3 - TICK_PX).abs() < 1e-9, "tick font-size {}", tick.3);
        for (s, _, _, size) in &t {
            assert!(*size >= 14.0 - 1e-9, "'{s}' at {size} px");
        }
    }

    /// Labels of crowded markers are left out where they would run into the
    /// next line (harmonics of 1.1 Hz on a 0–500 Hz axis); every line stays.
    #[test]
    fn crowded_marker_labels_are_thinned_but_all_lines_kept() {
        let fig = Figure::new("c", "Crowded").with_panel(
            Panel::new(Axis::linear("f", "Hz"), Axis::log("P", "N²/Hz"))
                .with_series(Series::line("P", vec![0.1, 500.0], vec![1.0, 2.0]))
                .with_vlines(crate::report::Marker::harmonics(1.1, 3, "f_c"))
                .with_vlines([crate::report::Marker::red_dashed(100.0, "far")]),
        );
        let r = render_svg(&fig).unwrap();
        let t: Vec<String> = texts(&r.svg).into_iter().map(|x| x.0).collect();
        assert!(t.contains(&"far".to_string()), "{t:?}");
        assert!(t.contains(&"f_c".to_string()), "the crowd's first: {t:?}");
        for gone in ["2f_c", "3f_c"] {
            assert!(!t.contains(&gone.to_string()), "{gone} in {t:?}");
        }
    }

    /// Regression: long titles (a full file path) ran off the figure. They
    /// are drawn smaller, then cut in the middle.
    #[test]
    fn long_titles_fit_the_figure() {
        let long = format!(
            "{}/v09_r1.csv: optical signal",
            "/a/very/long/folder".repeat(8)
        );
        let (t, em) = fit_text(&long, 20.0, 850.0, 1.0);
        assert!(text::text_width(&t, em) <= 850.0);
        assert!(t.contains('…') && t.ends_with("optical signal"), "{t}");
        let (t, em) = fit_text("short", 20.0, 850.0, 1.0);
        assert_eq!((t.as_str(), em), ("short", 20.0));
    }

    /// A marker label near the right edge is drawn left of its line, inside
    /// the plot (the "f_c" label was clipped).
    #[test]
    fn marker_labels_stay_inside_the_plot() {
        let x: Vec<f64> = (0..=100).map(f64::from).collect();
        let fig = Figure::new("m", "Markers").with_panel(
            Panel::new(
                Axis::linear("x", "Hz").with_range(0.0, 100.0),
                Axis::linear("y", ""),
            )
            .with_series(Series::line("p", x.clone(), x))
            .with_vlines([crate::report::Marker::red_dashed(99.5, "f_c")]),
        );
        let r = render_svg(&fig).unwrap();
        let right = f64::from(r.geometry[0].plot[2]);
        let t = texts(&r.svg);
        let (_, x, _, size) = t.iter().find(|x| x.0 == "f_c").unwrap();
        let w = text::text_width("f_c", *size);
        // anchored at its right end ("end"), left of the line
        assert!(r.svg.contains("text-anchor=\"end\""));
        assert!(
            *x <= right && x - w >= 0.0,
            "label at {x}, plot ends at {right}"
        );
    }
}
