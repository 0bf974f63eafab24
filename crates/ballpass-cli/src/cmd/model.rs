//! `ballpass model`: the signal and stage models of thesis chapter 6
//! (corrected per docs/methods.md §2–7), written as CSV/JSON tables to plot from.

use std::f64::consts::PI;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use ballpass::model::pulse_train::{sigma_ratio_from_fwhm_ratio, GaussianTrain, RectangularTrain};
use ballpass::model::signals::{LagConvention, ModelSignal, SinusoidModel};
use ballpass::model::stage::{
    difference_responses, velocity_response, FrequencyAxis, PdLoop, VelocityResponseSettings,
};
use clap::{Args, Subcommand, ValueEnum};
use serde::Serialize;

use ballpass::report::{self, Block, Level, Report, Section, Table, Verdict};

use crate::args::{command_line, BearingArgs, ReportArgs};
use crate::output::{self, write_csv, write_json};
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "snake_case")]
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

impl RatioArgs {
    fn sigma_ratio(&self) -> f64 {
        match self.ratio_kind {
            RatioKind::Sigma => self.ratio,
            RatioKind::Fwhm => sigma_ratio_from_fwhm_ratio(self.ratio),
        }
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

/// One lag of `correlations.csv`; each column carries the unit of its
/// product (friction N, velocity error mm/s, optical V).
#[derive(Serialize)]
struct CorrelationRow {
    tau_s: f64,
    #[serde(rename = "r_ff_n2")]
    r_ff: f64,
    #[serde(rename = "r_veve_mm2_s2")]
    r_veve: f64,
    #[serde(rename = "r_ss_v2")]
    r_ss: f64,
    #[serde(rename = "r_fve_n_mm_s")]
    r_fve: f64,
    #[serde(rename = "r_fs_n_v")]
    r_fs: f64,
    #[serde(rename = "r_sve_v_mm_s")]
    r_sve: f64,
}

#[derive(Serialize)]
struct SpectrumRow {
    pair: String,
    omega_rad_s: f64,
    f_hz: f64,
    weight_re: f64,
    weight_im: f64,
}

#[derive(Serialize)]
struct PeakRow {
    pair: String,
    #[serde(skip)]
    names: (&'static str, &'static str),
    tau_phi_s: f64,
    phase_deg: f64,
    y_lags_x_s: f64,
}

#[derive(Serialize)]
struct SignalsJson<'a> {
    schema: &'static str,
    version: &'static str,
    model: &'a SinusoidModel,
    convention: LagConvention,
    convention_note: &'static str,
    spectra_note: &'static str,
    peaks: Vec<PeakRow>,
    spectral_lines: Vec<SpectrumRow>,
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
    m.validate()?;
    if !(a.periods.is_finite() && a.periods > 0.0 && (2..=1_000_000).contains(&a.points)) {
        bail!("invalid --periods/--points: need periods > 0 and 2 to 1000000 points");
    }
    let conv = match a.convention {
        Convention::Eq71 => LagConvention::Eq71,
        Convention::Eq612 => LagConvention::Eq612,
    };
    use ModelSignal::{Friction as F, Optical as S, VelocityError as V};
    let span = a.periods * m.tau_c_s();
    let rows: Vec<CorrelationRow> = (0..a.points)
        .map(|i| {
            let tau = -span + 2.0 * span * i as f64 / (a.points - 1) as f64;
            let r = |x, y| m.correlation(x, y, tau, conv);
            CorrelationRow {
                tau_s: tau,
                r_ff: r(F, F),
                r_veve: r(V, V),
                r_ss: r(S, S),
                r_fve: r(F, V),
                r_fs: r(F, S),
                r_sve: r(S, V),
            }
        })
        .collect();
    let pairs = [(F, F), (V, V), (S, S), (F, V), (F, S), (S, V)];
    let name = |x: ModelSignal, y: ModelSignal| format!("{}_{}", x.symbol(), y.symbol());
    let mut lines = Vec::new();
    let mut peaks = Vec::new();
    for (x, y) in pairs {
        for l in m.cross_spectrum(x, y) {
            lines.push(SpectrumRow {
                pair: name(x, y),
                omega_rad_s: l.omega_rad_s,
                f_hz: l.omega_rad_s / (2.0 * PI),
                weight_re: l.weight_re,
                weight_im: l.weight_im,
            });
        }
        if let Some(p) = m.correlation_peak(x, y, conv) {
            peaks.push(PeakRow {
                pair: name(x, y),
                names: (x.symbol(), y.symbol()),
                tau_phi_s: p.tau_phi_s,
                phase_deg: p.phase_deg,
                y_lags_x_s: p.y_lags_x_s,
            });
        }
    }
    let out = output::open_dir(&a.out, "model signals")?;
    let dir = out.path().to_path_buf();
    write_csv(&dir.join("correlations.csv"), &rows)?;
    write_csv(&dir.join("spectral_lines.csv"), &lines)?;
    let json = SignalsJson {
        schema: "ballpass.model.signals/1",
        version: ballpass::VERSION,
        model: &m,
        convention: conv,
        convention_note: match conv {
            LagConvention::Eq71 => "R_xy(tau) = <x(t+tau) y(t)> (thesis Eq. 7.1, scipy correlate); a peak at -d means y lags x by d",
            LagConvention::Eq612 => "R_xy(tau) = <x(t) y(t+tau)> (thesis Eq. 6.12); a peak at +d means y lags x by d",
        },
        spectra_note: "Dirac line weights of the unitary Fourier transform of the Eq. 6.12 correlation (conj(X)*Y, as scipy csd), with the signs of Eq. 6.17 corrected (docs/methods.md §4)",
        peaks,
        spectral_lines: lines,
    };
    write_json(&dir.join("signals.json"), &json)?;
    let tau: Vec<f64> = rows.iter().map(|r| r.tau_s).collect();
    let col = |g: fn(&CorrelationRow) -> f64| rows.iter().map(g).collect::<Vec<f64>>();
    let cols = [
        ("R_FF", col(|r| r.r_ff)),
        ("R_vv", col(|r| r.r_veve)),
        ("R_SS", col(|r| r.r_ss)),
        ("R_Fv", col(|r| r.r_fve)),
        ("R_FS", col(|r| r.r_fs)),
        ("R_Sv", col(|r| r.r_sve)),
    ];
    let pairs: Vec<(&str, &[f64])> = cols.iter().map(|(n, v)| (*n, v.as_slice())).collect();
    let mut peaks = Table::new(["pair", "peak lag (s)", "phase (deg)", "y lags x by (s)"]);
    for p in &json.peaks {
        peaks = peaks.with_row([
            p.pair.clone(),
            format!("{:+.5}", p.tau_phi_s),
            format!("{:+.1}", p.phase_deg),
            format!("{:+.5}", p.y_lags_x_s),
        ]);
    }
    let fig = report::model::correlations_figure(&tau, &pairs, m.tau_c_s())
        .with_data("correlations.csv", "tau_s and the six model correlations")
        .interactive();
    let rep = Report::new(format!("ballpass model signals: f_c = {f_c:.5} Hz"))
        .with_command(command_line())
        .with_section(
            Section::new("Correlation peaks nearest zero lag")
                .with(Block::Paragraph(format!(
                    "{} The correlations over lag are in {{fig:{}}}.",
                    json.convention_note, fig.id
                )))
                .with(Block::Table(peaks))
                .with_figure(fig),
        )
        .with_section(Section::new("Settings").with(Block::settings(&m)?));
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

#[derive(Serialize)]
struct GaussianRow {
    n: usize,
    f_over_f_c: f64,
    c_re: f64,
    c_im: f64,
    c_abs: f64,
    c_over_p: f64,
    thesis_printed_c_over_p: f64,
}

#[derive(Serialize)]
struct RectRow {
    n: usize,
    a_n: f64,
    b_n: f64,
}

#[derive(Serialize)]
struct TrainRow {
    t_s: f64,
    gaussian: f64,
    gaussian_series: f64,
    rectangular: f64,
    rectangular_series: f64,
}

#[derive(Serialize)]
struct PulsesJson {
    schema: &'static str,
    version: &'static str,
    tau_c_s: f64,
    ratio: f64,
    ratio_kind: RatioKind,
    gaussian: GaussianTrain,
    gaussian_fwhm_s: f64,
    gaussian_series_order: usize,
    rectangular: RectangularTrain,
    rectangular_order: usize,
    rectangular_a0: f64,
    rectangular_gibbs_overshoot_fraction: f64,
    fit_rms_gaussian_series: f64,
    fit_rms_rectangular_series: f64,
}

fn run_pulses(a: &PulsesArgs) -> Result<()> {
    let tau_c = a.freq.f_c_hz()?.map_or(1.0, |f| 1.0 / f);
    let sigma_ratio = a.ratio.sigma_ratio();
    let g = GaussianTrain::new(tau_c, sigma_ratio, a.amplitude, a.dc, 0.0)?;
    // The rectangle's duty ratio is --ratio as given, whatever its kind: the
    // thesis compares both trains at the same r = 0.155 (docs/methods.md §5–6).
    let r = RectangularTrain::new(tau_c, a.ratio.ratio, a.amplitude, a.dc)?;
    if a.order == 0 || a.order > 100_000 {
        bail!("invalid --order: must be 1 to 100000, got {}", a.order);
    }
    if a.harmonics > 100_000
        || a.periods == 0
        || a.periods > 1000
        || !(2..=1_000_000).contains(&a.points)
    {
        bail!("invalid --harmonics/--periods/--points: need harmonics ≤ 100000, 1 to 1000 periods, 2 to 1000000 points per period");
    }
    let grows: Vec<GaussianRow> = (0..=a.harmonics)
        .map(|n| {
            let c = g.coefficient(n as i64);
            GaussianRow {
                n,
                f_over_f_c: n as f64,
                c_re: c.re,
                c_im: c.im,
                c_abs: c.norm(),
                c_over_p: if a.amplitude != 0.0 {
                    c.norm() / a.amplitude.abs()
                } else {
                    0.0
                },
                thesis_printed_c_over_p: g.thesis_printed_coefficient(n as i64),
            }
        })
        .collect();
    let coef = r.coefficients(a.order);
    let mut rrows = vec![RectRow {
        n: 0,
        a_n: coef.a0,
        b_n: 0.0,
    }];
    rrows.extend((1..=a.order).map(|n| RectRow {
        n,
        a_n: coef.a[n - 1],
        b_n: coef.b[n - 1],
    }));
    let gorder = g.order_for(1e-16).max(1);
    let total = a.periods * a.points;
    let trows: Vec<TrainRow> = (0..total)
        .map(|i| {
            let t = tau_c * i as f64 / a.points as f64;
            TrainRow {
                t_s: t,
                gaussian: g.value(t),
                gaussian_series: g.partial_sum(t, gorder),
                rectangular: r.value(t),
                rectangular_series: r.partial_sum(t, a.order),
            }
        })
        .collect();
    let rms = |f: &dyn Fn(&TrainRow) -> f64| {
        (trows.iter().map(|x| f(x).powi(2)).sum::<f64>() / trows.len() as f64).sqrt()
    };
    let gibbs = r.gibbs_overshoot(a.order)?;
    let json = PulsesJson {
        schema: "ballpass.model.pulses/1",
        version: ballpass::VERSION,
        tau_c_s: tau_c,
        ratio: a.ratio.ratio,
        ratio_kind: a.ratio.ratio_kind,
        gaussian: g,
        gaussian_fwhm_s: g.fwhm_s(),
        gaussian_series_order: gorder,
        rectangular: r,
        rectangular_order: a.order,
        rectangular_a0: coef.a0,
        rectangular_gibbs_overshoot_fraction: gibbs,
        fit_rms_gaussian_series: rms(&|x| x.gaussian_series - x.gaussian),
        fit_rms_rectangular_series: rms(&|x| x.rectangular_series - x.rectangular),
    };
    let out = output::open_dir(&a.out, "model pulses")?;
    let dir = out.path().to_path_buf();
    write_csv(&dir.join("gaussian_coefficients.csv"), &grows)?;
    write_csv(&dir.join("rectangular_coefficients.csv"), &rrows)?;
    write_csv(&dir.join("trains.csv"), &trows)?;
    write_json(&dir.join("pulses.json"), &json)?;
    let ns: Vec<f64> = grows.iter().map(|r| r.n as f64).collect();
    let cn: Vec<f64> = grows.iter().map(|r| r.c_over_p).collect();
    let printed: Vec<f64> = grows.iter().map(|r| r.thesis_printed_c_over_p).collect();
    let tt: Vec<f64> = trows.iter().map(|r| r.t_s).collect();
    let col = |g: fn(&TrainRow) -> f64| trows.iter().map(g).collect::<Vec<f64>>();
    let (gv, gs, rv, rs) = (
        col(|r| r.gaussian),
        col(|r| r.gaussian_series),
        col(|r| r.rectangular),
        col(|r| r.rectangular_series),
    );
    let rs_name = format!("rectangular, order {}", a.order);
    let gs_name = format!("Gaussian series, order {gorder}");
    let coef_fig =
        report::model::gaussian_coefficients_figure(&ns, &cn, Some(&printed), sigma_ratio)
            .with_data(
                "gaussian_coefficients.csv",
                "n, c_over_p, thesis_printed_c_over_p",
            );
    let trains_fig = report::model::trains_figure(
        &tt,
        &[
            ("Gaussian", &gv, false),
            (&gs_name, &gs, true),
            ("rectangular", &rv, false),
            (&rs_name, &rs, true),
        ],
    )
    .with_data("trains.csv", "t_s and the four trains")
    .interactive();
    let refs = format!(
        "The Gaussian train's Fourier coefficients are in {{fig:{}}}, the trains and their \
         truncated series over time in {{fig:{}}}.",
        coef_fig.id, trains_fig.id
    );
    let rep = Report::new(format!(
        "ballpass model pulses: τc = {tau_c:.5} s, σ/τc = {sigma_ratio:.4}"
    ))
    .with_command(command_line())
    .with_section(Section::new("Pulse trains").with(Block::KeyValues(vec![
        ("τc".into(), format!("{tau_c:.6} s")),
        ("σ / τc".into(), format!("{sigma_ratio:.5}")),
        (
            "width at half maximum / τc".into(),
            format!("{:.5}", g.fwhm_s() / tau_c),
        ),
        ("rectangular τp / τc".into(), format!("{:.5}", r.ratio)),
        (
            "Gibbs overshoot, order N".into(),
            format!("{:.2}% of the jump", 100.0 * gibbs),
        ),
        (
            "rms series error (rectangular / Gaussian)".into(),
            format!(
                "{:.4} / {:.1e}",
                json.fit_rms_rectangular_series, json.fit_rms_gaussian_series
            ),
        ),
    ])))
    .with_section(
        Section::new("Figures")
            .with(Block::Paragraph(refs))
            .with_figure(coef_fig)
            .with_figure(trains_fig),
    )
    .with_section(Section::new("Settings").with(Block::KeyValues(vec![
        ("amplitude P".into(), a.amplitude.to_string()),
        ("dc S".into(), a.dc.to_string()),
        ("order N".into(), a.order.to_string()),
        ("harmonics listed".into(), a.harmonics.to_string()),
        (
            "periods × points".into(),
            format!("{} × {}", a.periods, a.points),
        ),
    ])));
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
    writeln!(
        out,
        "rectangular (tau_p/tau_c = {:.5}, Eq. 6.22 corrected, docs/methods.md §5): a0 = {:.5}, a1 = {:.5}, b1 = {:.5}",
        r.ratio,
        coef.a0,
        coef.a.first().copied().unwrap_or(0.0),
        coef.b.first().copied().unwrap_or(0.0)
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

#[derive(Serialize)]
struct VelocityRow {
    t_s: f64,
    friction_n: f64,
    velocity_mm_s: f64,
    position_um: f64,
    velocity_magnitude_only_mm_s: f64,
}

#[derive(Serialize)]
struct StageJson<'a> {
    schema: &'static str,
    version: &'static str,
    stage: PdLoop,
    features: ballpass::model::LoopFeatures,
    units_note: &'static str,
    velocity_response: Option<VelocitySummary<'a>>,
}

#[derive(Serialize)]
struct VelocitySummary<'a> {
    f_c_hz: f64,
    friction: GaussianTrain,
    harmonics: &'a [ballpass::model::HarmonicRow],
    velocity_peak_to_peak_mm_s: f64,
    magnitude_only_error_of_peak: f64,
}

fn run_stage(a: &StageArgs) -> Result<()> {
    let stage = match (a.kp, a.kd, a.natural_frequency, a.damping) {
        (Some(kp), Some(kd), None, None) => PdLoop::from_gains(a.mass, a.motor_constant, kp, kd)?,
        (None, None, Some(f), Some(z)) => PdLoop::from_natural(a.mass, f, z)?,
        _ => bail!("model stage needs either --kp and --kd (with --motor-constant) or --natural-frequency and --damping"),
    };
    let features = stage.features();
    let bode = stage.bode(&FrequencyAxis {
        f_min_hz: a.f_min,
        f_max_hz: a.f_max,
        points: a.points,
    })?;
    let diff = difference_responses(a.fs, 500)?;
    let f_c = a.freq.f_c_hz()?;
    let resp = match f_c {
        Some(f) => {
            let tc = 1.0 / f;
            let friction = GaussianTrain::new(
                tc,
                a.ratio.sigma_ratio(),
                a.friction_amplitude,
                0.0,
                0.5 * tc,
            )?;
            let r = velocity_response(
                &stage,
                &friction,
                &VelocityResponseSettings {
                    harmonics: a.harmonics,
                    points_per_period: a.period_points,
                },
            )?;
            Some((friction, r))
        }
        None => None,
    };
    let out = output::open_dir(&a.out, "model stage")?;
    let dir = out.path().to_path_buf();
    write_csv(&dir.join("bode.csv"), &bode)?;
    write_csv(&dir.join("difference.csv"), &diff)?;
    let mut written = vec!["bode.csv", "difference.csv"];
    if let Some((_, r)) = &resp {
        write_csv(&dir.join("harmonics.csv"), &r.harmonics)?;
        let rows: Vec<VelocityRow> = (0..r.time_s.len())
            .map(|i| VelocityRow {
                t_s: r.time_s[i],
                friction_n: r.friction_n[i],
                velocity_mm_s: r.velocity_mm_s[i],
                position_um: r.position_um[i],
                velocity_magnitude_only_mm_s: r.velocity_magnitude_only_mm_s[i],
            })
            .collect();
        write_csv(&dir.join("velocity_response.csv"), &rows)?;
        written.extend(["harmonics.csv", "velocity_response.csv"]);
    }
    let json = StageJson {
        schema: "ballpass.model.stage/1",
        version: ballpass::VERSION,
        stage,
        features,
        units_note: "SI: G_xf in m/N (dB re 1 m/N), G_vf in (m/s)/N (dB re 1 (m/s)/N); velocity response in mm/s, position in um",
        velocity_response: resp.as_ref().map(|(friction, r)| VelocitySummary {
            f_c_hz: r.f_c_hz,
            friction: *friction,
            harmonics: &r.harmonics,
            velocity_peak_to_peak_mm_s: r.velocity_peak_to_peak_mm_s,
            magnitude_only_error_of_peak: r.magnitude_only_error_of_peak,
        }),
    };
    write_json(&dir.join("stage.json"), &json)?;
    written.push("stage.json");
    let rep = stage_report(
        &json,
        f_c,
        a.fs,
        &bode,
        &diff,
        resp.as_ref().map(|(_, r)| r),
    )?;
    if a.report.write(&rep, &dir)?.is_some() {
        written.extend(["report.html", "figures/"]);
    }
    output::commit(out)?;
    summarize_stage(&json, f_c, a.fs, &diff, &a.out, &written)
}

fn report_note(written: &Option<ballpass::report::ReportFiles>) -> &'static str {
    if written.is_some() {
        ", report.html, figures/"
    } else {
        ""
    }
}

fn stage_report(
    json: &StageJson,
    f_c: Option<f64>,
    fs: f64,
    bode: &[ballpass::model::BodeRow],
    diff: &[ballpass::model::DifferenceRow],
    resp: Option<&ballpass::model::VelocityResponse>,
) -> Result<Report> {
    let f = &json.features;
    let mut kv = vec![
        (
            "natural frequency f_n".to_string(),
            format!("{:.4} Hz ({:.4} rad/s)", f.f_n_hz, f.omega_n_rad_s),
        ),
        ("damping ratio".into(), format!("{:.4}", f.damping_ratio)),
        (
            "G_xr peak".into(),
            format!(
                "{:.4} ({:+.3} dB) at {:.4} rad/s",
                f.g_xr_peak_gain,
                20.0 * f.g_xr_peak_gain.log10(),
                f.g_xr_peak_rad_s
            ),
        ),
        (
            "G_vf peak 1/(K K_D)".into(),
            format!(
                "{} (m/s)/N at ω_n",
                report::kinds::fmt_sig(f.g_vf_peak_m_s_per_n, 5)
            ),
        ),
    ];
    if let Some(fc) = f_c {
        kv.push((
            "ball-pass frequency f_c".into(),
            format!("{fc:.5} Hz (f_c / f_n = {:.3})", fc / f.f_n_hz),
        ));
    }
    let mut verdicts = Vec::new();
    if let Some(fc) = f_c {
        let ratio = fc / f.f_n_hz;
        let level = if (0.7..1.4).contains(&ratio) {
            Level::Warn
        } else {
            Level::Info
        };
        verdicts.push(Verdict::new(
            level,
            "f_c vs f_n",
            format!("f_c is {ratio:.2} f_n: {}", if level == Level::Warn {
                "the ball passages excite the stage near its resonance, where G_vf peaks (thesis §6.1, Fig. 42)"
            } else {
                "away from the stage resonance"
            }),
        ));
    }
    let bode_figs: Vec<report::Figure> = report::model::stage_bode_figures(bode, f.f_n_hz, f_c)
        .into_iter()
        .map(|fig| {
            fig.with_data(
                "bode.csv",
                "f_hz and each response's gain (dB) and phase (deg)",
            )
        })
        .collect();
    let mut stage = Section::new("Stage")
        .with(Block::KeyValues(kv))
        .with(Block::Paragraph(format!(
            "The responses to the reference and to friction: {} (thesis Figs. 41–42).",
            bode_figs
                .iter()
                .map(|b| format!("{{fig:{}}}", b.id))
                .collect::<Vec<_>>()
                .join(", ")
        )));
    for fig in bode_figs {
        stage = stage.with_figure(fig);
    }
    let mut rep = Report::new(format!(
        "ballpass model stage: f_n = {:.4} Hz, ζ = {:.3}",
        f.f_n_hz, f.damping_ratio
    ))
    .with_command(command_line())
    .with_section(stage);
    if !verdicts.is_empty() {
        rep = rep.with_section(Section::new("Conditions").with(Block::Verdicts(verdicts)));
    }
    let diff_fig = report::model::difference_figure(diff, fs)
        .with_data("difference.csv", "gain ratios and absolute phases (deg)");
    rep = rep.with_section(
        Section::new("Velocity from position")
            .with(Block::Paragraph(format!(
                "The centred and the forward difference as differentiators at F_s = {} Hz: {{fig:{}}} (thesis Fig. 28).",
                report::kinds::fmt_sig(fs, 4),
                diff_fig.id
            )))
            .with_figure(diff_fig),
    );
    if let Some(v) = &json.velocity_response {
        let mut sec =
            Section::new("Velocity response to the friction pulses").with(Block::KeyValues(vec![
                (
                    "velocity peak to peak".into(),
                    format!(
                        "{} mm/s",
                        report::kinds::fmt_sig(v.velocity_peak_to_peak_mm_s, 5)
                    ),
                ),
                (
                    "error of the thesis' magnitude-only sum".into(),
                    format!(
                        "{:.1} % of the peak",
                        100.0 * v.magnitude_only_error_of_peak
                    ),
                ),
            ]));
        if let Some(r) = resp {
            let fig = report::model::velocity_response_figure(r)
                .with_data("velocity_response.csv", "t_s, friction_n, velocity_mm_s")
                .with_data("harmonics.csv", "C_n, G_vf and D_n per harmonic");
            sec = sec
                .with(Block::Paragraph(format!(
                    "One period of the friction pulses and the velocity error they cause: {{fig:{}}} (thesis Fig. 51).",
                    fig.id
                )))
                .with_figure(fig);
        }
        rep = rep.with_section(sec);
    }
    rep = rep.with_section(Section::new("Settings").with(Block::settings(&json.stage)?));
    Ok(rep)
}

fn summarize_stage(
    json: &StageJson,
    f_c: Option<f64>,
    fs: f64,
    diff: &[ballpass::model::DifferenceRow],
    out_dir: &Path,
    written: &[&str],
) -> Result<()> {
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
