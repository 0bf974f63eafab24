//! The demo's report as a reader meets it: the numbers in the right
//! places, figures numbered and discussed where they stand, every figure's
//! data linked, one notation, no internal names. Each test guards an item
//! a bench engineer caught in an earlier version (named in its comment).
//!
//! The demo runs once per test binary (about 15 s at the test profile's
//! optimisation) and its outputs stay under
//! `target/tmp/demo-report/` for a person to open.

use std::path::PathBuf;
use std::sync::OnceLock;

use ballpass::demo::{run_demo, write_outputs, Demo, DemoFiles, DemoSettings};
use ballpass::report::{Level, ReportOptions, Rgb, Scale};

struct Run {
    demo: Demo,
    files: DemoFiles,
    dir: PathBuf,
    html: String,
}

fn run() -> &'static Run {
    static RUN: OnceLock<Run> = OnceLock::new();
    RUN.get_or_init(|| {
        let demo = run_demo(&DemoSettings::default()).expect("the demo runs");
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("demo-report");
        let _ = std::fs::remove_dir_all(&dir);
        let files = write_outputs(&demo, &dir, ReportOptions::default(), true).expect("written");
        let html = std::fs::read_to_string(&files.report.html).unwrap();
        Run {
            demo,
            files,
            dir,
            html,
        }
    })
}

/// The figure of the demo's report with this id.
fn figure(r: &'static Run, id: &str) -> &'static ballpass::report::Figure {
    r.demo
        .report
        .all_figures()
        .into_iter()
        .find(|f| f.id == id)
        .unwrap_or_else(|| panic!("no figure {id}"))
}

/// The page without its scripts, settings tables, code spans and the data
/// links under the figures (which name files and columns on purpose).
fn visible_text(html: &str) -> String {
    let mut s = html.to_string();
    for (open, close) in [
        ("<script", "</script>"),
        ("<details", "</details>"),
        ("<code>", "</code>"),
        ("<span class=\"files\">", "</span>"),
        ("<svg", "</svg>"),
    ] {
        while let Some(a) = s.find(open) {
            let b = s[a..].find(close).map_or(s.len(), |b| a + b + close.len());
            s.replace_range(a..b, " ");
        }
    }
    // tags out, entities for spaces back
    let mut out = String::with_capacity(s.len());
    let mut in_tag = false;
    for c in s.chars() {
        match c {
            '<' => in_tag = true,
            '>' => {
                in_tag = false;
                out.push(' ');
            }
            c if !in_tag => out.push(c),
            _ => {}
        }
    }
    out.replace("&nbsp;", " ")
}

/// Regression: `analyze` of repeats showed the first record's velocity-error
/// std (108.6 µm/s) where the sweep of the same records said 99.5. The
/// analysis and the sweep now agree on the mean over the five records.
#[test]
fn the_analysis_and_the_sweep_agree_on_the_velocity_error() {
    let r = run();
    let a = r.demo.analysis.velocity_error.as_ref().unwrap();
    let v = r.demo.analysis.prediction.velocity_mm_s;
    let row = r
        .demo
        .sweep
        .velocities
        .iter()
        .find(|x| x.velocity_mm_s == v)
        .unwrap();
    let s = row.velocity_error_std_um_s.unwrap();
    assert_eq!(a.records, 5);
    // the same five records, the same per-record std, summed in another
    // order: equal to rounding
    assert!(
        (a.std_um_s - s.mean).abs() < 1e-9 * s.mean,
        "{a:?} vs {s:?}"
    );
    assert!((a.std_spread_um_s.unwrap() - s.std).abs() < 1e-9 * s.mean);
}

/// Every figure is numbered, listed in the contents, referred to by its
/// number in the text of its section, and followed by links to the data
/// files it is drawn from, which exist.
#[test]
fn figures_are_numbered_discussed_and_linked_to_their_data() {
    let r = run();
    let figures = r.demo.report.all_figures();
    assert_eq!(figures.len(), r.files.figures);
    assert!(r.html.contains("<nav class=\"toc\">"));
    assert!(!r.html.contains("{fig:"), "an unresolved figure reference");
    for (i, f) in figures.iter().enumerate() {
        let n = i + 1;
        assert!(
            r.html
                .contains(&format!("<p class=\"figtitle\">Figure {n}. ")),
            "figure {n} ({}) not numbered",
            f.id
        );
        let link = format!("href=\"#fig-{}\"", f.id);
        // once in the contents, at least once in the text
        assert!(
            r.html.matches(&link).count() >= 2,
            "figure {} is not referred to in the text",
            f.id
        );
        if f.id == "diagnose_friction_examples" || f.id == "signals" {
            // simulated in memory: no file to link (write_outputs links the
            // signals figure in its copy when it writes the recordings)
            continue;
        }
        assert!(!f.data.is_empty(), "figure {} links no data", f.id);
        for d in &f.data {
            let p = r.dir.join(&d.path);
            assert!(p.is_file(), "figure {}: {} missing", f.id, p.display());
        }
    }
    // the signals figure links its recording (written with `recordings`)
    assert!(r.html.contains("href=\"recordings/v09_r1.csv\""));
    assert!(r.dir.join("recordings/v09_r1.csv").is_file());
}

/// Regression: the demo said "26 figures and tables" for 26 figures and 12
/// tables. It counts them apart, and the counts are the page's.
#[test]
fn figure_and_table_counts_are_the_pages() {
    let r = run();
    assert_eq!(
        r.files.figures,
        r.html.matches("<p class=\"figtitle\">").count()
    );
    let tables = r.html.matches("<table>").count();
    assert_eq!(r.files.tables, tables);
    assert!(tables >= 5, "{tables}");
    assert!(r.files.data.len() >= 15, "{:?}", r.files.data);
}

/// Regression: labels and tables showed internal names
/// (`R friction__velocity_error`, `tau_c`).
#[test]
fn no_internal_names_in_the_text_or_the_figures() {
    let r = run();
    let text = visible_text(&r.html);
    for bad in ["__", "tau_c", "tau_p", "ERRATA"] {
        if let Some(at) = text.find(bad) {
            panic!(
                "'{bad}' in the page: …{}…",
                &text[at.saturating_sub(80)..(at + 80).min(text.len())]
            );
        }
    }
    for f in r.demo.report.all_figures() {
        for p in &f.panels {
            for t in [p.x.title(), p.y.title(), p.title.clone()]
                .into_iter()
                .chain(p.series.iter().map(|s| s.name.clone()))
            {
                assert!(
                    !t.contains("__") && !t.contains("tau_") && !t.contains("ERRATA"),
                    "figure {}: '{t}'",
                    f.id
                );
            }
        }
    }
}

/// Regression: "±" was written three ways. Every `a ± b` of two numbers
/// gives them the same number of decimals (the uncertainty to two
/// significant digits, the value rounded to match).
#[test]
fn one_plus_minus_notation() {
    let r = run();
    let text = visible_text(&r.html);
    assert!(!text.contains("+/-") && !text.contains("+-"));
    let decimals = |s: &str| s.split_once('.').map_or(0, |(_, d)| d.len());
    let number = |s: &str| {
        let t = s.trim_matches(|c: char| "(),;:".contains(c));
        t.trim_start_matches('−')
            .parse::<f64>()
            .ok()
            .map(|_| t.to_string())
    };
    let mut pairs = 0;
    let words: Vec<&str> = text.split_whitespace().collect();
    for w in words.windows(3) {
        if w[1] != "±" {
            continue;
        }
        let (Some(a), Some(b)) = (number(w[0]), number(w[2])) else {
            continue;
        };
        if w[0].starts_with('(') || w[2].ends_with(")e") {
            continue; // (m ± u)eN: checked by fmt_pm's own test
        }
        pairs += 1;
        assert_eq!(decimals(&a), decimals(&b), "'{a} ± {b}'");
    }
    assert!(pairs >= 20, "only {pairs} value ± uncertainty pairs");
}

/// Regression: the bad bearing was blue and a good one red in the fleet
/// spectra, and the headline "bad: bearing4" had a grey INFO badge.
#[test]
fn bad_is_red_in_the_fleet_and_in_the_headline() {
    let r = run();
    let fig = figure(r, "diagnose_fleet_spectra");
    let series = &fig.panels[0].series;
    assert_eq!(series.len(), 5);
    for s in series {
        if s.name.contains("(bad)") {
            assert_eq!(s.color, Some(Rgb::RED), "{}", s.name);
            assert!(s.highlight);
        } else {
            assert_ne!(s.color, Some(Rgb::RED), "{}", s.name);
            assert_ne!(s.color, Some(Rgb::ORANGE), "{}", s.name);
        }
    }
    let bad = r
        .demo
        .headlines
        .iter()
        .find(|h| h.text.starts_with("bad:"))
        .unwrap();
    assert_eq!(bad.level, Level::Fail);
    assert!(r.html.contains(
        "<span class=\"badge fail\">FAIL</span><strong>finding</strong> — bad: bearing4"
    ));
}

/// Regression: the full-range spectra were drawn on a linear 0–500 Hz axis
/// down to 1e-25 (the low-pass' stop band), the k·f_c markers merged into
/// one bar. They are the unfiltered spectra on log–log axes with a floor.
#[test]
fn full_range_spectra_are_unfiltered_on_log_axes_with_a_floor() {
    let r = run();
    let fig = figure(r, "spectra");
    let u = &r.demo.analysis.spectra_unfiltered;
    assert_eq!(fig.panels.len(), 3);
    for (p, (_, psd)) in fig.panels.iter().zip(&u.auto) {
        assert_eq!(p.x.scale, Scale::Log);
        assert_eq!(p.y.scale, Scale::Log);
        let (lo, hi) = p.y.range.unwrap();
        let max = psd.iter().skip(1).copied().fold(0.0, f64::max);
        assert!(lo >= max * 1e-8 * (1.0 - 1e-12), "{lo} vs {max}");
        assert!(hi >= max);
        // the data are the unfiltered spectrum itself, without the 0 Hz bin
        // (no place on a log axis)
        assert_eq!(u.freq_hz[0], 0.0);
        assert_eq!(&p.series[0].y[..], &psd[1..]);
        // above 100 Hz the unfiltered spectrum is a noise floor, not the
        // filter's stop band, and it lies inside the axis (its median: the
        // velocity error falls to 0 at Nyquist, the centred difference's
        // zero, and may leave the axis there)
        let f = &u.freq_hz;
        let mut high: Vec<f64> = psd
            .iter()
            .zip(f)
            .filter(|(_, f)| **f > 100.0)
            .map(|(p, _)| *p)
            .collect();
        high.sort_by(f64::total_cmp);
        let floor = high[high.len() / 2];
        assert!(floor > lo, "noise floor {floor} below the axis {lo}");
        // five harmonics marked, spread over the log axis
        assert_eq!(p.vlines.len(), 5);
    }
}

/// Regression: the difference-filter "phase error relative to jω" panel
/// plotted the absolute phase (centred at 90°) under a caption saying it
/// has no phase error.
#[test]
fn the_difference_phase_panel_shows_the_error_against_j_omega() {
    let r = run();
    let fig = figure(r, "difference");
    let phase = &fig.panels[1];
    assert!(phase.title.contains("phase error"));
    let (centred, forward) = (&phase.series[0], &phase.series[1]);
    let fs = 1000.0;
    for i in 0..centred.x.len() {
        let f = centred.x[i];
        // exact +90° in theory; atan2 of a purely imaginary value: 1e-9 deg
        assert!(
            centred.y[i].abs() < 1e-9,
            "centred at {f} Hz: {}",
            centred.y[i]
        );
        // the forward difference leads by 180 f / fs degrees (below Nyquist)
        if f < fs / 2.0 {
            assert!(
                (forward.y[i] - 180.0 * f / fs).abs() < 1e-6,
                "forward at {f} Hz: {}",
                forward.y[i]
            );
        }
    }
}

/// The spectra, signal and correlation figures carry their data for
/// zooming; the page stays one file with nothing to fetch.
#[test]
fn interactive_figures_are_embedded_and_nothing_is_fetched() {
    let r = run();
    let live = r
        .html
        .matches("<script type=\"application/json\" class=\"bp-data\">")
        .count();
    let marked = r
        .demo
        .report
        .all_figures()
        .iter()
        .filter(|f| f.interactive)
        .count();
    assert_eq!(live, marked);
    for id in [
        "signals",
        "corr_friction",
        "spectra",
        "spectra_hires",
        "diagnose_fleet_spectra",
    ] {
        let f = figure(r, id);
        assert!(f.interactive, "{id}");
    }
    let lower = r.html.to_lowercase();
    for bad in [
        "src=",
        "<link",
        "@import",
        "<iframe",
        "<img",
        "fetch(",
        "xmlhttprequest",
        "http://",
        "https://",
    ] {
        let hits = lower.matches(bad).count();
        // the SVG namespace is a name, not a fetch
        let ns = if bad == "http://" {
            lower.matches("http://www.w3.org/").count()
        } else {
            0
        };
        assert_eq!(hits, ns, "the page contains {bad}");
    }
    // url() only for references inside the page (clip paths)
    for (i, _) in lower.match_indices("url(") {
        let next = &lower[i + 4..i + 6];
        assert!(
            next.starts_with('#') || next.starts_with("\"#"),
            "url({next}…"
        );
    }
    let size = r.html.len();
    assert!(size < 12_000_000, "report.html is {size} bytes");
}
