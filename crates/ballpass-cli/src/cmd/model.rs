//! `ballpass model`: the signal and stage models of thesis chapter 6
//! (corrected per docs/methods.md §2–7), written as CSV/JSON tables to plot from.
//!
//! The tables are computed by [`ballpass::model::tables`]; this module
//! parses the flags, writes the library's files and report, and prints a
//! summary.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use ballpass::model::signals::{LagConvention, SinusoidModel};
use ballpass::model::stage::{FrequencyAxis, PdLoop, VelocityResponseSettings};
use ballpass::model::tables::{
    pulses_tables, signals_tables, stage_tables, PulsesTableSettings, SignalsTableSettings,
    StageTableSettings, StageTables,
};
use clap::{Args, Subcommand, ValueEnum};

use ballpass::report;

use crate::args::{command_line, BearingArgs, ReportArgs};
use crate::output;
use crate::text;

/// Arguments of `ballpass model`.
#[derive(Debug, Args)]
pub struct ModelArgs {
    #[command(subcommand)]
    command: ModelCommand,
}

#[derive(Debug, Subcommand)]
enum ModelCommand {
    /// Sinusoid model signals (§6.2): analytic correlations and spectral lines.
    Signals(SignalsArgs),
    /// Gaussian and rectangular pulse trains (§6.3): Fourier coefficients and synthesis.
    Pulses(PulsesArgs),
    /// PD-controlled stage (§6.1): Bode tables, differentiators, velocity response.
    Stage(StageArgs),
}

/// Where the ball-pass frequency comes from.
#[derive(Debug, Clone, Args)]
struct FrequencyArgs {
    /// Tracking velocity, mm/s (f_c from the bearing geometry).
    #[arg(long, short = 'v', conflicts_with = "f_c", value_name = "MM/S")]
    velocity: Option<f64>,
    /// Ball-pass frequency f_c, Hz, given directly.
    #[arg(long = "f-c", value_name = "HZ")]
    f_c: Option<f64>,
    #[command(flatten)]
    bearing: BearingArgs,
}

impl FrequencyArgs {
    /// `Some(f_c)` when a velocity or f_c was given.
    fn f_c_hz(&self) -> Result<Option<f64>> {
        match (self.velocity, self.f_c) {
            (Some(v), _) => {
                let (_, g) = self.bearing.geometry()?;
                Ok(Some(g.predict(v, 1)?.f_c_hz))
            }
            (None, Some(f)) => {
                if !(f.is_finite() && f > 0.0) {
                    bail!("invalid --f-c: must be a positive number of Hz, got {f}");
                }
                Ok(Some(f))
            }
            (None, None) => Ok(None),
        }
    }
}

/// What `--ratio` measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum RatioKind {
    /// Gaussian sigma over τ_c (the r of thesis Eq. 6.23 and docs/methods.md §6).
    Sigma,
    /// Width at half maximum over τ_c (the τ_p that `ballpass passage` measures).
    Fwhm,
}

/// The pulse shape shared by `pulses` and `stage`.
#[derive(Debug, Clone, Args)]
struct RatioArgs {
    /// Pulse width ratio (see --ratio-kind). The thesis measured 0.155.
    #[arg(long, default_value_t = 0.155, value_name = "R")]
    ratio: f64,
    /// Whether --ratio is sigma/τ_c or width-at-half-maximum/τ_c.
    #[arg(long, value_enum, default_value_t = RatioKind::Sigma)]
    ratio_kind: RatioKind,
}

impl From<RatioKind> for ballpass::model::RatioKind {
    fn from(k: RatioKind) -> Self {
        match k {
            RatioKind::Sigma => Self::Sigma,
            RatioKind::Fwhm => Self::Fwhm,
        }
    }
}

impl RatioArgs {
    fn sigma_ratio(&self) -> f64 {
        ballpass::model::RatioKind::from(self.ratio_kind).sigma_ratio(self.ratio)
    }
}

#[derive(Debug, Args)]
struct SignalsArgs {
    #[command(flatten)]
    freq: FrequencyArgs,
    /// Coulomb friction F_c, N.
    #[arg(
        long,
        default_value_t = 1.0,
        allow_hyphen_values = true,
        value_name = "N"
    )]
    friction_dc: f64,
    /// Friction sinusoid amplitude a_f, N.
    #[arg(
        long,
        default_value_t = 1.0,
        allow_hyphen_values = true,
        value_name = "N"
    )]
    friction_amp: f64,
    /// Velocity-error amplitude a_v, mm/s.
    #[arg(
        long,
        default_value_t = 1.0,
        allow_hyphen_values = true,
        value_name = "MM/S"
    )]
    velocity_amp: f64,
    /// Photodetector DC level S, V.
    #[arg(
        long,
        default_value_t = 1.0,
        allow_hyphen_values = true,
        value_name = "V"
    )]
    optical_dc: f64,
    /// Photodetector sinusoid amplitude a_s, V.
    #[arg(
        long,
        default_value_t = 1.0,
        allow_hyphen_values = true,
        value_name = "V"
    )]
    optical_amp: f64,
    /// Lag convention of the correlation table.
    #[arg(long, value_enum, default_value_t = Convention::Eq71)]
    convention: Convention,
    /// Lags from −P·τ_c to +P·τ_c.
    #[arg(long, default_value_t = 2.0, value_name = "N")]
    periods: f64,
    /// Number of lags in the correlation table.
    #[arg(long, default_value_t = 401, value_name = "N")]
    points: usize,
    /// Output folder for correlations.csv, spectral_lines.csv, signals.json
    /// and the report.
    #[arg(long, short = 'o', value_name = "DIR")]
    out: PathBuf,
    #[command(flatten)]
    report: ReportArgs,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Convention {
    /// R_xy(τ) = ⟨x(t+τ) y(t)⟩ (thesis Eq. 7.1, scipy correlate, MATLAB xcorr).
    Eq71,
    /// R_xy(τ) = ⟨x(t) y(t+τ)⟩ (thesis Eq. 6.12).
    Eq612,
}

#[derive(Debug, Args)]
struct PulsesArgs {
    #[command(flatten)]
    ratio: RatioArgs,
    #[command(flatten)]
    freq: FrequencyArgs,
    /// Pulse height P (any unit; coefficients scale with it).
    #[arg(
        long,
        default_value_t = 1.0,
        allow_hyphen_values = true,
        value_name = "P"
    )]
    amplitude: f64,
    /// Base level S.
    #[arg(
        long,
        default_value_t = 0.0,
        allow_hyphen_values = true,
        value_name = "S"
    )]
    dc: f64,
    /// Gaussian coefficients C_0..C_K listed.
    #[arg(long, default_value_t = 10, value_name = "K")]
    harmonics: usize,
    /// Order N of the rectangular Fourier series (thesis Fig. 47 used 20).
    #[arg(long, default_value_t = 20, value_name = "N")]
    order: usize,
    /// Periods of the trains synthesised.
    #[arg(long, default_value_t = 2, value_name = "N")]
    periods: usize,
    /// Samples per period of the synthesised trains.
    #[arg(long, default_value_t = 500, value_name = "N")]
    points: usize,
    /// Output folder for gaussian_coefficients.csv,
    /// rectangular_coefficients.csv, trains.csv, pulses.json and the report.
    #[arg(long, short = 'o', value_name = "DIR")]
    out: PathBuf,
    #[command(flatten)]
    report: ReportArgs,
}

#[derive(Debug, Args)]
struct StageArgs {
    /// Moving mass m, kg.
    #[arg(long, value_name = "KG")]
    mass: f64,
    /// Motor constant K, N/A (with --kp and --kd).
    #[arg(long, default_value_t = 1.0, value_name = "N/A")]
    motor_constant: f64,
    /// Proportional gain K_P, A/m.
    #[arg(
        long,
        requires = "kd",
        conflicts_with_all = ["natural_frequency", "damping"],
        value_name = "A/M"
    )]
    kp: Option<f64>,
    /// Derivative gain K_D, A·s/m.
    #[arg(long, requires = "kp", value_name = "A·S/M")]
    kd: Option<f64>,
    /// Natural frequency f_n, Hz (with --damping; instead of --kp/--kd).
    #[arg(long, requires = "damping", value_name = "HZ")]
    natural_frequency: Option<f64>,
    /// Damping ratio ζ (with --natural-frequency).
    #[arg(long, requires = "natural_frequency", value_name = "ZETA")]
    damping: Option<f64>,
    /// Lowest frequency of the Bode table, Hz.
    #[arg(long, default_value_t = 0.01, value_name = "HZ")]
    f_min: f64,
    /// Highest frequency of the Bode table, Hz.
    #[arg(long, default_value_t = 1000.0, value_name = "HZ")]
    f_max: f64,
    /// Points of the Bode table (log-spaced).
    #[arg(long, default_value_t = 500, value_name = "N")]
    points: usize,
    /// Sampling rate for the differentiator comparison (Fig. 28), Hz.
    #[arg(long, default_value_t = 1000.0, value_name = "HZ")]
    fs: f64,
    #[command(flatten)]
    freq: FrequencyArgs,
    #[command(flatten)]
    ratio: RatioArgs,
    /// Height P of the friction pulses, N.
    #[arg(
        long,
        default_value_t = 1.0,
        allow_hyphen_values = true,
        value_name = "N"
    )]
    friction_amplitude: f64,
    /// Harmonics kept in the velocity response (default: all above 1e-16 C_0).
    #[arg(long, value_name = "K")]
    harmonics: Option<usize>,
    /// Samples over the one period of velocity response.
    #[arg(long, default_value_t = 1000, value_name = "N")]
    period_points: usize,
    /// Output folder for bode.csv, difference.csv, harmonics.csv,
    /// velocity_response.csv, stage.json and the report.
    #[arg(long, short = 'o', value_name = "DIR")]
    out: PathBuf,
    #[command(flatten)]
    report: ReportArgs,
}

/// Runs `ballpass model`.
pub fn run(a: &ModelArgs) -> Result<()> {
    match &a.command {
        ModelCommand::Signals(s) => run_signals(s),
        ModelCommand::Pulses(p) => run_pulses(p),
        ModelCommand::Stage(s) => run_stage(s),
    }
}

fn need_f_c(freq: &FrequencyArgs, what: &str) -> Result<f64> {
    freq.f_c_hz()?.with_context(|| {
        format!("{what} needs the ball-pass frequency: give --velocity V (mm/s) or --f-c HZ")
    })
}

fn run_signals(a: &SignalsArgs) -> Result<()> {
    let f_c = need_f_c(&a.freq, "model signals")?;
    let m = SinusoidModel {
        f_c_hz: f_c,
        friction_dc_n: a.friction_dc,
        friction_amp_n: a.friction_amp,
        velocity_amp_mm_s: a.velocity_amp,
        optical_dc_v: a.optical_dc,
        optical_amp_v: a.optical_amp,
    };
    let json = signals_tables(
        &m,
        &SignalsTableSettings {
            periods: a.periods,
            points: a.points,
            convention: match a.convention {
                Convention::Eq71 => LagConvention::Eq71,
                Convention::Eq612 => LagConvention::Eq612,
            },
        },
    )?;
    let out = output::open_dir(&a.out, "model signals")?;
    let dir = out.path().to_path_buf();
    json.write(&dir)?;
    let rep = report::model::signals_report(&json)?.with_command(command_line());
    let written = a.report.write(&rep, &dir)?;
    output::commit(out)?;
    let mut out = output::stdout();
    writeln!(
        out,
        "sinusoid model signals at f_c = {f_c:.6} Hz (tau_c = {:.5} s)",
        m.tau_c_s()
    )?;
    for p in &json.peaks {
        let (x, y) = p.names;
        let words = if p.y_lags_x_s.abs() < 1e-15 {
            "in phase".to_string()
        } else if p.y_lags_x_s > 0.0 {
            format!("{y} lags {x} by {:.5} s", p.y_lags_x_s)
        } else {
            format!("{y} leads {x} by {:.5} s", -p.y_lags_x_s)
        };
        writeln!(
            out,
            "  R_{:<5} peak nearest 0 at tau = {:+.5} s, phase {:+.1} deg ({words})",
            p.pair, p.tau_phi_s, p.phase_deg
        )?;
    }
    writeln!(
        out,
        "wrote {}/{{correlations.csv, spectral_lines.csv, signals.json{}}}",
        text::path(&a.out),
        report_note(&written)
    )?;
    Ok(())
}

fn run_pulses(a: &PulsesArgs) -> Result<()> {
    let settings = PulsesTableSettings {
        f_c_hz: a.freq.f_c_hz()?,
        ratio: a.ratio.ratio,
        ratio_kind: a.ratio.ratio_kind.into(),
        amplitude: a.amplitude,
        dc: a.dc,
        harmonics: a.harmonics,
        order: a.order,
        periods: a.periods,
        points: a.points,
    };
    let json = pulses_tables(&settings)?;
    let (tau_c, sigma_ratio) = (json.tau_c_s, json.sigma_ratio());
    let (g, r) = (&json.gaussian, &json.rectangular);
    let grows = &json.gaussian_coefficients;
    let gorder = json.gaussian_series_order;
    let gibbs = json.rectangular_gibbs_overshoot_fraction;
    let out = output::open_dir(&a.out, "model pulses")?;
    let dir = out.path().to_path_buf();
    json.write(&dir)?;
    let rep = report::model::pulses_report(&json, &settings).with_command(command_line());
    let written = a.report.write(&rep, &dir)?;
    output::commit(out)?;
    let mut out = output::stdout();
    writeln!(
        out,
        "pulse trains, tau_c = {tau_c:.5} s, sigma/tau_c = {sigma_ratio:.5} (FWHM/tau_c = {:.5}), P = {}",
        g.fwhm_s() / tau_c,
        a.amplitude
    )?;
    writeln!(
        out,
        "Gaussian C_n = sqrt(2 pi) P r exp(-2 pi^2 n^2 r^2) (Eq. 6.28 corrected, docs/methods.md §6):"
    )?;
    for row in grows.iter().take(6) {
        writeln!(out, "  n = {:<2} C_n/P = {:.6e}", row.n, row.c_over_p)?;
    }
    let first = json.rectangular_coefficients.get(1);
    writeln!(
        out,
        "rectangular (tau_p/tau_c = {:.5}, Eq. 6.22 corrected, docs/methods.md §5): a0 = {:.5}, a1 = {:.5}, b1 = {:.5}",
        r.ratio,
        json.rectangular_a0,
        first.map_or(0.0, |c| c.a_n),
        first.map_or(0.0, |c| c.b_n)
    )?;
    writeln!(
        out,
        "order-{} series: Gibbs overshoot {:.2}% of the jump, rms error {:.4} (Gaussian series order {gorder}: {:.1e})",
        a.order,
        100.0 * gibbs,
        json.fit_rms_rectangular_series,
        json.fit_rms_gaussian_series
    )?;
    writeln!(
        out,
        "wrote {}/{{gaussian_coefficients.csv, rectangular_coefficients.csv, trains.csv, pulses.json{}}}",
        text::path(&a.out),
        report_note(&written)
    )?;
    Ok(())
}

fn run_stage(a: &StageArgs) -> Result<()> {
    let stage = match (a.kp, a.kd, a.natural_frequency, a.damping) {
        (Some(kp), Some(kd), None, None) => PdLoop::from_gains(a.mass, a.motor_constant, kp, kd)?,
        (None, None, Some(f), Some(z)) => PdLoop::from_natural(a.mass, f, z)?,
        _ => bail!("model stage needs either --kp and --kd (with --motor-constant) or --natural-frequency and --damping"),
    };
    // The frequency flags are checked before the tables are computed.
    let f_c = a.freq.f_c_hz()?;
    let json = stage_tables(
        &stage,
        &StageTableSettings {
            axis: FrequencyAxis {
                f_min_hz: a.f_min,
                f_max_hz: a.f_max,
                points: a.points,
            },
            difference_fs_hz: a.fs,
            f_c_hz: f_c,
            sigma_ratio: a.ratio.sigma_ratio(),
            friction_amplitude_n: a.friction_amplitude,
            velocity: VelocityResponseSettings {
                harmonics: a.harmonics,
                points_per_period: a.period_points,
            },
        },
    )?;
    let out = output::open_dir(&a.out, "model stage")?;
    let dir = out.path().to_path_buf();
    let paths = json.write(&dir)?;
    let mut written: Vec<String> = paths
        .iter()
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    let rep = report::model::stage_report(&json, f_c, a.fs)?.with_command(command_line());
    if a.report.write(&rep, &dir)?.is_some() {
        written.extend(["report.html".to_string(), "figures/".to_string()]);
    }
    output::commit(out)?;
    summarize_stage(&json, f_c, a.fs, &a.out, &written)
}

fn report_note(written: &Option<ballpass::report::ReportFiles>) -> &'static str {
    if written.is_some() {
        ", report.html, figures/"
    } else {
        ""
    }
}

fn summarize_stage(
    json: &StageTables,
    f_c: Option<f64>,
    fs: f64,
    out_dir: &Path,
    written: &[String],
) -> Result<()> {
    let diff = &json.difference;
    let f = &json.features;
    let mut out = output::stdout();
    writeln!(
        out,
        "PD stage: m = {} kg, K*KP = {:.6e} N/m, K*KD = {:.6e} N*s/m",
        json.stage.mass_kg, json.stage.stiffness_n_per_m, json.stage.damping_n_s_per_m
    )?;
    writeln!(
        out,
        "  natural frequency {:.4} Hz ({:.4} rad/s), damping ratio {:.4}",
        f.f_n_hz, f.omega_n_rad_s, f.damping_ratio
    )?;
    writeln!(
        out,
        "  G_xr: zero at {:.4} rad/s, peak {:.4} ({:+.3} dB) at {:.4} rad/s, > 1 below {:.4} rad/s",
        f.g_xr_zero_rad_s,
        f.g_xr_peak_gain,
        20.0 * f.g_xr_peak_gain.log10(),
        f.g_xr_peak_rad_s,
        f.g_xr_above_unity_until_rad_s
    )?;
    match f.g_xf_peak_rad_s {
        Some(w) => writeln!(
            out,
            "  G_xf: peak {:.4e} m/N at {:.4} rad/s",
            f.g_xf_peak_m_per_n, w
        )?,
        None => writeln!(
            out,
            "  G_xf: no resonant peak (damping ratio ≥ 0.707); {:.4e} m/N at DC",
            f.g_xf_peak_m_per_n
        )?,
    }
    writeln!(
        out,
        "  G_vf: peak 1/(K*KD) = {:.4e} (m/s)/N at omega_n",
        f.g_vf_peak_m_s_per_n
    )?;
    if let Some(r) = diff
        .iter()
        .min_by(|a, b| (a.f_hz - 20.0).abs().total_cmp(&(b.f_hz - 20.0).abs()))
    {
        writeln!(
            out,
            "  differentiators at {:.2} Hz (F_s = {fs} Hz): centred gain {:.5}, phase {:.1} deg; forward gain {:.5}, phase {:.1} deg",
            r.f_hz, r.centred_gain_ratio, r.centred_phase_deg, r.forward_gain_ratio, r.forward_phase_deg
        )?;
    }
    match (&json.velocity_response, f_c) {
        (Some(v), Some(f_c)) => {
            writeln!(
                out,
                "  friction pulses at f_c = {f_c:.5} Hz (sigma/tau_c = {:.4}, P = {} N): velocity {:.4e} mm/s peak to peak",
                v.friction.sigma_ratio, v.friction.amplitude, v.velocity_peak_to_peak_mm_s
            )?;
            writeln!(
                out,
                "  (the thesis' magnitude-only D_n = C_n |G_vf| would be off by {:.0}% of the peak)",
                100.0 * v.magnitude_only_error_of_peak
            )?;
        }
        _ => writeln!(
            out,
            "  no --velocity or --f-c given: velocity response to friction pulses not computed"
        )?,
    }
    writeln!(
        out,
        "wrote {}/{{{}}}",
        text::path(out_dir),
        written.join(", ")
    )?;
    Ok(())
}
