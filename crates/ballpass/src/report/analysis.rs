//! The report of an [`Analysis`] (thesis Figs. 54–65): the signals, each
//! correlation full range and zoomed with dashed lines at multiples of
//! `tau_c`, the full-range spectra of the unfiltered signals on log–log
//! axes, the high-resolution spectra of the low-passed ones with `f_c` and
//! its harmonics marked, and the coherence; each figure in the section
//! whose text discusses it, with the table it was drawn from linked.
//!
//! Everything is drawn from the analysis' own numbers (nothing is
//! recomputed); the signals figure needs the first recording.

use crate::analysis::export::{correlation_column, psd_column};
use crate::analysis::{Analysis, CorrNorm, Signal};
use crate::error::Result;
use crate::recording::Recording;
use crate::report::kinds::{self, fmt_pm, fmt_sig, SpectrumView};
use crate::report::{
    Axis, Block, Figure, Level, Marker, Report, Rgb, Section, Series, Table, Verdict,
};

/// Where the report's data files are and how its figure ids start.
#[derive(Debug, Clone, Default)]
pub struct AnalysisLinks {
    /// Folder of `analysis.json` and the CSV tables relative to the report's
    /// folder, ending in `/` (empty when they are beside it).
    pub tables_dir: String,
    /// The recording the signals figure shows, as a link (a path relative
    /// to the report's folder or absolute), when it is a file.
    pub recording: Option<String>,
    /// Prefix of the figure ids (when several parts share one report).
    pub id_prefix: String,
}

/// Unit of a signal squared per hertz: `N²/Hz`, `(mm/s)²/Hz`.
fn unit2(s: Signal) -> String {
    let u = s.unit();
    if u.contains('/') {
        format!("({u})²/Hz")
    } else {
        format!("{u}²/Hz")
    }
}

/// Unit of the product of two signals: `N·V`, `N·mm/s`, `V²`.
fn product_unit(x: Signal, y: Signal) -> String {
    if x == y {
        let u = x.unit();
        return if u.contains('/') {
            format!("({u})²")
        } else {
            format!("{u}²")
        };
    }
    format!("{}·{}", x.unit(), y.unit())
}

/// The pair in words: `friction` or `friction and optical`.
fn pair_words(x: Signal, y: Signal) -> String {
    if x == y {
        x.words().to_string()
    } else {
        format!("{} and {}", x.words(), y.words())
    }
}

/// Text from the analysis in the report's words: series names
/// (`friction__optical`, `velocity_error`) and symbols (`tau_c`) as a
/// reader writes them.
pub fn humanize(text: &str) -> String {
    let mut t = text.to_string();
    for (x, y) in crate::analysis::CROSS_PAIRS {
        t = t.replace(&crate::analysis::pair_name(x, y), &pair_words(x, y));
    }
    t.replace("velocity_error", "velocity error")
        .replace("tau_c", "τc")
        .replace("tau_p", "τp")
}

/// Builds the report of `a`; `raw` (the first record) adds the signals figure.
///
/// # Errors
/// [`crate::Error::Report`] if the settings cannot be tabulated.
pub fn report(a: &Analysis, raw: Option<&Recording>, links: &AnalysisLinks) -> Result<Report> {
    let mut r = Report::new(format!(
        "ballpass analyze: {} mm/s",
        a.prediction.velocity_mm_s
    ));
    for s in sections(a, raw, links)? {
        r = r.with_section(s);
    }
    Ok(r)
}

/// The sections of the report of `a`, figures in place (see [`report`]).
///
/// # Errors
/// [`crate::Error::Report`] if the settings cannot be tabulated.
pub fn sections(
    a: &Analysis,
    raw: Option<&Recording>,
    links: &AnalysisLinks,
) -> Result<Vec<Section>> {
    let id = |s: &str| format!("{}{s}", links.id_prefix);
    let table = |f: &str| format!("{}{f}", links.tables_dir);
    let p = &a.prediction;
    let tau = a.measured_period.period_s.unwrap_or(p.tau_c_s);
    let f_c = 1.0 / tau;
    let k = a.settings.harmonics;
    let n_rec = a.inputs.len();

    // Summary
    let mut kv = vec![
        ("f_c predicted".to_string(), format!("{:.4} Hz", p.f_c_hz)),
        (
            "f_c measured".to_string(),
            a.measured_period
                .f_c_hz
                .map(|f| format!("{f:.4} Hz ({})", humanize(&a.measured_period.choice)))
                .unwrap_or_else(|| "not measured".into()),
        ),
        (
            "records".to_string(),
            format!("{n_rec} × {:.2} s at {} Hz", a.duration_analysed_s, a.fs_hz),
        ),
    ];
    if let Some(v) = &a.velocity_error {
        let value = match v.std_spread_um_s {
            Some(sd) => format!(
                "{} µm/s (mean of {} records ± their spread; encoder quantisation floor {:.1} µm/s)",
                fmt_pm(v.std_um_s, sd, 3),
                v.records,
                v.quantisation_floor_um_s
            ),
            None => format!(
                "{:.1} µm/s (encoder quantisation floor {:.1} µm/s)",
                v.std_um_s, v.quantisation_floor_um_s
            ),
        };
        kv.push(("velocity-error std".into(), value));
    }
    let level = if a.verdict.signals_showing_f_c.is_empty() {
        Level::Warn
    } else {
        Level::Pass
    };
    let mut summary = Section::new("Summary")
        .with(Block::Verdicts(vec![Verdict::new(
            level,
            "ball-pass frequency",
            humanize(&a.verdict.text),
        )]))
        .with(Block::KeyValues(kv));
    if !a.warnings.is_empty() {
        summary = summary.with(Block::Warnings(
            a.warnings.iter().map(|w| humanize(w)).collect(),
        ));
    }
    let mut out = vec![summary];

    // Signals: of the first record as loaded, or as a streamed analysis
    // gathered them (the same samples).
    let gathered = raw.map(|rec| super::envelope::SignalSamples::of(rec, tau));
    let samples = gathered
        .as_ref()
        .or_else(|| a.stream.as_ref().and_then(|s| s.signals.as_ref()));
    if let Some(rec) = samples {
        let mut fig = super::envelope::signals(
            &id("signals"),
            &format!(
                "Signals of {}",
                crate::report::passage::short_name(&rec.source_name)
            ),
            rec,
        )
        .with_caption(format!(
            "As loaded, before the velocity error is formed and before any filtering (thesis Fig. \
             54).{}",
            super::envelope::envelope_words(rec)
        ));
        if let Some(path) = &links.recording {
            fig = fig.with_data(path.clone(), "the recording");
        }
        let text = if n_rec > 1 {
            format!(
                "{{fig:{}}} shows the first of the {n_rec} records; the analysis averages the \
                 correlations and spectra of all of them.",
                id("signals")
            )
        } else {
            format!("{{fig:{}}} shows the record as loaded.", id("signals"))
        };
        let mut section = Section::new("Signals")
            .with(Block::Paragraph(text))
            .with_figure(fig);
        // A long record: a few ball periods from its middle, sample by
        // sample (the measured period, else the predicted one).
        let detail_title = format!(
            "{} ball periods from the middle of the record",
            super::envelope::DETAIL_PERIODS
        );
        if let Some(d) = super::envelope::detail(&id("signals_detail"), &detail_title, rec) {
            section = section.with(Block::Paragraph(format!(
                "{{fig:{}}} shows {} ball periods (τc = {} s) from the middle of the record, \
                 sample by sample.",
                id("signals_detail"),
                super::envelope::DETAIL_PERIODS,
                fmt_sig(tau, 4)
            )));
            section = section.with_figure(d.with_caption(
                "As loaded, every sample: the pulses and the friction ripple the envelope above \
                 cannot show.",
            ));
        }
        out.push(section);
    }

    // Correlations
    let c = &a.correlations;
    let norm = a.settings.corr_norm;
    let norm_words = match norm {
        CorrNorm::Coeff => "normalised to 1 at zero lag for an autocorrelation (coefficient)",
        CorrNorm::Biased => "divided by the record length (biased)",
        CorrNorm::Unbiased => "divided by the number of overlapping samples (unbiased)",
        CorrNorm::None => "not normalised (sums of products)",
    };
    let mut corr = Section::new("Correlations").with(Block::Paragraph(format!(
        "Correlations R(x, y)[m] = Σ x[n+m]·y[n] of the low-passed, detrended signals (thesis \
         Eq. 7.1; a peak at a negative lag means y lags x), {norm_words}, averaged over the \
         records. The measured period τc = {} s comes from the {} autocorrelation{}. The dashed \
         lines of each zoom mark multiples of that period.",
        fmt_sig(tau, 5),
        a.measured_period
            .from_signal
            .map_or("(none: predicted period used)", |s| s.words()),
        a.measured_period
            .from_signal
            .map(|s| format!(" ({{fig:{}}})", id(&format!("corr_{}", s.name()))))
            .unwrap_or_default(),
    )));
    let list = |auto: bool| {
        c.series
            .iter()
            .filter(|((x, y), _)| (x == y) == auto)
            .map(|((x, y), _)| {
                format!(
                    "{} ({{fig:{}}})",
                    pair_words(*x, *y),
                    id(&format!("corr_{}", crate::analysis::pair_name(*x, *y)))
                )
            })
            .collect::<Vec<_>>()
            .join(", ")
    };
    let autos = list(true);
    let crosses = list(false);
    corr = corr.with(Block::Paragraph(if crosses.is_empty() {
        format!("The autocorrelations: {autos}.")
    } else {
        format!("The autocorrelations: {autos}; the cross-correlations: {crosses}.")
    }));
    if !a.phases.is_empty() {
        let mut t = Table::new([
            "pair",
            "figure",
            "lag (s)",
            "phase (deg)",
            "± 95 % (deg)",
            "in words",
        ]);
        let opt = |v: Option<f64>, digits: usize| {
            v.map_or("—".to_string(), |v| {
                format!("{v:+.digits$}").replace('-', "−")
            })
        };
        for ph in &a.phases {
            t = t.with_row([
                pair_words(ph.x, ph.y),
                format!(
                    "{{fig:{}}}",
                    id(&format!("corr_{}", crate::analysis::pair_name(ph.x, ph.y)))
                ),
                opt(ph.lag_s, 3),
                opt(ph.phase_deg, 0),
                ph.phase_ci95_deg
                    .map_or("—".to_string(), |v| format!("{v:.0}")),
                humanize(&ph.words),
            ]);
        }
        corr = corr
            .with(Block::Paragraph(
                "Phases at the measured f_c from the cross spectrum (records cut into whole \
                 ball-pass periods), with their 95 % intervals from the coherence; a pair \
                 whose coherence at f_c is not significant has no phase:"
                    .into(),
            ))
            .with(Block::Table(t));
    }
    for ((x, y), v) in &c.series {
        let name = crate::analysis::pair_name(*x, *y);
        let title = if x == y {
            format!("Autocorrelation of {}", x.words())
        } else {
            format!("Cross-correlation of {} (Eq. 7.1)", pair_words(*x, *y))
        };
        // the pair is in the title; the axis says what R is
        let (label, unit) = match norm {
            CorrNorm::Coeff => ("R (normalised)".to_string(), String::new()),
            _ => ("R".to_string(), product_unit(*x, *y)),
        };
        let mut fig = kinds::correlation(
            &id(&format!("corr_{name}")),
            &title,
            &c.lag_s,
            v,
            Axis::linear(label, unit),
            Some(tau),
            3.0,
        );
        if !c.is_full_range() {
            fig.panels[0].title = format!(
                "(a) lags within ±{} s (the lag window, --max-lag)",
                kinds::fmt_sig(c.max_lag_samples() as f64 / c.fs_hz, 4)
            );
        }
        corr = corr.with_figure(
            fig.with_caption(format!(
                "Averaged over {n_rec} record{}; (b) within ±3 τc.",
                if n_rec == 1 { "" } else { "s" }
            ))
            .with_data(
                table("correlations.csv"),
                format!("lag_s, {}", correlation_column(*x, *y, norm)),
            ),
        );
    }
    out.push(corr);

    // Spectra
    let view_full = SpectrumView {
        f_c_hz: Some(f_c),
        n_harmonics: k,
        range_hz: None,
        unfiltered: true,
    };
    let view_hires = SpectrumView {
        f_c_hz: Some(f_c),
        n_harmonics: k,
        range_hz: Some((0.0, (k as f64 + 1.0) * f_c)),
        unfiltered: false,
    };
    let lp = a
        .settings
        .lowpass_hz
        .map_or("without a low-pass".to_string(), |f| {
            format!("low-passed at {} Hz", fmt_sig(f, 3))
        });
    let u = &a.spectra_unfiltered;
    let h = &a.spectra_hires;
    let mut spectra = Section::new("Spectra").with(Block::Paragraph(format!(
        "{} shows the full range of the auto-spectra of the signals as recorded (before the \
         low-pass and the detrend, as the thesis' Fig. 62), on logarithmic axes so that both \
         the ball-pass harmonics near {} Hz and the white-noise floor at high frequencies read; \
         {} shows their cross-spectra (Fig. 64). The signals {lp} and detrended are resolved \
         finely around f_c in {}{}, with k·f_c marked (Figs. 63, 65), and their coherence in {}.",
        if u.auto.is_empty() {
            "No figure".to_string()
        } else {
            format!("{{fig:{}}}", id("spectra"))
        },
        fmt_sig(f_c, 3),
        if u.cross.is_empty() {
            "no figure".to_string()
        } else {
            format!("{{fig:{}}}", id("cross_spectra"))
        },
        format_args!("{{fig:{}}}", id("spectra_hires")),
        if h.cross.is_empty() {
            String::new()
        } else {
            format!(" and {{fig:{}}}", id("cross_spectra_hires"))
        },
        if h.cross.is_empty() {
            "no figure".to_string()
        } else {
            format!("{{fig:{}}}", id("coherence"))
        },
    )));
    let harm = harmonics_table(a);
    if !harm.rows.is_empty() {
        spectra = spectra
            .with(Block::Paragraph(format!(
                "Each harmonic's PSD against the local floor of its spectrum ({} confidence; \
                 the floor is the median over ±1.5 f_c without the bins at harmonics):",
                fmt_percent(a.settings.confidence)
            )))
            .with(Block::Table(harm));
    }
    let info = |s: &crate::analysis::Spectra| {
        format!(
            "Welch ({}), {}-sample segments, {} records, resolution {} Hz; dashed lines at k·f_c, f_c = {} Hz.",
            s.info.window,
            s.info.nperseg,
            s.info.n_records,
            fmt_sig(s.info.resolution_hz, 3),
            fmt_sig(f_c, 5)
        ) + &band_words(s)
    };
    let full = SpectrumFigure {
        spectra: u,
        view: view_full,
        log_frequency: true,
        caption: info(u),
        table: table("spectra_unfiltered.csv"),
    };
    let hires = SpectrumFigure {
        spectra: h,
        view: view_hires,
        log_frequency: false,
        caption: format!("{}, {lp}. {}", h.info.method, info(h)),
        table: table("spectra_hires.csv"),
    };
    for fig in [
        full.auto(id("spectra"), "Auto-spectra, full range, unfiltered"),
        full.cross(
            id("cross_spectra"),
            "Cross-spectra magnitude, full range, unfiltered",
        ),
        hires.auto(id("spectra_hires"), "Auto-spectra, high resolution"),
        hires.cross(
            id("cross_spectra_hires"),
            "Cross-spectra magnitude, high resolution",
        ),
    ]
    .into_iter()
    .flatten()
    {
        spectra = spectra.with_figure(fig);
    }
    if !h.cross.is_empty() {
        let mut fig = Figure::new(id("coherence"), "Coherence, high resolution")
            .with_caption(format!(
                "Magnitude-squared coherence |Pxy|²/(Pxx·Pyy) of the averaged spectra; {}{}",
                info(h),
                coherence_words(h, a.settings.confidence)
            ))
            .with_data(table("spectra_hires.csv"), "freq_hz, coh_*");
        for cr in &h.cross {
            let mut panel = kinds::coherence_panel(
                &h.freq_hz,
                &cr.coherence,
                &pair_words(cr.x, cr.y),
                view_hires,
            )
            .titled(pair_words(cr.x, cr.y));
            if let Some(t) = h.info.coherence_threshold {
                panel = panel.with_hlines([Marker::black_dashed(t, "significance")]);
            }
            fig = fig.with_panel(panel);
        }
        spectra = spectra.with_figure(fig.interactive());
    }
    if let Some(pos) = &a.position {
        spectra = spectra.with(Block::Paragraph(format!(
            "Against the travel instead of time, {} shows the spectra in cycles/mm, where the \
             balls pass every 2 d_avg at any speed (line at {} cycles/mm).",
            format_args!("{{fig:{}}}", id("spectra_position")),
            fmt_sig(pos.line_per_mm, 5)
        )));
        spectra = spectra.with_figure(super::position::figure(
            pos,
            a.settings.harmonics,
            id("spectra_position"),
            table("spectra_position.csv"),
        ));
    }
    out.push(spectra);

    if let Some(st) = &a.stage {
        let mut sec = Section::new("Stage").with(Block::Paragraph(format!(
            "The stage identified from the data: the friction → velocity-error response \
             (cross spectrum over the friction's auto spectrum, with its coherence), fitted with \
             the PD-controlled stage of the thesis; identified only when f_n is known to ±5 % \
             and ζ to ±20 % (95 %). {}.",
            humanize(&st.text)
        )));
        if st.natural_frequency_hz.is_some() {
            let row = |name: &str, e: Option<crate::model::identify::Estimate>, unit: &str| {
                [
                    name.to_string(),
                    e.map_or("—".into(), |e| fmt_sig(e.value, 4)),
                    e.map_or("—".into(), |e| fmt_sig(e.ci95, 2)),
                    unit.to_string(),
                ]
            };
            let t = Table::new(["quantity", "value", "± 95 %", "unit"])
                .with_row(row("natural frequency f_n", st.natural_frequency_hz, "Hz"))
                .with_row(row("damping ratio ζ", st.damping_ratio, ""))
                .with_row(row("moving mass m", st.mass_kg, "kg"))
                .with_row(row("K K_D", st.kkd_n_s_per_m, "N s/m"))
                .with_row(row("K K_P", st.kkp_n_per_m, "N/m"))
                .with_row(row("peak |G_vf|", st.peak_gain_mm_s_per_n, "(mm/s)/N"));
            sec = sec.with(Block::Table(t));
        }
        out.push(sec);
    }
    out.extend(super::sync::section(
        a,
        &id("sync_average"),
        &table("sync_average.csv"),
    ));

    let mut settings = Section::new("Settings and method").with(Block::settings(&a.settings)?);
    if !a.method_notes.is_empty() {
        settings = settings.with(Block::Paragraph(format!(
            "Method: {}.",
            humanize(&a.method_notes.join("; "))
        )));
    }
    settings = settings.with(Block::Paragraph(format!(
        "All numbers behind the figures: {}, {}, {}, {} and {} (column names end in their \
         units; see the user guide).",
        table("analysis.json"),
        table("correlations.csv"),
        table("spectra_unfiltered.csv"),
        table("spectra.csv"),
        table("spectra_hires.csv")
    )));
    out.push(settings);
    Ok(out)
}

/// Colour of the PSD confidence bands: a pale blue under the curves.
const BAND: Rgb = Rgb(160, 190, 225);

/// What the pale lines of an auto-spectrum figure are; empty without a band.
fn band_words(s: &crate::analysis::Spectra) -> String {
    s.info.band.map_or(String::new(), |b| {
        format!(
            " Pale lines: the {} confidence band of each PSD (chi-square with ν = {} \
             equivalent degrees of freedom, the segments' overlap and window accounted for; \
             ×{} to ×{} of the estimate).",
            fmt_percent(b.confidence),
            fmt_sig(b.dof, 3),
            fmt_sig(b.lower_factor, 3),
            fmt_sig(b.upper_factor, 3)
        )
    })
}

/// What the dashed horizontal line of the coherence figure is.
fn coherence_words(s: &crate::analysis::Spectra, confidence: f64) -> String {
    s.info.coherence_threshold.map_or(String::new(), |t| {
        format!(
            " The dashed horizontal line at {} is the {} significance level of a coherence \
             row whose k·f_c falls on a bin: noise (in both signals, or beside a line in one \
             of them) exceeds it in any of the three bins nearest k·f_c with probability at \
             most a = 1 − c^(1/3) = {} for the three pairs tested at confidence c; rows \
             between bins have a lower level, stated in their rows (`coherence` in \
             analysis.json; ν = {} equivalent degrees of freedom).",
            fmt_sig(t, 3),
            fmt_percent(confidence),
            fmt_percent(crate::analysis::confidence::coherence_row_rate(confidence)),
            fmt_sig(s.info.dof, 3)
        )
    })
}

/// The auto- and cross-spectrum figures of one [`crate::analysis::Spectra`].
struct SpectrumFigure<'a> {
    spectra: &'a crate::analysis::Spectra,
    view: SpectrumView,
    /// Log–log axes over the full range (else linear frequency).
    log_frequency: bool,
    caption: String,
    table: String,
}

impl SpectrumFigure<'_> {
    fn panel(&self, values: &[f64], name: &str, y: Axis) -> crate::report::Panel {
        let f = &self.spectra.freq_hz;
        if self.log_frequency {
            kinds::spectrum_panel_loglog(f, values, name, y, self.view)
        } else {
            kinds::spectrum_panel(f, values, name, y, self.view)
        }
        .titled(name)
    }

    /// One panel per auto-spectrum; `None` without any.
    fn auto(&self, id: String, title: &str) -> Option<Figure> {
        let s = self.spectra;
        if s.auto.is_empty() {
            return None;
        }
        let columns: Vec<String> = s.auto.iter().map(|(x, _)| psd_column(*x)).collect();
        let mut fig = Figure::new(id, title)
            .with_caption(self.caption.clone())
            .with_data(
                self.table.clone(),
                format!("freq_hz, {}", columns.join(", ")),
            );
        for (sig, psd) in &s.auto {
            let mut panel = self.panel(
                psd,
                sig.words(),
                Axis::log(format!("PSD of {}", sig.words()), unit2(*sig)),
            );
            if let Some(bounds) = crate::analysis::confidence::band_of(s, psd) {
                for b in bounds {
                    let (f, v): (Vec<f64>, Vec<f64>) = s
                        .freq_hz
                        .iter()
                        .zip(b)
                        .filter(|(f, _)| !self.log_frequency || **f > 0.0)
                        .map(|(f, v)| (*f, v))
                        .unzip();
                    panel = panel.with_series(Series::line("", f, v).with_color(BAND));
                }
            }
            fig = fig.with_panel(panel);
        }
        Some(fig.interactive())
    }

    /// One panel per cross pair, the magnitude |P_xy|; `None` without any.
    fn cross(&self, id: String, title: &str) -> Option<Figure> {
        let s = self.spectra;
        if s.cross.is_empty() {
            return None;
        }
        let mut fig = Figure::new(id, title)
            .with_caption(self.caption.clone())
            .with_data(self.table.clone(), "freq_hz, csd_*_re, csd_*_im");
        for cr in &s.cross {
            let mag: Vec<f64> = cr.pxy.iter().map(|z| z.norm()).collect();
            fig = fig.with_panel(self.panel(
                &mag,
                &pair_words(cr.x, cr.y),
                Axis::log("|CSD|", format!("{}/Hz", product_unit(cr.x, cr.y))),
            ));
        }
        Some(fig.interactive())
    }
}

fn fmt_percent(p: f64) -> String {
    format!("{} %", fmt_sig(100.0 * p, 3))
}

/// Harmonics of each signal: PSD against its floor, at the measured `f_c`
/// where there is one.
fn harmonics_table(a: &Analysis) -> Table {
    let mut t = Table::new([
        "signal",
        "k",
        "k·f_c (Hz)",
        "PSD / floor (dB)",
        "threshold (dB)",
        "above the floor",
    ]);
    for r in &a.harmonics {
        let Some(v) = r.measured.as_ref().or(r.predicted.as_ref()) else {
            continue;
        };
        let db =
            |x: Option<f64>| x.map_or("–".to_string(), |d| format!("{d:+.1}").replace('-', "−"));
        t = t.with_row([
            r.signal.words().to_string(),
            r.k.to_string(),
            fmt_sig(v.f_hz, 4),
            db(v.ratio_db),
            db(v.threshold_db),
            match v.significant {
                Some(true) => "yes".to_string(),
                Some(false) => "no".to_string(),
                None => "–".to_string(),
            },
        ]);
    }
    t
}
