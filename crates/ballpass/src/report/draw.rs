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
use crate::error::{Error, Result};

/// The embedded font (DejaVu Sans, Bitstream Vera licence, see
/// `assets/fonts/DejaVuSans-LICENSE.txt`).
static FONT_TTF: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Font family name written into the SVG and under which the embedded font
/// is registered with `plotters`.
const FAMILY: &str = "DejaVu Sans, Bitstream Vera Sans, Verdana, sans-serif";

/// Registers the embedded font once per process.
fn ensure_font() -> Result<()> {
    static REGISTERED: OnceLock<std::result::Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            plotters::style::register_font(FAMILY, FontStyle::Normal, FONT_TTF)
                .map_err(|_| "the embedded DejaVu Sans font could not be parsed".to_string())
        })
        .clone()
        .map_err(|reason| Error::Report {
            what: "font".into(),
            reason,
        })
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
}

/// Height of the figure title strip, px at scale 1.
const TITLE_PX: f64 = 36.0;

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
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        draw(&root, &p, 1.0, false).map_err(|e| draw_err(fig, e))?;
        root.present().map_err(|e| draw_err(fig, e))?;
    }
    Ok(Rendered {
        svg,
        warnings: p.warnings,
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
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
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

fn font(px: f64) -> TextStyle<'static> {
    TextStyle::from((FAMILY, px)).color(&BLACK)
}

type DrawResult<DB> =
    std::result::Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

/// `bitmap`: the target rasterises thick polylines itself (see `draw_panel`).
fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    p: &Prepared,
    s: f64,
    bitmap: bool,
) -> DrawResult<DB> {
    root.fill(&WHITE)?;
    let body = if p.title.is_empty() {
        root.clone()
    } else {
        let (top, rest) = root.split_vertically((TITLE_PX * s) as u32);
        let (w, h) = top.dim_in_pixel();
        top.draw(&Text::new(
            p.title.clone(),
            ((w / 2) as i32, (h / 2) as i32 + (3.0 * s) as i32),
            font(20.0 * s).pos(Pos::new(HPos::Center, VPos::Center)),
        ))?;
        rest
    };
    let areas = body.split_evenly((p.panels.len(), 1));
    for (area, panel) in areas.iter().zip(&p.panels) {
        draw_panel(area, panel, s, bitmap)?;
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
) -> DrawResult<DB> {
    let x_key: Vec<f64> = p.x.ticks.major.iter().map(|t| t.0).collect();
    let y_key: Vec<f64> = p.y.ticks.major.iter().map(|t| t.0).collect();
    let mut builder = ChartBuilder::on(area);
    builder
        .margin_top((8.0 * s) as u32)
        .margin_right((24.0 * s) as u32)
        .margin_left((6.0 * s) as u32)
        .margin_bottom((4.0 * s) as u32)
        .x_label_area_size((46.0 * s) as u32)
        .y_label_area_size((78.0 * s) as u32);
    if !p.title.is_empty() {
        builder.caption(&p.title, font(15.0 * s));
    }
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
        .label_style(font(13.0 * s))
        .axis_desc_style(font(14.0 * s))
        .bold_line_style(RGBColor(215, 215, 215).stroke_width((1.0 * s) as u32))
        .light_line_style(RGBColor(238, 238, 238).stroke_width((1.0 * s) as u32))
        .axis_style(BLACK.stroke_width((1.0 * s).max(1.0) as u32))
        .set_all_tick_mark_size((5.0 * s) as u32)
        .draw()?;

    // frame around the plotting area
    chart.draw_series(std::iter::once(Rectangle::new(
        [(p.x.lo, p.y.lo), (p.x.hi, p.y.hi)],
        BLACK.stroke_width((1.0 * s).max(1.0) as u32),
    )))?;

    for m in &p.vlines {
        draw_marker(&mut chart, m, [(m.at, p.y.lo), (m.at, p.y.hi)], s)?;
    }
    for m in &p.hlines {
        draw_marker(&mut chart, m, [(p.x.lo, m.at), (p.x.hi, m.at)], s)?;
    }

    // legend entries in declared order, whatever the drawing order
    let mut by_index: Vec<&super::prepare::PreparedSeries> = p.series.iter().collect();
    by_index.sort_by_key(|s| s.index);
    for series in by_index {
        if p.legend && !series.name.is_empty() {
            let color = rgb(series.color);
            let line_style = color.stroke_width(((series.stroke_px * s).round() as u32).max(1));
            let r = (3.0 * s).round() as i32;
            let anno = chart.draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?;
            anno.label(series.name.clone());
            let len = (22.0 * s) as i32;
            let (dash, gap) = ((6.0 * s) as i32, (3.0 * s) as i32);
            match series.legend {
                LegendSample::Line => {
                    anno.legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + len, y)], line_style)
                    });
                }
                LegendSample::Dashed => {
                    anno.legend(move |(x, y)| {
                        plotters::element::DashedPathElement::new(
                            vec![(x, y), (x + len, y)],
                            dash,
                            gap,
                            line_style,
                        )
                    });
                }
                LegendSample::Point => {
                    anno.legend(move |(x, y)| Circle::new((x + len / 2, y), r, color.filled()));
                }
            }
        }
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

    if p.legend && p.series.iter().any(|s| !s.name.is_empty()) {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .margin((6.0 * s) as u32)
            .legend_area_size((28.0 * s) as u32)
            .label_font(font(12.0 * s))
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK.mix(0.4))
            .draw()?;
    }
    Ok(())
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

fn draw_marker<DB: DrawingBackend, X, Y>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, Y>>,
    m: &PreparedMarker,
    ends: [(f64, f64); 2],
    s: f64,
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
        let (anchor, offset, pos) = if vertical {
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
                    font(12.0 * s).color(&color).pos(pos),
                ),
        ))?;
    }
    Ok(())
}
