//! The self-contained HTML report and the files written beside it.

use std::fs;
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::draw::{render_png, render_svg};
use super::page;
use super::spec::Figure;
use crate::error::{Error, Result};
use crate::fsutil::write_atomic;

/// How good a verdict is; drawn as a coloured badge.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Level {
    /// As expected / healthy (green "PASS").
    Pass,
    /// Worth a look (amber "WARN").
    Warn,
    /// Not as expected / faulty (red "FAIL").
    Fail,
    /// Information only (grey "INFO").
    Info,
}

impl Level {
    pub(crate) fn badge(self) -> (&'static str, &'static str) {
        match self {
            Level::Pass => ("pass", "PASS"),
            Level::Warn => ("warn", "WARN"),
            Level::Fail => ("fail", "FAIL"),
            Level::Info => ("info", "INFO"),
        }
    }
}

/// One judgement: a badge, what it is about, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Verdict {
    /// Badge.
    pub level: Level,
    /// What is judged ("friction", "bearing 4").
    pub subject: String,
    /// The judgement in words, with the numbers behind it.
    pub text: String,
}

impl Verdict {
    /// A verdict.
    pub fn new(level: Level, subject: impl Into<String>, text: impl Into<String>) -> Self {
        Verdict {
            level,
            subject: subject.into(),
            text: text.into(),
        }
    }
}

/// A table with a header row; every row has as many cells as the header.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Table {
    /// Column titles (with units: "f_c (Hz)").
    pub headers: Vec<String>,
    /// Rows of cells, already formatted.
    pub rows: Vec<Vec<String>>,
}

impl Table {
    /// An empty table with these column titles.
    pub fn new<S: Into<String>>(headers: impl IntoIterator<Item = S>) -> Self {
        Table {
            headers: headers.into_iter().map(Into::into).collect(),
            rows: Vec::new(),
        }
    }

    /// The same table with one more row.
    pub fn with_row<S: Into<String>>(mut self, cells: impl IntoIterator<Item = S>) -> Self {
        self.rows.push(cells.into_iter().map(Into::into).collect());
        self
    }
}

/// One piece of a summary section.
#[derive(Debug, Clone, PartialEq)]
pub enum Block {
    /// A paragraph of plain text.
    Paragraph(String),
    /// Two-column table of names and values ("f_c predicted" → "1.110 Hz").
    KeyValues(Vec<(String, String)>),
    /// A table (prediction vs measurement, per-bearing scores).
    Table(Table),
    /// Verdict badges with their reasons.
    Verdicts(Vec<Verdict>),
    /// Warnings, highlighted.
    Warnings(Vec<String>),
    /// The settings that produced the results, as name → value rows (see
    /// [`Block::settings`]).
    Settings(Vec<(String, String)>),
    /// A figure, placed here next to the text that discusses it. Figures
    /// are numbered in the order they appear in the report.
    Figure(Box<Figure>),
}

impl Block {
    /// The settings block of any serialisable settings struct: nested fields
    /// become dotted names (`welch.nperseg`), arrays of numbers or strings
    /// one comma-separated value.
    ///
    /// # Errors
    ///
    /// [`Error::Report`] when `settings` cannot be serialised to JSON.
    pub fn settings<T: Serialize>(settings: &T) -> Result<Block> {
        let value = serde_json::to_value(settings).map_err(|e| Error::Report {
            what: "settings".into(),
            reason: format!("cannot be serialised: {e}"),
        })?;
        let mut rows = Vec::new();
        flatten("", &value, &mut rows);
        Ok(Block::Settings(rows))
    }
}

fn flatten(prefix: &str, v: &serde_json::Value, out: &mut Vec<(String, String)>) {
    use serde_json::Value;
    let name = |k: &str| {
        if prefix.is_empty() {
            k.to_string()
        } else {
            format!("{prefix}.{k}")
        }
    };
    match v {
        Value::Object(map) => {
            if map.is_empty() {
                out.push((prefix.to_string(), "{}".into()));
            }
            for (k, v) in map {
                flatten(&name(k), v, out);
            }
        }
        Value::Array(items) if items.iter().all(|i| !i.is_object() && !i.is_array()) => {
            let parts: Vec<String> = items.iter().map(scalar).collect();
            out.push((prefix.to_string(), format!("[{}]", parts.join(", "))));
        }
        Value::Array(items) => {
            for (i, v) in items.iter().enumerate() {
                flatten(&name(&i.to_string()), v, out);
            }
        }
        other => out.push((prefix.to_string(), scalar(other))),
    }
}

fn scalar(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::String(s) => s.clone(),
        serde_json::Value::Null => "none".into(),
        other => other.to_string(),
    }
}

/// A titled part of the report: text, tables and figures, then any
/// subsections (a part of the demo report holds a command's sections).
///
/// Text may refer to a figure of the same report by its id as
/// `{fig:<id>}`; the report writes it as a link "Figure N" (N in order of
/// appearance). A reference to an id the report does not have is an error.
#[derive(Debug, Clone, PartialEq)]
pub struct Section {
    /// Heading ("Prediction vs measurement", "Verdicts", "Settings").
    pub heading: String,
    /// Content, in order.
    pub blocks: Vec<Block>,
    /// Sections inside this one, after its blocks.
    pub subsections: Vec<Section>,
}

impl Section {
    /// An empty section.
    pub fn new(heading: impl Into<String>) -> Self {
        Section {
            heading: heading.into(),
            blocks: Vec::new(),
            subsections: Vec::new(),
        }
    }

    /// The same section with one more block.
    pub fn with(mut self, block: Block) -> Self {
        self.blocks.push(block);
        self
    }

    /// The same section with a figure placed after its content so far.
    pub fn with_figure(self, figure: Figure) -> Self {
        self.with(Block::Figure(Box::new(figure)))
    }

    /// The same section with one more subsection.
    pub fn with_subsection(mut self, section: Section) -> Self {
        self.subsections.push(section);
        self
    }

    /// Figures of this section and its subsections, in order.
    fn collect_figures<'a>(&'a self, out: &mut Vec<&'a Figure>) {
        for b in &self.blocks {
            if let Block::Figure(f) = b {
                out.push(f);
            }
        }
        for s in &self.subsections {
            s.collect_figures(out);
        }
    }

    /// Tables of this section and its subsections.
    fn count_tables(&self) -> usize {
        self.blocks
            .iter()
            .filter(|b| matches!(b, Block::Table(_)))
            .count()
            + self
                .subsections
                .iter()
                .map(Section::count_tables)
                .sum::<usize>()
    }
}

/// Everything a report shows: the summary a person reads first, then figures.
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    /// Page title ("ballpass analyze: test 9 mm/s").
    pub title: String,
    /// The command line or a one-line description of what was run; empty for none.
    pub command: String,
    /// ballpass version that produced it ([`crate::VERSION`] by default).
    pub version: String,
    /// Sections, in order (with the figures placed in them).
    pub summary: Vec<Section>,
    /// Figures not placed in a section, shown after the sections under
    /// "Figures", in order. Ids must be unique over the whole report.
    pub figures: Vec<Figure>,
}

impl Report {
    /// An empty report with the current ballpass version.
    pub fn new(title: impl Into<String>) -> Self {
        Report {
            title: title.into(),
            command: String::new(),
            version: crate::VERSION.to_string(),
            summary: Vec::new(),
            figures: Vec::new(),
        }
    }

    /// The same report with the command that produced it.
    pub fn with_command(mut self, command: impl Into<String>) -> Self {
        self.command = command.into();
        self
    }

    /// The same report with one more summary section.
    pub fn with_section(mut self, section: Section) -> Self {
        self.summary.push(section);
        self
    }

    /// The same report with one more figure after the sections (prefer
    /// [`Section::with_figure`], which puts it next to its text).
    pub fn with_figure(mut self, figure: Figure) -> Self {
        self.figures.push(figure);
        self
    }

    /// Every figure in the order the report shows and numbers them: those
    /// placed in sections, then the others.
    pub fn all_figures(&self) -> Vec<&Figure> {
        let mut out = Vec::new();
        for s in &self.summary {
            s.collect_figures(&mut out);
        }
        out.extend(self.figures.iter());
        out
    }

    /// The figure with this id, wherever it is placed.
    pub fn figure_mut(&mut self, id: &str) -> Option<&mut Figure> {
        fn in_section<'a>(s: &'a mut Section, id: &str) -> Option<&'a mut Figure> {
            for b in &mut s.blocks {
                if let Block::Figure(f) = b {
                    if f.id == id {
                        return Some(f);
                    }
                }
            }
            s.subsections.iter_mut().find_map(|x| in_section(x, id))
        }
        if let Some(i) = self.figures.iter().position(|f| f.id == id) {
            return self.figures.get_mut(i);
        }
        self.summary.iter_mut().find_map(|s| in_section(s, id))
    }

    /// How many tables (not counting key–value and settings lists) the
    /// report shows.
    pub fn table_count(&self) -> usize {
        self.summary.iter().map(Section::count_tables).sum()
    }
}

/// What [`write_report`] writes besides `report.html` and the SVGs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReportOptions {
    /// Also write `figures/<id>.png`.
    pub png: bool,
    /// PNG pixels per SVG pixel, 1..=4.
    pub png_scale: u32,
}

impl Default for ReportOptions {
    fn default() -> Self {
        ReportOptions {
            png: false,
            png_scale: 2,
        }
    }
}

/// The files [`write_report`] wrote and the drawing notes it made.
#[derive(Debug, Clone, PartialEq)]
pub struct ReportFiles {
    /// `DIR/report.html`.
    pub html: PathBuf,
    /// `DIR/figures/<id>.svg`, in figure order.
    pub svgs: Vec<PathBuf>,
    /// `DIR/figures/<id>.png`, in figure order (empty unless requested).
    pub pngs: Vec<PathBuf>,
    /// Drawing notes of all figures (also printed in the report under each
    /// figure), each prefixed with its figure id.
    pub warnings: Vec<String>,
}

/// The figure subdirectory of a report directory.
pub const FIGURES_DIR: &str = "figures";
/// The report file name.
pub const REPORT_FILE: &str = "report.html";

/// A report rendered in memory.
#[derive(Debug, Clone, PartialEq)]
pub struct HtmlReport {
    /// The whole HTML document.
    pub html: String,
    /// Drawing notes of all figures (see [`ReportFiles::warnings`]).
    pub warnings: Vec<String>,
}

/// Renders the report as one self-contained HTML document (inline SVG,
/// CSS and script, nothing fetched) without writing anything.
///
/// `png` adds links to `figures/<id>.png` under each figure.
///
/// # Errors
///
/// As [`write_report`], minus the I/O.
pub fn render_html(report: &Report, png: bool) -> Result<HtmlReport> {
    check_report(report)?;
    let figures = report.all_figures();
    let svgs = figures
        .iter()
        .map(|f| render_svg(f))
        .collect::<Result<Vec<_>>>()?;
    let mut warnings = Vec::new();
    let html = page::document(report, &figures, &svgs, png, &mut warnings)?;
    Ok(HtmlReport { html, warnings })
}

/// Figure ids unique, table rows as wide as their header, every figure
/// reference to a figure of the report.
fn check_report(report: &Report) -> Result<()> {
    let mut seen = std::collections::HashSet::new();
    for f in report.all_figures() {
        if !seen.insert(f.id.as_str()) {
            return Err(Error::Report {
                what: format!("figure '{}'", f.id),
                reason: "id is used by another figure of the same report".into(),
            });
        }
    }
    fn walk(s: &Section, ids: &std::collections::HashSet<&str>) -> Result<()> {
        for b in &s.blocks {
            if let Block::Table(t) = b {
                if let Some((i, row)) = t
                    .rows
                    .iter()
                    .enumerate()
                    .find(|(_, r)| r.len() != t.headers.len())
                {
                    return Err(Error::Report {
                        what: format!("section '{}' table", s.heading),
                        reason: format!(
                            "row {} has {} cells but the header has {}",
                            i + 1,
                            row.len(),
                            t.headers.len()
                        ),
                    });
                }
            }
            for text in page::block_texts(b) {
                if let Some(id) = page::figure_refs(text).find(|id| !ids.contains(id)) {
                    return Err(Error::Report {
                        what: format!("section '{}'", s.heading),
                        reason: format!("refers to figure '{id}', which the report does not have"),
                    });
                }
            }
        }
        s.subsections.iter().try_for_each(|x| walk(x, ids))
    }
    report.summary.iter().try_for_each(|s| walk(s, &seen))?;
    for f in report.all_figures() {
        if let Some(id) = page::figure_refs(&f.caption).find(|id| !seen.contains(id)) {
            return Err(Error::Report {
                what: format!("figure '{}' caption", f.id),
                reason: format!("refers to figure '{id}', which the report does not have"),
            });
        }
    }
    Ok(())
}

/// Writes `dir/report.html` and `dir/figures/<id>.svg` (and `.png` when
/// `options.png`), creating the directories.
///
/// Every figure is drawn in memory before anything is written, so a bad
/// figure leaves the directory untouched. Each file is written to a temporary
/// name in its own directory and renamed into place ([`write_atomic`]). A previous
/// `report.html` is removed before the figures are replaced and the new one
/// is written last, so a `report.html` on disk always matches the figures
/// beside it. Figures of earlier runs with other ids are left alone.
///
/// # Errors
///
/// [`Error::Report`] when a figure is malformed (see [`render_svg`]) or two
/// figures share an id or a table row has the wrong width;
/// [`Error::InvalidSetting`] when `options.png_scale` is not 1..=4; [`Error::Io`] naming the file when a directory or file
/// cannot be written.
pub fn write_report(report: &Report, dir: &Path, options: ReportOptions) -> Result<ReportFiles> {
    check_report(report)?;
    if options.png && !(1..=4).contains(&options.png_scale) {
        return Err(Error::setting(
            "png_scale",
            format!("{} is not in 1..=4", options.png_scale),
        ));
    }
    let figures = report.all_figures();
    let svgs = figures
        .iter()
        .map(|f| render_svg(f))
        .collect::<Result<Vec<_>>>()?;
    let pngs = if options.png {
        figures
            .iter()
            .map(|f| render_png(f, options.png_scale))
            .collect::<Result<Vec<_>>>()?
    } else {
        Vec::new()
    };
    let mut warnings = Vec::new();
    let html = page::document(report, &figures, &svgs, options.png, &mut warnings)?;

    let fig_dir = dir.join(FIGURES_DIR);
    fs::create_dir_all(&fig_dir).map_err(|source| Error::Io {
        path: fig_dir.clone(),
        source,
    })?;
    let html_path = dir.join(REPORT_FILE);
    match fs::remove_file(&html_path) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(source) => {
            return Err(Error::Io {
                path: html_path,
                source,
            })
        }
    }
    let mut files = ReportFiles {
        html: html_path.clone(),
        svgs: Vec::new(),
        pngs: Vec::new(),
        warnings,
    };
    for (fig, r) in figures.iter().zip(&svgs) {
        let path = fig_dir.join(format!("{}.svg", fig.id));
        write_atomic(&path, r.svg.as_bytes())?;
        files.svgs.push(path);
    }
    for (fig, png) in figures.iter().zip(&pngs) {
        let path = fig_dir.join(format!("{}.png", fig.id));
        write_atomic(&path, png)?;
        files.pngs.push(path);
    }
    write_atomic(&html_path, html.as_bytes())?;
    Ok(files)
}

/// Escapes text for HTML element content and quoted attribute values.
pub fn escape_html(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}
