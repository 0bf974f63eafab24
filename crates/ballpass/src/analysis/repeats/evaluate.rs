//! What the averaged correlations and spectra say ([`super`], step 6): the
//! findings (period, phases, harmonics, the signals showing `f_c`), the
//! averaging of the records' correlations and spectra, the per-record
//! scalars with their spread, and the verdict.

use serde::Serialize;

use crate::analysis::correlation::{self, pairs_for, Correlations, MeasuredPeriod, SignalPeriod};
use crate::analysis::harmonics::{self, HarmonicRow};
use crate::analysis::phase::{self, LineSpectra, Phase};
use crate::analysis::preprocess::Prepared;
use crate::analysis::spectra::Spectra;
use crate::analysis::{AnalyzeSettings, Signal, Verdict};
use crate::bearing::Prediction;
use crate::stats::MeanStd;

/// Scalars of one record analysed alone.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RecordScalars {
    /// Record name.
    pub source: String,
    /// Measured `f_c` from the preferred autocorrelation, Hz.
    pub f_c_measured_hz: Option<f64>,
    /// Each signal's own period, s.
    pub periods_s: Vec<(Signal, Option<f64>)>,
    /// Phase of each cross pair (lag s, degrees).
    pub phases: Vec<(String, f64, f64)>,
    /// Ratio of the PSD at the measured (else predicted) `f_c` to its floor, dB.
    pub f_c_ratio_db: Vec<(Signal, Option<f64>)>,
    /// Velocity-error standard deviation (ddof 0, raw), µm/s.
    pub velocity_error_std_um_s: Option<f64>,
}

/// Mean and spread of one scalar across repeats.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Spread {
    /// What (`f_c_measured_hz`, `phase_deg friction__optical`, ...).
    pub quantity: String,
    /// Records that had a value.
    pub count: usize,
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (ddof 1; `None` for one value).
    pub std: Option<f64>,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
}

/// Per-record results and their spread.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Repeats {
    /// Records averaged.
    pub count: usize,
    /// Each record's scalars.
    pub records: Vec<RecordScalars>,
    /// Mean and spread of each scalar.
    pub spread: Vec<Spread>,
}

/// What the correlations and spectra say, before packaging.
pub(crate) struct Findings {
    pub(crate) measured: MeasuredPeriod,
    pub(crate) phases: Vec<Phase>,
    pub(crate) harmonics: Vec<HarmonicRow>,
    pub(crate) coherence: Vec<harmonics::CoherenceRow>,
    pub(crate) showing: Vec<Signal>,
    /// The ball-pass frequency the phases are taken at (measured, else
    /// predicted), Hz.
    pub(crate) f_used: f64,
}

fn is_sig(r: &HarmonicRow) -> Option<bool> {
    r.significant
}

fn ratio(r: &HarmonicRow) -> f64 {
    r.predicted
        .as_ref()
        .and_then(|v| v.ratio_db)
        .unwrap_or(f64::NEG_INFINITY)
}

pub(crate) fn evaluate(
    corr: &Correlations,
    hires: &Spectra,
    pred: &Prediction,
    settings: &AnalyzeSettings,
    warnings: &mut Vec<String>,
) -> Findings {
    let signals: Vec<Signal> = hires.auto.iter().map(|(s, _)| *s).collect();
    // Which signals show f_c at the prediction (chooses the period's source).
    let pre = harmonics::harmonics(hires, pred.f_c_hz, None, settings);
    let k1: Vec<&HarmonicRow> = pre.iter().filter(|r| r.k == 1).collect();
    let shows = |s: Signal| pre.iter().any(|r| r.signal == s && is_sig(r) == Some(true));
    let per_signal: Vec<SignalPeriod> = signals
        .iter()
        .filter_map(|&s| correlation::signal_period(corr, s, pred.tau_c_s, settings))
        .collect();
    let has_period = |s: Signal| {
        per_signal
            .iter()
            .any(|p| p.signal == s && p.period_s.is_some())
    };
    let (from, choice) = if shows(Signal::Optical) && has_period(Signal::Optical) {
        (
            Some(Signal::Optical),
            "optical: it shows f_c above its floor (preferred)".to_string(),
        )
    } else if let Some(r) = k1
        .iter()
        .filter(|r| shows(r.signal) && has_period(r.signal))
        .max_by(|a, b| ratio(a).total_cmp(&ratio(b)))
    {
        (
            Some(r.signal),
            format!(
                "{}: the strongest signal at f_c above its floor (optical {})",
                r.signal.words(),
                if signals.contains(&Signal::Optical) {
                    "does not show f_c"
                } else {
                    "absent"
                }
            ),
        )
    } else {
        let fallback = [Signal::Optical, Signal::Friction, Signal::VelocityError]
            .into_iter()
            .find(|&s| has_period(s));
        if let Some(s) = fallback {
            warnings.push(format!(
                "no signal shows f_c above its noise floor at {:.0}% confidence; the measured \
                 period comes from the {} autocorrelation and may be noise",
                settings.confidence * 100.0,
                s.words()
            ));
        }
        (
            fallback,
            "no signal shows f_c above its floor; first signal with autocorrelation peaks".into(),
        )
    };
    let period_s = from.and_then(|s| {
        per_signal
            .iter()
            .find(|p| p.signal == s)
            .and_then(|p| p.period_s)
    });
    if from.is_none() {
        warnings.push(
            "no autocorrelation has peaks near multiples of tau_c: no measured period; phases use \
             the predicted period"
                .into(),
        );
    }
    let f_meas = period_s.map(|t| 1.0 / t);
    let f_spec = from
        .and_then(|s| hires.auto_of(s))
        .and_then(|psd| harmonics::spectral_peak(hires, psd, pred.f_c_hz));
    if let (Some(a), Some(b)) = (f_meas, f_spec) {
        if (a - b).abs() > hires.info.resolution_hz {
            warnings.push(format!(
                "measured f_c {a:.5} Hz (autocorrelation) and {b:.5} Hz (spectral peak) differ by \
                 more than the resolution {:.4} Hz",
                hires.info.resolution_hz
            ));
        }
    }
    let t_used = period_s.unwrap_or(pred.tau_c_s);
    let f_used = 1.0 / t_used;
    let mut phases = Vec::new();
    for (x, y) in pairs_for(&signals).into_iter().filter(|(x, y)| x != y) {
        let Some(ph) = phase::correlation_peak(corr, x, y, t_used) else {
            continue;
        };
        phases.push(ph);
    }
    // The tests at the prediction are those of `pre` (same spectra,
    // prediction and settings): taken, not recomputed.
    let harmonics =
        harmonics::harmonics_reusing(hires, pred.f_c_hz, f_meas.zip(from), settings, &pre);
    // A signal shows f_c when any of its harmonics stands above its floor
    // after the family correction.
    let showing: Vec<Signal> = signals
        .iter()
        .copied()
        .filter(|&s| {
            harmonics
                .iter()
                .any(|r| r.signal == s && is_sig(r) == Some(true))
        })
        .collect();
    let coherence = harmonics::coherence_rows(hires, f_used, settings);
    Findings {
        measured: MeasuredPeriod {
            from_signal: from,
            choice,
            period_s,
            f_c_hz: f_meas,
            f_c_spectral_hz: f_spec,
            per_signal,
        },
        phases,
        harmonics,
        coherence,
        showing,
        f_used,
    }
}

/// Fills in every phase at `f_c` from the records' line spectra.
pub(crate) fn fill_phases(phases: &mut [Phase], lines: &LineSpectra, f_hz: f64, confidence: f64) {
    for ph in phases {
        phase::fill_phase(ph, lines, f_hz, confidence);
    }
}

fn average_into(acc: &mut [f64], v: &[f64]) {
    acc.iter_mut().zip(v).for_each(|(a, b)| *a += b);
}

pub(super) fn average_correlations(all: &[Correlations]) -> Correlations {
    let r = all.len() as f64;
    let mut out = all[0].clone();
    if all.len() == 1 {
        return out;
    }
    for c in &all[1..] {
        for ((_, acc), (_, v)) in out.series.iter_mut().zip(&c.series) {
            average_into(acc, v);
        }
    }
    if all.len() > 1 {
        for (_, acc) in &mut out.series {
            acc.iter_mut().for_each(|a| *a /= r);
        }
    }
    out
}

pub(super) fn average_spectra(all: &[Spectra]) -> Spectra {
    let mut out = all[0].clone();
    let r = all.len();
    if r == 1 {
        return out;
    }
    for s in &all[1..] {
        for ((_, acc), (_, v)) in out.auto.iter_mut().zip(&s.auto) {
            average_into(acc, v);
        }
        for (acc, c) in out.cross.iter_mut().zip(&s.cross) {
            acc.pxy.iter_mut().zip(&c.pxy).for_each(|(a, b)| *a += b);
        }
    }
    let rf = r as f64;
    for (_, acc) in &mut out.auto {
        acc.iter_mut().for_each(|a| *a /= rf);
    }
    for c in &mut out.cross {
        c.pxy.iter_mut().for_each(|a| *a /= rf);
    }
    out.refresh_coherence();
    out.info.n_records = r;
    out.info.dof *= rf;
    out
}

fn spread(quantity: String, values: &[f64]) -> Option<Spread> {
    let m = MeanStd::of(values)?;
    Some(Spread {
        quantity,
        count: values.len(),
        mean: m.mean,
        std: (m.n > 1).then_some(m.std),
        min: values.iter().copied().fold(f64::INFINITY, f64::min),
        max: values.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    })
}

pub(super) fn scalars(source: String, f: &Findings, p: &Prepared) -> RecordScalars {
    RecordScalars {
        source,
        f_c_measured_hz: f.measured.f_c_hz,
        periods_s: f
            .measured
            .per_signal
            .iter()
            .map(|s| (s.signal, s.period_s))
            .collect(),
        phases: f
            .phases
            .iter()
            .filter_map(|ph| Some((ph.pair.clone(), ph.lag_s?, ph.phase_deg?)))
            .collect(),
        f_c_ratio_db: f
            .harmonics
            .iter()
            .filter(|r| r.k == 1)
            .map(|r| (r.signal, r.value().and_then(|v| v.ratio_db)))
            .collect(),
        velocity_error_std_um_s: p.velocity_error.as_ref().map(|v| v.std_um_s),
    }
}

pub(super) fn spreads(records: &[RecordScalars]) -> Vec<Spread> {
    let mut out = Vec::new();
    let collect = |f: &dyn Fn(&RecordScalars) -> Option<f64>| -> Vec<f64> {
        records.iter().filter_map(f).collect()
    };
    out.extend(spread(
        "f_c_measured_hz".into(),
        &collect(&|r| r.f_c_measured_hz),
    ));
    out.extend(spread(
        "velocity_error_std_um_s".into(),
        &collect(&|r| r.velocity_error_std_um_s),
    ));
    for s in Signal::ALL {
        out.extend(spread(
            format!("period_s {}", s.name()),
            &collect(&|r| {
                r.periods_s
                    .iter()
                    .find(|(k, _)| *k == s)
                    .and_then(|(_, v)| *v)
            }),
        ));
        out.extend(spread(
            format!("f_c_ratio_db {}", s.name()),
            &collect(&|r| {
                r.f_c_ratio_db
                    .iter()
                    .find(|(k, _)| *k == s)
                    .and_then(|(_, v)| *v)
            }),
        ));
    }
    let pairs: Vec<String> = records
        .first()
        .map(|r| r.phases.iter().map(|p| p.0.clone()).collect())
        .unwrap_or_default();
    for pair in pairs {
        let lags = collect(&|r| r.phases.iter().find(|p| p.0 == pair).map(|p| p.1));
        out.extend(spread(format!("lag_s {pair}"), &lags));
        // Phases are circular; spread them about the first record's value.
        let degs = collect(&|r| r.phases.iter().find(|p| p.0 == pair).map(|p| p.2));
        if let Some(&d0) = degs.first() {
            let unwrapped: Vec<f64> = degs.iter().map(|d| d0 + phase::wrap_deg(d - d0)).collect();
            out.extend(spread(format!("phase_deg {pair}"), &unwrapped));
        }
    }
    out
}

pub(crate) fn verdict(pred: &Prediction, f: &Findings) -> Verdict {
    let flagged: Vec<usize> = f
        .harmonics
        .iter()
        .filter(|r| r.signal == Signal::Friction && is_sig(r) == Some(true))
        .map(|r| r.k)
        .collect();
    let dev = f
        .measured
        .f_c_hz
        .map(|m| 100.0 * (m - pred.f_c_hz) / pred.f_c_hz);
    let mut text = match (f.measured.f_c_hz, f.showing.is_empty()) {
        (Some(m), false) => format!(
            "ball-pass frequency found: measured f_c = {m:.4} Hz vs predicted {:.4} Hz ({:+.2} %), \
             shown by {}",
            pred.f_c_hz,
            dev.unwrap_or(0.0),
            f.showing
                .iter()
                .map(|s| s.words())
                .collect::<Vec<_>>()
                .join(", ")
        ),
        (Some(m), true) => format!(
            "no signal shows f_c above its noise floor; the autocorrelation period gives {m:.4} Hz \
             (predicted {:.4} Hz) but is not confirmed by the spectra",
            pred.f_c_hz
        ),
        (None, _) => format!(
            "ball-pass frequency not found (predicted {:.4} Hz): no autocorrelation peaks near \
             multiples of tau_c",
            pred.f_c_hz
        ),
    };
    if !flagged.is_empty() {
        let ks: Vec<String> = flagged.iter().map(|k| k.to_string()).collect();
        text.push_str(&format!(
            "; friction stands above its floor at k = {} (a periodic friction ripple at the \
             ball-pass frequency, which every bearing has; sticking is told by sporadic spikes, \
             `ballpass diagnose`)",
            ks.join(", ")
        ));
    } else if f.harmonics.iter().any(|r| r.signal == Signal::Friction) {
        text.push_str("; friction shows no ball-pass harmonic above its floor");
    }
    Verdict {
        f_c_predicted_hz: pred.f_c_hz,
        f_c_measured_hz: f.measured.f_c_hz,
        f_c_deviation_percent: dev,
        signals_showing_f_c: f.showing.clone(),
        friction_harmonics_flagged: flagged,
        text,
    }
}
