//! Figures (SVG, PNG) and the self-contained HTML report.
//!
//! Commands describe *what* to show as data — a [`Figure`] of stacked
//! [`Panel`]s with [`Axis`]es, [`Series`] and [`Marker`]s, and a [`Report`]
//! with a summary of [`Section`]s — and this module decides *how* it looks.
//! [`render_svg`] and [`render_png`] draw one figure; [`write_report`] writes
//! `report.html` (inline SVG and CSS, no network, no JavaScript) and each
//! figure as `figures/<id>.svg` (and `.png` on request), every file written
//! to a temporary name and renamed into place.
//!
//! Long series are thinned for *display* only (M4 decimation per pixel
//! column, see `prepare`); exported data is never altered.
//!
//! On a log axis, points `<= 0` (and NaN anywhere) cannot be drawn: they are
//! left out of the drawing and each such omission is reported in
//! [`Rendered::warnings`] and in the report's "Drawing notes", never silently.
//! A panel left with nothing drawable, or an explicit log range that is not
//! positive, is an [`Error::Report`](crate::Error::Report).

mod draw;
mod html;
pub mod kinds;
mod prepare;
mod spec;
mod ticks;

pub use draw::{render_png, render_svg, Rendered};
pub use html::{
    escape_html, render_html, write_atomic, write_report, Block, HtmlReport, Level, Report,
    ReportFiles, ReportOptions, Section, Table, Verdict, FIGURES_DIR, REPORT_FILE,
};
pub use spec::{
    Axis, Figure, Marker, MarkerStyle, Panel, Rgb, Scale, Series, SeriesStyle,
    DEFAULT_PANEL_HEIGHT_PX, DEFAULT_WIDTH_PX,
};
