//! Report sections and figures of campaigns (thesis Figs. 29, 52, 53, 66–68).

use crate::campaign::batch::BatchOutcome;
use crate::campaign::diagnose::{Condition, Diagnosis};
use crate::campaign::run::CampaignSettings;
use crate::campaign::sweep::Sweep;
use crate::error::Result;
use crate::recording::{Channel, Recording};
use crate::report::kinds::{self, fmt_pm, fmt_sig, Overlaid, PowerLaw, SpectrumView};
use crate::report::{
    Axis, Block, Figure, Level, Panel, Report, Rgb, Section, Series, SeriesStyle, Table, Verdict,
};

/// What a campaign report shows: sections with their figures in place, and
/// figures without a section (none today; kept for callers that add some).
#[derive(Debug, Clone, Default)]
pub struct ReportParts {
    /// Sections, figures placed next to their text.
    pub sections: Vec<Section>,
    /// Figures shown after the sections.
    pub figures: Vec<Figure>,
}

/// The report of a campaign (`sweep`, `diagnose`): its inputs and
/// selection, the command's `parts`, the failed records, the settings, then
/// the figures without a section. `title` names the command, `source` the
/// manifest or folder, `n_records` the records selected, `notes` the
/// selection's notes. The caller adds the command line.
///
/// # Errors
/// [`crate::Error::Report`] if the settings cannot be tabulated.
pub fn campaign_report<T>(
    title: &str,
    source: &std::path::Path,
    n_records: usize,
    outcome: &BatchOutcome<T>,
    notes: &[String],
    parts: ReportParts,
    settings: &CampaignSettings,
) -> Result<Report> {
    let mut report = Report::new(format!("{title}: {}", source.display()));
    let mut inputs = vec![
        ("source".to_string(), source.display().to_string()),
        (
            "records".to_string(),
            format!("{n_records} ({} failed)", outcome.n_failed()),
        ),
    ];
    for n in notes {
        inputs.push(("selection".into(), n.clone()));
    }
    report = report.with_section(Section::new("Inputs").with(Block::KeyValues(inputs)));
    for s in parts.sections {
        report = report.with_section(s);
    }
    let failed: Vec<String> = outcome
        .failed()
        .map(|(e, why)| format!("{}: {why}", e.label()))
        .collect();
    if !failed.is_empty() {
        report = report.with_section(Section::new("Failed records").with(Block::Warnings(failed)));
    }
    report = report.with_section(Section::new("Settings").with(Block::settings(settings)?));
    for f in parts.figures {
        report = report.with_figure(f);
    }
    Ok(report)
}

/// A link to a recording file: its absolute path (the report may live in
/// another folder than the one the path was given relative to).
pub(crate) fn recording_link(rec: &Recording) -> Option<String> {
    let p = rec.meta.source.as_ref()?;
    let abs = std::path::absolute(p).unwrap_or_else(|_| p.clone());
    Some(abs.display().to_string())
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
/// unique when several parts share a report; `tables_dir` is the folder of
/// `sweep.csv` relative to the report, ending in `/` (empty when beside it).
///
/// # Errors
/// [`crate::Error::Report`] if the settings cannot be tabulated.
pub fn sweep_parts(sweep: &Sweep, prefix: &str, tables_dir: &str) -> Result<ReportParts> {
    let mut parts = ReportParts::default();
    let sweep_csv = format!("{tables_dir}sweep.csv");
    let mut figures: Vec<Figure> = Vec::new();
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
        m.map(|m| fmt_pm(m.mean, m.std, sig))
            .unwrap_or_else(|| "–".into())
    };
    for r in &sweep.velocities {
        table = table.with_row([
            format!("{}", r.velocity_mm_s),
            r.records.to_string(),
            fmt_sig(r.f_c_predicted_hz, 5),
            ms(r.f_c_measured_hz, 5),
            ms(r.velocity_error_std_um_s, 3),
            ms(r.tau_c_s, 4),
            ms(r.tau_p_s, 3),
            ms(r.tau_ratio, 3),
        ]);
    }
    let mut section = Section::new("Velocity sweep")
        .with(Block::Paragraph(
            sweep
                .findings
                .iter()
                .map(|f| capitalised(f))
                .collect::<Vec<_>>()
                .join(". ")
                + ".",
        ))
        .with(Block::Table(table))
        .with(Block::Paragraph(
            "Each value is the mean over the repeats at that velocity ± their sample standard \
             deviation."
                .into(),
        ));

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
        figures.push(
            fig.with_caption(
                "Mean over repeats with ± one standard deviation; dashed: the PD-loop response |G_vf(j2πf_c)| fitted to the means.",
            )
            .with_data(
                sweep_csv.clone(),
                "velocity_mm_s, velocity_error_std_um_s, velocity_error_std_spread_um_s",
            ),
        );
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
                            "fit: {} v^({})",
                            fmt_sig(f.coefficient, 3),
                            fmt_pm(f.slope, f.slope_ci95, 4)
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
        figures.push(
            kinds::loglog_fit(
                &format!("{prefix}tau_vs_velocity"),
                "Ball-pass period τc and pulse width τp against velocity (thesis Fig. 52)",
                Axis::log("Tracking velocity", "mm/s"),
                Axis::log("Time", "s"),
                &xc,
                &[("τc", &mc, &sc), ("τp", &mp, &sp)],
                &fits,
            )
            .with_caption("Mean over repeats ± one standard deviation; dashed: power laws fitted on log–log axes, exponent ± its 95 % interval. Both are inversely proportional to velocity when the exponent is −1.")
            .with_data(sweep_csv.clone(), "velocity_mm_s, tau_c_s, tau_c_spread_s, tau_p_s, tau_p_spread_s"),
        );
    }
    let ra: Vec<_> = sweep
        .velocities
        .iter()
        .map(|r| (r.velocity_mm_s, r.tau_ratio))
        .collect();
    let (xr, mr, sr) = mean_std_cols(&ra);
    if !xr.is_empty() {
        figures.push(
            kinds::ratio_with_mean(
                &format!("{prefix}tau_ratio"),
                "Ratio τp / τc against velocity (thesis Fig. 53; thesis mean 0.155)",
                Axis::linear("Tracking velocity", "mm/s"),
                Axis::linear("τp / τc", ""),
                &xr,
                &mr,
                &sr,
            )
            .with_caption(
                "Mean over repeats ± one standard deviation; dashed: the mean over the velocities.",
            )
            .with_data(
                sweep_csv.clone(),
                "velocity_mm_s, tau_ratio, tau_ratio_spread",
            ),
        );
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
        figures.push(
            Figure::new(
                format!("{prefix}f_c_vs_velocity"),
                "Measured ball-pass frequency against velocity",
            )
            .with_caption("Mean over repeats ± one standard deviation; dashed: the catalog prediction; solid: f_c = v/(2 d_avg) fitted through the origin.")
            .with_data(sweep_csv.clone(), "velocity_mm_s, f_c_predicted_hz, f_c_measured_hz, f_c_measured_std_hz")
            .with_panel(p),
        );
    }
    if let Some(f) = ripple_figure(sweep, prefix, &sweep_csv) {
        figures.push(f);
    }
    if !figures.is_empty() {
        let refs: Vec<String> = figures
            .iter()
            .map(|f| format!("{{fig:{}}}", f.id))
            .collect();
        section = section.with(Block::Paragraph(format!(
            "Against velocity: {}.",
            figure_list(&figures, &refs)
        )));
    }
    for f in figures {
        section = section.with_figure(f);
    }
    parts.sections.push(section);
    Ok(parts)
}

/// The fundamental's amplitude in the position domain against velocity,
/// friction (N) and velocity error (µm/s) in two panels, each point with its
/// confidence interval as asymmetric bars; `None` when no velocity has one.
fn ripple_figure(sweep: &Sweep, prefix: &str, sweep_csv: &str) -> Option<Figure> {
    use crate::campaign::ripple::{unit_token, RIPPLE_SIGNALS};
    let mut panels = Vec::new();
    let mut confidence = None;
    let mut columns = vec!["velocity_mm_s".to_string()];
    for (signal, unit, _) in RIPPLE_SIGNALS {
        let (mut x, mut y, mut lo, mut hi) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for r in &sweep.velocities {
            let Some(l) = r.ripple.iter().find(|l| l.signal == signal && l.k == 1) else {
                continue;
            };
            x.push(r.velocity_mm_s);
            y.push(l.amplitude);
            lo.push((l.amplitude - l.amplitude_lower.unwrap_or(l.amplitude)).max(0.0));
            hi.push((l.amplitude_upper.unwrap_or(l.amplitude) - l.amplitude).max(0.0));
            confidence = confidence.or(Some(l.confidence));
        }
        if x.is_empty() {
            continue;
        }
        let t = unit_token(unit);
        let n = signal.name();
        columns.push(format!(
            "ripple_{n}_h1_{t}, ripple_{n}_h1_lower_{t}, ripple_{n}_h1_upper_{t}"
        ));
        let mut p = Panel::new(
            Axis::linear("Tracking velocity", "mm/s"),
            Axis::linear(format!("{} amplitude", capitalised(signal.words())), unit),
        )
        .with_series(Series::line(signal.words(), x, y).with_style(
            SeriesStyle::ErrorBars {
                minus: lo,
                plus: hi,
                line: true,
            },
        ));
        p.legend = Some(false);
        panels.push(p);
    }
    confidence?;
    let level = sweep
        .velocities
        .iter()
        .find_map(|r| r.ripple.first())
        .map_or(String::new(), |l| format!("{:.0} %", 100.0 * l.confidence));
    let mut fig = Figure::new(
        format!("{prefix}ripple_vs_velocity"),
        "Ball-pass ripple against velocity in the position domain (line at 1/(2 d_avg) cycles/mm)",
    )
    .with_caption(format!(
        "Amplitude of the friction's and the velocity error's line at 1/(2 d_avg) cycles/mm, from \
         the position-domain spectra of the repeats at each velocity pooled (their line powers \
         averaged, their degrees of freedom added); bars: the {level} confidence interval from \
         the chi-square band of the Welch estimate. A velocity is missing where its records have \
         too little travel in one direction to tell the line from its floor. The harmonics are in \
         the same table."
    ))
    .with_data(sweep_csv.to_string(), columns.join(", "));
    for p in panels {
        fig = fig.with_panel(p);
    }
    Some(fig)
}

/// A sentence with its first letter in capitals, unless it starts with a
/// symbol (τc stays τc, not Τc).
fn capitalised(s: &str) -> String {
    let mut c = s.chars();
    match c.next() {
        Some(f) if f.is_ascii_lowercase() => f.to_uppercase().chain(c).collect(),
        Some(f) => std::iter::once(f).chain(c).collect(),
        None => String::new(),
    }
}

/// "the velocity-error std (Figure 1), τc and τp (Figure 2), ..." from the
/// figures' ids.
fn figure_list(figures: &[Figure], refs: &[String]) -> String {
    figures
        .iter()
        .zip(refs)
        .map(|(f, r)| {
            let what = if f.id.ends_with("velocity_error_std") {
                "the velocity-error standard deviation"
            } else if f.id.ends_with("tau_vs_velocity") {
                "the ball-pass period τc and pulse width τp"
            } else if f.id.ends_with("tau_ratio") {
                "their ratio τp/τc"
            } else if f.id.ends_with("ripple_vs_velocity") {
                "the ripple amplitude at 1/(2 d_avg) in the position domain"
            } else {
                "the measured ball-pass frequency"
            };
            format!("{what} in {r}")
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// A raw friction trace shown in a diagnosis report.
#[derive(Debug, Clone)]
pub struct FrictionTrace {
    /// Legend/panel title (bearing and verdict).
    pub name: String,
    /// The bearing's verdict (sets the colour: bad is red).
    pub verdict: Condition,
    /// Sample times, s.
    pub t_s: Vec<f64>,
    /// Friction force, N.
    pub friction_n: Vec<f64>,
    /// The recording file, absolute, when it came from one.
    pub source: Option<String>,
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
                verdict: b.verdict,
                t_s: (0..f.len()).map(|i| rec.time_s(i)).collect(),
                friction_n: f.to_vec(),
                source: recording_link(&rec),
            })
        })
        .collect()
}

/// The colour of a bearing in the fleet figures: bad red, suspect orange,
/// good ones from [`Rgb::CALM`] (never red or orange), by `good_index`.
fn verdict_color(v: Condition, good_index: usize) -> Rgb {
    match v {
        Condition::Bad => Rgb::RED,
        Condition::Suspect => Rgb::ORANGE,
        Condition::Inconclusive => Rgb::GREY,
        Condition::Good => Rgb::calm(good_index),
    }
}

/// Sections and figures of a bearing diagnosis.
///
/// `friction_examples`: optional raw friction traces of the best and worst
/// bearing (thesis Fig. 66). `prefix` keeps figure ids unique when several
/// parts share a report; `tables_dir` is the folder of the diagnosis tables
/// relative to the report, ending in `/` (empty when beside it).
///
/// # Errors
/// [`crate::Error::Report`] if the settings cannot be tabulated.
pub fn diagnosis_parts(
    d: &Diagnosis,
    f_c_hz: Option<f64>,
    friction_examples: &[FrictionTrace],
    prefix: &str,
    tables_dir: &str,
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
                .map(|r| format!("{r:+.1}").replace('-', "−"))
                .unwrap_or_else(|| "–".into()),
        ]);
    }
    let id = |s: &str| format!("{prefix}{s}");
    let mut figures: Vec<Figure> = Vec::new();
    if !d.freq_hz.is_empty() {
        let names: Vec<String> = d
            .bearings
            .iter()
            .map(|b| format!("{} ({})", b.bearing, b.verdict.name()))
            .collect();
        let mut good = 0;
        let spectra: Vec<Overlaid<'_>> = d
            .bearings
            .iter()
            .zip(&names)
            .zip(&d.friction_psd)
            .map(|((b, name), psd)| {
                let color = verdict_color(b.verdict, good);
                if b.verdict == Condition::Good {
                    good += 1;
                }
                Overlaid {
                    name,
                    values: psd,
                    color,
                    highlight: b.verdict == Condition::Bad,
                }
            })
            .collect();
        let spectra_csv = format!("{tables_dir}friction_spectra.csv");
        let y = Axis::log("Friction PSD", "N²/Hz");
        // up to 1.5 times the highest frequency where a spectrum still
        // stands above the axis' floor (the low-passed spectra fall below
        // it within a few times the cut-off)
        let first = d.freq_hz.iter().copied().find(|f| *f > 0.0);
        let psds: Vec<&[f64]> = d.friction_psd.iter().map(Vec::as_slice).collect();
        let floor =
            kinds::log_range(&d.freq_hz, &psds, None, kinds::LOG_DECADES_FILTERED).map(|r| r.0);
        let last = floor.and_then(|lo| {
            d.freq_hz
                .iter()
                .enumerate()
                .rfind(|(i, _)| psds.iter().any(|p| p.get(*i).is_some_and(|v| *v >= lo)))
                .map(|(_, f)| *f)
        });
        let nyquist = d.freq_hz.last().copied();
        let last = match (last, nyquist) {
            (Some(l), Some(n)) => Some((1.5 * l).min(n)),
            (None, n) => n,
            (l, None) => l,
        };
        let x_full = match (first, last) {
            (Some(a), Some(b)) if b > a => Axis::log("Frequency", "Hz").with_range(a, b),
            _ => Axis::log("Frequency", "Hz"),
        };
        figures.push(
            kinds::overlay_spectra(
                &id("fleet_spectra"),
                "Friction auto-spectra of the bearings, averaged over repeats (thesis Fig. 67)",
                &d.freq_hz,
                &spectra,
                x_full,
                y.clone(),
                SpectrumView {
                    f_c_hz,
                    n_harmonics: 5,
                    range_hz: None,
                    unfiltered: false,
                },
            )
            .with_caption(format!(
                "On log–log axes; the signals are low-passed as analysed, so the spectra fall \
                 off above the low-pass: they are shown down to {} decades below their peak \
                 and up to 1.5 times the frequency where they reach that floor. Bad in red, \
                 suspect in orange; dashed lines at k·f_c.",
                kinds::LOG_DECADES_FILTERED
            ))
            .with_data(
                spectra_csv.clone(),
                "freq_hz, psd_friction_<bearing>_n2_per_hz",
            ),
        );
        figures.push(
            kinds::overlay_spectra(
                &id("fleet_spectra_low"),
                "Friction auto-spectra below the low-band edge with f_c and harmonics (thesis Fig. 68)",
                &d.freq_hz,
                &spectra,
                Axis::linear("Frequency", "Hz"),
                y,
                SpectrumView {
                    f_c_hz,
                    n_harmonics: 5,
                    range_hz: Some((0.0, d.settings.low_band_hz)),
                    unfiltered: false,
                },
            )
            .with_caption(format!(
                "0 to {} Hz, the band whose power the verdicts compare; dashed lines at k·f_c.",
                fmt_sig(d.settings.low_band_hz, 3)
            ))
            .with_data(spectra_csv, "freq_hz, psd_friction_<bearing>_n2_per_hz"),
        );
    }
    if !friction_examples.is_empty() {
        let mut fig = Figure::new(
            id("friction_examples"),
            "Friction force of the best and the worst bearing (thesis Fig. 66)",
        )
        .with_caption("The first recording of each, as loaded.")
        .interactive();
        let mut good = 0;
        for tr in friction_examples {
            let color = verdict_color(tr.verdict, good);
            if tr.verdict == Condition::Good {
                good += 1;
            }
            let mut p = Panel::new(Axis::linear("Time", "s"), Axis::linear("Friction", "N"))
                .titled(tr.name.clone());
            p.series.push(
                Series::line(tr.name.clone(), tr.t_s.clone(), tr.friction_n.clone())
                    .with_color(color),
            );
            p.legend = Some(false);
            fig = fig.with_panel(p);
            if let Some(src) = &tr.source {
                fig = fig.with_data(src.clone(), tr.name.clone());
            }
        }
        figures.push(fig);
    }
    let mut section = Section::new("Bearing diagnosis").with(Block::Verdicts(verdicts));
    if !figures.is_empty() {
        let refs: Vec<String> = figures
            .iter()
            .map(|f| format!("{{fig:{}}}", f.id))
            .collect();
        let what = |f: &Figure| {
            if f.id.ends_with("fleet_spectra") {
                "the bearings' friction spectra over the full range"
            } else if f.id.ends_with("fleet_spectra_low") {
                "the low band the verdicts compare"
            } else {
                "the friction of the best and the worst bearing"
            }
        };
        section = section.with(Block::Paragraph(format!(
            "Bad bearings are drawn in red, suspect ones in orange. See {}.",
            figures
                .iter()
                .zip(&refs)
                .map(|(f, r)| format!("{} in {r}", what(f)))
                .collect::<Vec<_>>()
                .join("; ")
        )));
    }
    section = section
        .with(Block::Table(table))
        .with(Block::Paragraph(format!(
            "Each ball-pass period's height is its friction peak above the bearing's slowly \
             varying baseline. A period is a sticking spike when its height stands more than {} \
             spreads above the bearing's typical period (the spread is taken from the lower half \
             of its periods, which sticking does not reach). \"Spikes (bad at)\" counts them \
             against the count a good bearing reaches with probability {} (a binomial bar); \
             \"typical rise × batch\" is the bearing's typical period over the batch's, for \
             sticking on most passages. Inconclusive (grey) bearings have too few periods to \
             show mild sticking. Every number per bearing is in {tables_dir}diagnosis.csv and \
             per record in {tables_dir}records.csv.",
            fmt_sig(d.settings.sticking.outlier_spreads, 3),
            fmt_sig(d.settings.bad_false_alarm, 2),
        )));
    if !d.warnings.is_empty() {
        section = section.with(Block::Warnings(d.warnings.clone()));
    }
    for f in figures {
        section = section.with_figure(f);
    }
    parts.sections.push(section);
    parts
        .sections
        .push(Section::new("Diagnosis thresholds").with(Block::settings(&d.settings)?));
    Ok(parts)
}

#[cfg(test)]
mod tests {
    use super::capitalised;

    /// Findings start with a capital, but a symbol keeps its case (a
    /// capital τ reads as a T).
    #[test]
    fn sentences_are_capitalised_but_not_symbols() {
        assert_eq!(capitalised("the velocity error"), "The velocity error");
        assert_eq!(capitalised("τc ∝ v^(−1)"), "τc ∝ v^(−1)");
        assert_eq!(capitalised(""), "");
    }
}
