//! Report sections and figures of campaigns (thesis Figs. 29, 52, 53, 66–68).

use crate::campaign::diagnose::{Condition, Diagnosis};
use crate::campaign::sweep::Sweep;
use crate::error::Result;
use crate::recording::{Channel, Recording};
use crate::report::kinds::{self, fmt_sig, PowerLaw, SpectrumView};
use crate::report::{
    Axis, Block, Figure, Level, Panel, Section, Series, SeriesStyle, Table, Verdict,
};

/// What a campaign report shows: summary sections, then figures.
#[derive(Debug, Clone, Default)]
pub struct ReportParts {
    /// Summary sections.
    pub sections: Vec<Section>,
    /// Figures.
    pub figures: Vec<Figure>,
}

fn mean_std_cols(rows: &[(f64, Option<crate::stats::MeanStd>)]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let mut x = Vec::new();
    let mut m = Vec::new();
    let mut s = Vec::new();
    for (v, ms) in rows {
        if let Some(ms) = ms {
            x.push(*v);
            m.push(ms.mean);
            s.push(ms.std);
        }
    }
    (x, m, s)
}

/// Sections and figures of a velocity sweep. `prefix` keeps figure ids
/// unique when several parts share a report.
///
/// # Errors
/// [`crate::Error::Report`] if the settings cannot be tabulated.
pub fn sweep_parts(sweep: &Sweep, prefix: &str) -> Result<ReportParts> {
    let mut parts = ReportParts::default();
    let mut table = Table::new([
        "v (mm/s)",
        "records",
        "f_c predicted (Hz)",
        "f_c measured (Hz)",
        "velocity-error std (µm/s)",
        "τc (s)",
        "τp (s)",
        "τp/τc",
    ]);
    let ms = |m: Option<crate::stats::MeanStd>, sig: usize| {
        m.map(|m| format!("{} ± {}", fmt_sig(m.mean, sig), fmt_sig(m.std, 2)))
            .unwrap_or_else(|| "–".into())
    };
    for r in &sweep.velocities {
        table = table.with_row([
            fmt_sig(r.velocity_mm_s, 3),
            r.records.to_string(),
            fmt_sig(r.f_c_predicted_hz, 5),
            ms(r.f_c_measured_hz, 5),
            ms(r.velocity_error_std_um_s, 3),
            ms(r.tau_c_s, 4),
            ms(r.tau_p_s, 3),
            ms(r.tau_ratio, 3),
        ]);
    }
    parts.sections.push(
        Section::new("Velocity sweep")
            .with(Block::Paragraph(sweep.findings.join(". ") + "."))
            .with(Block::Table(table)),
    );

    let ve: Vec<(f64, Option<crate::stats::MeanStd>)> = sweep
        .velocities
        .iter()
        .map(|r| (r.velocity_mm_s, r.velocity_error_std_um_s))
        .collect();
    let (x, m, s) = mean_std_cols(&ve);
    if !x.is_empty() {
        let mut fig = kinds::error_bar_plot(
            &format!("{prefix}velocity_error_std"),
            "Velocity-error standard deviation against tracking velocity (thesis Fig. 29)",
            Axis::linear("Tracking velocity", "mm/s"),
            Axis::linear("Velocity-error std", "µm/s"),
            &x,
            &m,
            &s,
        );
        if let Some(t) = &sweep.stage_trend {
            let fine: Vec<f64> = (0..200)
                .map(|i| x[0] + (x[x.len() - 1] - x[0]) * f64::from(i) / 199.0)
                .collect();
            // f_c is proportional to v: one ratio maps the fine velocity grid.
            let slope = sweep.velocities[0].f_c_predicted_hz / sweep.velocities[0].velocity_mm_s;
            let curve: Vec<f64> = fine
                .iter()
                .map(|v| t.velocity_error_std_um_s(slope * v))
                .collect();
            if let Some(p) = fig.panels.first_mut() {
                p.series.push(
                    Series::line(
                        format!(
                            "PD stage, f_n = {} Hz, ζ = {}",
                            fmt_sig(t.natural_frequency_hz, 3),
                            fmt_sig(t.damping_ratio, 2)
                        ),
                        fine,
                        curve,
                    )
                    .with_style(SeriesStyle::DashedLine),
                );
                p.legend = Some(true);
            }
        }
        parts.figures.push(fig.with_caption(
            "Mean over repeats with ± one standard deviation; dashed: the PD-loop response |G_vf(j2πf_c)| fitted to the means.",
        ));
    }

    let tc: Vec<_> = sweep
        .velocities
        .iter()
        .map(|r| (r.velocity_mm_s, r.tau_c_s))
        .collect();
    let tp: Vec<_> = sweep
        .velocities
        .iter()
        .map(|r| (r.velocity_mm_s, r.tau_p_s))
        .collect();
    let (xc, mc, sc) = mean_std_cols(&tc);
    let (xp, mp, sp) = mean_std_cols(&tp);
    if !xc.is_empty() && xc == xp {
        let names: Vec<String> = [&sweep.tau_c_fit, &sweep.tau_p_fit]
            .iter()
            .map(|f| {
                f.as_ref()
                    .map(|f| {
                        format!(
                            "fit: {} v^({} ± {})",
                            fmt_sig(f.coefficient, 3),
                            fmt_sig(f.slope, 4),
                            fmt_sig(f.slope_ci95, 2)
                        )
                    })
                    .unwrap_or_default()
            })
            .collect();
        let mut fits = Vec::new();
        for (f, name) in [&sweep.tau_c_fit, &sweep.tau_p_fit].iter().zip(&names) {
            if let Some(f) = f {
                fits.push(PowerLaw {
                    name,
                    coefficient: f.coefficient,
                    exponent: f.slope,
                });
            }
        }
        parts.figures.push(
            kinds::loglog_fit(
                &format!("{prefix}tau_vs_velocity"),
                "Ball-pass period τc and pulse width τp against velocity (thesis Fig. 52)",
                Axis::log("Tracking velocity", "mm/s"),
                Axis::log("Time", "s"),
                &xc,
                &[("τc", &mc, &sc), ("τp", &mp, &sp)],
                &fits,
            )
            .with_caption("Both inversely proportional to velocity when the fitted exponent is −1 within its 95 % interval."),
        );
    }
    let ra: Vec<_> = sweep
        .velocities
        .iter()
        .map(|r| (r.velocity_mm_s, r.tau_ratio))
        .collect();
    let (xr, mr, sr) = mean_std_cols(&ra);
    if !xr.is_empty() {
        parts.figures.push(kinds::ratio_with_mean(
            &format!("{prefix}tau_ratio"),
            "Ratio τp / τc against velocity (thesis Fig. 53; thesis mean 0.155)",
            Axis::linear("Tracking velocity", "mm/s"),
            Axis::linear("τp / τc", ""),
            &xr,
            &mr,
            &sr,
        ));
    }
    let fc: Vec<_> = sweep
        .velocities
        .iter()
        .map(|r| (r.velocity_mm_s, r.f_c_measured_hz))
        .collect();
    let (xf, mf, sf) = mean_std_cols(&fc);
    if !xf.is_empty() {
        let mut p = Panel::new(
            Axis::linear("Tracking velocity", "mm/s"),
            Axis::linear("Ball-pass frequency", "Hz"),
        )
        .with_series(Series::error_bars("measured f_c", xf.clone(), mf, sf));
        let pred: Vec<f64> = sweep
            .velocities
            .iter()
            .filter(|r| r.f_c_measured_hz.is_some())
            .map(|r| r.f_c_predicted_hz)
            .collect();
        p.series.push(
            Series::line("catalog v / (2 d_avg)", xf.clone(), pred)
                .with_style(SeriesStyle::DashedLine),
        );
        if let Some(d) = sweep.d_avg_fitted_mm {
            let fit: Vec<f64> = xf.iter().map(|v| v / (2.0 * d)).collect();
            p.series.push(Series::line(
                format!("fit: d_avg = {} mm", fmt_sig(d, 5)),
                xf.clone(),
                fit,
            ));
        }
        p.legend = Some(true);
        parts.figures.push(
            Figure::new(
                format!("{prefix}f_c_vs_velocity"),
                "Measured ball-pass frequency against velocity",
            )
            .with_panel(p),
        );
    }
    Ok(parts)
}

/// A raw friction trace shown in a diagnosis report.
#[derive(Debug, Clone)]
pub struct FrictionTrace {
    /// Legend/panel title (bearing and verdict).
    pub name: String,
    /// Sample times, s.
    pub t_s: Vec<f64>,
    /// Friction force, N.
    pub friction_n: Vec<f64>,
}

/// The friction of the best and the worst bearing (thesis Fig. 66): the
/// first recording `recording_of(bearing)` gives for each, titled with the
/// bearing and its verdict. Bearings without a recording or a friction
/// channel are left out.
pub fn friction_examples(
    d: &Diagnosis,
    mut recording_of: impl FnMut(&str) -> Option<Recording>,
) -> Vec<FrictionTrace> {
    let (Some(worst), Some(best)) = (d.bearings.first(), d.bearings.last()) else {
        return Vec::new();
    };
    [best, worst]
        .into_iter()
        .filter_map(|b| {
            let rec = recording_of(&b.bearing)?;
            let f = rec.channel(Channel::Friction)?;
            Some(FrictionTrace {
                name: format!("{} ({})", b.bearing, b.verdict.name()),
                t_s: (0..f.len()).map(|i| rec.time_s(i)).collect(),
                friction_n: f.to_vec(),
            })
        })
        .collect()
}

/// Sections and figures of a bearing diagnosis.
///
/// `friction_examples`: optional raw friction traces
/// of the best and worst bearing (thesis Fig. 66).
///
/// # Errors
/// [`crate::Error::Report`] if the settings cannot be tabulated.
pub fn diagnosis_parts(
    d: &Diagnosis,
    f_c_hz: Option<f64>,
    friction_examples: &[FrictionTrace],
    prefix: &str,
) -> Result<ReportParts> {
    let mut parts = ReportParts::default();
    let verdicts: Vec<Verdict> = d
        .bearings
        .iter()
        .map(|b| {
            let level = match b.verdict {
                Condition::Good => Level::Pass,
                Condition::Inconclusive | Condition::Suspect => Level::Warn,
                Condition::Bad => Level::Fail,
            };
            Verdict::new(
                level,
                format!("#{} {}: {}", b.rank, b.bearing, b.verdict.name()),
                b.evidence.join("; "),
            )
        })
        .collect();
    let mut table = Table::new([
        "rank",
        "bearing",
        "verdict",
        "records",
        "periods",
        "spikes (bad at)",
        "typical rise × batch",
        "low band × median",
        "f_c line (dB)",
    ]);
    for b in &d.bearings {
        table = table.with_row([
            b.rank.to_string(),
            b.bearing.clone(),
            b.verdict.name().to_string(),
            b.records.to_string(),
            b.periods.to_string(),
            format!("{} ({})", b.spikes, b.spikes_for_bad),
            b.typical_over_batch
                .map(|r| fmt_sig(r, 3))
                .unwrap_or_else(|| "–".into()),
            fmt_sig(b.low_band_ratio, 3),
            b.harmonics
                .first()
                .and_then(|h| h.ratio_db)
                .map(|r| fmt_sig(r, 3))
                .unwrap_or_else(|| "–".into()),
        ]);
    }
    let mut section = Section::new("Bearing diagnosis")
        .with(Block::Verdicts(verdicts))
        .with(Block::Table(table));
    if !d.warnings.is_empty() {
        section = section.with(Block::Warnings(d.warnings.clone()));
    }
    parts.sections.push(section);
    parts
        .sections
        .push(Section::new("Diagnosis thresholds").with(Block::settings(&d.settings)?));

    if !d.freq_hz.is_empty() {
        let names: Vec<String> = d
            .bearings
            .iter()
            .map(|b| format!("{} ({})", b.bearing, b.verdict.name()))
            .collect();
        let spectra: Vec<(&str, &[f64])> = names
            .iter()
            .map(String::as_str)
            .zip(d.friction_psd.iter().map(Vec::as_slice))
            .collect();
        let worst = d.bearings.iter().position(|b| b.verdict == Condition::Bad);
        let y = Axis::log("Friction PSD", "N²/Hz");
        parts.figures.push(kinds::overlay_spectra(
            &format!("{prefix}fleet_spectra"),
            "Friction auto-spectra of the bearings, averaged over repeats (thesis Fig. 67)",
            &d.freq_hz,
            &spectra,
            y.clone(),
            worst,
            SpectrumView {
                f_c_hz: None,
                n_harmonics: 0,
                range_hz: None,
            },
        ));
        parts.figures.push(kinds::overlay_spectra(
            &format!("{prefix}fleet_spectra_low"),
            "Friction auto-spectra below the low-band edge with f_c and harmonics (thesis Fig. 68)",
            &d.freq_hz,
            &spectra,
            y,
            worst,
            SpectrumView {
                f_c_hz,
                n_harmonics: 5,
                range_hz: Some((0.0, d.settings.low_band_hz)),
            },
        ));
    }
    if !friction_examples.is_empty() {
        let mut fig = Figure::new(
            format!("{prefix}friction_examples"),
            "Friction force of the best and the worst bearing (thesis Fig. 66)",
        );
        for tr in friction_examples {
            let mut p = Panel::new(Axis::linear("Time", "s"), Axis::linear("Friction", "N"))
                .titled(tr.name.clone());
            p.series.push(Series::line(
                tr.name.clone(),
                tr.t_s.clone(),
                tr.friction_n.clone(),
            ));
            p.legend = Some(false);
            fig = fig.with_panel(p);
        }
        parts.figures.push(fig);
    }
    Ok(parts)
}
