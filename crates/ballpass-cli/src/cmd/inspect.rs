//! `ballpass inspect`: what a user must know about recording files before
//! analysing them.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{anyhow, Result};
use ballpass::recording::inspect::{inspect, inspect_file, InspectSettings, Inspection, Severity};
use ballpass::recording::io::contents;
use ballpass::recording::load;
use ballpass::recording::segment::{self, Plateau, SegmentSettings, Window};
use clap::Args;
use serde::Serialize;

use crate::args::LoadArgs;
use crate::records::SegmentArgs;
use crate::{output, text};

/// Arguments of `ballpass inspect`.
#[derive(Debug, Args)]
pub struct InspectArgs {
    /// Recording files: CSV/TSV, MATLAB .mat (v5/v7/v7.3), NI .tdms or MDF
    /// .mf4. Each is listed (columns, variables and struct fields, groups and
    /// channels: the names to give as --*-col) and, when its channels are
    /// found, inspected; gaps are reported, not refused.
    #[arg(required = true, value_name = "FILE")]
    files: Vec<PathBuf>,
    #[command(flatten)]
    load: LoadArgs,
    /// Print JSON for a program instead of text for a person.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    segment: SegmentArgs,
}

/// Most items of a file listed.
const CONTENTS_LIMIT: usize = 500;

/// One thing a file holds.
#[derive(Serialize)]
struct Item {
    name: String,
    what: String,
}

#[derive(Serialize)]
struct FileReport {
    path: PathBuf,
    /// What the file holds (its listing), when it can be read at all.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    contents: Vec<Item>,
    #[serde(skip_serializing_if = "Option::is_none")]
    inspection: Option<Inspection>,
    /// With --segment: the constant-velocity plateaus from the encoder.
    #[serde(skip_serializing_if = "Option::is_none")]
    plateaus: Option<Vec<Plateau>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    error: Option<String>,
}

#[derive(Serialize)]
struct Output<'a> {
    schema: &'static str,
    version: &'static str,
    settings: InspectSettings,
    #[serde(skip_serializing_if = "Option::is_none")]
    window: Option<Window>,
    files: &'a [FileReport],
}

/// Runs `ballpass inspect`.
pub fn run(a: &InspectArgs) -> Result<()> {
    let opts = a.load.options()?;
    let settings = InspectSettings::default();
    let mut reports = Vec::new();
    let mut first_error = None;
    let window = a.load.window.parsed()?;
    for path in &a.files {
        let listing = || -> Vec<Item> {
            contents(path, &opts, CONTENTS_LIMIT)
                .unwrap_or_default()
                .into_iter()
                .map(|(name, what)| Item { name, what })
                .collect()
        };
        let one = || -> Result<FileReport> {
            // The file as it is, gaps reported rather than refused; with a
            // window or plateaus, the record as the analyses load it.
            let (inspection, plateaus) = if window.is_none() && !a.segment.segment {
                (inspect_file(path, &opts, &settings)?, None)
            } else {
                let rec = a.load.window.apply(load(path, &opts)?)?;
                let plateaus = if a.segment.segment {
                    Some(segment::plateaus(&rec, &SegmentSettings::default())?)
                } else {
                    None
                };
                (inspect(&rec, opts.geometry.as_ref(), &settings), plateaus)
            };
            Ok(FileReport {
                path: path.clone(),
                contents: listing(),
                inspection: Some(inspection),
                plateaus,
                error: None,
            })
        };
        match one() {
            Ok(r) => reports.push(r),
            Err(e) => {
                let msg = e.to_string();
                if a.files.len() > 1 {
                    eprintln!("error: {}", text::line(&msg));
                }
                first_error.get_or_insert_with(|| msg.clone());
                reports.push(FileReport {
                    path: path.clone(),
                    contents: listing(),
                    inspection: None,
                    plateaus: None,
                    error: Some(msg),
                });
            }
        }
    }
    let mut out = output::stdout();
    if a.json {
        let o = Output {
            schema: "ballpass.inspect/1",
            version: ballpass::VERSION,
            settings,
            window,
            files: &reports,
        };
        serde_json::to_writer_pretty(&mut out, &o)?;
        writeln!(out)?;
    } else {
        for (k, r) in reports.iter().enumerate() {
            if k > 0 && (r.inspection.is_some() || !r.contents.is_empty()) {
                writeln!(out)?;
            }
            match &r.inspection {
                Some(i) => print_text(&mut out, i)?,
                None if !r.contents.is_empty() => writeln!(out, "{}", text::path(&r.path))?,
                None => {}
            }
            if let Some(p) = &r.plateaus {
                print_plateaus(&mut out, p)?;
            }
            if !r.contents.is_empty() {
                writeln!(out, "  holds:")?;
                for it in &r.contents {
                    writeln!(
                        out,
                        "    {:<40} {}",
                        text::line(&it.name),
                        text::line(&it.what)
                    )?;
                }
            }
        }
    }
    out.flush()?;
    let failed = reports.iter().filter(|r| r.error.is_some()).count();
    match (failed, first_error) {
        (0, _) => Ok(()),
        (_, Some(msg)) if a.files.len() == 1 => Err(anyhow!(msg)),
        (n, _) => Err(anyhow!(
            "{n} of {} files could not be loaded",
            a.files.len()
        )),
    }
}

fn print_plateaus(out: &mut impl Write, p: &[Plateau]) -> std::io::Result<()> {
    writeln!(
        out,
        "  {} constant-velocity plateau(s) from the encoder:",
        p.len()
    )?;
    for (k, p) in p.iter().enumerate() {
        writeln!(
            out,
            "    {:>2}. t = {:.3}–{:.3} s ({:.2} s) at {:+.4} mm/s ({:?}), blocks within {:.2} %",
            k + 1,
            p.start_s,
            p.end_s,
            p.end_s - p.start_s,
            p.velocity_mm_s,
            p.direction,
            100.0 * p.max_deviation
        )?;
    }
    Ok(())
}

fn print_text(out: &mut impl Write, i: &Inspection) -> std::io::Result<()> {
    writeln!(out, "{}", text::line(&i.source))?;
    writeln!(
        out,
        "  {} samples at {} Hz = {:.3} s, first sample at t = {} s",
        i.samples, i.fs_hz, i.duration_s, i.start_time_s
    )?;
    let v = i
        .velocity_mm_s
        .map(|v| format!("{v} mm/s"))
        .unwrap_or_else(|| "unknown".into());
    let b = i.bearing.as_deref().unwrap_or("unknown");
    write!(out, "  velocity {v}, bearing {b}")?;
    if let (Some(t), Some(p)) = (i.tau_c_s, i.periods) {
        write!(out, ": tau_c = {t:.4} s, {p:.1} periods")?;
    }
    writeln!(out)?;
    writeln!(
        out,
        "  {:<12} {:<4} {:>13} {:>13} {:>13} {:>12} {:>13}",
        "channel", "unit", "min", "max", "mean", "std", "slope /s"
    )?;
    for c in &i.channels {
        writeln!(
            out,
            "  {:<12} {:<4} {:>13.6} {:>13.6} {:>13.6} {:>12.6} {:>13.6}",
            c.channel, c.unit, c.min, c.max, c.mean, c.std, c.slope_per_s
        )?;
    }
    if !i.missing.is_empty() {
        writeln!(out, "  missing: {}", i.missing.join(", "))?;
    }
    for n in &i.notes {
        writeln!(out, "  read: {n}")?;
    }
    if i.gap_count > 0 {
        writeln!(out, "  gaps: {} ({} samples)", i.gap_count, i.gap_samples)?;
        for g in i.gaps.iter().take(20) {
            writeln!(
                out,
                "    t = {:.6} s: {} sample(s) ({:.6} s) at {}: {}",
                g.start_time_s,
                g.len,
                g.duration_s,
                g.place,
                g.channels.join(", ")
            )?;
        }
        if i.gap_count > 20 {
            writeln!(
                out,
                "    ... and {} more (--json lists {})",
                i.gap_count - 20,
                i.gaps.len()
            )?;
        }
    }
    for f in &i.findings {
        let sev = match f.severity {
            Severity::Info => "note",
            Severity::Warning => "WARNING",
        };
        match &f.channel {
            Some(c) => writeln!(out, "  {sev}: {c}: {}", text::line(&f.message))?,
            None => writeln!(out, "  {sev}: {}", text::line(&f.message))?,
        }
    }
    Ok(())
}
