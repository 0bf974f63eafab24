//! `ballpass demo`: the thesis campaign on simulated data, analysed end to
//! end into one report.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use ballpass::demo::{run_demo, write_outputs, DemoSettings};
use ballpass::report::ReportOptions;
use clap::Args;

use crate::{output, text};

/// Arguments of `ballpass demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Output folder for the report and every part's tables.
    #[arg(long, short = 'o', default_value = "ballpass-demo", value_name = "DIR")]
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
    let files = write_outputs(
        &demo,
        staging.path(),
        ReportOptions {
            png: a.png,
            ..Default::default()
        },
        a.write_recordings,
    )?;
    let html = staging.final_path(&files.report.html);
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
        "wrote a report of {} figures and {} tables, and {} data files (CSV, JSON) under {}\nopen {}",
        files.figures,
        files.tables,
        files.data.len(),
        text::path(&dir),
        text::path(&html)
    )?;
    o.flush()?;
    Ok(())
}
