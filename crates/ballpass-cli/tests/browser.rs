//! The demo report in a real browser: headless Chromium loads
//! `report.html` from `ballpass demo`, and the test checks that every figure
//! is present and non-empty, that the page logs no errors, and saves a
//! screenshot (`target/tmp/browser/screenshot.png`) for a person to look at.
//!
//! Chromium is found as `$BALLPASS_CHROMIUM`, `chromium`, `chromium-browser`
//! or `google-chrome`. Without one the test says so and passes, except under
//! CI (`CI` set), where `.ci/run` installs Debian's `chromium` and a missing
//! browser is a failure.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{bin, run_ok};

fn chromium() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("BALLPASS_CHROMIUM") {
        return Some(PathBuf::from(p));
    }
    let path = std::env::var_os("PATH")?;
    for name in ["chromium", "chromium-browser", "google-chrome"] {
        for dir in std::env::split_paths(&path) {
            let p = dir.join(name);
            if p.is_file() {
                return Some(p);
            }
        }
    }
    None
}

/// Runs headless Chromium on `page` with the flags that keep it off the
/// network and quiet on a machine without D-Bus or a GPU.
fn run_chromium(browser: &Path, profile: &Path, page: &Path, extra: &[&str]) -> (String, String) {
    let out = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--enable-logging=stderr",
            "--v=0",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(extra)
        .arg(format!("file://{}", page.display()))
        .output()
        .expect("chromium runs");
    assert!(
        out.status.success(),
        "chromium failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn demo_report_renders_in_headless_chromium() {
    let Some(browser) = chromium() else {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI must have chromium: .ci/run installs Debian's chromium"
        );
        eprintln!("browser test skipped: no chromium on this machine (set BALLPASS_CHROMIUM)");
        return;
    };
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("browser");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let demo = dir.join("demo");
    run_ok(bin().args(["demo", "--out"]).arg(&demo));
    let page = demo.join("report.html").canonicalize().unwrap();

    // Every figure file is well-formed SVG with something drawn in it.
    let mut ids = Vec::new();
    for e in std::fs::read_dir(demo.join("figures")).unwrap() {
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

    // The DOM Chromium built holds every figure, inline, each with its SVG.
    let profile = dir.join("profile");
    let (dom, log) = run_chromium(&browser, &profile, &page, &["--dump-dom"]);
    for id in &ids {
        let at = dom
            .find(&format!("id=\"fig-{id}\""))
            .unwrap_or_else(|| panic!("figure {id} missing from the page"));
        let rest = &dom[at..];
        let end = rest.find("</figure>").expect("figure closed");
        assert!(
            rest[..end].contains("<svg"),
            "figure {id} has no inline SVG"
        );
    }
    assert!(
        !dom.contains("parsererror"),
        "the page has an XML parse error"
    );
    // Console errors of the page (JavaScript or resources) appear as CONSOLE lines.
    let console_errors: Vec<&str> = log
        .lines()
        .filter(|l| l.contains("CONSOLE") || l.contains("Uncaught") || l.contains("net::ERR_"))
        .collect();
    assert!(
        console_errors.is_empty(),
        "page errors: {console_errors:#?}"
    );

    // A screenshot with content (not a blank page).
    let shot = dir.join("screenshot.png");
    run_chromium(
        &browser,
        &profile,
        &page,
        &[
            &format!("--screenshot={}", shot.display()),
            "--window-size=1280,7000",
        ],
    );
    let bytes = std::fs::read(&shot).expect("screenshot written");
    let decoder = png::Decoder::new(std::io::Cursor::new(&bytes));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (1280, 7000));
    let dark = buf
        .chunks(info.line_size / info.width as usize)
        .filter(|px| px[0] < 128)
        .count();
    // Text, axes and curves cover well over 1 % of a 1280 × 7000 page.
    assert!(
        dark > 90_000,
        "only {dark} dark pixels: the page looks blank"
    );
    eprintln!("screenshot: {}", shot.display());
}
