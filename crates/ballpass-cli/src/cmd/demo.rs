//! `ballpass demo`: the thesis campaign on simulated data, analysed end to
//! end into one report.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use ballpass::analysis::write_outputs;
use ballpass::campaign::export;
use ballpass::demo::{run_demo, DemoSettings};
use ballpass::recording::write_csv;
use ballpass::report::{write_report, ReportOptions};
use clap::Args;

use crate::{output, text};

/// Arguments of `ballpass demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Output folder.
    #[arg(long, default_value = "ballpass-demo")]
    out: PathBuf,
    /// Campaign seed of the simulation.
    #[arg(long, default_value_t = DemoSettings::default().seed)]
    seed: u64,
    /// Also write each figure as PNG.
    #[arg(long)]
    png: bool,
    /// Also write the five 9 mm/s recordings as CSV (for `ballpass analyze`).
    #[arg(long)]
    write_recordings: bool,
}

/// Runs `ballpass demo`.
pub fn run(a: &DemoArgs) -> Result<()> {
    let t0 = Instant::now();
    let settings = DemoSettings {
        seed: a.seed,
        ..DemoSettings::default()
    };
    let staging = output::open_dir(&a.out, "demo")?;
    let demo = run_demo(&settings).context("demo")?;
    let out = staging.path();
    write_outputs(&demo.analysis, &out.join("analyze"))?;
    let sweep_dir = out.join("sweep");
    let diag_dir = out.join("diagnose");
    let passage_dir = out.join("passage");
    for d in [&sweep_dir, &diag_dir, &passage_dir] {
        std::fs::create_dir_all(d).with_context(|| format!("cannot create {}", d.display()))?;
    }
    let k = demo.analysis.settings.harmonics;
    export::write_text(
        &sweep_dir,
        "records.csv",
        &export::records_csv(&demo.sweep_records, k),
    )?;
    export::write_text(&sweep_dir, "sweep.csv", &export::sweep_csv(&demo.sweep))?;
    export::write_json(&sweep_dir, "sweep.json", &demo.sweep)?;
    export::write_text(
        &diag_dir,
        "records.csv",
        &export::records_csv(&demo.diagnosis_records, k),
    )?;
    export::write_text(
        &diag_dir,
        "diagnosis.csv",
        &export::diagnosis_csv(&demo.diagnosis),
    )?;
    export::write_text(
        &diag_dir,
        "friction_spectra.csv",
        &export::friction_spectra_csv(&demo.diagnosis),
    )?;
    export::write_json(&diag_dir, "diagnosis.json", &demo.diagnosis)?;
    export::write_json(&passage_dir, "passage.json", &demo.passages)?;
    if a.write_recordings {
        let rec_dir = out.join("recordings");
        std::fs::create_dir_all(&rec_dir)
            .with_context(|| format!("cannot create {}", rec_dir.display()))?;
        for (i, r) in demo.analysis_recordings.iter().enumerate() {
            write_csv(r, &rec_dir.join(format!("v09_r{}.csv", i + 1)))?;
        }
    }
    let files = write_report(
        &demo.report,
        out,
        ReportOptions {
            png: a.png,
            ..Default::default()
        },
    )?;
    let html = staging.final_path(&files.html);
    let dir = output::commit(staging)?;

    let mut o = output::stdout();
    writeln!(
        o,
        "simulated the thesis campaign (seed {}): 100 sweep records (1–20 mm/s × 5) and 50 batch records (5 bearings × 10 at 20 mm/s, bearing 4 sticking)",
        a.seed
    )?;
    writeln!(
        o,
        "ran analyze (5 × 9 mm/s), passage, model, sweep and diagnose:"
    )?;
    for h in &demo.headlines {
        writeln!(o, "  • {h}")?;
    }
    let stages: Vec<String> = demo
        .timings
        .iter()
        .map(|(n, s)| format!("{n} {s:.2} s"))
        .collect();
    writeln!(
        o,
        "time: {} (total {:.2} s)",
        stages.join(", "),
        t0.elapsed().as_secs_f64()
    )?;
    writeln!(
        o,
        "wrote {} figures and tables under {}\nopen {}",
        files.svgs.len(),
        text::path(&dir),
        text::path(&html)
    )?;
    o.flush()?;
    Ok(())
}
