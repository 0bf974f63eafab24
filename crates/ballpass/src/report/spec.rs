//! The data-only description of a figure: what to draw, never how.
//!
//! A [`Figure`] is one or more [`Panel`]s stacked top to bottom. Each panel
//! has two [`Axis`]es (label, unit, linear or log scale, optional range),
//! any number of [`Series`] and vertical / horizontal [`Marker`] lines.
//! Nothing here depends on the drawing library; [`super::render_svg`] and
//! [`super::render_png`] turn a figure into pixels.

/// An sRGB colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Rgb(pub u8, pub u8, pub u8);

impl Rgb {
    /// Black.
    pub const BLACK: Rgb = Rgb(0, 0, 0);
    /// The red of the thesis' dashed marker lines.
    pub const RED: Rgb = Rgb(214, 39, 40);
    /// Mid grey.
    pub const GREY: Rgb = Rgb(127, 127, 127);
    /// The orange of a suspect (worth a look) item.
    pub const ORANGE: Rgb = Rgb(255, 127, 14);

    /// Colours for items that are fine (good bearings): [`Rgb::PALETTE`]
    /// without its red and orange, which mean bad and suspect.
    pub const CALM: [Rgb; 7] = [
        Rgb(31, 119, 180),
        Rgb(44, 160, 44),
        Rgb(148, 103, 189),
        Rgb(23, 190, 207),
        Rgb(140, 86, 75),
        Rgb(127, 127, 127),
        Rgb(188, 189, 34),
    ];

    /// Colour `i` of [`Rgb::CALM`], cycling.
    pub fn calm(i: usize) -> Rgb {
        Rgb::CALM[i % Rgb::CALM.len()]
    }

    /// `#rrggbb`.
    pub fn hex(self) -> String {
        format!("#{:02x}{:02x}{:02x}", self.0, self.1, self.2)
    }

    /// The default series colours, in order (matplotlib's `tab10`).
    pub const PALETTE: [Rgb; 10] = [
        Rgb(31, 119, 180),
        Rgb(255, 127, 14),
        Rgb(44, 160, 44),
        Rgb(214, 39, 40),
        Rgb(148, 103, 189),
        Rgb(140, 86, 75),
        Rgb(227, 119, 194),
        Rgb(127, 127, 127),
        Rgb(188, 189, 34),
        Rgb(23, 190, 207),
    ];

    /// Colour `i` of [`Rgb::PALETTE`], cycling.
    pub fn palette(i: usize) -> Rgb {
        Rgb::PALETTE[i % Rgb::PALETTE.len()]
    }
}

/// How an axis maps values to positions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Scale {
    /// Equal distances for equal differences.
    #[default]
    Linear,
    /// Base-10 logarithmic: equal distances for equal ratios. Only positive
    /// values can be drawn; non-positive ones are left out of the drawing and
    /// reported as a warning (see [`super::Rendered::warnings`]).
    Log,
}

/// One axis of a panel: what is measured, in which unit, on which scale.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// What the axis measures ("Lag τ", "Frequency").
    pub label: String,
    /// Unit symbol ("s", "Hz", "N²/Hz", "dB", "deg"); empty for a
    /// dimensionless quantity. Drawn as `label (unit)`.
    pub unit: String,
    /// Linear or logarithmic.
    pub scale: Scale,
    /// Visible range `(low, high)` in data units, `low < high`; `None` fits
    /// the data (with a small margin). Data outside the range is clipped from
    /// the drawing.
    pub range: Option<(f64, f64)>,
}

impl Axis {
    /// A linear axis fitted to the data.
    pub fn linear(label: impl Into<String>, unit: impl Into<String>) -> Self {
        Axis {
            label: label.into(),
            unit: unit.into(),
            scale: Scale::Linear,
            range: None,
        }
    }

    /// A base-10 logarithmic axis fitted to the data.
    pub fn log(label: impl Into<String>, unit: impl Into<String>) -> Self {
        Axis {
            scale: Scale::Log,
            ..Axis::linear(label, unit)
        }
    }

    /// The same axis with a fixed visible range.
    pub fn with_range(mut self, low: f64, high: f64) -> Self {
        self.range = Some((low, high));
        self
    }

    /// The text drawn along the axis: `label (unit)`, or `label` when the
    /// unit is empty.
    pub fn title(&self) -> String {
        if self.unit.is_empty() {
            self.label.clone()
        } else {
            format!("{} ({})", self.label, self.unit)
        }
    }
}

/// How a series is drawn.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum SeriesStyle {
    /// A solid polyline through the points, in order.
    #[default]
    Line,
    /// A dashed polyline (model curves, fitted lines).
    DashedLine,
    /// A small filled circle at each point.
    Points,
    /// A solid polyline with a circle at each point.
    LinePoints,
    /// A vertical line from the baseline (0, or the bottom of a log axis) to
    /// each point, with a circle on top.
    Stem,
    /// A circle at each point with a vertical bar from `y - minus[i]` to
    /// `y + plus[i]` and caps; `line` also joins the points.
    ErrorBars {
        /// Downward extent of each bar, same length as the data, `>= 0`.
        minus: Vec<f64>,
        /// Upward extent of each bar, same length as the data, `>= 0`.
        plus: Vec<f64>,
        /// Join the points with a solid line as well.
        line: bool,
    },
}

/// One named set of `(x, y)` points.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Name shown in the legend; an empty name keeps the series out of it.
    pub name: String,
    /// Abscissae, in data units of the panel's x axis.
    pub x: Vec<f64>,
    /// Ordinates, same length as `x`.
    pub y: Vec<f64>,
    /// How to draw it.
    pub style: SeriesStyle,
    /// Colour; `None` takes the next colour of [`Rgb::PALETTE`].
    pub color: Option<Rgb>,
    /// Draw this series thicker and on top of the others (the bad bearing of
    /// a fleet); the others are drawn thinner.
    pub highlight: bool,
}

impl Series {
    /// A solid line series.
    pub fn line(name: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Series {
            name: name.into(),
            x,
            y,
            style: SeriesStyle::Line,
            color: None,
            highlight: false,
        }
    }

    /// A series sampled uniformly: `x[i] = x0 + i * dx`.
    pub fn uniform(name: impl Into<String>, x0: f64, dx: f64, y: Vec<f64>) -> Self {
        let x = (0..y.len()).map(|i| x0 + i as f64 * dx).collect();
        Series::line(name, x, y)
    }

    /// A point (scatter) series.
    pub fn points(name: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Series::line(name, x, y).with_style(SeriesStyle::Points)
    }

    /// Points with symmetric error bars `y ± err`.
    pub fn error_bars(name: impl Into<String>, x: Vec<f64>, y: Vec<f64>, err: Vec<f64>) -> Self {
        Series::line(name, x, y).with_style(SeriesStyle::ErrorBars {
            minus: err.clone(),
            plus: err,
            line: false,
        })
    }

    /// The same series drawn in another style.
    pub fn with_style(mut self, style: SeriesStyle) -> Self {
        self.style = style;
        self
    }

    /// The same series in a fixed colour.
    pub fn with_color(mut self, color: Rgb) -> Self {
        self.color = Some(color);
        self
    }

    /// The same series, highlighted.
    pub fn highlighted(mut self) -> Self {
        self.highlight = true;
        self
    }
}

/// How a marker line is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MarkerStyle {
    /// Red dashed, as the thesis marks multiples of `tau_c` and harmonics of `f_c`.
    #[default]
    RedDashed,
    /// Black dashed, as the thesis marks a mean (Fig. 53).
    BlackDashed,
    /// Thin solid grey (a zero line, a threshold).
    GreySolid,
}

/// A vertical or horizontal reference line across a panel.
#[derive(Debug, Clone, PartialEq)]
pub struct Marker {
    /// Position in data units of the axis it crosses.
    pub at: f64,
    /// Short text drawn next to the line ("f_c", "2 τc", "mean 0.31"); empty
    /// for none.
    pub label: String,
    /// Line style.
    pub style: MarkerStyle,
}

impl Marker {
    /// A red dashed marker.
    pub fn red_dashed(at: f64, label: impl Into<String>) -> Self {
        Marker {
            at,
            label: label.into(),
            style: MarkerStyle::RedDashed,
        }
    }

    /// A black dashed marker.
    pub fn black_dashed(at: f64, label: impl Into<String>) -> Self {
        Marker {
            at,
            label: label.into(),
            style: MarkerStyle::BlackDashed,
        }
    }

    /// Red dashed markers at every integer multiple `k * period` (k ≠ 0 unless
    /// `include_zero`) that lies in `[low, high]`. Only `±period` is labelled,
    /// with `symbol` ("τc" → "τc", "−τc").
    ///
    /// Returns no markers when `period` is not finite and positive, or when
    /// more than 200 multiples fall in the range (they would paint the panel red).
    pub fn multiples(
        period: f64,
        low: f64,
        high: f64,
        symbol: &str,
        include_zero: bool,
    ) -> Vec<Marker> {
        if !(period.is_finite() && period > 0.0 && low.is_finite() && high.is_finite()) {
            return Vec::new();
        }
        let k_lo = (low / period).ceil() as i64;
        let k_hi = (high / period).floor() as i64;
        if k_hi < k_lo || k_hi - k_lo > 200 {
            return Vec::new();
        }
        (k_lo..=k_hi)
            .filter(|&k| include_zero || k != 0)
            .map(|k| {
                let label = match k {
                    1 => symbol.to_string(),
                    -1 => format!("−{symbol}"),
                    _ => String::new(),
                };
                Marker::red_dashed(k as f64 * period, label)
            })
            .collect()
    }

    /// Red dashed markers at the fundamental `f0` and its harmonics `k * f0`,
    /// `k = 1..=n`, labelled `symbol`, `2symbol`, ...
    pub fn harmonics(f0: f64, n: usize, symbol: &str) -> Vec<Marker> {
        if !(f0.is_finite() && f0 > 0.0) {
            return Vec::new();
        }
        (1..=n)
            .map(|k| {
                let label = if k == 1 {
                    symbol.to_string()
                } else {
                    format!("{k}{symbol}")
                };
                Marker::red_dashed(k as f64 * f0, label)
            })
            .collect()
    }
}

/// One plot: two axes, the series drawn on them and reference lines.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// Sub-title above the panel ("(a) full range"); empty for none.
    pub title: String,
    /// Horizontal axis.
    pub x: Axis,
    /// Vertical axis.
    pub y: Axis,
    /// The data, drawn in order (highlighted series last).
    pub series: Vec<Series>,
    /// Vertical lines at x positions.
    pub vlines: Vec<Marker>,
    /// Horizontal lines at y positions.
    pub hlines: Vec<Marker>,
    /// Show a legend of the named series (in a strip above the plot, never
    /// over the data); `None` shows one when two or more series have names.
    pub legend: Option<bool>,
}

impl Panel {
    /// An empty panel with two axes.
    pub fn new(x: Axis, y: Axis) -> Self {
        Panel {
            title: String::new(),
            x,
            y,
            series: Vec::new(),
            vlines: Vec::new(),
            hlines: Vec::new(),
            legend: None,
        }
    }

    /// The same panel with a sub-title.
    pub fn titled(mut self, title: impl Into<String>) -> Self {
        self.title = title.into();
        self
    }

    /// The same panel with one more series.
    pub fn with_series(mut self, series: Series) -> Self {
        self.series.push(series);
        self
    }

    /// The same panel with more vertical markers.
    pub fn with_vlines(mut self, markers: impl IntoIterator<Item = Marker>) -> Self {
        self.vlines.extend(markers);
        self
    }

    /// The same panel with more horizontal markers.
    pub fn with_hlines(mut self, markers: impl IntoIterator<Item = Marker>) -> Self {
        self.hlines.extend(markers);
        self
    }

    /// Whether the legend is drawn.
    pub fn shows_legend(&self) -> bool {
        self.legend
            .unwrap_or_else(|| self.series.iter().filter(|s| !s.name.is_empty()).count() >= 2)
    }
}

/// Default figure width, px.
pub const DEFAULT_WIDTH_PX: u32 = 900;
/// Default height of one panel, px.
pub const DEFAULT_PANEL_HEIGHT_PX: u32 = 300;

/// A data file behind a figure, linked under it in the report.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DataFile {
    /// Path relative to the report's folder (`analyze/spectra.csv`), or an
    /// absolute path (an input recording).
    pub path: String,
    /// Which columns or part of it the figure shows, in a few words.
    pub what: String,
}

/// A figure: panels stacked top to bottom under one title, with a caption.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// File stem of the figure (`figures/<id>.svg`) and its anchor in the
    /// report: ASCII letters, digits, `_` and `-` only, unique in a report.
    pub id: String,
    /// Title drawn above the panels.
    pub title: String,
    /// Caption printed under the figure in the report (not drawn in the
    /// image): what is shown, with which settings.
    pub caption: String,
    /// The panels, top to bottom; at least one.
    pub panels: Vec<Panel>,
    /// Width of the image, px (SVG user units).
    pub width_px: u32,
    /// Height of each panel, px.
    pub panel_height_px: u32,
    /// The data files behind the figure, linked under it in the report.
    pub data: Vec<DataFile>,
    /// Whether the HTML report lets the reader zoom, pan and read values
    /// off this figure (its line and point series are embedded, thinned to
    /// a few thousand points per pixel row; the static SVG stays for
    /// readers without scripts).
    pub interactive: bool,
}

impl Figure {
    /// A figure with the default size and no panels yet.
    pub fn new(id: impl Into<String>, title: impl Into<String>) -> Self {
        Figure {
            id: id.into(),
            title: title.into(),
            caption: String::new(),
            panels: Vec::new(),
            width_px: DEFAULT_WIDTH_PX,
            panel_height_px: DEFAULT_PANEL_HEIGHT_PX,
            data: Vec::new(),
            interactive: false,
        }
    }

    /// The same figure with one more data file linked under it.
    pub fn with_data(mut self, path: impl Into<String>, what: impl Into<String>) -> Self {
        self.data.push(DataFile {
            path: path.into(),
            what: what.into(),
        });
        self
    }

    /// The same figure, zoomable in the HTML report (see
    /// [`Figure::interactive`]).
    pub fn interactive(mut self) -> Self {
        self.interactive = true;
        self
    }

    /// The same figure with a caption.
    pub fn with_caption(mut self, caption: impl Into<String>) -> Self {
        self.caption = caption.into();
        self
    }

    /// The same figure with one more panel at the bottom.
    pub fn with_panel(mut self, panel: Panel) -> Self {
        self.panels.push(panel);
        self
    }

    /// The same figure with another size.
    pub fn with_size(mut self, width_px: u32, panel_height_px: u32) -> Self {
        self.width_px = width_px;
        self.panel_height_px = panel_height_px;
        self
    }
}
