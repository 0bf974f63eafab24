//! `ballpass analyze`: correlations, spectra, period, phases and harmonics of
//! one recording or several repeats at one velocity (thesis ch. 4 and 7).

use std::io::Write;
use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use ballpass::analysis::{
    self, Analysis, AnalyzeSettings, CorrNorm, Detrend, HiresMethod, WindowKind,
};
use ballpass::recording;
use clap::{Args, ValueEnum};
use rayon::prelude::*;

use crate::args::{command_line, LoadArgs, ReportArgs};

/// Trend removal choices.
#[derive(Debug, Clone, Copy, ValueEnum)]
enum DetrendArg {
    Linear,
    Constant,
    None,
}

/// Correlation normalisations.
#[derive(Debug, Clone, Copy, ValueEnum)]
enum CorrNormArg {
    Biased,
    Unbiased,
    Coeff,
    None,
}

/// Welch windows.
#[derive(Debug, Clone, Copy, ValueEnum)]
enum WindowArg {
    Hann,
    Hamming,
    Boxcar,
}

/// Arguments of `ballpass analyze`.
#[derive(Debug, Args)]
pub struct AnalyzeArgs {
    /// Recording files: CSV/TSV, MATLAB .mat (v5/v7/v7.3), NI .tdms or MDF .mf4; several files (or the pieces of
    /// --split-gaps) are repeats at one velocity and are averaged.
    #[arg(required = true, value_name = "REC")]
    recs: Vec<PathBuf>,
    #[command(flatten)]
    load: LoadArgs,
    /// Output folder for analysis.json, correlations.csv, spectra.csv,
    /// spectra_hires.csv.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Seconds dropped at the start of each record (start transient) [default: 0].
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    trim: Option<f64>,
    /// Butterworth low-pass cutoff, Hz [default: 20].
    #[arg(long, value_name = "HZ", allow_hyphen_values = true)]
    lowpass: Option<f64>,
    /// Skip the low-pass.
    #[arg(long)]
    no_lowpass: bool,
    /// Butterworth order [default: 5].
    #[arg(long, value_name = "N")]
    order: Option<usize>,
    /// Trend removed after the low-pass [default: linear].
    #[arg(long, value_enum)]
    detrend: Option<DetrendArg>,
    /// Full-range Welch segment length, capped at the record length [default: 4096].
    #[arg(long, value_name = "N")]
    nperseg: Option<usize>,
    /// Full-range Welch overlap (default: half a segment).
    #[arg(long, value_name = "N")]
    noverlap: Option<usize>,
    /// Welch window [default: hann].
    #[arg(long, value_enum)]
    window: Option<WindowArg>,
    /// Correlation normalisation [default: coeff].
    #[arg(long, value_enum)]
    corr_norm: Option<CorrNormArg>,
    /// High-resolution spectrum by the thesis' zoom processing with factor M
    /// (polyphase average; aliases, see ERRATA §10) instead of decimation.
    #[arg(long, value_name = "M")]
    zoom: Option<usize>,
    /// High-resolution decimation factor (default floor(fs / (2.5 lowpass))).
    #[arg(long, value_name = "Q")]
    hires_q: Option<usize>,
    /// High-resolution segment length (default: f_c/4 resolution).
    #[arg(long, value_name = "N")]
    nperseg_hr: Option<usize>,
    /// High-resolution overlap (default: half a segment).
    #[arg(long, value_name = "N")]
    noverlap_hr: Option<usize>,
    /// Harmonics k = 1..=K examined [default: 5].
    #[arg(long, value_name = "K")]
    harmonics: Option<usize>,
    /// Confidence of the significance tests [default: 0.99].
    #[arg(long, value_name = "P", allow_hyphen_values = true)]
    confidence: Option<f64>,
    #[command(flatten)]
    report: ReportArgs,
    /// Print analysis.json to stdout instead of the summary.
    #[arg(long)]
    json: bool,
}

impl AnalyzeArgs {
    /// Settings: defaults, then the profile's `[analysis]` keys that name
    /// an [`AnalyzeSettings`] field, then the flags given.
    fn settings(&self, profile_analysis: Option<&serde_json::Value>) -> Result<AnalyzeSettings> {
        let mut s = AnalyzeSettings::default();
        if let Some(serde_json::Value::Object(table)) = profile_analysis {
            let known = serde_json::to_value(&s)?;
            let known = known.as_object().expect("settings serialise to an object");
            let mut merged = known.clone();
            for (k, v) in table {
                if known.contains_key(k) {
                    merged.insert(k.clone(), v.clone());
                }
            }
            s = serde_json::from_value(serde_json::Value::Object(merged))
                .context("profile [analysis] table")?;
        }
        if let Some(v) = self.trim {
            s.trim_start_s = v;
        }
        if self.no_lowpass {
            s.lowpass_hz = None;
        } else if let Some(v) = self.lowpass {
            s.lowpass_hz = Some(v);
        }
        if let Some(v) = self.order {
            s.order = v;
        }
        if let Some(v) = self.detrend {
            s.detrend = match v {
                DetrendArg::Linear => Detrend::Linear,
                DetrendArg::Constant => Detrend::Constant,
                DetrendArg::None => Detrend::None,
            };
        }
        if let Some(v) = self.corr_norm {
            s.corr_norm = match v {
                CorrNormArg::Biased => CorrNorm::Biased,
                CorrNormArg::Unbiased => CorrNorm::Unbiased,
                CorrNormArg::Coeff => CorrNorm::Coeff,
                CorrNormArg::None => CorrNorm::None,
            };
        }
        if let Some(v) = self.nperseg {
            s.nperseg = v;
        }
        if self.noverlap.is_some() {
            s.noverlap = self.noverlap;
        }
        if let Some(v) = self.window {
            s.window = match v {
                WindowArg::Hann => WindowKind::Hann,
                WindowArg::Hamming => WindowKind::Hamming,
                WindowArg::Boxcar => WindowKind::Boxcar,
            };
        }
        if let Some(m) = self.zoom {
            s.hires = HiresMethod::PolyphaseZoom { m };
        }
        if self.hires_q.is_some() {
            s.hires_q = self.hires_q;
        }
        if self.nperseg_hr.is_some() {
            s.hires_nperseg = self.nperseg_hr;
        }
        if self.noverlap_hr.is_some() {
            s.hires_noverlap = self.noverlap_hr;
        }
        if let Some(v) = self.harmonics {
            s.harmonics = v;
        }
        if let Some(v) = self.confidence {
            s.confidence = v;
        }
        s.validate()?;
        Ok(s)
    }
}

/// Runs `ballpass analyze`.
pub fn run(a: &AnalyzeArgs) -> Result<()> {
    let profile = a.load.profile()?;
    let settings = a.settings(profile.as_ref().and_then(|p| p.analysis.as_ref()))?;
    let mut opts = a.load.options()?;
    if a.load.min_periods.is_none() {
        // analyze needs two periods (and says so itself); the loader's
        // default of three would reject records analyze can handle.
        opts.min_periods = opts.min_periods.min(2.0);
    }
    let bearing_name = opts.bearing.clone().unwrap_or_default();
    let geometry = opts.geometry.expect("options() resolves the bearing");
    // Repeats are read in parallel; the first failure in argument order is
    // the one reported.
    let recs = a
        .recs
        .par_iter()
        .map(|p| recording::load_all(p, &opts).with_context(|| format!("loading {}", p.display())))
        .collect::<Vec<_>>()
        .into_iter()
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .flatten()
        .collect::<Vec<_>>();
    let velocity = match a.load.velocity {
        Some(v) => v,
        None => {
            let vs: Vec<f64> = recs.iter().filter_map(|r| r.meta.velocity_mm_s).collect();
            match vs.first() {
                Some(&v) if vs.len() == recs.len() && vs.iter().all(|&w| w == v) => v,
                Some(_) => bail!(
                    "the recordings' metadata disagree on the velocity or lack it; give --velocity"
                ),
                None => bail!("no velocity: give --velocity V (mm/s)"),
            }
        }
    };
    let prediction = geometry.predict(velocity, settings.harmonics)?;
    let analysis = analysis::analyze(&recs, &prediction, &settings)?;
    {
        let mut err = std::io::stderr().lock();
        for w in &analysis.warnings {
            writeln!(err, "warning: {w}")?;
        }
    }
    analysis::write_outputs(&analysis, &a.out)?;
    if !a.report.no_report {
        let report = ballpass::report::analysis::report(&analysis, recs.first())?
            .with_command(command_line());
        a.report.write(&report, &a.out)?;
    }
    let mut out = std::io::stdout().lock();
    if a.json {
        serde_json::to_writer_pretty(&mut out, &analysis)?;
        writeln!(out)?;
    } else {
        summary(&mut out, &analysis, &bearing_name)?;
        writeln!(out, "wrote {}", a.out.display())?;
    }
    Ok(())
}

fn summary<W: Write>(w: &mut W, a: &Analysis, bearing: &str) -> std::io::Result<()> {
    let p = &a.prediction;
    writeln!(
        w,
        "{} record(s), {:.2} s at {} Hz, {bearing} at {} mm/s ({:.1} periods)",
        a.inputs.len(),
        a.duration_analysed_s,
        a.fs_hz,
        p.velocity_mm_s,
        a.periods_in_record
    )?;
    write!(
        w,
        "f_c predicted {:.4} Hz (tau_c {:.4} s)",
        p.f_c_hz, p.tau_c_s
    )?;
    match (a.measured_period.f_c_hz, a.measured_period.from_signal) {
        (Some(f), Some(s)) => writeln!(
            w,
            ", measured {f:.4} Hz from the {} autocorrelation ({:+.2} %)",
            s.words(),
            100.0 * (f - p.f_c_hz) / p.f_c_hz
        )?,
        _ => writeln!(w, ", not measured")?,
    }
    for s in &a.measured_period.per_signal {
        if let Some(t) = s.period_s {
            writeln!(
                w,
                "  {:<15} period {t:.4} s from {} peaks",
                s.signal.words(),
                s.peaks.len()
            )?;
        }
    }
    let shows: Vec<&str> = a
        .verdict
        .signals_showing_f_c
        .iter()
        .map(|s| s.words())
        .collect();
    writeln!(
        w,
        "shows f_c above its floor ({:.0} %): {}",
        a.settings.confidence * 100.0,
        if shows.is_empty() {
            "none".to_string()
        } else {
            shows.join(", ")
        }
    )?;
    for ph in &a.phases {
        write!(w, "  {}", ph.words)?;
        if let Some(d) = ph.cross_spectrum_phase_deg {
            write!(w, "; cross spectrum {d:+.0}°")?;
        }
        writeln!(w)?;
    }
    if let Some(v) = &a.velocity_error {
        writeln!(
            w,
            "velocity error std {:.1} µm/s (low-passed {:.1}, quantisation floor {:.1})",
            v.std_um_s, v.lowpassed_std_um_s, v.quantisation_floor_um_s
        )?;
    }
    writeln!(w, "verdict: {}", a.verdict.text)?;
    Ok(())
}
