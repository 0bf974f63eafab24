//! `ballpass analyze`: correlations, spectra, period, phases and harmonics of
//! one recording or several repeats at one velocity (thesis ch. 4 and 7).

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use ballpass::analysis::load_cell::LoadCellCorrection;
use ballpass::analysis::preflight::{self, VelocitySource};
use ballpass::analysis::stream::file::{
    self as stream_file, Choice, FileSource, Naming, StreamMode,
};
use ballpass::analysis::MaxLag;
use ballpass::analysis::{
    self, Analysis, AnalyzeSettings, CorrNorm, Detrend, HiresMethod, WindowKind,
};

use ballpass::recording::segment::Window;
use ballpass::recording::Recording;
use clap::{Args, ValueEnum};

use crate::args::{command_line, LoadArgs, ReportArgs};
use crate::records::{self, CheckArgs, SegmentArgs};
use crate::{output, text};

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
    /// Recording files: CSV/TSV, MATLAB .mat (v5/v7/v7.3), NI .tdms or MDF
    /// .mf4; several files (or the pieces of --split-gaps) are repeats at one
    /// velocity and are averaged. The velocity is --velocity, else the
    /// files' (profile, metadata), else measured from the encoder; with
    /// --segment, each speed's plateaus are analysed into DIR/v<speed>/.
    #[arg(required = true, value_name = "REC")]
    recs: Vec<PathBuf>,
    #[command(flatten)]
    load: LoadArgs,
    /// Output folder for analysis.json, correlations.csv, spectra.csv,
    /// spectra_hires.csv, spectra_unfiltered.csv, spectra_position.csv
    /// (with a position channel), sync_average.csv, the report and
    /// ballpass-run.json (written last: the folder holds a complete run
    /// exactly when it is there).
    #[arg(long, short = 'o', value_name = "DIR")]
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
    /// Welch window [default: hann] (`--window` is the time window).
    #[arg(long = "welch-window", value_enum, value_name = "WINDOW")]
    welch_window: Option<WindowArg>,
    /// Correlation normalisation [default: coeff].
    #[arg(long, value_enum)]
    corr_norm: Option<CorrNormArg>,
    /// High-resolution spectrum by the thesis' zoom processing with factor M
    /// (polyphase average; it aliases, see docs/methods.md §10) instead of decimation.
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
    /// Two-sided confidence of the PSD bands exported and drawn with every
    /// spectrum [default: 0.95].
    #[arg(long, value_name = "P", allow_hyphen_values = true)]
    band_confidence: Option<f64>,
    /// The quartz load cell's discharge time constant in seconds, undone
    /// before the analysis; `auto` (default) estimates it from each record,
    /// `off` leaves the friction as recorded (a DC-coupled sensor).
    #[arg(long, value_name = "S|auto|off", value_parser = parse_load_cell)]
    load_cell_tau: Option<LoadCellCorrection>,
    /// Lags of the correlations (and correlations.csv), in seconds, or
    /// `full` for every lag of the record; `auto` (default) is 100
    /// predicted ball periods and at least 60 s.
    #[arg(long, value_name = "S|auto|full", value_parser = parse_max_lag)]
    max_lag: Option<MaxLag>,
    #[command(flatten)]
    report: ReportArgs,
    /// Print analysis.json to stdout instead of the summary.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    check: CheckArgs,
    #[command(flatten)]
    segment: SegmentArgs,
    /// Read a long CSV/TSV, TDMS, MF4 or MATLAB v7.3 record block by block in bounded memory
    /// (`auto`, the default: files of 1 GiB and more, about 4.5 hours at
    /// 1 kHz as CSV), or always (`on`), or never (`off`: the whole record in
    /// memory, with every output). A streamed record gives no passages,
    /// synchronous average or position spectra.
    #[arg(long, value_enum, default_value = "auto", value_name = "WHEN")]
    stream: StreamArg,
}

/// When to stream a record.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum StreamArg {
    Auto,
    On,
    Off,
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
        if let Some(v) = self.load_cell_tau {
            s.load_cell = v;
        }
        if let Some(v) = self.max_lag {
            s.max_lag = v;
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
        if let Some(v) = self.welch_window {
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
        if let Some(v) = self.band_confidence {
            s.band_confidence = v;
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
    let out = output::open_dir(&a.out, "analyze")?;
    let steps = output::steps("reading the records");
    if let Some(src) = streamable(a, &opts)? {
        return run_streamed(a, &settings, &opts, src, out, steps, &bearing_name);
    }
    let recs = records::load_all(&a.recs, &opts, &a.load.window)?;
    let window = a.load.window.parsed()?;
    let ctx = Ctx {
        a,
        settings: &settings,
        geometry,
        window,
        steps: steps.clone(),
    };
    let mut done = Vec::new();
    if a.segment.segment {
        let (found, parts) = records::segment_all(&recs)?;
        drop(recs);
        let tolerance = a.check.preflight().velocity_tolerance;
        let mut groups = records::group_by_speed(parts, tolerance);
        if let Some(v) = a.load.velocity {
            let speeds: Vec<String> = groups.iter().map(|(s, _)| format!("{s:.2}")).collect();
            groups.retain(|(s, _)| (s - v).abs() <= tolerance * v);
            if groups.is_empty() {
                bail!(
                    "no plateau at {v} mm/s (within {:.0} %); the plateaus run at {} mm/s",
                    100.0 * tolerance,
                    speeds.join(", ")
                );
            }
        }
        ballpass::fsutil::write_json_pretty(
            &out.path().join("segments.json"),
            &serde_json::json!({
                "schema": "ballpass.segments/1",
                "version": ballpass::VERSION,
                "settings": ballpass::recording::segment::SegmentSettings::default(),
                "records": found,
                "groups": groups.iter().map(|(s, r)| serde_json::json!({
                    "speed_mm_s": s,
                    "folder": group_dir(*s),
                    "plateaus": r.iter().map(|x| x.source_name()).collect::<Vec<_>>(),
                })).collect::<Vec<_>>(),
            }),
        )?;
        for (speed, recs) in groups {
            let dir = out.path().join(group_dir(speed));
            let analysis = ctx.analyze(recs, None, &dir)?;
            done.push((Some(group_dir(speed)), analysis));
        }
    } else {
        let stated = stated_velocity(a.load.velocity, &recs)?;
        let analysis = ctx.analyze(recs, stated, out.path())?;
        done.push((None, analysis));
    }
    if let Some(s) = steps {
        s.finish_and_clear();
    }
    let dir = output::commit(out)?;
    let mut out = output::stdout();
    if a.json {
        if let [(_, (one, _))] = done.as_slice() {
            serde_json::to_writer_pretty(&mut out, one)?;
        } else {
            let all: Vec<&Analysis> = done.iter().map(|(_, (x, _))| x).collect();
            serde_json::to_writer_pretty(&mut out, &all)?;
        }
        writeln!(out)?;
    } else {
        for (k, (sub, (analysis, source))) in done.iter().enumerate() {
            if k > 0 {
                writeln!(out)?;
            }
            if let Some(sub) = sub {
                writeln!(out, "{sub}/:")?;
            }
            summary(&mut out, analysis, &bearing_name, *source)?;
        }
        writeln!(out, "wrote {}", text::path(&dir))?;
    }
    out.flush()?;
    Ok(())
}

/// What every analysis of one run shares.
struct Ctx<'a> {
    a: &'a AnalyzeArgs,
    settings: &'a AnalyzeSettings,
    geometry: ballpass::bearing::Geometry,
    window: Option<Window>,
    /// The step shown on a terminal.
    steps: Option<indicatif::ProgressBar>,
}

impl Ctx<'_> {
    fn step(&self, what: &str) {
        if let Some(s) = &self.steps {
            s.set_message(what.to_string());
        }
    }

    /// Checks, analyses and writes one set of repeats into `dir` (staged).
    fn analyze(
        &self,
        recs: Vec<Recording>,
        stated: Option<f64>,
        dir: &Path,
    ) -> Result<(Analysis, VelocitySource)> {
        let a = self.a;
        let checked = preflight::check(recs, stated, &self.geometry, &a.check.preflight())?;
        records::check_memory(
            &checked.recordings,
            !a.report.no_report,
            self.settings.max_lag,
            "analyse a part with --window T0:T1 (and --no-report saves about half)",
        )?;
        let prediction = self
            .geometry
            .predict(checked.velocity_mm_s, self.settings.harmonics)?;
        self.step(&format!(
            "analysing {} record(s) of {} samples",
            checked.recordings.len(),
            checked
                .recordings
                .iter()
                .map(Recording::len)
                .max()
                .unwrap_or(0)
        ));
        let mut analysis = analysis::analyze(&checked.recordings, &prediction, self.settings)?;
        analysis
            .warnings
            .splice(0..0, checked.warnings.iter().cloned());
        let mut operations = Vec::new();
        if let Some(w) = &self.window {
            operations.push(("window".to_string(), w.describe()));
            analysis.method_notes.push(format!(
                "window {} of each record (its time axis); inputs are named with it",
                w.describe()
            ));
        }
        operations.push((
            "velocity".to_string(),
            format!(
                "{:.4} mm/s, {}",
                checked.velocity_mm_s,
                checked.velocity_source.words()
            ),
        ));
        analysis.method_notes.extend(checked.notes.iter().cloned());
        let print = || -> std::io::Result<()> {
            let mut err = std::io::stderr().lock();
            for n in &checked.notes {
                writeln!(err, "note: {}", text::line(n))?;
            }
            for w in &analysis.warnings {
                writeln!(err, "warning: {}", text::line(w))?;
            }
            Ok(())
        };
        match &self.steps {
            Some(s) => s.suspend(print)?,
            None => print()?,
        }
        self.step("writing the tables");
        analysis::write_outputs(&analysis, dir)?;
        if !a.report.no_report {
            self.step("drawing the report");
            let links = ballpass::report::analysis::AnalysisLinks {
                tables_dir: String::new(),
                recording: checked
                    .recordings
                    .first()
                    .and_then(|r| r.meta.source.as_ref())
                    .map(|p| std::path::absolute(p).unwrap_or_else(|_| p.clone()))
                    .map(|p| p.display().to_string()),
                id_prefix: String::new(),
            };
            let report =
                ballpass::report::analysis::report(&analysis, checked.recordings.first(), &links)?
                    .with_command(command_line())
                    .with_section(
                        ballpass::report::Section::new("Record operations")
                            .with(ballpass::report::Block::KeyValues(operations)),
                    );
            a.report.write(&report, dir)?;
        }
        Ok((analysis, checked.velocity_source))
    }
}

/// The library's stream choice for this run (`--stream`); a long file
/// read whole gets its warning printed.
fn streamable(
    a: &AnalyzeArgs,
    opts: &ballpass::recording::LoadOptions,
) -> Result<Option<FileSource>> {
    let mode = match a.stream {
        StreamArg::Auto => StreamMode::Auto,
        StreamArg::On => StreamMode::On,
        StreamArg::Off => StreamMode::Off,
    };
    let needs_whole = if a.segment.segment {
        Some("--segment needs the record in memory")
    } else if a.load.window.window.is_some() {
        Some("a --window part is read whole (it is shorter)")
    } else {
        None
    };
    match stream_file::choose(&a.recs, opts, mode, needs_whole, NAMING)? {
        Choice::Stream(src) => Ok(Some(*src)),
        Choice::Whole(warning) => {
            if let Some(w) = warning {
                eprintln!("warning: {}", text::line(&w));
            }
            Ok(None)
        }
    }
}

/// How the stream choice's messages name the flags.
const NAMING: Naming = Naming {
    stream: "--stream",
    velocity: "--velocity",
};

/// `ballpass analyze` of one record streamed from its file.
fn run_streamed(
    a: &AnalyzeArgs,
    settings: &AnalyzeSettings,
    opts: &ballpass::recording::LoadOptions,
    mut src: FileSource,
    out: ballpass::outdir::OutputDir,
    steps: Option<indicatif::ProgressBar>,
    bearing_name: &str,
) -> Result<()> {
    let geometry = opts.geometry.expect("options() resolves the bearing");
    let mut progress = |m: &str| {
        if let Some(s) = &steps {
            s.set_message(m.to_string());
        }
    };
    let analysis = stream_file::analyze_streamed(
        &mut src,
        a.load.velocity,
        &geometry,
        settings,
        NAMING,
        &mut progress,
    )?;
    let print = || -> std::io::Result<()> {
        let mut err = std::io::stderr().lock();
        for w in &analysis.warnings {
            writeln!(err, "warning: {}", text::line(w))?;
        }
        Ok(())
    };
    match &steps {
        Some(s) => s.suspend(print)?,
        None => print()?,
    }
    progress("writing the tables");
    analysis::write_outputs(&analysis, out.path())?;
    if !a.report.no_report {
        progress("drawing the report");
        let links = ballpass::report::analysis::AnalysisLinks {
            tables_dir: String::new(),
            recording: Some(
                std::path::absolute(src.path())
                    .unwrap_or_else(|_| src.path().to_path_buf())
                    .display()
                    .to_string(),
            ),
            id_prefix: String::new(),
        };
        let report = ballpass::report::analysis::report(&analysis, None, &links)?
            .with_command(command_line());
        a.report.write(&report, out.path())?;
    }
    if let Some(s) = steps {
        s.finish_and_clear();
    }
    let dir = output::commit(out)?;
    let mut w = output::stdout();
    if a.json {
        serde_json::to_writer_pretty(&mut w, &analysis)?;
        writeln!(w)?;
    } else {
        summary(&mut w, &analysis, bearing_name, VelocitySource::Stated)?;
        writeln!(w, "wrote {}", text::path(&dir))?;
    }
    w.flush()?;
    Ok(())
}

/// `--max-lag`: seconds, `auto` or `full`.
fn parse_max_lag(v: &str) -> std::result::Result<MaxLag, String> {
    match v {
        "auto" => Ok(MaxLag::Auto),
        "full" => Ok(MaxLag::Full),
        _ => match v.parse::<f64>() {
            Ok(t) if t.is_finite() && t > 0.0 => Ok(MaxLag::Seconds(t)),
            _ => Err(format!(
                "expected a lag in seconds (> 0), `auto` or `full`, got `{v}`"
            )),
        },
    }
}

/// `--load-cell-tau`: seconds, `auto` or `off`.
pub(crate) fn parse_load_cell(v: &str) -> std::result::Result<LoadCellCorrection, String> {
    match v {
        "auto" => Ok(LoadCellCorrection::Auto),
        "off" | "none" | "dc" => Ok(LoadCellCorrection::Off),
        _ => match v.parse::<f64>() {
            Ok(t) if t.is_finite() && t > 0.0 => Ok(LoadCellCorrection::TimeConstant(t)),
            _ => Err(format!(
                "expected a time constant in seconds (> 0), `auto` or `off`, got `{v}`"
            )),
        },
    }
}

/// The stated velocity: the flag, else the records' metadata when they
/// all agree; `None` (measured from the encoder) when none has one.
pub(crate) fn stated_velocity(flag: Option<f64>, recs: &[Recording]) -> Result<Option<f64>> {
    if flag.is_some() {
        return Ok(flag);
    }
    let vs: Vec<f64> = recs.iter().filter_map(|r| r.meta.velocity_mm_s).collect();
    match vs.first() {
        None => Ok(None),
        Some(&v) if vs.len() == recs.len() && vs.iter().all(|&w| w == v) => Ok(Some(v)),
        Some(_) => {
            bail!("the recordings' metadata disagree on the velocity or lack it; give --velocity")
        }
    }
}

/// The folder of one speed's plateaus: `v` and the speed to three
/// significant digits (`v42.0`, `v125`, `v0.106`).
fn group_dir(speed: f64) -> String {
    let digits = (2 - speed.abs().log10().floor() as i32).max(0) as usize;
    format!("v{speed:.digits$}")
}

fn summary<W: Write>(
    w: &mut W,
    a: &Analysis,
    bearing: &str,
    source: VelocitySource,
) -> std::io::Result<()> {
    let p = &a.prediction;
    let velocity = match source {
        VelocitySource::Stated => format!("{} mm/s", p.velocity_mm_s),
        VelocitySource::Measured => format!("{:.4} mm/s (measured)", p.velocity_mm_s),
    };
    writeln!(
        w,
        "{} record(s), {:.2} s at {} Hz, {bearing} at {velocity} ({:.1} periods)",
        a.inputs.len(),
        a.duration_analysed_s,
        a.fs_hz,
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
        writeln!(w, "  {}", ph.words)?;
    }
    if let Some(v) = &a.velocity_error {
        let of = match v.std_spread_um_s {
            Some(sd) => format!(" ± {sd:.1} (mean of {} records ± their spread)", v.records),
            None => String::new(),
        };
        writeln!(
            w,
            "velocity error std {:.1}{of} µm/s (low-passed {:.1}, quantisation floor {:.1})",
            v.std_um_s, v.lowpassed_std_um_s, v.quantisation_floor_um_s
        )?;
    }
    writeln!(w, "verdict: {}", a.verdict.text)?;
    Ok(())
}
