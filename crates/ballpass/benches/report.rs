//! Rendering the twelve demo figures (every figure kind, a 30 000-sample
//! signal stack, a 59 999-lag correlation and 16 385-bin spectra): SVG, PNG
//! and the whole report written to disk.
//!
//! There is no SciPy counterpart (SciPy does not plot and matplotlib is not
//! part of the pinned tools).

// criterion_group! generates an undocumented `pub fn benches`.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};

#[path = "../tests/common/report_demo.rs"]
mod report_demo;

use ballpass::report::{render_png, render_svg, write_report, Report, ReportOptions};

fn bench(c: &mut Criterion) {
    let figures = report_demo::figures();
    let mut g = c.benchmark_group("report");
    g.sample_size(10);
    g.bench_function("svg_12_figures", |b| {
        b.iter(|| {
            for f in &figures {
                std::hint::black_box(render_svg(f).unwrap());
            }
        })
    });
    g.bench_function("png_12_figures_scale2", |b| {
        b.iter(|| {
            for f in &figures {
                std::hint::black_box(render_png(f, 2).unwrap());
            }
        })
    });
    let dir = std::env::temp_dir().join(format!("ballpass-bench-report-{}", std::process::id()));
    let mut report = Report::new("bench");
    report.figures = figures.clone();
    g.bench_function("write_report_12_figures_svg_only", |b| {
        b.iter(|| write_report(&report, &dir, ReportOptions::default()).unwrap())
    });
    g.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, bench);
criterion_main!(benches);
