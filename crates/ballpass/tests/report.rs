//! The report layer end to end: a dozen figures of a synthetic 9 mm/s test
//! rendered to SVG, PNG and one HTML file.

#[path = "common/report_demo.rs"]
mod report_demo;

use std::fs;
use std::path::PathBuf;

use ballpass::report::{
    self, render_png, render_svg, write_report, Axis, Block, Figure, Level, Panel, Report,
    ReportOptions, Section, Series, Table, Verdict,
};

fn out_dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("report-tests")
        .join(name);
    let _ = fs::remove_dir_all(&d);
    d
}

/// All text content of an SVG document, parsed as XML.
fn svg_texts(svg: &str) -> Vec<String> {
    let doc = roxmltree::Document::parse(svg)
        .unwrap_or_else(|e| panic!("SVG is not well-formed XML: {e}"));
    assert_eq!(doc.root_element().tag_name().name(), "svg");
    doc.descendants()
        .filter(|n| n.has_tag_name("text"))
        .map(|n| n.text().unwrap_or("").trim().to_string())
        .collect()
}

fn demo_report() -> Report {
    Report::new("ballpass analyze: demo 9 mm/s")
        .with_command("ballpass analyze demo.csv --velocity 9")
        .with_section(
            Section::new("Prediction vs measurement").with(Block::Table(
                Table::new(["quantity", "predicted", "measured", "difference"])
                    .with_row(["f_c (Hz)", "1.110", "1.108", "−0.2 %"])
                    .with_row(["τc (s)", "0.901", "0.903", "+0.2 %"]),
            )),
        )
        .with_section(Section::new("Verdicts").with(Block::Verdicts(vec![
            Verdict::new(Level::Pass, "friction", "peak at f_c, 14 dB above the floor"),
            Verdict::new(Level::Fail, "optical", "no pulses found"),
        ])))
        .with_section(Section::new("Warnings").with(Block::Warnings(vec!["record shorter than 10 τc".into()])))
        .with_section(
            Section::new("Settings").with(
                Block::settings(&serde_json::json!({"lowpass": {"order": 5, "cutoff_hz": 20.0}, "detrend": "linear"}))
                    .unwrap(),
            ),
        )
}

#[test]
fn every_demo_figure_is_well_formed_svg_with_its_axis_titles() {
    for fig in report_demo::figures() {
        let r = render_svg(&fig).unwrap();
        let texts = svg_texts(&r.svg);
        assert!(
            texts.iter().any(|t| t == &fig.title),
            "{}: title missing",
            fig.id
        );
        for p in &fig.panels {
            for axis in [&p.x, &p.y] {
                assert!(
                    texts.iter().any(|t| *t == axis.title()),
                    "{}: axis title '{}' missing from {texts:?}",
                    fig.id,
                    axis.title()
                );
            }
        }
        // a viewBox makes the inline SVG scale with the page
        assert!(r.svg.contains("viewBox=\"0 0 900 "), "{}", fig.id);
    }
}

#[test]
fn units_are_in_the_axis_titles() {
    let figs = report_demo::figures();
    let corr = render_svg(&figs[1]).unwrap();
    let texts = svg_texts(&corr.svg);
    assert!(texts.contains(&"Lag τ (s)".to_string()), "{texts:?}");
    assert!(texts.contains(&"R_FF (N²)".to_string()), "{texts:?}");
    let bode = render_svg(&figs[6]).unwrap();
    let texts = svg_texts(&bode.svg);
    for t in ["Magnitude (dB)", "Phase (deg)", "Frequency (Hz)"] {
        assert!(texts.contains(&t.to_string()), "{t} missing: {texts:?}");
    }
    // log frequency axis labelled in decades
    assert!(
        texts.iter().any(|t| t == "10⁻¹") && texts.iter().any(|t| t == "10¹"),
        "{texts:?}"
    );
}

#[test]
fn correlation_zoom_has_red_dashed_lines_at_multiples_of_tau_c() {
    let fig = &report_demo::figures()[1];
    let r = render_svg(fig).unwrap();
    let texts = svg_texts(&r.svg);
    assert!(
        texts.contains(&"τc".to_string()) && texts.contains(&"−τc".to_string()),
        "{texts:?}"
    );
    // the marker colour of Rgb::RED (214, 39, 40) = #D62728; a dashed line is
    // many short strokes, and six markers make far more than six
    let red = r.svg.matches("stroke=\"#D62728\"").count();
    assert!(red > 6 * 5, "only {red} red strokes");
    // the 59 999-lag correlation is thinned for display: two panels of at
    // most 4 points per pixel column, so the file stays small
    assert!(r.svg.len() < 400_000, "SVG is {} bytes", r.svg.len());
    // ... but the figure data is untouched
    assert_eq!(fig.panels[0].series[0].x.len(), 59_999);
}

#[test]
fn spectra_have_log_y_axes_and_harmonic_markers() {
    let fig = &report_demo::figures()[2];
    let r = render_svg(fig).unwrap();
    let texts = svg_texts(&r.svg);
    for t in ["f_c", "2f_c", "3f_c", "PSD (N²/Hz)"] {
        assert!(texts.contains(&t.to_string()), "{t} missing: {texts:?}");
    }
    assert!(
        texts.iter().any(|t| t.starts_with("10⁻")),
        "no decade labels: {texts:?}"
    );
    // the exact 0 at DC cannot go on a log axis: dropped, and said so
    assert_eq!(r.warnings.len(), 2, "{:?}", r.warnings);
    assert!(
        r.warnings[0].contains("1 of 16385 points have y <= 0"),
        "{}",
        r.warnings[0]
    );
}

#[test]
fn fleet_legend_names_every_bearing() {
    let fig = &report_demo::figures()[10];
    let r = render_svg(fig).unwrap();
    let texts = svg_texts(&r.svg);
    for b in 1..=5 {
        assert!(texts.contains(&format!("bearing {b}")), "{texts:?}");
    }
}

#[test]
fn report_is_one_self_contained_html_with_every_figure_inlined() {
    let mut rep = demo_report();
    rep.figures = report_demo::figures();
    let dir = out_dir("full");
    let files = write_report(
        &rep,
        &dir,
        ReportOptions {
            png: true,
            png_scale: 1,
        },
    )
    .unwrap();
    let html = fs::read_to_string(&files.html).unwrap();

    assert!(html.starts_with("<!DOCTYPE html>"));
    assert_eq!(html.matches("<svg").count(), rep.figures.len());
    for f in &rep.figures {
        assert!(
            html.contains(&format!("<figure id=\"fig-{}\">", f.id)),
            "{} not inlined",
            f.id
        );
    }
    // nothing to fetch: the only script is inline (zoom on the marked
    // figures), url() only points inside the page
    let lower = html.to_lowercase();
    for bad in ["src=", "<link", "@import", "<iframe", "<object", "<img"] {
        assert!(!lower.contains(bad), "report contains {bad}");
    }
    for (i, _) in lower.match_indices("url(") {
        assert!(lower[i + 4..].starts_with('#') || lower[i + 4..].starts_with("\"#"));
    }
    // the SVG namespace (in the figures and the script) is a name, not a fetch
    let without_ns = lower.replace("http://www.w3.org/2000/svg", "");
    assert!(!without_ns.contains("http://") && !without_ns.contains("https://"));
    // summary first, with the version
    let summary_at = html.find("Prediction vs measurement").unwrap();
    assert!(summary_at < html.find("<svg").unwrap());
    assert!(html.contains(&format!("ballpass {}", ballpass::VERSION)));
    assert!(html.contains("<span class=\"badge fail\">FAIL</span>"));
    assert!(
        html.contains("<code>lowpass.cutoff_hz</code></th><td>20.0</td>"),
        "settings flattened"
    );
    // drawing notes surface in the report and the returned warnings
    assert!(
        html.contains("Drawing note: figure &#39;spectrum_ff&#39; panel 1 series &#39;P_FF&#39;")
    );
    assert!(files.warnings.iter().any(|w| w.contains("spectrum_ff")));

    // every figure also on its own, as SVG and PNG
    assert_eq!(files.svgs.len(), rep.figures.len());
    assert_eq!(files.pngs.len(), rep.figures.len());
    for (svg, f) in files.svgs.iter().zip(&rep.figures) {
        assert_eq!(svg, &dir.join("figures").join(format!("{}.svg", f.id)));
        svg_texts(&fs::read_to_string(svg).unwrap());
    }
    for png in &files.pngs {
        let bytes = fs::read(png).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    }
    // no temporary files left behind
    for d in [&dir, &dir.join("figures")] {
        for e in fs::read_dir(d).unwrap() {
            let name = e.unwrap().file_name().to_string_lossy().into_owned();
            assert!(!name.ends_with(".tmp"), "left over: {name}");
        }
    }
}

#[test]
fn png_decodes_to_the_figure_size_and_draws_text_with_the_embedded_font() {
    let fig = report_demo::figures().swap_remove(1);
    let decode = |bytes: &[u8]| {
        let dec = png::Decoder::new(bytes);
        let mut reader = dec.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        buf.truncate(info.buffer_size());
        (info.width, info.height, info.color_type, buf)
    };
    let (w, h, color, pixels) = decode(&render_png(&fig, 2).unwrap());
    // two panels of 300 px under a 38 px title strip, at scale 2
    assert_eq!((w, h), (1800, 2 * (38 + 2 * 300)));
    assert_eq!(color, png::ColorType::Rgb);
    let dark = pixels
        .chunks(3)
        .filter(|p| p.iter().all(|&c| c < 80))
        .count();
    assert!(dark > 5_000, "only {dark} dark pixels");
    // glyphs are really drawn: another title changes the title strip only
    let mut other = fig.clone();
    other.title = "MMMMMMMMMMMMMMMMMMMMMMMMMMMMMMMMMMMMMMMMMMMMMMMMMMM".into();
    let (_, _, _, pixels2) = decode(&render_png(&other, 2).unwrap());
    let row = (w * 3) as usize;
    let strip = 76 * row;
    assert_ne!(pixels[..strip], pixels2[..strip], "title text not drawn");
    assert_eq!(pixels[strip..], pixels2[strip..]);
}

#[test]
fn text_is_escaped_in_html_and_svg() {
    let nasty = "R<xy> & \"friends\" </svg><script>alert(1)</script>";
    let fig = Figure::new("esc", nasty).with_caption(nasty).with_panel(
        Panel::new(Axis::linear(nasty, "<s>"), Axis::linear("y", "&"))
            .with_series(Series::line(nasty, vec![0.0, 1.0], vec![0.0, 1.0]))
            .titled(nasty),
    );
    let svg = render_svg(&fig).unwrap().svg;
    let texts = svg_texts(&svg);
    assert!(texts.contains(&nasty.to_string()));
    assert!(texts.contains(&format!("{nasty} (<s>)")));

    let rep = Report::new(nasty)
        .with_command(nasty)
        .with_section(Section::new(nasty).with(Block::Paragraph(nasty.into())))
        .with_figure(fig);
    let html = report::render_html(&rep, false).unwrap().html;
    assert!(!html.contains("<script>"), "unescaped script tag");
    assert!(!html.contains("<xy>"));
    assert!(html.contains("R&lt;xy&gt; &amp; &quot;friends&quot; &lt;/svg&gt;"));
    assert_eq!(
        report::escape_html("a<b&c>'\""),
        "a&lt;b&amp;c&gt;&#39;&quot;"
    );
}

#[test]
fn log_axis_with_only_non_positive_data_is_an_error_naming_the_series() {
    let fig = Figure::new("bad", "bad").with_panel(
        Panel::new(Axis::linear("f", "Hz"), Axis::log("P", "N²/Hz")).with_series(Series::line(
            "Pxx",
            vec![1.0, 2.0],
            vec![0.0, -1.0],
        )),
    );
    let err = render_svg(&fig).unwrap_err().to_string();
    assert!(
        err.contains("figure 'bad'") && err.contains("no drawable data"),
        "{err}"
    );
}

#[test]
fn a_bad_figure_leaves_the_directory_untouched() {
    let dir = out_dir("bad");
    let rep = demo_report()
        .with_figure(report_demo::figures().swap_remove(11))
        .with_figure(report_demo::figures().swap_remove(11));
    let err = write_report(&rep, &dir, ReportOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("figure 'markers'") && err.contains("another figure"),
        "{err}"
    );
    assert!(!dir.exists());

    let rep = demo_report().with_section(
        Section::new("Scores").with(Block::Table(Table::new(["a", "b"]).with_row(["1"]))),
    );
    let err = write_report(&rep, &dir, ReportOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("row 1 has 1 cells but the header has 2"),
        "{err}"
    );
    assert!(!dir.exists());
}

#[test]
fn rewriting_a_report_replaces_it_whole() {
    let dir = out_dir("rewrite");
    let mut rep = demo_report();
    rep.figures = report_demo::figures()[..2].to_vec();
    write_report(&rep, &dir, ReportOptions::default()).unwrap();
    rep.title = "second run".into();
    let files = write_report(&rep, &dir, ReportOptions::default()).unwrap();
    let html = fs::read_to_string(files.html).unwrap();
    assert!(html.contains("<title>second run</title>"));
    assert!(files.pngs.is_empty() && !dir.join("figures/signals.png").exists());
}
