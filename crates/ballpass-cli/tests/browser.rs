//! The demo report in a real browser: headless Chromium loads
//! `report.html` from `ballpass demo` through the DevTools protocol (over a
//! pipe, see `common/cdp.rs`), and the tests check that every figure is
//! present and non-empty, that zooming and panning an interactive figure
//! with the mouse changes its visible range and shows values under the
//! cursor, that the page logs no errors, and that it reads the same with
//! scripts off. Screenshots are saved under `target/tmp/browser/` for a
//! person to look at.
//!
//! The demo's own outputs (counts, headers with units) are checked here too,
//! so that the demo runs once for all of these tests.
//!
//! Chromium is found as `$BALLPASS_CHROMIUM`, `chromium`, `chromium-browser`
//! or `google-chrome`. Without one the browser tests say so and pass,
//! except under CI (`CI` set), where `.ci/run` installs Debian's `chromium`
//! and a missing browser is a failure.

#[path = "common/cdp.rs"]
mod cdp;
mod common;

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use serde_json::json;

use cdp::{chromium, Browser};
use common::{bin, output};

struct Demo {
    dir: PathBuf,
    page: PathBuf,
    stdout: String,
}

/// `ballpass demo --write-recordings`, once per test binary.
fn demo() -> &'static Demo {
    static DEMO: OnceLock<Demo> = OnceLock::new();
    DEMO.get_or_init(|| {
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("browser");
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let out = dir.join("demo");
        let r = output(
            bin()
                .args(["demo", "--write-recordings", "--out"])
                .arg(&out),
        );
        assert!(r.ok(), "demo failed: {}", r.stderr);
        Demo {
            page: out.join("report.html").canonicalize().unwrap(),
            dir: out,
            stdout: r.stdout,
        }
    })
}

fn browser_or_skip() -> Option<PathBuf> {
    let b = chromium();
    if b.is_none() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI must have chromium: .ci/run installs Debian's chromium"
        );
        eprintln!("browser test skipped: no chromium on this machine (set BALLPASS_CHROMIUM)");
    }
    b
}

/// Regression: the demo said "26 figures and tables" for 26 figures and 12
/// tables; it names each count.
#[test]
fn the_demo_counts_figures_tables_and_data_files_apart() {
    let d = demo();
    let line = d
        .stdout
        .lines()
        .find(|l| l.starts_with("wrote a report of"))
        .unwrap_or_else(|| panic!("{}", d.stdout));
    let html = std::fs::read_to_string(&d.page).unwrap();
    let figures = html.matches("<p class=\"figtitle\">").count();
    let tables = html.matches("<table>").count();
    assert!(
        line.contains(&format!("{figures} figures and {tables} tables")),
        "{line}"
    );
    let svgs = std::fs::read_dir(d.dir.join("figures")).unwrap().count();
    assert_eq!(svgs, figures);
}

/// Units in every exported table's header: each column of every CSV the
/// demo writes ends in a unit token, or is one of the dimensionless or
/// text columns (docs/user-guide.md lists both).
#[test]
fn every_exported_column_names_its_unit() {
    // `_mm3_s2`: (mm/s)² per cycle/mm, the position-domain PSD of the
    // velocity error
    const UNITS: [&str; 23] = [
        "_s", "_hz", "_n", "_v", "_mm", "_mm_s", "_um_s", "_um", "_deg", "_db", "_n2", "_per_hz",
        "_kg", "_rad_s", "_m", "_n_v", "_n_mm_s", "_mm_s_v", "_v2", "_mm2_s2", "_n_per_m",
        "_s_per_m", "_mm3_s2",
    ];
    // counts, ratios, fractions, flags, names: no unit
    const PLAIN: [&str; 28] = [
        "phase",
        "periods",
        "spikes",
        "spikes_for_bad",
        "spikes_for_suspect",
        "typical_over_batch",
        "spread_over_batch",
        "path",
        "bearing",
        "repeat",
        "condition",
        "status",
        "error",
        "passages",
        "tau_ratio",
        "tau_ratio_spread",
        "rank",
        "verdict",
        "records",
        "manifest_condition",
        "low_band_ratio",
        "evidence",
        "n",
        "c_over_p",
        "thesis_printed_c_over_p",
        "plateau",
        "plateaus_in_file",
        "direction",
    ];
    // a coefficient-normalised correlation: r_<series>, no unit
    const SERIES: [&str; 6] = [
        "friction",
        "velocity_error",
        "optical",
        "friction__velocity_error",
        "friction__optical",
        "velocity_error__optical",
    ];
    let plain = |c: &str| {
        PLAIN.contains(&c)
            || c.starts_with("coh_")
            || c.ends_with("_significant")
            || c.ends_with("_gain_ratio")
            || c.strip_prefix("r_").is_some_and(|s| SERIES.contains(&s))
    };
    let d = demo();
    let mut checked = 0;
    let mut stack = vec![d.dir.clone()];
    while let Some(p) = stack.pop() {
        for e in std::fs::read_dir(&p).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                if !p.ends_with("figures") {
                    stack.push(p);
                }
                continue;
            }
            if p.extension().is_none_or(|x| x != "csv") {
                continue;
            }
            let head = std::fs::read_to_string(&p).unwrap();
            let head = head.lines().next().unwrap().to_string();
            for c in csv_fields(&head) {
                let c = c.to_lowercase();
                assert!(
                    plain(&c) || UNITS.iter().any(|u| c.ends_with(u)),
                    "{}: column '{c}' has no unit",
                    p.display()
                );
                checked += 1;
            }
        }
    }
    assert!(checked > 100, "only {checked} columns");
}

/// Header fields of a CSV line (quoted fields may hold commas).
fn csv_fields(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    for c in line.chars() {
        match c {
            '"' => quoted = !quoted,
            ',' if !quoted => out.push(std::mem::take(&mut cur)),
            c => cur.push(c),
        }
    }
    out.push(cur);
    out
}

/// Every figure file is well-formed SVG with something drawn in it, and
/// Chromium's DOM holds every figure inline, with no console error, also
/// with scripts off.
#[test]
fn demo_report_renders_in_headless_chromium() {
    let Some(browser) = browser_or_skip() else {
        return;
    };
    let d = demo();
    let mut ids = Vec::new();
    for e in std::fs::read_dir(d.dir.join("figures")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "svg") {
            let text = std::fs::read_to_string(&p).unwrap();
            let doc = roxmltree::Document::parse(&text)
                .unwrap_or_else(|e| panic!("{}: not well-formed: {e}", p.display()));
            let drawn = doc
                .descendants()
                .filter(|n| {
                    matches!(
                        n.tag_name().name(),
                        "path" | "polyline" | "line" | "rect" | "circle"
                    )
                })
                .count();
            assert!(drawn > 10, "{}: only {drawn} drawn elements", p.display());
            ids.push(p.file_stem().unwrap().to_string_lossy().into_owned());
        }
    }
    assert!(ids.len() >= 20, "the demo has {} figures", ids.len());

    // With scripts: every figure inline; the interactive ones got their tools.
    let profile = d.dir.parent().unwrap().join("profile-dom");
    let mut b = Browser::start(&browser, &profile);
    b.open(&format!("file://{}", d.page.display()), 1280, 1000);
    let found = b.eval(&format!(
        "{:?}.filter(id => {{ const f = document.getElementById('fig-' + id); \
         return f && f.querySelector('svg'); }}).length",
        ids
    ));
    assert_eq!(found, json!(ids.len()), "figures missing from the page");
    let live = b.eval("+document.documentElement.getAttribute('data-live-figures')");
    let marked = std::fs::read_to_string(&d.page)
        .unwrap()
        .matches("class=\"bp-data\"")
        .count();
    assert_eq!(live, json!(marked), "interactive figures started");
    assert!(marked >= 10, "{marked}");
    let tools = b.eval("document.querySelectorAll('.bp-tools').length");
    assert_eq!(tools, json!(marked));
    // a full-page screenshot with content (not a blank page)
    let shot = b.screenshot(Some((0.0, 0.0, 1280.0, 4000.0)));
    std::fs::write(d.dir.parent().unwrap().join("screenshot.png"), &shot).unwrap();
    let dark = dark_pixels(&shot);
    assert!(
        dark > 40_000,
        "only {dark} dark pixels: the page looks blank"
    );
    let problems = b.problems();
    assert!(problems.is_empty(), "page errors: {problems:#?}");
    drop(b);

    // Without scripts: the same figures, static, no tools.
    let mut b = Browser::start(&browser, &d.dir.parent().unwrap().join("profile-noscript"));
    b.scripts_off();
    b.open(&format!("file://{}", d.page.display()), 1280, 1000);
    let found = b.eval(&format!(
        "{:?}.filter(id => {{ const f = document.getElementById('fig-' + id); \
         return f && f.querySelector('svg'); }}).length",
        ids
    ));
    assert_eq!(found, json!(ids.len()), "figures missing without scripts");
    assert_eq!(
        b.eval("document.querySelectorAll('.bp-tools').length"),
        json!(0)
    );
    assert_eq!(
        b.eval("document.documentElement.getAttribute('data-live-figures')"),
        json!(null)
    );
}

/// PNG bytes → number of dark pixels.
fn dark_pixels(png_bytes: &[u8]) -> usize {
    let decoder = png::Decoder::new(std::io::Cursor::new(png_bytes));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    let bpp = info.line_size / info.width as usize;
    buf[..info.buffer_size()]
        .chunks(bpp)
        .filter(|px| px[0] < 128)
        .count()
}

/// The plot area of panel `k` of a figure, in page coordinates, and its
/// visible x range in data units.
fn plot_area(b: &mut Browser, fig: &str, k: usize) -> ([f64; 4], (f64, f64)) {
    let v = b.eval(&format!(
        "(() => {{ const f = document.getElementById('fig-{fig}'); f.scrollIntoView(); \
         const g = f.querySelectorAll('g.bp-live')[{k}]; \
         const r = g.querySelector('rect.bp-capture').getBoundingClientRect(); \
         return [r.left, r.top, r.width, r.height, g.getAttribute('data-x')]; }})()"
    ));
    let a = v.as_array().unwrap();
    let n = |i: usize| a[i].as_f64().unwrap();
    let range: Vec<f64> = a[4]
        .as_str()
        .unwrap()
        .split(' ')
        .map(|s| s.parse().unwrap())
        .collect();
    ([n(0), n(1), n(2), n(3)], (range[0], range[1]))
}

/// Zoom by dragging across a plot and by the wheel, pan, read values under
/// the cursor, reset: each changes the visible range as it should, on a
/// log axis (the full-range spectra) and a linear one (a correlation), and
/// the page logs no error.
#[test]
fn zoom_pan_and_readout_work_with_the_mouse() {
    let Some(browser) = browser_or_skip() else {
        return;
    };
    let d = demo();
    let mut b = Browser::start(&browser, &d.dir.parent().unwrap().join("profile-zoom"));
    b.open(&format!("file://{}", d.page.display()), 1280, 1000);

    // Drag from 30 % to 60 % of the width of the first full-range spectrum
    // (log x): the new range spans those 30 % of the decades.
    let ([l, t, w, h], (lo, hi)) = plot_area(&mut b, "spectra", 0);
    let y = t + h / 2.0;
    let left = json!({"button": "left", "buttons": 1, "clickCount": 1});
    b.mouse("mousePressed", l + 0.3 * w, y, left.clone());
    b.mouse("mouseMoved", l + 0.45 * w, y, json!({"buttons": 1}));
    b.mouse("mouseMoved", l + 0.6 * w, y, json!({"buttons": 1}));
    b.mouse("mouseReleased", l + 0.6 * w, y, left.clone());
    let (_, (a, z)) = plot_area(&mut b, "spectra", 0);
    let decades = (hi / lo).log10();
    let want_a = lo * 10f64.powf(0.3 * decades);
    let want_z = lo * 10f64.powf(0.6 * decades);
    // the drag lands on whole CSS pixels: 1 px of ~770 is 0.13 %
    assert!(
        ((a / want_a).log10() / decades).abs() < 0.005
            && ((z / want_z).log10() / decades).abs() < 0.005,
        "dragged to [{a}, {z}], want [{want_a}, {want_z}] of [{lo}, {hi}]"
    );
    // the other panels of the figure keep theirs (not linked: each its signal)
    // … but a zoomed panel is redrawn: new tick labels in the live layer
    let ticks = b.eval(
        "document.getElementById('fig-spectra').querySelectorAll('g.bp-live')[0]\
         .querySelectorAll('text').length",
    );
    assert!(ticks.as_u64().unwrap() >= 4, "{ticks}");

    // Values under the cursor.
    b.mouse("mouseMoved", l + 0.5 * w, y, json!({}));
    let readout = b.eval(
        "Array.from(document.querySelectorAll('#fig-spectra text.bp-readout'))\
         .map(t => t.textContent).join(' | ')",
    );
    let readout = readout.as_str().unwrap().to_string();
    assert!(
        readout.contains("Frequency (Hz)") && readout.contains("friction: "),
        "readout '{readout}'"
    );

    // Double-click resets to the whole range.
    b.mouse(
        "mousePressed",
        l + 0.5 * w,
        y,
        json!({"button": "left", "buttons": 1, "clickCount": 2}),
    );
    b.mouse(
        "mouseReleased",
        l + 0.5 * w,
        y,
        json!({"button": "left", "clickCount": 2}),
    );
    let (_, (a, z)) = plot_area(&mut b, "spectra", 0);
    assert!(
        (a / lo - 1.0).abs() < 1e-4 && (z / hi - 1.0).abs() < 1e-4,
        "[{a}, {z}]"
    );

    // The wheel zooms a clicked (active) figure around the cursor; a linear
    // axis: the zoom panel of a correlation.
    let ([l, t, w, h], (lo, hi)) = plot_area(&mut b, "corr_friction", 1);
    let (x, y) = (l + 0.5 * w, t + h / 2.0);
    b.mouse("mousePressed", x, y, left.clone());
    b.mouse("mouseReleased", x, y, left.clone());
    b.mouse("mouseWheel", x, y, json!({"deltaX": 0, "deltaY": -200}));
    let (_, (a, z)) = plot_area(&mut b, "corr_friction", 1);
    // zoomed in about the centre by exp(0.4): the width shrinks to 67 %
    let ratio = (z - a) / (hi - lo);
    assert!((ratio - (-0.4f64).exp()).abs() < 0.01, "{ratio}");
    assert!(((a + z) / 2.0 - (lo + hi) / 2.0).abs() < 0.01 * (hi - lo));
    // Shift-drag pans by the distance dragged.
    b.mouse(
        "mousePressed",
        x,
        y,
        json!({"button": "left", "buttons": 1, "clickCount": 1, "modifiers": 8}),
    );
    b.mouse(
        "mouseMoved",
        x - 0.1 * w,
        y,
        json!({"buttons": 1, "modifiers": 8}),
    );
    b.mouse(
        "mouseReleased",
        x - 0.1 * w,
        y,
        json!({"button": "left", "modifiers": 8}),
    );
    let (_, (a2, z2)) = plot_area(&mut b, "corr_friction", 1);
    let shift = a2 - a;
    assert!(
        (shift - 0.1 * (z - a)).abs() < 0.01 * (z - a)
            && ((z2 - a2) - (z - a)).abs() < 1e-9 * (hi - lo),
        "panned by {shift} of {}",
        z - a
    );
    // The page's own scrolling is left alone when no figure is active.
    b.mouse("mousePressed", 5.0, 5.0, left.clone());
    b.mouse("mouseReleased", 5.0, 5.0, left);
    let ([l, t, w, h], before) = plot_area(&mut b, "corr_friction", 1);
    b.mouse(
        "mouseWheel",
        l + w / 2.0,
        t + h / 2.0,
        json!({"deltaX": 0, "deltaY": -200}),
    );
    let (_, after) = plot_area(&mut b, "corr_friction", 1);
    assert_eq!(before, after);

    // the zoomed figure, with the readout, for a person to look at
    let ([l, t, w, h], _) = plot_area(&mut b, "corr_friction", 1);
    b.mouse("mouseMoved", l + 0.3 * w, t + h / 2.0, json!({}));
    let r = b.eval(
        "(() => { const r = document.getElementById('fig-corr_friction').getBoundingClientRect(); \
         return [r.left + window.scrollX, r.top + window.scrollY, r.width, r.height]; })()",
    );
    let r: Vec<f64> = r
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let shot = b.screenshot(Some((r[0], r[1], r[2], r[3])));
    std::fs::write(d.dir.parent().unwrap().join("zoomed.png"), shot).unwrap();
    let problems = b.problems();
    assert!(problems.is_empty(), "page errors: {problems:#?}");
}

/// Screenshots of every command's report for a person to look at (not a
/// check; run with `--ignored`): the demo's, and analyze, passage, model,
/// sweep and diagnose on simulated recordings, each figure and the top of
/// each page, under `target/tmp/browser/shots/`.
#[test]
#[ignore]
fn screenshots_of_every_report() {
    let Some(browser) = browser_or_skip() else {
        return;
    };
    let d = demo(); // first: it clears target/tmp/browser
    let root = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("browser/shots");
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(&root).unwrap();
    let rec = d.dir.join("recordings");
    let run = |args: &[&str]| {
        let r = output(bin().current_dir(&root).args(args));
        assert!(r.ok() || args[0] == "diagnose", "{args:?}: {}", r.stderr);
    };
    let r1 = rec.join("v09_r1.csv");
    let all: Vec<String> = (1..=5)
        .map(|k| rec.join(format!("v09_r{k}.csv")).display().to_string())
        .collect();
    let mut analyze = vec!["analyze"];
    analyze.extend(all.iter().map(String::as_str));
    analyze.extend(["--velocity", "9", "--out", "analyze"]);
    run(&analyze);
    run(&[
        "passage",
        r1.to_str().unwrap(),
        "--velocity",
        "9",
        "--out",
        "passage",
    ]);
    run(&[
        "model",
        "stage",
        "--mass",
        "10",
        "--natural-frequency",
        "1",
        "--damping",
        "1.3",
        "--velocity",
        "9",
        "--out",
        "model",
    ]);
    run(&["simulate-campaign", "--out", "campaign"]);
    run(&["sweep", "campaign/manifest.csv", "--out", "sweep"]);
    run(&["diagnose", "campaign/manifest.csv", "--out", "diagnose"]);
    let pages: Vec<(String, PathBuf)> = vec![
        ("demo".into(), d.page.clone()),
        ("analyze".into(), root.join("analyze/report.html")),
        ("passage".into(), root.join("passage/report.html")),
        ("model".into(), root.join("model/report.html")),
        ("sweep".into(), root.join("sweep/report.html")),
        ("diagnose".into(), root.join("diagnose/report.html")),
    ];
    for (name, page) in pages {
        shoot(&browser, &root, &name, &page);
    }
}

fn shoot(browser: &Path, root: &Path, name: &str, page: &Path) {
    let page = page.canonicalize().unwrap();
    let mut b = Browser::start(browser, &root.join(format!("profile-{name}")));
    b.open(&format!("file://{}", page.display()), 1100, 1400);
    let top = b.screenshot(Some((0.0, 0.0, 1100.0, 1800.0)));
    std::fs::write(root.join(format!("{name}-top.png")), top).unwrap();
    let ids = b.eval("Array.from(document.querySelectorAll('figure')).map(f => f.id)");
    for id in ids.as_array().unwrap() {
        let id = id.as_str().unwrap();
        let r = b.eval(&format!(
            "(() => {{ const r = document.getElementById('{id}').getBoundingClientRect(); \
             return [r.left + window.scrollX, r.top + window.scrollY, r.width, r.height]; }})()"
        ));
        let r = r.as_array().unwrap();
        let n = |i: usize| r[i].as_f64().unwrap();
        let png = b.screenshot(Some((n(0), n(1), n(2), n(3))));
        std::fs::write(root.join(format!("{name}-{id}.png")), png).unwrap();
    }
    let problems = b.problems();
    assert!(problems.is_empty(), "{name}: {problems:#?}");
}
