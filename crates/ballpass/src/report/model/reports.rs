//! The reports of `ballpass model signals`, `pulses` and `stage`: the
//! tables of [`crate::model::tables`] as sections, key values, verdicts and
//! the figures of this module.

use super::super::kinds::fmt_sig;
use super::super::Figure;
use super::super::{Block, Level, Report, Section, Table, Verdict};
use super::{
    correlations_figure, difference_figure, gaussian_coefficients_figure, stage_bode_figures,
    trains_figure, velocity_response_figure,
};
use crate::error::Result;
use crate::model::tables::{
    CorrelationRow, PulsesTableSettings, PulsesTables, SignalsTables, StageTables, TrainRow,
};

/// The report of `ballpass model signals`: the correlation peaks nearest
/// zero lag and the six model correlations over lag.
///
/// # Errors
/// When the model cannot be written as settings (not expected).
pub fn signals_report(json: &SignalsTables) -> Result<Report> {
    let m = &json.model;
    let f_c = m.f_c_hz;
    let rows = &json.correlations;
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
    let fig = correlations_figure(&tau, &pairs, m.tau_c_s())
        .with_data("correlations.csv", "tau_s and the six model correlations")
        .interactive();
    Ok(
        Report::new(format!("ballpass model signals: f_c = {f_c:.5} Hz"))
            .with_section(
                Section::new("Correlation peaks nearest zero lag")
                    .with(Block::Paragraph(format!(
                        "{} The correlations over lag are in {{fig:{}}}.",
                        json.convention_note, fig.id
                    )))
                    .with(Block::Table(peaks))
                    .with_figure(fig),
            )
            .with_section(Section::new("Settings").with(Block::settings(m)?)),
    )
}

/// The report of `ballpass model pulses`: the Gaussian and rectangular
/// trains, their Fourier coefficients and truncated series, for the
/// settings `s` the tables were computed with.
pub fn pulses_report(json: &PulsesTables, s: &PulsesTableSettings) -> Report {
    let (tau_c, sigma_ratio) = (json.tau_c_s, json.sigma_ratio());
    let (g, r) = (&json.gaussian, &json.rectangular);
    let (grows, trows) = (&json.gaussian_coefficients, &json.trains);
    let gorder = json.gaussian_series_order;
    let gibbs = json.rectangular_gibbs_overshoot_fraction;
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
    let rs_name = format!("rectangular, order {}", s.order);
    let gs_name = format!("Gaussian series, order {gorder}");
    let coef_fig = gaussian_coefficients_figure(&ns, &cn, Some(&printed), sigma_ratio).with_data(
        "gaussian_coefficients.csv",
        "n, c_over_p, thesis_printed_c_over_p",
    );
    let trains_fig = trains_figure(
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
    Report::new(format!(
        "ballpass model pulses: τc = {tau_c:.5} s, σ/τc = {sigma_ratio:.4}"
    ))
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
        ("amplitude P".into(), s.amplitude.to_string()),
        ("dc S".into(), s.dc.to_string()),
        ("order N".into(), s.order.to_string()),
        ("harmonics listed".into(), s.harmonics.to_string()),
        (
            "periods × points".into(),
            format!("{} × {}", s.periods, s.points),
        ),
    ])))
}

/// The report of `ballpass model stage`: the PD stage's features and Bode
/// plots, the differentiators at `fs` Hz, and the velocity response to the
/// friction pulses at `f_c` when given.
///
/// # Errors
/// When the stage cannot be written as settings (not expected).
pub fn stage_report(json: &StageTables, f_c: Option<f64>, fs: f64) -> Result<Report> {
    let (bode, diff, resp) = (&json.bode, &json.difference, json.response.as_ref());
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
            format!("{} (m/s)/N at ω_n", fmt_sig(f.g_vf_peak_m_s_per_n, 5)),
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
    let bode_figs: Vec<Figure> = stage_bode_figures(bode, f.f_n_hz, f_c)
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
    .with_section(stage);
    if !verdicts.is_empty() {
        rep = rep.with_section(Section::new("Conditions").with(Block::Verdicts(verdicts)));
    }
    let diff_fig = difference_figure(diff, fs)
        .with_data("difference.csv", "gain ratios and absolute phases (deg)");
    rep = rep.with_section(
        Section::new("Velocity from position")
            .with(Block::Paragraph(format!(
                "The centred and the forward difference as differentiators at F_s = {} Hz: {{fig:{}}} (thesis Fig. 28).",
                fmt_sig(fs, 4),
                diff_fig.id
            )))
            .with_figure(diff_fig),
    );
    if let Some(v) = &json.velocity_response {
        let mut sec =
            Section::new("Velocity response to the friction pulses").with(Block::KeyValues(vec![
                (
                    "velocity peak to peak".into(),
                    format!("{} mm/s", fmt_sig(v.velocity_peak_to_peak_mm_s, 5)),
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
            let fig = velocity_response_figure(r)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::stage::PdLoop;
    use crate::model::tables::{stage_tables, StageTableSettings};

    fn verdict_level(f_c_over_f_n: f64) -> Option<Level> {
        let stage = PdLoop::from_natural(2.0, 1.1, 0.35).unwrap();
        let f_c = 1.1 * f_c_over_f_n;
        let s = StageTableSettings {
            f_c_hz: Some(f_c),
            ..StageTableSettings::default()
        };
        let json = stage_tables(&stage, &s).unwrap();
        let rep = stage_report(&json, Some(f_c), s.difference_fs_hz).unwrap();
        rep.summary
            .iter()
            .flat_map(|sec| &sec.blocks)
            .find_map(|b| match b {
                Block::Verdicts(v) => v.first().map(|v| v.level),
                _ => None,
            })
    }

    /// The stage report warns when the ball passages excite the stage near
    /// its resonance (f_c within 0.7–1.4 f_n) and only informs away from it.
    #[test]
    fn stage_report_warns_near_resonance_only() {
        assert_eq!(verdict_level(1.0), Some(Level::Warn));
        assert_eq!(verdict_level(0.8), Some(Level::Warn));
        assert_eq!(verdict_level(3.0), Some(Level::Info));
        assert_eq!(verdict_level(0.3), Some(Level::Info));
    }
}
