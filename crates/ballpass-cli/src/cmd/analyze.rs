//! `ballpass analyze`: correlations, spectra, period, phases and harmonics of
//! one recording or several repeats at one velocity (thesis ch. 4 and 7).

use std::io::Write;
use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use ballpass::analysis::{
    self, Analysis, AnalyzeSettings, CorrNorm, Detrend, HiresMethod, WindowKind,
};
use ballpass::recording::{self, LoadOptions};
use clap::{Args, ValueEnum};

use crate::args::BearingArgs;

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
    /// Recording files (CSV/TSV); several files are repeats at one velocity
    /// and are averaged.
    #[arg(required = true, value_name = "REC")]
    recs: Vec<PathBuf>,
    /// Commanded tracking velocity, mm/s (default: from the files' metadata).
    #[arg(long, short = 'v', allow_hyphen_values = true)]
    velocity: Option<f64>,
    #[command(flatten)]
    bearing: BearingArgs,
    /// Sampling rate, Hz, for files without a time column.
    #[arg(long, value_name = "HZ")]
    fs: Option<f64>,
    /// Output folder for analysis.json, correlations.csv, spectra.csv,
    /// spectra_hires.csv.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Seconds dropped at the start of each record (start transient).
    #[arg(long, value_name = "S", default_value_t = 0.0)]
    trim: f64,
    /// Butterworth low-pass cutoff, Hz.
    #[arg(long, value_name = "HZ", default_value_t = 20.0)]
    lowpass: f64,
    /// Skip the low-pass.
    #[arg(long)]
    no_lowpass: bool,
    /// Butterworth order.
    #[arg(long, value_name = "N", default_value_t = 5)]
    order: usize,
    /// Trend removed after the low-pass.
    #[arg(long, value_enum, default_value = "linear")]
    detrend: DetrendArg,
    /// Full-range Welch segment length (capped at the record length).
    #[arg(long, value_name = "N", default_value_t = 4096)]
    nperseg: usize,
    /// Full-range Welch overlap (default: half a segment).
    #[arg(long, value_name = "N")]
    noverlap: Option<usize>,
    /// Welch window.
    #[arg(long, value_enum, default_value = "hann")]
    window: WindowArg,
    /// Correlation normalisation.
    #[arg(long, value_enum, default_value = "coeff")]
    corr_norm: CorrNormArg,
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
    /// Harmonics k = 1..=K examined.
    #[arg(long, value_name = "K", default_value_t = 5)]
    harmonics: usize,
    /// Confidence of the significance tests.
    #[arg(long, value_name = "P", default_value_t = 0.99)]
    confidence: f64,
    /// Print analysis.json to stdout instead of the summary.
    #[arg(long)]
    json: bool,
}

impl AnalyzeArgs {
    fn settings(&self) -> AnalyzeSettings {
        AnalyzeSettings {
            trim_start_s: self.trim,
            lowpass_hz: (!self.no_lowpass).then_some(self.lowpass),
            order: self.order,
            detrend: match self.detrend {
                DetrendArg::Linear => Detrend::Linear,
                DetrendArg::Constant => Detrend::Constant,
                DetrendArg::None => Detrend::None,
            },
            corr_norm: match self.corr_norm {
                CorrNormArg::Biased => CorrNorm::Biased,
                CorrNormArg::Unbiased => CorrNorm::Unbiased,
                CorrNormArg::Coeff => CorrNorm::Coeff,
                CorrNormArg::None => CorrNorm::None,
            },
            nperseg: self.nperseg,
            noverlap: self.noverlap,
            window: match self.window {
                WindowArg::Hann => WindowKind::Hann,
                WindowArg::Hamming => WindowKind::Hamming,
                WindowArg::Boxcar => WindowKind::Boxcar,
            },
            hires: match self.zoom {
                Some(m) => HiresMethod::PolyphaseZoom { m },
                None => HiresMethod::Decimate,
            },
            hires_q: self.hires_q,
            hires_nperseg: self.nperseg_hr,
            hires_noverlap: self.noverlap_hr,
            harmonics: self.harmonics,
            confidence: self.confidence,
            ..AnalyzeSettings::default()
        }
    }
}

/// Runs `ballpass analyze`.
pub fn run(a: &AnalyzeArgs) -> Result<()> {
    let (bearing_name, geometry) = a.bearing.geometry()?;
    let settings = a.settings();
    settings.validate()?;
    let opts = LoadOptions {
        fs_hz: a.fs,
        velocity_mm_s: a.velocity,
        bearing: Some(bearing_name.clone()),
        geometry: Some(geometry),
        min_periods: 2.0,
        ..LoadOptions::default()
    };
    let recs = a
        .recs
        .iter()
        .map(|p| recording::load(p, &opts).with_context(|| format!("loading {}", p.display())))
        .collect::<Result<Vec<_>>>()?;
    let velocity = match a.velocity {
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
    let mut err = std::io::stderr().lock();
    for w in &analysis.warnings {
        writeln!(err, "warning: {w}")?;
    }
    analysis::write_outputs(&analysis, &a.out)?;
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
