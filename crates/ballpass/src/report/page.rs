//! The HTML page of a [`Report`]: header, contents, sections with their
//! figures in place (numbered in order, referred to as "Figure N"), the
//! data files behind each figure, and the interactive layer.

use std::collections::HashMap;
use std::fmt::Write as _;

use super::draw::Rendered;
use super::html::{escape_html, Block, Report, Section, FIGURES_DIR};
use super::live;
use super::spec::Figure;
use crate::error::Result;

/// The texts of a block that may hold figure references.
pub(crate) fn block_texts(b: &Block) -> Vec<&str> {
    match b {
        Block::Paragraph(p) => vec![p.as_str()],
        Block::KeyValues(rows) => rows.iter().map(|(_, v)| v.as_str()).collect(),
        Block::Table(t) => t.rows.iter().flatten().map(String::as_str).collect(),
        Block::Verdicts(vs) => vs.iter().map(|v| v.text.as_str()).collect(),
        Block::Warnings(ws) => ws.iter().map(String::as_str).collect(),
        Block::Settings(_) => Vec::new(),
        Block::Figure(f) => vec![f.caption.as_str()],
    }
}

/// The figure ids referred to as `{fig:<id>}` in `text`.
pub(crate) fn figure_refs(text: &str) -> impl Iterator<Item = &str> {
    text.split("{fig:")
        .skip(1)
        .filter_map(|rest| rest.split_once('}').map(|(id, _)| id))
}

/// Escapes `text` for HTML, writes figure references as links and keeps a
/// number with its unit or its uncertainty on one line (a no-break space
/// around `±` and after a digit followed by a unit or word).
fn rich(text: &str, numbers: &HashMap<&str, usize>) -> String {
    let escaped = escape_html(text);
    let mut out = String::with_capacity(escaped.len() + 16);
    let mut rest = escaped.as_str();
    while let Some(at) = rest.find("{fig:") {
        out.push_str(&rest[..at]);
        let after = &rest[at + 5..];
        match after.split_once('}') {
            Some((id, tail)) => {
                match numbers.get(id) {
                    Some(n) => {
                        let _ = write!(out, "<a href=\"#fig-{id}\">Figure&nbsp;{n}</a>");
                    }
                    // check_report refuses unknown ids; keep the text if one slips by
                    None => out.push_str(&rest[at..at + 6 + id.len()]),
                }
                rest = tail;
            }
            None => {
                out.push_str(&rest[at..]);
                rest = "";
            }
        }
    }
    out.push_str(rest);
    no_break_numbers(&out)
}

/// `a ± b` and `12.3 µm/s` kept on one line, and a hyphen before a number
/// (after a space, `(` or at the start) written as a minus sign.
fn no_break_numbers(s: &str) -> String {
    let chars: Vec<char> = s.chars().collect();
    let mut out = String::with_capacity(s.len() + 16);
    for (i, &c) in chars.iter().enumerate() {
        let prev = i.checked_sub(1).map(|j| chars[j]);
        let next = chars.get(i + 1).copied();
        if c == '-'
            && next.is_some_and(|n| n.is_ascii_digit())
            && prev.is_none_or(|p| p == ' ' || p == '(' || p == '[')
        {
            out.push('−');
            continue;
        }
        let joins = c == ' '
            && (next == Some('±')
                || prev == Some('±')
                || (prev.is_some_and(|p| p.is_ascii_digit())
                    && next.is_some_and(|n| {
                        !n.is_whitespace() && !n.is_ascii_digit() && n != '(' && n != '<'
                    })));
        if joins {
            out.push_str("&nbsp;");
        } else {
            out.push(c);
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
h2 { font-size: 1.3rem; border-bottom: 1px solid var(--line); padding-bottom: .2rem; margin-top: 2.2rem; }
h3 { font-size: 1.1rem; margin: 1.6rem 0 .4rem; }
h4 { font-size: 1rem; margin: 1.2rem 0 .4rem; }
.meta { color: var(--muted); margin: 0; font-size: .9rem; }
code { background: var(--bg2); padding: .05rem .3rem; border-radius: 3px; overflow-wrap: anywhere; }
table { border-collapse: collapse; margin: .5rem 0 1rem; font-size: .9rem; }
.scroll { overflow-x: auto; max-width: 100%; }
th, td { border: 1px solid var(--line); padding: .25rem .6rem; text-align: left; vertical-align: top; }
th { background: var(--bg2); }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
table.kv th { font-weight: normal; color: var(--muted); }
table.kv td.num { text-align: left; }
ul.verdicts { list-style: none; padding: 0; }
ul.verdicts li { margin: .3rem 0; }
.badge { display: inline-block; min-width: 3.6em; text-align: center; font-weight: bold; font-size: .8rem;
         padding: .1rem .4rem; border-radius: 3px; color: #fff; margin-right: .5rem; }
.badge.pass { background: #1a7f37; } .badge.warn { background: #9a6700; }
.badge.fail { background: #cf222e; } .badge.info { background: #57606a; }
.warnings { background: #fff8c5; border: 1px solid #d4a72c; border-radius: 4px; padding: .5rem 1rem .5rem 2rem; }
details.settings summary { cursor: pointer; color: var(--muted); }
nav.toc { background: var(--bg2); border: 1px solid var(--line); border-radius: 4px; padding: .4rem 1rem; margin-top: 1rem; }
nav.toc h2 { border: 0; margin: .3rem 0; font-size: 1.1rem; }
nav.toc ol { margin: .2rem 0; padding-left: 1.4rem; font-size: .92rem; }
nav.toc ul.figs { margin: .1rem 0 .3rem; padding-left: 1.2rem; list-style: none; font-size: .85rem; color: var(--muted); }
figure { margin: 1.2rem 0 2rem; page-break-inside: avoid; }
figure svg { display: block; max-width: 100%; height: auto; border: 1px solid var(--line); }
figure.bp-active svg { outline: 2px solid #1f77b4; }
.figtitle { font-weight: bold; margin: 0 0 .3rem; }
figcaption { color: var(--fg); font-size: .92rem; margin-top: .4rem; }
figcaption .files { color: var(--muted); display: block; margin-top: .2rem; }
.bp-tools { font-size: .8rem; color: var(--muted); margin-top: .25rem; }
.bp-tools button { font-size: .8rem; margin-right: .25rem; padding: .05rem .45rem; }
.bp-hint { margin-left: .5rem; }
.note { color: #9a6700; font-size: .88rem; }
footer { color: var(--muted); font-size: .85rem; border-top: 1px solid var(--line); margin-top: 2rem; padding-top: .5rem; }
@media print { .bp-tools, nav.toc { display: none; } .scroll { overflow: visible; } }
"#;

/// Whether a cell looks like a number (right-aligned, not wrapped).
fn numeric(cell: &str) -> bool {
    let t = cell.trim();
    let head = t.split_whitespace().next().unwrap_or("");
    !head.is_empty()
        && head
            .trim_start_matches(['−', '-', '+', '±'])
            .trim_end_matches('%')
            .parse::<f64>()
            .is_ok()
        && t.len() <= 40
}

/// What the page writer needs about one figure.
struct Placed<'a> {
    number: usize,
    rendered: &'a Rendered,
}

struct Writer<'a> {
    h: String,
    numbers: HashMap<&'a str, usize>,
    placed: HashMap<&'a str, Placed<'a>>,
    png: bool,
    warnings: &'a mut Vec<String>,
    live: Vec<String>,
}

/// The whole HTML document. `figures` are the report's figures in order
/// ([`Report::all_figures`]) and `svgs` their drawings.
pub(crate) fn document(
    report: &Report,
    figures: &[&Figure],
    svgs: &[Rendered],
    png: bool,
    warnings: &mut Vec<String>,
) -> Result<String> {
    let e = escape_html;
    let numbers: HashMap<&str, usize> = figures
        .iter()
        .enumerate()
        .map(|(i, f)| (f.id.as_str(), i + 1))
        .collect();
    let placed = figures
        .iter()
        .zip(svgs)
        .enumerate()
        .map(|(i, (f, r))| {
            (
                f.id.as_str(),
                Placed {
                    number: i + 1,
                    rendered: r,
                },
            )
        })
        .collect();
    let mut w = Writer {
        h: String::with_capacity(64 * 1024 + svgs.iter().map(|s| s.svg.len()).sum::<usize>()),
        numbers,
        placed,
        png,
        warnings,
        live: Vec::new(),
    };
    let _ = write!(
        w.h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <meta name=\"generator\" content=\"ballpass {v}\">\n<title>{t}</title>\n<style>{CSS}</style>\n</head>\n<body>\n\
         <header>\n<h1>{t}</h1>\n<p class=\"meta\">ballpass {v}",
        t = e(&report.title),
        v = e(&report.version),
    );
    if !report.command.is_empty() {
        let _ = write!(w.h, " · <code>{}</code>", e(&report.command));
    }
    w.h.push_str("</p>\n</header>\n");
    contents(&mut w, report);
    w.h.push_str("<main>\n");
    for (i, s) in report.summary.iter().enumerate() {
        section(&mut w, s, &format!("s{}", i + 1), 2)?;
    }
    if !report.figures.is_empty() {
        w.h.push_str("<section id=\"figures\">\n<h2>Figures</h2>\n");
        for f in &report.figures {
            figure(&mut w, f)?;
        }
        w.h.push_str("</section>\n");
    }
    let live_note = if w.live.is_empty() {
        "no scripts"
    } else {
        "an inline script adds zoom and value readouts to the marked figures, and the page reads \
         the same without it"
    };
    let _ = write!(
        w.h,
        "</main>\n<footer>Written by ballpass {}. This file is self-contained: figures are inline \
         SVG, {live_note}; nothing is fetched from the network. Data files and figure images are \
         linked beside it.</footer>\n",
        e(&report.version)
    );
    if !w.live.is_empty() {
        for json in &w.live {
            let _ = writeln!(
                w.h,
                "<script type=\"application/json\" class=\"bp-data\">{json}</script>"
            );
        }
        let _ = writeln!(w.h, "<script>{}</script>", live::SCRIPT);
    }
    w.h.push_str("</body>\n</html>\n");
    Ok(w.h)
}

/// The contents list: every section and subsection, with the figures each
/// holds.
fn contents(w: &mut Writer<'_>, report: &Report) {
    fn figs_of(s: &Section) -> Vec<&Figure> {
        s.blocks
            .iter()
            .filter_map(|b| match b {
                Block::Figure(f) => Some(&**f),
                _ => None,
            })
            .collect()
    }
    fn item(w: &mut Writer<'_>, s: &Section, id: &str) {
        let _ = write!(w.h, "<li><a href=\"#{id}\">{}</a>", escape_html(&s.heading));
        let figs = figs_of(s);
        if !figs.is_empty() {
            w.h.push_str("<ul class=\"figs\">");
            for f in figs {
                let n = w.numbers.get(f.id.as_str()).copied().unwrap_or(0);
                let _ = write!(
                    w.h,
                    "<li><a href=\"#fig-{}\">Figure {n}</a>. {}</li>",
                    escape_html(&f.id),
                    escape_html(&f.title)
                );
            }
            w.h.push_str("</ul>");
        }
        if !s.subsections.is_empty() {
            w.h.push_str("<ol>");
            for (i, sub) in s.subsections.iter().enumerate() {
                item(w, sub, &format!("{id}-{}", i + 1));
            }
            w.h.push_str("</ol>");
        }
        w.h.push_str("</li>\n");
    }
    w.h.push_str("<nav class=\"toc\">\n<h2>Contents</h2>\n<ol>\n");
    for (i, s) in report.summary.iter().enumerate() {
        item(w, s, &format!("s{}", i + 1));
    }
    if !report.figures.is_empty() {
        w.h.push_str("<li><a href=\"#figures\">Figures</a><ul class=\"figs\">");
        for f in &report.figures {
            let n = w.numbers.get(f.id.as_str()).copied().unwrap_or(0);
            let _ = write!(
                w.h,
                "<li><a href=\"#fig-{}\">Figure {n}</a>. {}</li>",
                escape_html(&f.id),
                escape_html(&f.title)
            );
        }
        w.h.push_str("</ul></li>\n");
    }
    w.h.push_str("</ol>\n</nav>\n");
}

fn section(w: &mut Writer<'_>, s: &Section, id: &str, level: usize) -> Result<()> {
    let level = level.min(4);
    let _ = writeln!(
        w.h,
        "<section id=\"{id}\">\n<h{level}>{}</h{level}>",
        escape_html(&s.heading)
    );
    for b in &s.blocks {
        block(w, b)?;
    }
    for (i, sub) in s.subsections.iter().enumerate() {
        section(w, sub, &format!("{id}-{}", i + 1), level + 1)?;
    }
    w.h.push_str("</section>\n");
    Ok(())
}

fn figure(w: &mut Writer<'_>, f: &Figure) -> Result<()> {
    let e = escape_html;
    let Some(p) = w.placed.get(f.id.as_str()) else {
        return Ok(());
    };
    let (n, r) = (p.number, p.rendered);
    let html_id = format!("fig-{}", f.id);
    let _ = writeln!(
        w.h,
        "<figure id=\"{}\">\n<p class=\"figtitle\">Figure {n}. {}</p>",
        e(&html_id),
        e(&f.title)
    );
    let svg = r.svg.trim_start();
    match svg.strip_prefix("<svg") {
        Some(rest) => {
            let _ = write!(
                w.h,
                "<svg role=\"img\" aria-label=\"{}\"{rest}",
                e(&f.title)
            );
        }
        None => w.h.push_str(svg),
    }
    w.h.push_str("<figcaption>");
    if !f.caption.is_empty() {
        let _ = write!(w.h, "{} ", rich(&f.caption, &w.numbers));
    }
    w.h.push_str("<span class=\"files\">");
    if !f.data.is_empty() {
        w.h.push_str("Data: ");
        for (i, d) in f.data.iter().enumerate() {
            if i > 0 {
                w.h.push_str("; ");
            }
            let _ = write!(w.h, "<a href=\"{p}\">{p}</a>", p = e(&d.path));
            if !d.what.is_empty() {
                let _ = write!(w.h, " ({})", e(&d.what));
            }
        }
        w.h.push_str(". ");
    }
    let _ = write!(
        w.h,
        "Image: <a href=\"{d}/{id}.svg\">SVG</a>",
        d = FIGURES_DIR,
        id = e(&f.id)
    );
    if w.png {
        let _ = write!(
            w.h,
            " · <a href=\"{d}/{id}.png\">PNG</a>",
            d = FIGURES_DIR,
            id = e(&f.id)
        );
    }
    w.h.push_str("</span>");
    for warning in &r.warnings {
        let _ = write!(
            w.h,
            "<br><span class=\"note\">Drawing note: {}</span>",
            e(warning)
        );
        w.warnings.push(warning.clone());
    }
    w.h.push_str("</figcaption>\n</figure>\n");
    if f.interactive {
        let json = live::figure_json(f, &html_id, r)?;
        w.live.push(json);
    }
    Ok(())
}

fn block(w: &mut Writer<'_>, block: &Block) -> Result<()> {
    let e = escape_html;
    match block {
        Block::Paragraph(p) => {
            let _ = writeln!(w.h, "<p>{}</p>", rich(p, &w.numbers));
        }
        Block::KeyValues(rows) => {
            w.h.push_str("<table class=\"kv\">\n");
            for (k, v) in rows {
                let class = if numeric(v) { " class=\"num\"" } else { "" };
                let _ = writeln!(
                    w.h,
                    "<tr><th scope=\"row\">{}</th><td{class}>{}</td></tr>",
                    e(k),
                    rich(v, &w.numbers)
                );
            }
            w.h.push_str("</table>\n");
        }
        Block::Table(t) => {
            // a wide table (numbers are not wrapped) scrolls sideways
            // instead of running off the page
            w.h.push_str("<div class=\"scroll\"><table>\n<thead><tr>");
            for c in &t.headers {
                let _ = write!(w.h, "<th scope=\"col\">{}</th>", e(c));
            }
            w.h.push_str("</tr></thead>\n<tbody>\n");
            for row in &t.rows {
                w.h.push_str("<tr>");
                for c in row {
                    let class = if numeric(c) { " class=\"num\"" } else { "" };
                    let _ = write!(w.h, "<td{class}>{}</td>", rich(c, &w.numbers));
                }
                w.h.push_str("</tr>\n");
            }
            w.h.push_str("</tbody>\n</table></div>\n");
        }
        Block::Verdicts(vs) => {
            w.h.push_str("<ul class=\"verdicts\">\n");
            for v in vs {
                let (class, text) = v.level.badge();
                let _ = writeln!(
                    w.h,
                    "<li><span class=\"badge {class}\">{text}</span><strong>{}</strong> — {}</li>",
                    e(&v.subject),
                    rich(&v.text, &w.numbers)
                );
            }
            w.h.push_str("</ul>\n");
        }
        Block::Warnings(ws) => {
            if ws.is_empty() {
                w.h.push_str("<p>No warnings.</p>\n");
            } else {
                w.h.push_str("<ul class=\"warnings\">\n");
                for x in ws {
                    let _ = writeln!(w.h, "<li>{}</li>", rich(x, &w.numbers));
                }
                w.h.push_str("</ul>\n");
            }
        }
        Block::Settings(rows) => {
            let _ = writeln!(
                w.h,
                "<details class=\"settings\" open>\n<summary>{} settings</summary>\n<table class=\"kv\">",
                rows.len()
            );
            for (k, v) in rows {
                let _ = writeln!(
                    w.h,
                    "<tr><th scope=\"row\"><code>{}</code></th><td>{}</td></tr>",
                    e(k),
                    e(v)
                );
            }
            w.h.push_str("</table>\n</details>\n");
        }
        Block::Figure(f) => figure(w, f)?,
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_stay_with_their_units_and_uncertainties() {
        let n = HashMap::new();
        assert_eq!(
            rich("99.5 ± 4.1 µm/s over 5 records", &n),
            "99.5&nbsp;±&nbsp;4.1&nbsp;µm/s over 5&nbsp;records"
        );
    }

    #[test]
    fn minus_signs_are_typographic() {
        let n = HashMap::new();
        assert_eq!(
            rich("phase -165° (-0.1 dB), 1e-5", &n),
            "phase −165° (−0.1&nbsp;dB), 1e-5"
        );
    }

    #[test]
    fn figure_references_become_numbered_links() {
        let mut n = HashMap::new();
        n.insert("spectra", 3usize);
        assert_eq!(
            rich("as {fig:spectra} shows", &n),
            "as <a href=\"#fig-spectra\">Figure&nbsp;3</a> shows"
        );
        assert_eq!(
            figure_refs("{fig:a} and {fig:b_c}").collect::<Vec<_>>(),
            ["a", "b_c"]
        );
    }
}
