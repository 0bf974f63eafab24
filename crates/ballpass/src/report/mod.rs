//! Figures (SVG, PNG) and the self-contained HTML report.
//!
//! Commands describe *what* to show as data — a [`Figure`] of stacked
//! [`Panel`]s with [`Axis`]es, [`Series`] and [`Marker`]s, and a [`Report`]
//! of [`Section`]s holding text, tables and figures — and this module
//! decides *how* it looks. [`render_svg`] and [`render_png`] draw one
//! figure; [`write_report`] writes `report.html` and each figure as
//! `figures/<id>.svg` (and `.png` on request), every file written to a
//! temporary name and renamed into place.
//!
//! The page (see `page`) opens with a contents list; each figure stands in
//! the section whose text discusses it, numbered in order, and text refers
//! to it as `{fig:<id>}`, written "Figure N" with a link. Under each figure
//! are its caption and links to the data files behind it
//! ([`Figure::with_data`]). The page is one file: figures are inline SVG,
//! the CSS is inline, and figures marked [`Figure::interactive`] carry
//! their data as inline JSON for an inline script (`live.js`) that zooms,
//! pans and reads values under the cursor; nothing is fetched, and with
//! scripts off the page shows the same static figures.
//!
//! Legends stand in a strip above the plot, never over the data; marker
//! labels that would run into the next line or out of the plot are left out
//! or moved; titles too long for the figure are drawn smaller, then cut.
//!
//! Long series are thinned for *display* only (M4 decimation per pixel
//! column, see `prepare`); exported data is never altered.
//!
//! On a log axis, points `<= 0` (and NaN anywhere) cannot be drawn: they are
//! left out of the drawing and each such omission is reported in
//! [`Rendered::warnings`] and in the report's "Drawing notes", never silently.
//! A panel left with nothing drawable, or an explicit log range that is not
//! positive, is an [`Error::Report`](crate::Error::Report).
//!
//! Ready-made figures after the thesis (stacked signals, correlations with
//! `tau_c` markers, spectra with `f_c` harmonics, coherence, pulses with
//! models, Bode, error bars, log-log fits, ratio with mean, fleet overlay)
//! are in [`kinds`]; the figures and summaries of `ballpass analyze` in
//! [`analysis`], of `ballpass passage` in [`passage`], of `ballpass model` in
//! [`model`], and of the campaigns (`sweep`, `diagnose`) in [`campaign`].
//!
//! Text is drawn with the embedded DejaVu Sans (`assets/fonts/`, Bitstream
//! Vera licence) through `ab_glyph`: no fontconfig or system fonts, so PNGs
//! look the same on every machine. PNG text is laid out glyph by glyph at
//! sub-pixel positions (see `text`); sizes are chosen for print (16 px tick
//! labels on a 900 px figure: 8.5 pt at 17 cm).
//!
//! # Example
//!
//! ```
//! use ballpass::report::{self, Axis, Block, Figure, Level, Marker, Panel, Report, Section, Series, Verdict};
//!
//! let tau_c_s = 0.901;
//! let lag_s: Vec<f64> = (-3000..=3000).map(|i| i as f64 * 1e-3).collect();
//! let r: Vec<f64> = lag_s.iter().map(|t| (std::f64::consts::TAU * t / tau_c_s).cos()).collect();
//! let fig = Figure::new("corr_ff", "Autocorrelation of friction force")
//!     .with_caption("Low-pass 20 Hz, linear detrend.")
//!     .with_panel(
//!         Panel::new(Axis::linear("Lag τ", "s"), Axis::linear("R_FF", "N²"))
//!             .with_series(Series::line("R_FF", lag_s, r))
//!             .with_vlines(Marker::multiples(tau_c_s, -3.0, 3.0, "τc", false)),
//!     );
//! let svg = report::render_svg(&fig)?.svg;
//! assert!(svg.starts_with("<svg") && svg.contains("Lag τ (s)"));
//!
//! let report = Report::new("ballpass analyze: 9 mm/s")
//!     .with_section(Section::new("Verdicts").with(Block::Verdicts(vec![Verdict::new(
//!         Level::Pass,
//!         "friction",
//!         "peak at f_c = 1.110 Hz",
//!     )])))
//!     .with_figure(fig);
//! let page = report::render_html(&report, false)?;
//! // no figure is marked interactive: a page without any script
//! assert!(page.html.contains("PASS") && !page.html.contains("<script"));
//! # Ok::<(), ballpass::Error>(())
//! ```

pub mod analysis;
pub mod campaign;
mod draw;
pub mod envelope;
mod html;
pub mod kinds;
mod live;
pub mod model;
mod page;
pub mod passage;
mod position;
mod prepare;
mod spec;
mod sync;
mod text;
mod ticks;

pub use draw::{render_png, render_svg, Rendered};
pub use html::{
    escape_html, render_html, write_report, Block, HtmlReport, Level, Report, ReportFiles,
    ReportOptions, Section, Table, Verdict, FIGURES_DIR, REPORT_FILE,
};
pub use spec::{
    Axis, DataFile, Figure, Marker, MarkerStyle, Panel, Rgb, Scale, Series, SeriesStyle,
    DEFAULT_PANEL_HEIGHT_PX, DEFAULT_WIDTH_PX,
};
