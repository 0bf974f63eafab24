//! The report of `ballpass passage`: per record, the optical signal with the
//! passages found, the pulses with the fitted Gaussian and rectangular trains
//! (thesis Figs. 47–48), `τ_c` and `τ_p` per passage, and the summary.

use super::campaign::recording_link;
use super::html::{Block, Level, Report, Section, Table, Verdict};
use super::kinds::{fmt_pm, fmt_sig, pulses_with_models};
use super::spec::{Axis, Figure, Marker, Panel, Rgb, Series, SeriesStyle};
use crate::analysis::passage::{PassageAnalysis, PassageSettings};
use crate::analysis::passage_table::PassageFailure;
use crate::error::Result;
use crate::recording::{Channel, Recording};

/// Ball-pass periods of signal shown with the fitted models overlaid.
pub const MODEL_WINDOW_PERIODS: f64 = 6.0;

/// The name a report shows for a record: its file name without the folders
/// (the full path is in the command line and the data links).
pub(crate) fn short_name(source: &str) -> String {
    std::path::Path::new(source)
        .file_name()
        .map_or_else(|| source.to_string(), |n| n.to_string_lossy().into_owned())
}

/// The report of `ballpass passage` over `recs` (each with its analysis in
/// `done`): per record its sections, then the records that `failed`, then
/// the settings with the `bearing` named. The caller adds the command line.
///
/// # Errors
/// [`crate::Error::MissingChannel`] when a record has no optical channel;
/// [`crate::Error::Report`] if the settings cannot be tabulated.
pub fn passages_report(
    recs: &[Recording],
    done: &[PassageAnalysis],
    failed: &[PassageFailure],
    settings: &PassageSettings,
    bearing: &str,
) -> Result<Report> {
    let title = match done {
        [one] => format!("ballpass passage: {}", one.source),
        _ => format!("ballpass passage: {} records", done.len()),
    };
    let mut rep = Report::new(title);
    for (k, (rec, r)) in recs.iter().zip(done).enumerate() {
        for s in record_sections(k + 1, rec, r, "passages.csv", "")? {
            rep = rep.with_section(s);
        }
    }
    if !failed.is_empty() {
        rep = rep.with_section(
            Section::new("Records that failed").with(Block::Warnings(
                failed
                    .iter()
                    .map(|f| format!("{}: {}", f.record, f.error))
                    .collect(),
            )),
        );
    }
    let settings_block = Section::new("Settings")
        .with(Block::KeyValues(vec![(
            "bearing".into(),
            bearing.to_string(),
        )]))
        .with(Block::settings(settings)?);
    Ok(rep.with_section(settings_block))
}

/// One record's figures: `optical_<k>`, `pulses_<k>` (when fitted) and
/// `widths_<k>`, `k` being the record's 1-based number in the report.
///
/// # Errors
/// [`crate::Error::MissingChannel`] when `rec` has no optical channel.
pub fn passage_figures(k: usize, rec: &Recording, a: &PassageAnalysis) -> Result<Vec<Figure>> {
    let name = short_name(&a.source);
    let x = rec.require(Channel::Optical, "the passage report")?;
    let fs = rec.fs_hz();
    let t0 = rec.meta.start_time_s;
    let t: Vec<f64> = (0..x.len()).map(|i| t0 + i as f64 / fs).collect();
    let mut figs = Vec::new();

    // Optical signal, baseline, passages marked at their heights.
    let at = |time: f64| ((time - t0) * fs).round().clamp(0.0, (x.len() - 1) as f64) as usize;
    let (up, down): (Vec<_>, Vec<_>) = a.passages.iter().partition(|p| p.polarity > 0);
    let level = |p: &&crate::analysis::passage::Passage| {
        let b = a.baseline_v.get(at(p.time_s)).copied().unwrap_or(0.0);
        b + f64::from(p.polarity) * p.height_v
    };
    let mut panel = Panel::new(Axis::linear("Time", "s"), Axis::linear("Optical", "V"))
        .with_series(Series::line("optical", t.clone(), x.to_vec()).with_color(Rgb::BLACK));
    if a.baseline_v.len() == x.len() {
        panel.series.push(
            Series::line("running baseline", t.clone(), a.baseline_v.clone())
                .with_style(SeriesStyle::DashedLine)
                .with_color(Rgb::palette(2)),
        );
    }
    panel.series.push(
        Series::points(
            format!("passages ({})", up.len()),
            up.iter().map(|p| p.time_s).collect(),
            up.iter().map(level).collect(),
        )
        .with_color(Rgb::palette(1)),
    );
    if !down.is_empty() {
        panel.series.push(
            Series::points(
                format!("inverted ({})", down.len()),
                down.iter().map(|p| p.time_s).collect(),
                down.iter().map(level).collect(),
            )
            .with_color(Rgb::palette(3)),
        );
    }
    panel.legend = Some(true);
    figs.push(
        Figure::new(
            format!("optical_{k}"),
            format!("{name}: optical signal and the passages found"),
        )
        .with_caption(format!(
            "{} passages ({} inverted); dots at each passage's centre and height; prominence threshold {} V, noise {} V.",
            a.count,
            a.count_inverted,
            fmt_sig(a.prominence_threshold_v, 3),
            fmt_sig(a.noise_v, 3)
        ))
        .with_panel(panel)
        .interactive(),
    );

    // Pulses with the fitted models over the first periods of the fit.
    if let Some(f) = &a.fits {
        if f.gaussian.is_some() || f.rectangular.is_some() {
            let end = (f.from_s + MODEL_WINDOW_PERIODS * a.tau_c_s.mean).min(f.to_s);
            let (i0, i1) = (at(f.from_s), at(end));
            let tw = t[i0..=i1].to_vec();
            let yw: Vec<f64> = (i0..=i1)
                .map(|i| x[i] - a.baseline_v.get(i).copied().unwrap_or(0.0))
                .collect();
            let g: Option<Vec<f64>> = f
                .gaussian
                .as_ref()
                .map(|g| tw.iter().map(|&s| g.value(s)).collect());
            let r: Option<Vec<f64>> = f
                .rectangular
                .as_ref()
                .map(|r| tw.iter().map(|&s| r.value(s)).collect());
            let mut models: Vec<(&str, &[f64])> = Vec::new();
            let g_name = format!(
                "Gaussian train (R² {})",
                f.gaussian
                    .as_ref()
                    .map_or(String::new(), |g| fmt_sig(g.quality.r_squared, 4))
            );
            let r_name = format!(
                "rectangular N = {} (R² {})",
                a.settings.rectangular_order,
                f.rectangular
                    .as_ref()
                    .map_or(String::new(), |r| fmt_sig(r.quality.r_squared, 4))
            );
            if let Some(g) = &g {
                models.push((&g_name, g));
            }
            if let Some(r) = &r {
                models.push((&r_name, r));
            }
            let fig = pulses_with_models(
                &format!("pulses_{k}"),
                &format!("{name}: pulses and the fitted pulse trains"),
                &tw,
                &yw,
                Axis::linear("Optical − baseline", "V"),
                &models,
            )
            .with_caption(format!(
                "First {:.0} periods of the {} fitted ({} pulses, {:.2}–{:.2} s); R² over the whole fit. Thesis Figs. 47–48.",
                MODEL_WINDOW_PERIODS,
                if f.pulses == a.count { "whole record" } else { "stretch" },
                f.pulses,
                f.from_s,
                f.to_s
            ));
            figs.push(fig.interactive());
        }
    }

    // τ_c and τ_p per passage.
    let with_tau: Vec<_> = a.passages.iter().filter(|p| p.tau_c_s.is_some()).collect();
    let tc = Panel::new(Axis::linear("Time", "s"), Axis::linear("τc", "s"))
        .with_series(
            Series::line(
                "τc",
                with_tau.iter().map(|p| p.time_s).collect(),
                with_tau
                    .iter()
                    .map(|p| p.tau_c_s.unwrap_or(f64::NAN))
                    .collect(),
            )
            .with_style(SeriesStyle::LinePoints),
        )
        .with_hlines(
            [Marker::black_dashed(
                a.tau_c_s.mean,
                format!("mean {}", fmt_sig(a.tau_c_s.mean, 4)),
            )]
            .into_iter()
            .chain(
                a.f_c_predicted_hz
                    .map(|f| Marker::red_dashed(1.0 / f, "predicted")),
            ),
        );
    let tp = Panel::new(Axis::linear("Time", "s"), Axis::linear("τp", "s"))
        .with_series(
            Series::line(
                "τp",
                a.passages.iter().map(|p| p.time_s).collect(),
                a.passages.iter().map(|p| p.tau_p_s).collect(),
            )
            .with_style(SeriesStyle::LinePoints),
        )
        .with_hlines(a.tau_p_s.mean.is_finite().then(|| {
            Marker::black_dashed(
                a.tau_p_s.mean,
                format!("mean {}", fmt_sig(a.tau_p_s.mean, 4)),
            )
        }));
    let mut fig = Figure::new(
        format!("widths_{k}"),
        format!("{name}: period τc and width τp per passage"),
    )
    .with_caption(format!(
        "τc: time to the next passage; τp: width at half prominence. τp/τc = {} (thesis 0.155).",
        width_pm(&a.tau_p_over_tau_c, 4)
    ))
    .with_panel(tc)
    .with_panel(tp);
    for p in &mut fig.panels {
        p.legend = Some(false);
    }
    fig.panel_height_px = 220;
    figs.push(fig);
    Ok(figs)
}

fn pm(m: &crate::stats::MeanStd, sig: usize) -> String {
    fmt_pm(m.mean, m.std, sig)
}

/// A width statistic (τp, its ratio to τc, σ) as `mean ± std`, or the
/// word "withheld" where the record gives no width (the passage analysis
/// withholds widths it cannot measure right, and says why in its
/// conditions).
pub fn width_pm(m: &crate::stats::MeanStd, sig: usize) -> String {
    if m.mean.is_finite() {
        fmt_pm(m.mean, m.std, sig)
    } else {
        "withheld (see the conditions)".into()
    }
}

/// [`width_pm`] of a width in seconds, with its unit where there is one.
fn width_s(m: &crate::stats::MeanStd, sig: usize) -> String {
    if m.mean.is_finite() {
        format!("{} s", fmt_pm(m.mean, m.std, sig))
    } else {
        width_pm(m, sig)
    }
}

/// One record's sections with its figures placed in them: the passages
/// (with the optical signal, the fitted pulses and the widths per passage),
/// prediction vs measurement, the pulse-train fits and the conditions.
/// `k` numbers the record's figures (`optical_<k>`, ...); `table` is the
/// file holding the passages (relative to the report: `passages.csv`, or
/// `passage/passage.json` in the demo); `id_prefix` starts the figure ids.
///
/// # Errors
/// [`crate::Error::MissingChannel`] when `rec` has no optical channel.
pub fn record_sections(
    k: usize,
    rec: &Recording,
    a: &PassageAnalysis,
    table: &str,
    id_prefix: &str,
) -> Result<Vec<Section>> {
    let mut figures = passage_figures(k, rec, a)?;
    let link = recording_link(rec);
    for f in &mut figures {
        f.id = format!("{id_prefix}{}", f.id);
        if f.id.ends_with(&format!("optical_{k}")) || f.id.ends_with(&format!("pulses_{k}")) {
            if let Some(l) = &link {
                f.data.push(super::spec::DataFile {
                    path: l.clone(),
                    what: "the recording (optical_V)".into(),
                });
            }
        }
        f.data.push(super::spec::DataFile {
            path: table.to_string(),
            what: "every passage: time, τc, τp, amplitude".into(),
        });
    }
    let mut sections = passage_sections(a);
    let refs: Vec<String> = figures
        .iter()
        .map(|f| format!("{{fig:{}}}", f.id))
        .collect();
    let text = match refs.as_slice() {
        [optical, pulses, widths] => format!(
            "{optical} shows the optical signal with each passage found; {pulses} the first \
             pulses with the fitted pulse trains; {widths} the period τc to the next passage \
             and the width τp of each one."
        ),
        [optical, widths] => format!(
            "{optical} shows the optical signal with each passage found; {widths} the period \
             τc to the next passage and the width τp of each one (no pulse train was fitted)."
        ),
        _ => String::new(),
    };
    if let Some(first) = sections.first_mut() {
        if !text.is_empty() {
            first.blocks.push(Block::Paragraph(text));
        }
        for f in figures {
            first.blocks.push(Block::Figure(Box::new(f)));
        }
    }
    Ok(sections)
}

/// The summary sections of one record: measurements, prediction vs
/// measurement, pulse-train fits, conditions (with what to do).
pub fn passage_sections(a: &PassageAnalysis) -> Vec<Section> {
    let mut kv = vec![
        (
            "passages".to_string(),
            format!("{} ({} inverted)", a.count, a.count_inverted),
        ),
        (
            "duration".into(),
            format!("{} s at {} Hz", fmt_sig(a.duration_s, 4), a.fs_hz),
        ),
        (
            "velocity".into(),
            a.velocity_mm_s
                .map_or("unknown (period from the pulses)".into(), |v| {
                    format!("{v} mm/s ({})", a.velocity_source)
                }),
        ),
        ("τc".into(), format!("{} s", pm(&a.tau_c_s, 5))),
        (
            "τp (width at half prominence)".into(),
            width_s(&a.tau_p_s, 4),
        ),
        (
            "τp/τc".into(),
            format!("{} (thesis 0.155)", width_pm(&a.tau_p_over_tau_c, 4)),
        ),
        ("Gaussian sigma".into(), width_s(&a.sigma_s, 4)),
        ("amplitude".into(), format!("{} V", pm(&a.amplitude_v, 4))),
    ];
    if let Some(s) = &a.spacing {
        kv.push((
            "ball spacing v τc / 2".into(),
            format!(
                "{}–{} mm (std {} mm) against the possible [{}, {}] mm (balls touching to all free space d_ext in one gap); the spread uses {} % of d_ext, {} outside",
                fmt_sig(s.min_mm, 4),
                fmt_sig(s.max_mm, 4),
                fmt_sig(s.std_mm, 2),
                s.limit_min_mm,
                s.limit_max_mm,
                fmt_sig(100.0 * s.spread_over_free_space, 3),
                s.outside_limits
            ),
        ));
    }
    let mut sections = vec![
        Section::new(format!("{}: passages", short_name(&a.source))).with(Block::KeyValues(kv))
    ];

    let mut table = Table::new(["quantity", "predicted", "measured", "difference"]);
    let f_pred = a
        .f_c_predicted_hz
        .map_or("–".into(), |f| format!("{} Hz", fmt_sig(f, 5)));
    table = table.with_row([
        "f_c".to_string(),
        f_pred,
        format!("{} Hz", fmt_sig(a.f_c_measured_hz, 5)),
        a.f_c_relative_error
            .map_or("–".into(), |e| format!("{:+.2}%", 100.0 * e)),
    ]);
    if let (Some(d), Some(c)) = (a.d_avg_implied_mm, a.d_avg_catalog_mm) {
        table = table.with_row([
            "d_avg = v τc / 2".to_string(),
            format!("{} mm (catalog)", fmt_sig(c, 5)),
            format!("{} mm", fmt_sig(d, 5)),
            format!("{:+.2}%", 100.0 * (d / c - 1.0)),
        ]);
    }
    sections.push(Section::new("Prediction vs measurement").with(Block::Table(table)));

    if let Some(f) = &a.fits {
        let mut t = Table::new([
            "model",
            "R²",
            "rms residual (V)",
            "rms / amplitude",
            "τc (s)",
            "τp (s)",
            "iterations",
            "converged",
        ]);
        if let Some(g) = &f.gaussian {
            t = t.with_row([
                "Gaussian train (Eq. 6.24)".to_string(),
                fmt_sig(g.quality.r_squared, 4),
                fmt_sig(g.quality.rms_residual_v, 3),
                fmt_sig(g.quality.rms_over_amplitude, 3),
                fmt_sig(g.tau_c_s, 5),
                fmt_sig(g.tau_p_s, 4),
                g.quality.iterations.to_string(),
                g.quality.converged.to_string(),
            ]);
        }
        if let Some(r) = &f.rectangular {
            t = t.with_row([
                format!("rectangular, order {} (Eq. 6.22)", r.order),
                fmt_sig(r.quality.r_squared, 4),
                fmt_sig(r.quality.rms_residual_v, 3),
                fmt_sig(r.quality.rms_over_amplitude, 3),
                fmt_sig(r.tau_c_s, 5),
                fmt_sig(r.tau_p_s, 4),
                r.quality.iterations.to_string(),
                r.quality.converged.to_string(),
            ]);
        }
        let mut s = Section::new(format!(
            "Pulse-train fits over {} pulses ({:.2}–{:.2} s)",
            f.pulses, f.from_s, f.to_s
        ))
        .with(Block::Table(t));
        if let Some(b) = &f.better {
            s = s.with(Block::Paragraph(format!(
                "The {b} train describes this sensor better (lower rms residual)."
            )));
        }
        if !f.notes.is_empty() {
            s = s.with(Block::Warnings(f.notes.clone()));
        }
        sections.push(s);
    }

    let mut cond = Section::new("Conditions");
    if a.conditions.is_empty() {
        cond = cond.with(Block::Verdicts(vec![Verdict::new(
            Level::Pass,
            "optical signal",
            "no artefacts found (baseline drift, AC coupling, inverted pulses, gaps, period mismatch)",
        )]));
    } else {
        cond = cond.with(Block::Verdicts(
            a.conditions
                .iter()
                .map(|c| {
                    Verdict::new(
                        Level::Warn,
                        c.kind.name(),
                        format!("{} — what to do: {}", c.message, c.advice),
                    )
                })
                .collect(),
        ));
    }
    sections.push(cond);
    sections
}
