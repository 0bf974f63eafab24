//! The figure set and summary of an [`Analysis`] as a [`Report`] (thesis
//! Figs. 54–65): raw signals, each correlation full range and zoomed with
//! dashed lines at multiples of `tau_c`, full-range and high-resolution
//! auto-spectra with `f_c` and its harmonics marked, and coherence.
//!
//! Everything is drawn from the analysis' own numbers (nothing is
//! recomputed); the raw-signal figure needs the first recording.

use crate::analysis::{pair_name, Analysis, Signal};
use crate::error::Result;
use crate::recording::{Channel, Recording};
use crate::report::kinds::{self, SpectrumView, Trace};
use crate::report::{Axis, Block, Figure, Level, Report, Section, Verdict};

fn unit2(s: Signal) -> String {
    let u = s.unit();
    if u.contains('/') {
        format!("({u})²/Hz")
    } else {
        format!("{u}²/Hz")
    }
}

/// Builds the report of `a`; `raw` (the first record) adds the signals figure.
///
/// # Errors
/// [`crate::Error::Report`] if the settings cannot be tabulated.
pub fn report(a: &Analysis, raw: Option<&Recording>) -> Result<Report> {
    let p = &a.prediction;
    let tau = a.measured_period.period_s.unwrap_or(p.tau_c_s);
    let f_c = 1.0 / tau;
    let k = a.settings.harmonics;
    let mut kv = vec![
        ("f_c predicted".to_string(), format!("{:.4} Hz", p.f_c_hz)),
        (
            "f_c measured".to_string(),
            a.measured_period
                .f_c_hz
                .map(|f| format!("{f:.4} Hz ({})", a.measured_period.choice))
                .unwrap_or_else(|| "not measured".into()),
        ),
        (
            "records".to_string(),
            format!(
                "{} × {:.2} s at {} Hz",
                a.inputs.len(),
                a.duration_analysed_s,
                a.fs_hz
            ),
        ),
    ];
    for ph in &a.phases {
        kv.push((ph.pair.clone(), ph.words.clone()));
    }
    if let Some(v) = &a.velocity_error {
        kv.push((
            "velocity error std".into(),
            format!(
                "{:.1} µm/s (floor {:.1})",
                v.std_um_s, v.quantisation_floor_um_s
            ),
        ));
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
            &a.verdict.text,
        )]))
        .with(Block::KeyValues(kv));
    if !a.warnings.is_empty() {
        summary = summary.with(Block::Warnings(a.warnings.clone()));
    }
    let mut r = Report::new(format!("ballpass analyze: {} mm/s", p.velocity_mm_s))
        .with_section(summary)
        .with_section(Section::new("Settings").with(Block::settings(&a.settings)?));
    if let Some(rec) = raw {
        let t: Vec<f64> = (0..rec.len()).map(|i| rec.time_s(i)).collect();
        let traces: Vec<Trace<'_>> = Channel::ALL
            .iter()
            .filter_map(|&c| {
                rec.channel(c).map(|v| Trace {
                    label: match c {
                        Channel::Friction => "Friction force",
                        Channel::Position => "Position",
                        Channel::Optical => "Optical sensor",
                    },
                    unit: c.unit(),
                    values: v,
                })
            })
            .collect();
        r = r.with_figure(kinds::time_series_stack(
            "signals",
            &format!("Signals of {}", rec.source_name()),
            &t,
            &traces,
        ));
    }
    let c = &a.correlations;
    for ((x, y), v) in &c.series {
        let name = pair_name(*x, *y);
        let title = if x == y {
            format!("Autocorrelation of {}", x.words())
        } else {
            format!("Cross-correlation {} × {} (Eq. 7.1)", x.words(), y.words())
        };
        r = r.with_figure(kinds::correlation(
            &format!("corr_{name}"),
            &title,
            &c.lag_s,
            v,
            Axis::linear(format!("R {name}"), ""),
            Some(tau),
            3.0,
        ));
    }
    for (id, title, s, range) in [
        (
            "spectra",
            "Auto-spectra, full range (Welch)",
            &a.spectra,
            None,
        ),
        (
            "spectra_hires",
            "Auto-spectra, high resolution",
            &a.spectra_hires,
            Some((0.0, (k as f64 + 1.0) * f_c)),
        ),
    ] {
        let view = SpectrumView {
            f_c_hz: Some(f_c),
            n_harmonics: k,
            range_hz: range,
        };
        let mut fig = Figure::new(id, title).with_caption(format!(
            "{}, {}-sample segments, resolution {:.4} Hz; dashed lines at k·f_c, f_c = {:.4} Hz",
            s.info.method, s.info.nperseg, s.info.resolution_hz, f_c
        ));
        for (sig, psd) in &s.auto {
            fig = fig.with_panel(
                kinds::spectrum_panel(
                    &s.freq_hz,
                    psd,
                    sig.name(),
                    Axis::log(format!("PSD {}", sig.words()), unit2(*sig)),
                    view,
                )
                .titled(sig.words()),
            );
        }
        r = r.with_figure(fig);
    }
    let s = &a.spectra_hires;
    if !s.cross.is_empty() {
        let view = SpectrumView {
            f_c_hz: Some(f_c),
            n_harmonics: k,
            range_hz: Some((0.0, (k as f64 + 1.0) * f_c)),
        };
        let mut fig = Figure::new("coherence", "Coherence, high resolution");
        for cr in &s.cross {
            let name = pair_name(cr.x, cr.y);
            fig = fig.with_panel(
                kinds::coherence_panel(&s.freq_hz, &cr.coherence, &name, view).titled(name.clone()),
            );
        }
        r = r.with_figure(fig);
    }
    Ok(r)
}
