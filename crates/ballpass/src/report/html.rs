//! The self-contained HTML report and the files written beside it.

use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::draw::{render_png, render_svg};
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
    fn badge(self) -> (&'static str, &'static str) {
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

/// A titled part of the summary.
#[derive(Debug, Clone, PartialEq)]
pub struct Section {
    /// Heading ("Prediction vs measurement", "Verdicts", "Settings").
    pub heading: String,
    /// Content, in order.
    pub blocks: Vec<Block>,
}

impl Section {
    /// An empty section.
    pub fn new(heading: impl Into<String>) -> Self {
        Section {
            heading: heading.into(),
            blocks: Vec::new(),
        }
    }

    /// The same section with one more block.
    pub fn with(mut self, block: Block) -> Self {
        self.blocks.push(block);
        self
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
    /// Summary sections, shown first, in order.
    pub summary: Vec<Section>,
    /// Figures, shown after the summary, in order; ids must be unique.
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

    /// The same report with one more figure.
    pub fn with_figure(mut self, figure: Figure) -> Self {
        self.figures.push(figure);
        self
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

/// Renders the report as one self-contained HTML document (inline SVG and
/// CSS, no scripts, no external resources) without writing anything.
///
/// `png` adds links to `figures/<id>.png` under each figure.
///
/// # Errors
///
/// As [`write_report`], minus the I/O.
pub fn render_html(report: &Report, png: bool) -> Result<HtmlReport> {
    check_report(report)?;
    let svgs = report
        .figures
        .iter()
        .map(render_svg)
        .collect::<Result<Vec<_>>>()?;
    let mut warnings = Vec::new();
    let html = html_document(report, &svgs, png, &mut warnings);
    Ok(HtmlReport { html, warnings })
}

/// Figure ids unique, table rows as wide as their header.
fn check_report(report: &Report) -> Result<()> {
    let mut seen = std::collections::HashSet::new();
    for f in &report.figures {
        if !seen.insert(f.id.as_str()) {
            return Err(Error::Report {
                what: format!("figure '{}'", f.id),
                reason: "id is used by another figure of the same report".into(),
            });
        }
    }
    for s in &report.summary {
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
    let svgs = report
        .figures
        .iter()
        .map(render_svg)
        .collect::<Result<Vec<_>>>()?;
    let pngs = if options.png {
        report
            .figures
            .iter()
            .map(|f| render_png(f, options.png_scale))
            .collect::<Result<Vec<_>>>()?
    } else {
        Vec::new()
    };
    let mut warnings = Vec::new();
    let html = html_document(report, &svgs, options.png, &mut warnings);

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
    for (fig, r) in report.figures.iter().zip(&svgs) {
        let path = fig_dir.join(format!("{}.svg", fig.id));
        write_atomic(&path, r.svg.as_bytes())?;
        files.svgs.push(path);
    }
    for (fig, png) in report.figures.iter().zip(&pngs) {
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

const CSS: &str = r#"
:root { --fg: #1b1f23; --muted: #57606a; --line: #d0d7de; --bg2: #f6f8fa; }
* { box-sizing: border-box; }
body { font-family: "DejaVu Sans", Verdana, "Segoe UI", Helvetica, Arial, sans-serif; color: var(--fg);
       margin: 0 auto; max-width: 1000px; padding: 1.5rem; line-height: 1.45; }
h1 { font-size: 1.6rem; margin: 0 0 .3rem; }
h2 { font-size: 1.25rem; border-bottom: 1px solid var(--line); padding-bottom: .2rem; margin-top: 2rem; }
h3 { font-size: 1.05rem; margin: 0 0 .4rem; }
.meta { color: var(--muted); margin: 0; font-size: .9rem; }
code { background: var(--bg2); padding: .05rem .3rem; border-radius: 3px; word-break: break-all; }
table { border-collapse: collapse; margin: .5rem 0 1rem; font-size: .92rem; }
th, td { border: 1px solid var(--line); padding: .25rem .6rem; text-align: left; vertical-align: top; }
th { background: var(--bg2); }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
table.kv th { font-weight: normal; color: var(--muted); }
ul.verdicts { list-style: none; padding: 0; }
ul.verdicts li { margin: .3rem 0; }
.badge { display: inline-block; min-width: 3.6em; text-align: center; font-weight: bold; font-size: .8rem;
         padding: .1rem .4rem; border-radius: 3px; color: #fff; margin-right: .5rem; }
.badge.pass { background: #1a7f37; } .badge.warn { background: #9a6700; }
.badge.fail { background: #cf222e; } .badge.info { background: #57606a; }
.warnings { background: #fff8c5; border: 1px solid #d4a72c; border-radius: 4px; padding: .5rem 1rem .5rem 2rem; }
details.settings summary { cursor: pointer; color: var(--muted); }
nav ol { columns: 2; font-size: .92rem; }
figure { margin: 2rem 0; page-break-inside: avoid; }
figure svg { display: block; max-width: 100%; height: auto; border: 1px solid var(--line); }
figcaption { color: var(--fg); font-size: .92rem; margin-top: .4rem; }
figcaption .files { color: var(--muted); }
.note { color: #9a6700; font-size: .88rem; }
footer { color: var(--muted); font-size: .85rem; border-top: 1px solid var(--line); margin-top: 2rem; padding-top: .5rem; }
"#;

/// Whether a cell looks like a number (right-aligned).
fn numeric(cell: &str) -> bool {
    let t = cell.trim();
    let head = t.split_whitespace().next().unwrap_or("");
    !head.is_empty()
        && head
            .trim_start_matches(['−', '-', '+', '±'])
            .parse::<f64>()
            .is_ok()
}

fn html_document(
    report: &Report,
    svgs: &[super::Rendered],
    png: bool,
    warnings: &mut Vec<String>,
) -> String {
    let e = escape_html;
    let mut h = String::with_capacity(64 * 1024 + svgs.iter().map(|s| s.svg.len()).sum::<usize>());
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <meta name=\"generator\" content=\"ballpass {v}\">\n<title>{t}</title>\n<style>{CSS}</style>\n</head>\n<body>\n\
         <header>\n<h1>{t}</h1>\n<p class=\"meta\">ballpass {v}",
        t = e(&report.title),
        v = e(&report.version),
    );
    if !report.command.is_empty() {
        let _ = write!(h, " · <code>{}</code>", e(&report.command));
    }
    h.push_str("</p>\n</header>\n<main>\n");

    for section in &report.summary {
        let _ = writeln!(h, "<section>\n<h2>{}</h2>", e(&section.heading));
        for block in &section.blocks {
            write_block(&mut h, block);
        }
        h.push_str("</section>\n");
    }

    if !report.figures.is_empty() {
        h.push_str("<section>\n<h2>Figures</h2>\n<nav><ol>\n");
        for f in &report.figures {
            let _ = writeln!(
                h,
                "<li><a href=\"#fig-{}\">{}</a></li>",
                e(&f.id),
                e(&f.title)
            );
        }
        h.push_str("</ol></nav>\n");
        for (i, (f, r)) in report.figures.iter().zip(svgs).enumerate() {
            let _ = writeln!(
                h,
                "<figure id=\"fig-{id}\">\n<h3>Figure {n}. {t}</h3>",
                id = e(&f.id),
                n = i + 1,
                t = e(&f.title)
            );
            // inline the SVG; give it an accessible name
            let svg = r.svg.trim_start();
            match svg.strip_prefix("<svg") {
                Some(rest) => {
                    let _ = write!(h, "<svg role=\"img\" aria-label=\"{}\"{rest}", e(&f.title));
                }
                None => h.push_str(svg),
            }
            h.push_str("<figcaption>");
            if !f.caption.is_empty() {
                let _ = write!(h, "{} ", e(&f.caption));
            }
            let _ = write!(
                h,
                "<span class=\"files\">[<a href=\"{d}/{id}.svg\">SVG</a>",
                d = FIGURES_DIR,
                id = e(&f.id)
            );
            if png {
                let _ = write!(
                    h,
                    " · <a href=\"{d}/{id}.png\">PNG</a>",
                    d = FIGURES_DIR,
                    id = e(&f.id)
                );
            }
            h.push_str("]</span>");
            for w in &r.warnings {
                let _ = write!(h, "<br><span class=\"note\">Drawing note: {}</span>", e(w));
                warnings.push(w.clone());
            }
            h.push_str("</figcaption>\n</figure>\n");
        }
        h.push_str("</section>\n");
    }
    let _ = write!(
        h,
        "</main>\n<footer>Written by ballpass {}. This file is self-contained: \
         figures are inline SVG, no scripts, no network access.</footer>\n</body>\n</html>\n",
        e(&report.version)
    );
    h
}

fn write_block(h: &mut String, block: &Block) {
    let e = escape_html;
    match block {
        Block::Paragraph(p) => {
            let _ = writeln!(h, "<p>{}</p>", e(p));
        }
        Block::KeyValues(rows) => {
            h.push_str("<table class=\"kv\">\n");
            for (k, v) in rows {
                let class = if numeric(v) { " class=\"num\"" } else { "" };
                let _ = writeln!(
                    h,
                    "<tr><th scope=\"row\">{}</th><td{class}>{}</td></tr>",
                    e(k),
                    e(v)
                );
            }
            h.push_str("</table>\n");
        }
        Block::Table(t) => {
            h.push_str("<table>\n<thead><tr>");
            for c in &t.headers {
                let _ = write!(h, "<th scope=\"col\">{}</th>", e(c));
            }
            h.push_str("</tr></thead>\n<tbody>\n");
            for row in &t.rows {
                h.push_str("<tr>");
                for c in row {
                    let class = if numeric(c) { " class=\"num\"" } else { "" };
                    let _ = write!(h, "<td{class}>{}</td>", e(c));
                }
                h.push_str("</tr>\n");
            }
            h.push_str("</tbody>\n</table>\n");
        }
        Block::Verdicts(vs) => {
            h.push_str("<ul class=\"verdicts\">\n");
            for v in vs {
                let (class, text) = v.level.badge();
                let _ = writeln!(
                    h,
                    "<li><span class=\"badge {class}\">{text}</span><strong>{}</strong> — {}</li>",
                    e(&v.subject),
                    e(&v.text)
                );
            }
            h.push_str("</ul>\n");
        }
        Block::Warnings(ws) => {
            if ws.is_empty() {
                h.push_str("<p>No warnings.</p>\n");
            } else {
                h.push_str("<ul class=\"warnings\">\n");
                for w in ws {
                    let _ = writeln!(h, "<li>{}</li>", e(w));
                }
                h.push_str("</ul>\n");
            }
        }
        Block::Settings(rows) => {
            let _ = writeln!(
                h,
                "<details class=\"settings\" open>\n<summary>{} settings</summary>\n<table class=\"kv\">",
                rows.len()
            );
            for (k, v) in rows {
                let _ = writeln!(
                    h,
                    "<tr><th scope=\"row\"><code>{}</code></th><td>{}</td></tr>",
                    e(k),
                    e(v)
                );
            }
            h.push_str("</table>\n</details>\n");
        }
    }
}
