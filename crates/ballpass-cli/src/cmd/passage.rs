//! `ballpass passage`: ball passages seen by the optical sensor, per record.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{bail, Result};
use ballpass::analysis::passage::{PassageAnalysis, PassageSettings};
use ballpass::analysis::passage_table::{checked_passages, PassageFailure, PassageOutput};
use ballpass::analysis::preflight::PreflightSettings;
use ballpass::bearing::Geometry;
use ballpass::recording::io::load_all;
use ballpass::recording::Recording;
use ballpass::report;
use clap::Args;

use crate::args::{command_line, LoadArgs, ReportArgs};
use crate::output;
use crate::records::{self, CheckArgs, SegmentArgs};
use crate::text;

/// Arguments of `ballpass passage`.
#[derive(Debug, Args)]
pub struct PassageArgs {
    /// Recording files: CSV/TSV, MATLAB .mat (v5/v7/v7.3), NI .tdms or MDF .mf4.
    /// The velocity is --velocity, else the profile's or the file's; without
    /// one the period is found from the pulses and nothing is predicted.
    #[arg(required = true, value_name = "REC")]
    records: Vec<PathBuf>,
    #[command(flatten)]
    load: LoadArgs,
    /// Smallest pulse prominence, in noise standard deviations.
    #[arg(long, default_value_t = PassageSettings::default().min_snr, value_name = "X")]
    min_snr: f64,
    /// Pulses in the Gaussian/rectangular train fits (0: no fits).
    #[arg(long, default_value_t = PassageSettings::default().fit_pulses, value_name = "N")]
    fit_pulses: usize,
    /// Order of the rectangular Fourier series fitted.
    #[arg(long, default_value_t = PassageSettings::default().rectangular_order, value_name = "N")]
    order: usize,
    /// Output folder for passages.csv, passage.json and the report.
    #[arg(long, short = 'o', value_name = "DIR")]
    out: PathBuf,
    #[command(flatten)]
    report: ReportArgs,
    #[command(flatten)]
    check: CheckArgs,
    #[command(flatten)]
    segment: SegmentArgs,
}

/// Runs `ballpass passage`.
pub fn run(a: &PassageArgs) -> Result<()> {
    let opts = a.load.options()?;
    let bearing_name = opts.bearing.clone().unwrap_or_default();
    let geometry = opts.geometry.expect("options() resolves the bearing");
    let settings = PassageSettings {
        geometry: opts.geometry,
        min_snr: a.min_snr,
        fit_pulses: a.fit_pulses,
        rectangular_order: a.order,
        ..Default::default()
    };
    a.load.window.parsed()?;
    let out = output::open_dir(&a.out, "passage")?;
    let pre = a.check.preflight();
    let mut done = Vec::new();
    let mut recs: Vec<Recording> = Vec::new();
    let mut failed = Vec::new();
    let mut warnings = Vec::new();
    let mut notes = Vec::new();
    for path in &a.records {
        // One recording per file, or its pieces with --split-gaps; each cut
        // to the window, then taken apart into plateaus with --segment.
        let loaded = load_all(path, &opts)
            .map_err(anyhow::Error::from)
            .and_then(|pieces| a.load.window.apply_pieces(pieces));
        let parts = match loaded {
            Ok(pieces) if a.segment.segment => {
                records::segment_all(&pieces).map(|(found, parts)| {
                    for f in &found {
                        notes.push(format!(
                            "{}: {} plateau(s) from the encoder",
                            f.source,
                            f.plateaus.len()
                        ));
                    }
                    parts
                })
            }
            Ok(pieces) => Ok(pieces),
            Err(e) => Err(e),
        };
        let parts = match parts {
            Ok(p) => p,
            Err(e) => {
                failed.push(PassageFailure {
                    record: path.display().to_string(),
                    error: e.to_string(),
                });
                continue;
            }
        };
        for rec in parts {
            let name = rec.source_name();
            match one(rec, a, &settings, &geometry, &pre) {
                Ok((rec, r, w, n)) => {
                    warnings.extend(w);
                    notes.extend(n);
                    done.push(r);
                    recs.push(rec);
                }
                Err(e) => failed.push(PassageFailure {
                    record: name,
                    error: e.to_string(),
                }),
            }
        }
    }
    {
        let mut err = std::io::stderr().lock();
        for n in &notes {
            writeln!(err, "note: {}", text::line(n))?;
        }
        for w in &warnings {
            writeln!(err, "warning: {}", text::line(w))?;
        }
        for f in &failed {
            writeln!(err, "error: {}", text::line(&f.error))?;
        }
    }
    if done.is_empty() {
        bail!(
            "no passages measured in {} record(s); nothing written",
            a.records.len()
        );
    }
    let staged = out.path();
    let result = PassageOutput {
        window: a.load.window.parsed()?,
        warnings,
        ..PassageOutput::new(bearing_name.clone(), done, failed)
    };
    result.write(staged)?;
    let (done, failed) = (&result.records, &result.failed);
    let report = report::passage::passages_report(&recs, done, failed, &settings, &bearing_name)?
        .with_command(command_line());
    let written = a.report.write(&report, staged)?;
    let dir = output::commit(out)?;
    let mut out = output::stdout();
    for r in done {
        summarize(&mut out, r)?;
    }
    writeln!(
        out,
        "wrote {}/{{passages.csv, passage.json{}}}",
        text::path(&dir),
        if written.is_some() {
            ", report.html, figures/"
        } else {
            ""
        }
    )?;
    out.flush()?;
    if !failed.is_empty() {
        bail!(
            "{} of {} record(s) failed (see above); the others were written",
            failed.len(),
            a.records.len()
        );
    }
    Ok(())
}

/// The checks and the passages of one record: the record as analysed, its
/// passages, warnings and notes.
fn one(
    rec: Recording,
    a: &PassageArgs,
    settings: &PassageSettings,
    geometry: &Geometry,
    pre: &PreflightSettings,
) -> Result<(Recording, PassageAnalysis, Vec<String>, Vec<String>)> {
    // An explicit --velocity is a setting; a profile's or the file's
    // reaches the analysis through the recording's metadata; without
    // either, the encoder's is used when there is an encoder.
    // A plateau's velocity is the encoder's: measured, not stated.
    let file_velocity = rec.meta.velocity_mm_s.filter(|_| !a.segment.segment);
    let stated = a.load.velocity.or(file_velocity);
    let c = checked_passages(rec, stated, a.load.velocity, settings, geometry, pre)?;
    Ok((c.recording, c.passages, c.warnings, c.notes))
}

fn summarize(out: &mut impl Write, r: &PassageAnalysis) -> Result<()> {
    writeln!(out, "{}:", text::line(&r.source))?;
    let vel = match r.velocity_mm_s {
        Some(v) => format!("v = {v} mm/s ({})", r.velocity_source),
        None => "velocity unknown (period from the pulses)".into(),
    };
    writeln!(
        out,
        "  {} passages ({} inverted) in {:.2} s; {vel}; noise {:.3e} V, threshold {:.3e} V",
        r.count, r.count_inverted, r.duration_s, r.noise_v, r.prominence_threshold_v
    )?;
    if r.tau_p_s.mean.is_finite() {
        writeln!(
            out,
            "  tau_c = {:.5} ± {:.5} s, tau_p = {:.5} ± {:.5} s (width at half prominence), tau_p/tau_c = {:.4} ± {:.4} (thesis 0.155)",
            r.tau_c_s.mean, r.tau_c_s.std, r.tau_p_s.mean, r.tau_p_s.std, r.tau_p_over_tau_c.mean, r.tau_p_over_tau_c.std
        )?;
    } else {
        writeln!(
            out,
            "  tau_c = {:.5} ± {:.5} s, tau_p withheld (see the conditions)",
            r.tau_c_s.mean, r.tau_c_s.std
        )?;
    }
    match (r.f_c_predicted_hz, r.f_c_relative_error) {
        (Some(p), Some(e)) => writeln!(
            out,
            "  f_c measured {:.5} Hz, predicted {p:.5} Hz ({:+.2}%)",
            r.f_c_measured_hz,
            100.0 * e
        )?,
        _ => writeln!(out, "  f_c measured {:.5} Hz", r.f_c_measured_hz)?,
    }
    if let (Some(d), Some(c)) = (r.d_avg_implied_mm, r.d_avg_catalog_mm) {
        writeln!(
            out,
            "  d_avg = v tau_c / 2 = {d:.4} mm (catalog {c:.4} mm, {:+.2}%)",
            100.0 * (d / c - 1.0)
        )?;
    }
    if let Some(s) = &r.spacing {
        writeln!(
            out,
            "  spacing {:.3}–{:.3} mm (std {:.3} mm) against [{}, {}] mm: spread uses {:.0}% of d_ext, {} outside",
            s.min_mm,
            s.max_mm,
            s.std_mm,
            s.limit_min_mm,
            s.limit_max_mm,
            100.0 * s.spread_over_free_space,
            s.outside_limits
        )?;
    }
    if let Some(f) = &r.fits {
        let q = |x: Option<f64>| x.map_or("–".to_string(), |v| format!("{v:.4}"));
        writeln!(
            out,
            "  fits over {} pulses: Gaussian R² {} (rms/amplitude {}), rectangular R² {} (rms/amplitude {}) → {}",
            f.pulses,
            q(f.gaussian.as_ref().map(|g| g.quality.r_squared)),
            q(f.gaussian.as_ref().map(|g| g.quality.rms_over_amplitude)),
            q(f.rectangular.as_ref().map(|g| g.quality.r_squared)),
            q(f.rectangular.as_ref().map(|g| g.quality.rms_over_amplitude)),
            f.better.as_deref().unwrap_or("no fit")
        )?;
    }
    if r.conditions.is_empty() {
        writeln!(
            out,
            "  no artefacts found (drift, AC coupling, inverted pulses, gaps)"
        )?;
    }
    for c in &r.conditions {
        writeln!(out, "  {}: {}", c.kind.name(), text::line(&c.message))?;
        writeln!(out, "    → {}", c.advice)?;
    }
    Ok(())
}
