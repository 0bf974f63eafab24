//! `ballpass sweep` and `ballpass diagnose`: campaigns over many recordings.

use std::io::Write;
use std::path::PathBuf;

use ballpass::outdir::OutputDir;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use ballpass::campaign::diagnose::{diagnose, DiagnoseSettings};
use ballpass::campaign::output::{DIAGNOSIS_SCHEMA, SWEEP_SCHEMA};
use ballpass::campaign::record::RecordResult;
use ballpass::campaign::run::{geometry_for, process_entry, CampaignSettings};
use ballpass::campaign::segments::{load_entry, plan, Planned};
use ballpass::campaign::sweep::sweep;
use ballpass::campaign::{
    export, from_directory, read_manifest, run_batch, BatchOutcome, CampaignKind, CampaignOutput,
    Manifest, ManifestEntry, Selection,
};
use ballpass::report::campaign::{
    campaign_report, diagnosis_parts, friction_examples, sweep_parts, FrictionTrace, ReportParts,
};
use clap::Args;
use serde::Serialize;

use crate::args::{command_line, LoadArgs, ReportArgs};
use crate::records::{CheckArgs, SegmentArgs};
use crate::{output, text};

/// Arguments shared by `sweep` and `diagnose`.
#[derive(Debug, Args)]
pub struct CampaignArgs {
    /// A manifest CSV (path, bearing, velocity_mm_s, repeat[, condition, notes]),
    /// or a folder of recordings together with --pattern. Recordings may be
    /// CSV/TSV, MATLAB .mat (v5/v7/v7.3), NI .tdms or MDF .mf4.
    source: PathBuf,
    /// File-name pattern inside the folder: `*` matches anything, `{velocity}`,
    /// `{repeat}`, `{bearing}` capture fields (e.g. `v{velocity}_r{repeat}.csv`).
    #[arg(long, value_name = "PATTERN")]
    pattern: Option<String>,
    /// Output folder for records.csv, the command's tables and JSON, and the
    /// report.
    #[arg(long, short = 'o', value_name = "DIR")]
    out: PathBuf,
    /// Use only these bearings (repeatable).
    #[arg(long = "only-bearing", value_name = "NAME")]
    only_bearing: Vec<String>,
    /// Use only these velocities, mm/s (repeatable).
    #[arg(long = "only-velocity", value_name = "MM/S")]
    only_velocity: Vec<f64>,
    /// Butterworth low-pass of the analysis, Hz.
    #[arg(long, default_value_t = 20.0, value_name = "HZ")]
    lowpass: f64,
    /// Harmonics k·f_c examined.
    #[arg(long, default_value_t = 5, value_name = "K")]
    harmonics: usize,
    /// Worker threads (default: all cores).
    #[arg(long, value_name = "N")]
    jobs: Option<usize>,
    #[command(flatten)]
    report: ReportArgs,
    #[command(flatten)]
    load: LoadArgs,
    #[command(flatten)]
    check: CheckArgs,
    #[command(flatten)]
    segment: SegmentArgs,
}

/// Arguments of `ballpass diagnose`.
#[derive(Debug, Args)]
pub struct DiagnoseArgs {
    #[command(flatten)]
    common: CampaignArgs,
    /// Low-band edge, Hz.
    #[arg(long, default_value_t = 25.0, value_name = "HZ")]
    low_band: f64,
    /// A ball-pass period is a sticking spike when it rises this many
    /// spreads above the bearing's typical period.
    #[arg(long, default_value_t = 8.0, value_name = "K")]
    spike_spreads: f64,
    /// False-alarm probability per good bearing of the spike count for "bad".
    #[arg(long, default_value_t = 1e-4, value_name = "P")]
    bad_false_alarm: f64,
}

/// Everything one campaign run produced before writing.
struct Batch {
    manifest: Manifest,
    entries: Vec<ManifestEntry>,
    outcome: BatchOutcome<RecordResult>,
    notes: Vec<String>,
    /// Wall time of the batch, s: printed, never written (outputs are the
    /// same bytes for the same inputs).
    seconds: f64,
    out: OutputDir,
}

fn read_source(a: &CampaignArgs) -> Result<Manifest> {
    if a.source.is_dir() {
        let Some(p) = &a.pattern else {
            bail!("{} is a folder: give --pattern (e.g. 'v{{velocity}}_r{{repeat}}.csv') or a manifest CSV", a.source.display());
        };
        // Without {bearing} in the pattern, the bearing is --bearing, else the
        // profile's, else the default (sr25w), as for every other command.
        let bearing = a.load.options()?.bearing;
        // Segmented runs measure their speeds: none needs to be given
        // (NaN: "measured", as an empty manifest cell).
        let velocity = a.load.velocity.or(a.segment.segment.then_some(f64::NAN));
        Ok(from_directory(&a.source, p, bearing.as_deref(), velocity)?)
    } else {
        if a.pattern.is_some() {
            bail!(
                "--pattern goes with a folder, but {} is a file",
                a.source.display()
            );
        }
        Ok(read_manifest(&a.source)?)
    }
}

fn settings(
    a: &CampaignArgs,
    low_band_hz: f64,
    sticking: ballpass::campaign::sticking::StickingSettings,
) -> Result<CampaignSettings> {
    let mut s = CampaignSettings::default();
    s.analyze.lowpass_hz = Some(a.lowpass);
    s.analyze.harmonics = a.harmonics;
    s.low_band_hz = low_band_hz;
    s.sticking = sticking;
    s.preflight = a.check.preflight();
    s.window = a.load.window.parsed()?;
    s.segment = a.segment.segment.then(Default::default);
    Ok(s)
}

fn run(
    a: &CampaignArgs,
    command: &str,
    kind: CampaignKind,
    settings: &CampaignSettings,
) -> Result<Batch> {
    let out = output::open_dir(&a.out, command)?;
    let manifest = read_source(a)?;
    let load = a.load.options()?;
    let fallback = load.geometry.context("no bearing geometry")?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.jobs.unwrap_or(0))
        .build()?;
    // A multi-speed run: its plateaus are the records.
    let mut planned = pool.install(|| {
        plan(
            manifest,
            kind,
            &a.only_bearing,
            &a.only_velocity,
            &load,
            fallback,
            settings,
        )
    })?;
    let bar = crate::output::progress(planned.selection.entries.len(), "records");
    let t0 = Instant::now();
    let outcome = pool.install(|| {
        run_batch(
            &planned.selection.entries,
            |e| process_entry(e, &load, fallback, settings),
            |done, _| {
                if let Some(b) = &bar {
                    b.set_position(done as u64);
                }
            },
        )
    });
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    // Files that could not be segmented are failed records.
    let outcome = planned.finish(outcome);
    let Planned {
        manifest,
        selection: Selection { entries, notes },
        ..
    } = planned;
    Ok(Batch {
        manifest,
        entries,
        outcome,
        notes,
        seconds: t0.elapsed().as_secs_f64(),
        out,
    })
}

/// What `sweep` or `diagnose` found, to be written by [`finish`].
struct Outputs<'a, T: Serialize> {
    /// `ballpass sweep` or `ballpass diagnose`: the report's title.
    title: &'static str,
    /// Schema tag of the JSON file.
    schema: &'static str,
    /// Name of the JSON file.
    json_name: &'static str,
    /// CSV tables written after `records.csv`: file name and text.
    tables: Vec<(&'static str, String)>,
    /// The campaign answer, the JSON's `result`.
    result: &'a T,
    /// The summary lines printed after the selection notes.
    summary: Vec<String>,
}

/// Writes `records.csv`, the command's tables, its JSON and (unless
/// `--no-report`) the report with `parts()`, prints the summary, and fails
/// when a record failed.
fn finish<T: Serialize>(
    a: &CampaignArgs,
    b: &Batch,
    settings: &CampaignSettings,
    o: Outputs<'_, T>,
    parts: impl FnOnce() -> Result<ReportParts>,
) -> Result<(Option<PathBuf>, Vec<String>)> {
    let staged = b.out.path();
    export::write_text(
        staged,
        "records.csv",
        &export::records_csv(&b.outcome, a.harmonics),
    )?;
    for (name, text) in &o.tables {
        export::write_text(staged, name, text)?;
    }
    export::write_json(
        staged,
        o.json_name,
        &CampaignOutput::new(
            o.schema,
            b.manifest.source.display().to_string(),
            &b.outcome,
            &b.notes,
            settings,
            o.result,
        ),
    )?;
    let report = if a.report.no_report {
        None
    } else {
        let report = campaign_report(
            o.title,
            &b.manifest.source,
            b.entries.len(),
            &b.outcome,
            &b.notes,
            parts()?,
            settings,
        )?
        .with_command(command_line());
        a.report.write(&report, staged)?
    };
    Ok((report.map(|r| b.out.final_path(&r.html)), o.summary))
}

/// Commits the outputs, prints the summary, and fails when a record failed.
fn conclude(b: Batch, html: Option<PathBuf>, summary: Vec<String>) -> Result<()> {
    let Batch {
        manifest: _,
        entries,
        outcome,
        notes,
        seconds,
        out,
    } = b;
    let dir = output::commit(out)?;
    let mut out = output::stdout();
    writeln!(
        out,
        "{} records ({} failed) in {seconds:.2} s",
        entries.len(),
        outcome.n_failed(),
    )?;
    for n in &notes {
        writeln!(out, "  {}", text::line(n))?;
    }
    for line in &summary {
        writeln!(out, "{}", text::line(line))?;
    }
    for (e, why) in outcome.failed() {
        let l = format!("{}: {why}", e.label());
        writeln!(out, "  failed: {}", text::line(&l))?;
    }
    writeln!(
        out,
        "wrote {}{}",
        text::path(&dir),
        html.map(|h| format!(" (open {})", text::path(&h)))
            .unwrap_or_default()
    )?;
    out.flush()?;
    let n = outcome.n_failed();
    if n > 0 {
        bail!(
            "{n} of {} records failed (listed above and in the outputs)",
            entries.len()
        );
    }
    Ok(())
}

/// Runs `ballpass sweep`.
pub fn run_sweep(a: &CampaignArgs) -> Result<()> {
    let settings = settings(a, 25.0, Default::default())?;
    let b = run(a, "sweep", CampaignKind::Sweep, &settings)?;
    let ok: Vec<&RecordResult> = b.outcome.ok().map(|(_, r)| r).collect();
    let load = a.load.options()?;
    let geometry = geometry_for(
        ok.first().map_or("", |r| r.bearing.as_str()),
        load.geometry.context("no geometry")?,
    );
    let s = sweep(&ok, Some(geometry.d_avg_mm()));
    let (html, summary) = finish(
        a,
        &b,
        &settings,
        Outputs {
            title: "ballpass sweep",
            schema: SWEEP_SCHEMA,
            json_name: "sweep.json",
            tables: vec![("sweep.csv", export::sweep_csv(&s))],
            result: &s,
            summary: s.findings.clone(),
        },
        || Ok(sweep_parts(&s, "", "")?),
    )?;
    drop(ok);
    conclude(b, html, summary)
}

/// Runs `ballpass diagnose`.
pub fn run_diagnose(a: &DiagnoseArgs) -> Result<()> {
    let c = &a.common;
    let ds = DiagnoseSettings {
        low_band_hz: a.low_band,
        bad_false_alarm: a.bad_false_alarm,
        sticking: ballpass::campaign::sticking::StickingSettings {
            outlier_spreads: a.spike_spreads,
            ..Default::default()
        },
        ..Default::default()
    };
    let settings = settings(c, ds.low_band_hz, ds.sticking.clone())?;
    let b = run(c, "diagnose", CampaignKind::Diagnose, &settings)?;
    let ok: Vec<&RecordResult> = b.outcome.ok().map(|(_, r)| r).collect();
    let d = diagnose(&ok, &ds);
    let summary = d
        .bearings
        .iter()
        .map(|x| {
            format!(
                "#{} {:<12} {:<8} {}",
                x.rank,
                x.bearing,
                x.verdict.name(),
                x.evidence.join("; ")
            )
        })
        .collect();
    let (html, summary) = finish(
        c,
        &b,
        &settings,
        Outputs {
            title: "ballpass diagnose",
            schema: DIAGNOSIS_SCHEMA,
            json_name: "diagnosis.json",
            tables: vec![
                ("diagnosis.csv", export::diagnosis_csv(&d)),
                ("friction_spectra.csv", export::friction_spectra_csv(&d)),
            ],
            result: &d,
            summary,
        },
        || {
            let f_c = ok.first().map(|r| r.f_c_predicted_hz);
            let examples = examples(&d, &b.entries, c, &settings)?;
            Ok(diagnosis_parts(&d, f_c, &examples, "", "")?)
        },
    )?;
    drop(ok);
    conclude(b, html, summary)
}

/// Re-reads, for the report only, the first record of the best and the
/// worst bearing (thesis Fig. 66).
fn examples(
    d: &ballpass::campaign::diagnose::Diagnosis,
    entries: &[ManifestEntry],
    a: &CampaignArgs,
    settings: &CampaignSettings,
) -> Result<Vec<FrictionTrace>> {
    let load = a.load.options()?;
    let fallback = load.geometry.context("no bearing geometry")?;
    Ok(friction_examples(d, |bearing| {
        let e = entries.iter().find(|e| e.bearing == bearing)?;
        load_entry(e, &load, fallback, settings).ok()
    }))
}
