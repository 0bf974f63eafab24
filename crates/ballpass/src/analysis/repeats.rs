//! Step 6 and the orchestration of [`analyze`](super::analyze): one record
//! or several repeats at the same velocity.
//!
//! - All records must share the sampling rate (error otherwise); after the
//!   trim they are truncated to the shortest (a warning says so).
//! - Signals missing from any record are left out for all (warning).
//! - Each record is prepared, correlated and its spectra estimated; the
//!   correlations and the auto and cross spectra are averaged bin by bin
//!   (arithmetic mean, thesis §7); coherence is recomputed from the averaged
//!   spectra (= the coherence over all records' segments), and the
//!   chi-square degrees of freedom multiply by the number of records.
//! - The period, phases and harmonics are taken from the averages; each
//!   record's own scalars are kept with their mean and sample standard
//!   deviation (ddof 1).

use std::borrow::Cow;

use ballpass_dsp::{CorrelateSettings, Correlator, ZeroPhaseFilter};
use rayon::prelude::*;

use super::correlation::{self, pairs_for, Correlations};
use super::phase::LineSpectra;
use super::preprocess::{self, Prepared, VelocityErrorStats};
use super::spectra::{self, Spectra};
use super::{pair_name, Absent, Analysis, AnalyzeSettings, InputInfo, SeriesInfo, Signal, SCHEMA};
use crate::bearing::{check_velocity, Prediction};
use crate::error::{Error, Result};
use crate::recording::{Channel, Recording};
mod evaluate;

use evaluate::{
    average_correlations, average_spectra, evaluate, fill_phases, scalars, spreads, verdict,
};
pub(crate) use evaluate::{
    evaluate as evaluate_findings, fill_phases as fill_line_phases, verdict as verdict_of,
};
pub use evaluate::{RecordScalars, Repeats, Spread};

/// The stage, identified from every record's friction → velocity-error
/// response pooled (one segment length for all: the shortest record's);
/// `None` without a record holding both channels.
fn identify_stage(
    recs: &[Recording],
    restored: &[super::Restored<'_>],
    fs: f64,
    pred: &Prediction,
) -> Result<
    Option<(
        crate::model::identify::StageIdentification,
        crate::model::identify::StageSpectra,
    )>,
> {
    let n_min = recs.iter().map(Recording::len).min().unwrap_or(0);
    let nperseg = crate::model::identify::nperseg_for(n_min, fs);
    let mut pooled = crate::model::identify::StageSpectra::default();
    for (r, fr) in recs.iter().zip(restored) {
        if let (Some((f, dc)), Some(p)) = (fr, r.channel(Channel::Position)) {
            let sp = crate::model::identify::StageSpectra::of_signals(
                f,
                p,
                fs,
                pred.velocity_mm_s,
                nperseg,
            )?
            .restored_with(dc);
            pooled.add(&sp);
        }
    }
    Ok((pooled.records > 0).then(|| (crate::model::identify::identify(&pooled), pooled)))
}

/// One record's preparation, correlations, and full, high-resolution and
/// unfiltered spectra, and the signals of [`RecordJob::keep`] as
/// low-passed (before the detrend).
type PerRecord = (
    Prepared,
    Correlations,
    Spectra,
    Spectra,
    Spectra,
    preprocess::Kept,
);

/// What every record's preparation, correlations and spectra share.
struct RecordJob<'s> {
    pred: &'s Prediction,
    settings: &'s AnalyzeSettings,
    filter: Option<&'s ZeroPhaseFilter>,
    plan: &'s spectra::HiresPlan,
    /// Samples trimmed from the start and samples kept.
    trim_n: (usize, usize),
    signals: &'s [Signal],
    max_lag: usize,
    /// Signals whose low-passed samples are kept (for the position-domain
    /// spectra, which then do not filter them again).
    keep: &'s [Signal],
}

impl RecordJob<'_> {
    /// [`PerRecord`] of every record, all in parallel (rayon), in record
    /// order; `frictions[i]` replaces record `i`'s recorded friction (its
    /// load-cell discharge undone). An owned one is cut and filtered in
    /// its own buffer, and freed once filtered.
    fn run<'a>(
        &self,
        recs: &'a [Recording],
        frictions: Vec<Option<Cow<'a, [f64]>>>,
    ) -> Result<Vec<PerRecord>> {
        let (settings, (trim, n)) = (self.settings, self.trim_n);
        let one = |(r, fr): (&'a Recording, Option<Cow<'a, [f64]>>)| -> Result<PerRecord> {
            let v = self.pred.velocity_mm_s;
            let raw = preprocess::raw_signals(r, v, (trim, n), fr, self.signals)?;
            // The unfiltered spectra first; then each step-1 signal is
            // dropped as soon as it is filtered (on a long record the
            // velocity error, and an owned friction, are record-length
            // buffers).
            let u = spectra::full_of(&raw, r.fs_hz(), n, settings)?;
            let (p, kept) = preprocess::prepare_raw_keeping(
                r,
                raw,
                settings,
                self.filter,
                (trim, n),
                self.keep,
            )?;
            let (c, (f, h)) = rayon::join(
                || {
                    with_correlator(
                        CorrelateSettings {
                            normalization: settings.corr_norm.to_dsp(),
                        },
                        n,
                        |c| correlation::compute(&p, c, settings, self.max_lag),
                    )
                },
                || {
                    rayon::join(
                        || spectra::full(&p, settings),
                        || spectra::hires(&p, settings, self.plan),
                    )
                },
            );
            Ok((p, c?, f?, h?, u, kept))
        };
        recs.par_iter()
            .zip(frictions.into_par_iter())
            .map(one)
            .collect::<Vec<_>>()
            .into_iter()
            .collect()
    }
}

/// The load-cell correction of each record (`None` without friction):
/// `given` by a caller that needs the restored friction itself, else
/// made here.
fn restore_all<'a>(
    given: Option<Vec<super::Restored<'a>>>,
    recs: &'a [Recording],
    fs: f64,
    pred: &Prediction,
    settings: &AnalyzeSettings,
) -> Result<Vec<super::Restored<'a>>> {
    if let Some(r) = given {
        return Ok(r);
    }
    recs.par_iter()
        .map(|r| {
            r.channel(Channel::Friction)
                .map(|f| {
                    super::load_cell::restore_friction(f, fs, pred.tau_c_s, settings.load_cell)
                })
                .transpose()
        })
        .collect()
}

/// [`analyze`](super::analyze).
pub(crate) fn run(
    recs: &[Recording],
    pred: &Prediction,
    settings: &AnalyzeSettings,
    with_passages: bool,
    restored: Option<Vec<super::Restored<'_>>>,
) -> Result<Analysis> {
    run_staged_above(
        recs,
        pred,
        settings,
        with_passages,
        restored,
        STAGED_ABOVE_SAMPLES,
    )
}

/// [`run`], with records of more than `staged_above` samples (after the
/// trim) analysed in stages one after the other, so that few record-length
/// buffers are alive at once; shorter records run their independent
/// stages side by side. The results are the same either way.
pub(crate) fn run_staged_above(
    recs: &[Recording],
    pred: &Prediction,
    settings: &AnalyzeSettings,
    with_passages: bool,
    restored: Option<Vec<super::Restored<'_>>>,
    staged_above: usize,
) -> Result<Analysis> {
    settings.validate()?;
    check_velocity(pred.velocity_mm_s)?;
    let Some(first) = recs.first() else {
        return Err(Error::InvalidRecording {
            source_name: "analyze".into(),
            reason: "no recordings given".into(),
        });
    };
    let fs = first.fs_hz();
    for r in &recs[1..] {
        if (r.fs_hz() - fs).abs() > 1e-9 * fs {
            return Err(Error::InvalidRecording {
                source_name: r.source_name(),
                reason: format!(
                    "sampling rate {} Hz differs from {} Hz of {}; repeats must share it",
                    r.fs_hz(),
                    fs,
                    first.source_name()
                ),
            });
        }
    }
    let mut warnings = Vec::new();
    let mut notes = Vec::new();
    let trim = (settings.trim_start_s * fs).round() as usize;
    let mut n = usize::MAX;
    for r in recs {
        if r.len() <= trim {
            return Err(Error::InvalidRecording {
                source_name: r.source_name(),
                reason: format!(
                    "{} samples; trimming {} s ({trim} samples) leaves none",
                    r.len(),
                    settings.trim_start_s
                ),
            });
        }
        n = n.min(r.len() - trim);
    }
    if recs.iter().any(|r| r.len() - trim != n) {
        warnings.push(format!(
            "records differ in length; each is truncated to the shortest, {n} samples ({:.3} s) \
             after the trim",
            n as f64 / fs
        ));
    }
    let (duration, periods, max_lag) =
        span_checks(&first.source_name(), n, fs, pred, settings, &mut warnings)?;
    // Signals: those every record has.
    let mut signals = Vec::new();
    let mut absent = Vec::new();
    for s in Signal::ALL {
        let ch = match s {
            Signal::Friction => Channel::Friction,
            Signal::VelocityError => Channel::Position,
            Signal::Optical => Channel::Optical,
        };
        let missing: Vec<String> = recs
            .iter()
            .filter(|r| r.channel(ch).is_none())
            .map(|r| r.source_name())
            .collect();
        if missing.is_empty() {
            signals.push(s);
        } else {
            let reason = format!(
                "channel {} missing in {}",
                ch.column_name(),
                missing.join(", ")
            );
            warnings.push(format!("{} not analysed: {reason}", s.words()));
            absent.push((s, reason));
        }
    }
    if signals.is_empty() {
        return Err(Error::MissingChannel {
            channel: "friction_N",
            source_name: first.source_name(),
            needed_for: "analyze (no friction, position or optical channel)",
        });
    }
    // The filter and the high-resolution plan first (cheap; the plan's
    // warnings are reported after the load cell's, as they always were).
    let filter = preprocess::lowpass_filter(settings, fs);
    let mut plan_warnings = Vec::new();
    let plan = spectra::plan_hires(settings, fs, n, pred.f_c_hz, &mut plan_warnings);
    // Three independent branches run in parallel (rayon): the passages of
    // every record (they read the raw optical channel only); the load-cell
    // correction of each record and then the stage identification from it;
    // and, on the corrected friction, each record's correlations and
    // spectra. Their results are taken in the order of a sequential pass,
    // so the numbers, the warnings and the first error reported are that
    // pass's.
    // A long record is analysed in stages instead, one after the other,
    // each holding few record-length buffers beside the record: the
    // passages; the load-cell correction, the stage and the
    // position-domain spectra; then the correlations and spectra, which
    // take the corrected friction over (freed once filtered). Same results.
    let staged = n > staged_above;
    let detect = || {
        if with_passages {
            super::passage_summaries(recs, pred)
        } else {
            Vec::new()
        }
    };
    let wants_position = with_passages && signals.contains(&Signal::VelocityError);
    // `lowpassed[i]`: record i's friction and optical as the analysis
    // low-passed them (empty: filtered here).
    let position_of = |restored: &[super::Restored<'_>],
                       filter: Option<&ZeroPhaseFilter>,
                       lowpassed: &[Option<&super::position::Lowpassed>]| {
        let parts: Vec<super::position::RecordPart<'_>> = recs
            .iter()
            .zip(restored)
            .map(|(r, fr)| (r, fr.as_ref().map(|(f, _)| f.as_ref()), trim..trim + n))
            .collect();
        super::position::compute_lowpassed(&parts, lowpassed, settings, filter, pred.d_avg_mm)
    };
    // The non-staged run hands the position-domain spectra the friction and
    // optical its own preparation low-passed (the same filter on the same
    // samples: the same values), instead of filtering them twice.
    let keep: &[Signal] = if wants_position && !staged {
        &[Signal::Friction, Signal::Optical]
    } else {
        &[]
    };
    let job = match (&filter, &plan) {
        (Ok(filter), Ok(plan)) => Some(RecordJob {
            pred,
            settings,
            filter: filter.as_ref(),
            plan,
            trim_n: (trim, n),
            signals: &signals,
            max_lag,
            keep,
        }),
        _ => None,
    };
    let (main, passages, early_position) = if staged {
        let passages = detect();
        let mut early_position = None;
        let main = restore_all(restored, recs, fs, pred, settings).map(|mut restored| {
            let stage = identify_stage(recs, &restored, fs, pred);
            if let (true, Ok(filter)) = (wants_position, &filter) {
                early_position = Some(position_of(&restored, filter.as_ref(), &[]));
            }
            let frictions: Vec<_> = restored
                .iter_mut()
                .map(|fr| {
                    fr.as_mut()
                        .map(|(f, _)| std::mem::replace(f, Cow::Borrowed(&[])))
                })
                .collect();
            let per_record = job.as_ref().map(|j| j.run(recs, frictions));
            (restored, stage, per_record)
        });
        (main, passages, early_position)
    } else {
        // The passages (one long sequential job per record) start at once
        // on one thread; the other runs the load-cell correction and then
        // each record's preparation, correlations and spectra, leaving the
        // stage identification (independent of them) to whichever thread
        // is free first. The position-domain spectra read the per-record
        // step's low-passed friction and optical, so they run after it,
        // beside the period and phases and the synchronous average (below).
        let (main, passages) = rayon::join(
            || {
                let restored = restore_all(restored, recs, fs, pred, settings)?;
                let (per_record, stage) = rayon::join(
                    || {
                        let frictions = restored
                            .iter()
                            .map(|fr| fr.as_ref().map(|(f, _)| Cow::Borrowed(f.as_ref())))
                            .collect();
                        job.as_ref().map(|j| j.run(recs, frictions))
                    },
                    || identify_stage(recs, &restored, fs, pred),
                );
                Ok::<_, Error>((restored, stage, per_record))
            },
            detect,
        );
        (main, passages, None)
    };
    let (restored, stage, per_record) = main?;
    let load_cell: Vec<super::load_cell::DcRestoration> =
        restored.iter().flatten().map(|(_, d)| d.clone()).collect();
    if let Some(w) = load_cell.iter().find_map(|d| d.warning(pred.f_c_hz)) {
        warnings.push(w);
    }
    for (r, d) in recs.iter().zip(&restored) {
        if let Some((_, d)) = d {
            notes.push(format!("{}: {}", r.source_name(), d.note));
        }
    }
    let (stage, stage_spectra) = match stage? {
        Some((id, sp)) => (Some(id), Some(sp)),
        None => (None, None),
    };
    let filter = filter?;
    let plan = plan?;
    warnings.extend(plan_warnings);
    let per_record = per_record.expect("filter and plan are Ok");
    let mut prepared = Vec::with_capacity(recs.len());
    let mut corrs = Vec::with_capacity(recs.len());
    let mut fulls = Vec::with_capacity(recs.len());
    let mut hires = Vec::with_capacity(recs.len());
    let mut unfiltered = Vec::with_capacity(recs.len());
    let mut kept = Vec::with_capacity(recs.len());
    for (p, c, f, h, u, k) in per_record? {
        prepared.push(p);
        corrs.push(c);
        fulls.push(f);
        hires.push(h);
        unfiltered.push(u);
        kept.push(k);
    }
    let mut unfiltered = average_spectra(&unfiltered);
    // One record: its correlations are the result (no copy).
    let corr = if corrs.len() == 1 {
        corrs.pop().expect("one record")
    } else {
        average_correlations(&corrs)
    };
    let mut full = average_spectra(&fulls);
    let mut hr = average_spectra(&hires);
    for s in [&mut unfiltered, &mut full, &mut hr] {
        super::confidence::finish(s, settings);
    }
    if hr.info.n_segments < 2 && recs.len() < 2 {
        warnings.push(format!(
            "high-resolution spectrum has {} segment: coherence is 1 by construction and the \
             harmonic tests are weak",
            hr.info.n_segments
        ));
    }
    let (passages, passage_times): (Vec<_>, Vec<_>) = passages.into_iter().unzip();
    // Three independent parts, run in parallel: the position-domain
    // spectra (the longest; a staged run made them before its
    // correlations), the synchronous average, and the period, phases and
    // repeats. Their warnings and notes are added below in the order of a
    // sequential pass.
    let (position, ((findings, repeats), sync)) = rayon::join(
        || {
            // For `analyze` itself: the campaigns (which detect the
            // passages themselves, `with_passages` false) do not use them
            // and skip their cost.
            wants_position.then(|| {
                early_position.unwrap_or_else(|| {
                    let lowpassed: Vec<Option<&super::position::Lowpassed>> =
                        kept.iter().map(|k| Some(k.as_slice())).collect();
                    position_of(&restored, filter.as_ref(), &lowpassed)
                })
            })
        },
        || {
            rayon::join(
                || {
                    let mut findings = evaluate(&corr, &hr, pred, settings, &mut warnings);
                    let lines: Vec<LineSpectra> = prepared
                        .par_iter()
                        .map(|p| LineSpectra::of(p, findings.f_used))
                        .collect();
                    fill_phases(
                        &mut findings.phases,
                        &LineSpectra::merge(&lines),
                        findings.f_used,
                        settings.confidence,
                    );
                    let repeats = (recs.len() > 1).then(|| {
                        let mut records = Vec::new();
                        for ((r, p), (c, h)) in
                            recs.iter().zip(&prepared).zip(corrs.iter().zip(&hires))
                        {
                            let mut w = Vec::new();
                            let mut f = evaluate(c, h, pred, settings, &mut w);
                            let own = LineSpectra::of(p, f.f_used);
                            fill_phases(&mut f.phases, &own, f.f_used, settings.confidence);
                            records.push(scalars(r.source_name(), &f, p));
                        }
                        let spread = spreads(&records);
                        Repeats {
                            count: recs.len(),
                            records,
                            spread,
                        }
                    });
                    (findings, repeats)
                },
                || {
                    with_passages.then(|| {
                        super::sync::records::for_records(
                            recs,
                            &prepared,
                            &passage_times,
                            pred,
                            trim,
                            &super::sync::SyncSettings::default(),
                        )
                    })
                },
            )
        },
    );
    drop(kept);
    let velocity_error = VelocityErrorStats::mean_of(
        &prepared
            .iter()
            .filter_map(|p| p.velocity_error.as_ref())
            .collect::<Vec<_>>(),
    );
    common_notes(&mut notes, &hr, &plan, &corr, settings, pred, n, fs);
    let correlation_window = super::CorrelationWindow::of(&corr, settings.max_lag, pred.tau_c_s);
    if recs.len() > 1 {
        notes.push(
            "repeats: correlations and spectra are arithmetic means over records; coherence from \
             the averaged spectra; spread is the sample std (ddof 1) of per-record scalars"
                .into(),
        );
    }
    let sync = sync.and_then(|s| {
        s.map_err(|e| warnings.push(format!("no synchronous average: {e}")))
            .ok()
    });
    drop(prepared);
    let verdict = verdict(pred, &findings);
    let stage = super::stage_for_lines(stage, stage_spectra.as_ref(), &verdict);
    let position = position.and_then(|p| match p {
        Ok(p) => {
            notes.push(super::position::note(&p));
            Some(p)
        }
        Err(e) => {
            warnings.push(super::position::failure(&e));
            None
        }
    });
    Ok(Analysis {
        schema: SCHEMA,
        version: crate::VERSION,
        inputs: recs
            .iter()
            .map(|r| InputInfo {
                source: r.source_name(),
                test_id: r.meta.test_id.clone(),
                fs_hz: r.fs_hz(),
                samples: r.len(),
                duration_s: r.duration_s(),
                channels: r
                    .channels()
                    .iter()
                    .map(|c| c.column_name().to_string())
                    .collect(),
            })
            .collect(),
        settings: settings.clone(),
        method_notes: notes,
        samples_analysed: n,
        fs_hz: fs,
        duration_analysed_s: duration,
        periods_in_record: periods,
        prediction: pred.clone(),
        series: series_info(&signals, &absent),
        spectrum_full: full.info.clone(),
        spectrum_hires: hr.info.clone(),
        spectrum_unfiltered: unfiltered.info.clone(),
        correlation_window,
        measured_period: findings.measured,
        phases: findings.phases,
        harmonics: findings.harmonics,
        coherence: findings.coherence,
        velocity_error,
        load_cell,
        stage,
        stage_spectra,
        repeats,
        verdict,
        passages,
        sync,
        warnings,
        correlations: corr,
        spectra: full,
        spectra_hires: hr,
        spectra_unfiltered: unfiltered,
        position,
        stream: None,
    })
}

/// The method notes every analysis carries (high-resolution plan, the
/// harmonic test, the period, the lag window, the correlation convention),
/// in `analysis.json`'s order.
#[allow(clippy::too_many_arguments)]
pub(crate) fn common_notes(
    notes: &mut Vec<String>,
    hr: &Spectra,
    plan: &spectra::HiresPlan,
    corr: &Correlations,
    settings: &AnalyzeSettings,
    pred: &Prediction,
    n: usize,
    fs: f64,
) {
    notes.push(format!(
        "high-resolution spectrum: {} with q = {}, fs = {} Hz, {}-sample segments, {} overlap, \
         resolution {:.5} Hz",
        hr.info.method, plan.q, plan.fs_hz, plan.nperseg, plan.noverlap, hr.info.resolution_hz
    ));
    notes.push(
        "harmonic test: floor = polynomial fit of ln PSD against ln f around k·f_c (harmonic bins \
         excluded), mean-corrected for chi2; p-value of the largest tested bin with the floor's own \
         uncertainty; nu the Welch equivalent dof (Percival & Walden 292b) times the records; a \
         signal shows f_c when a harmonic is significant after Holm's correction over k = 1..K"
            .into(),
    );
    notes.push(
        "measured period: autocorrelation maxima within ±period_window·T of k·T (T re-fitted after \
         each peak, starting at tau_c predicted), k·T up to half the record, least squares through \
         the origin"
            .into(),
    );
    let correlation_window = super::CorrelationWindow::of(corr, settings.max_lag, pred.tau_c_s);
    if !correlation_window.full_range {
        notes.push(format!(
            "correlations within ±{:.3} s ({:.1} predicted ball periods; the record spans ±{:.3} \
             s): the values there are the whole-record correlation's, computed block by block; the \
             period uses the peaks within the window",
            correlation_window.max_lag_s,
            correlation_window.max_lag_periods,
            (n - 1) as f64 / fs
        ));
    }
    notes.push(
        "correlation convention Eq. 7.1: R_xy[m] = sum x[n+m] y[n]; a peak at negative lag means y \
         lags x. Phases at f_c: cross spectrum conj(X) Y at the measured f_c (segments of three \
         periods, DFT at f_c itself), 95 % interval from the coherence; lag = phase / (360 f_c). \
         The correlation-peak lag weighs every shared frequency and is reported beside it"
            .into(),
    );
}

/// The checks of the analysed span of `n` samples at `fs`: at least two
/// predicted periods, and a lag window holding two; the duration, the
/// periods and the lag window `L` in samples.
pub(crate) fn span_checks(
    name: &str,
    n: usize,
    fs: f64,
    pred: &Prediction,
    settings: &AnalyzeSettings,
    warnings: &mut Vec<String>,
) -> Result<(f64, f64, usize)> {
    let duration = n as f64 / fs;
    let periods = duration / pred.tau_c_s;
    if periods < 2.0 {
        return Err(Error::InvalidRecording {
            source_name: name.to_string(),
            reason: format!(
                "{duration:.3} s analysed spans {periods:.2} ball-pass periods at {} mm/s \
                 (tau_c = {:.4} s); at least 2 are needed",
                pred.velocity_mm_s, pred.tau_c_s
            ),
        });
    }
    let max_lag = settings.max_lag.samples(n, fs, pred.tau_c_s);
    if max_lag + 1 < n && (max_lag as f64 / fs) < 2.0 * pred.tau_c_s {
        return Err(Error::setting(
            "max-lag",
            format!(
                "a lag window of {:.3} s holds fewer than 2 ball-pass periods (tau_c = {:.4} s); \
                 the period and the phases need at least 2",
                max_lag as f64 / fs,
                pred.tau_c_s
            ),
        ));
    }
    if periods < 4.0 {
        warnings.push(format!(
            "only {periods:.1} ball-pass periods in the record: few autocorrelation peaks and a \
             coarse spectrum"
        ));
    }
    Ok((duration, periods, max_lag))
}

/// Longest record whose independent stages run side by side (2^20
/// samples, 17 minutes at 1 kHz); a longer one is analysed in stages, one
/// after the other ([`run_staged_above`]).
pub(crate) const STAGED_ABOVE_SAMPLES: usize = 1 << 20;

thread_local! {
    /// The correlator a worker thread used last, kept for its next record:
    /// its FFT plan and ~1.5 MB of buffers, which a new one would allocate
    /// and zero again (a campaign analyses hundreds of records per thread).
    static CORRELATOR: std::cell::Cell<Option<Correlator>> = const { std::cell::Cell::new(None) };
}

/// Runs `f` with this thread's kept correlator when its settings are
/// `settings`, else with a new one, and keeps it afterwards when the
/// records are at most [`KEEP_MAX_SAMPLES`] long (`n` samples now). The
/// correlator is taken out while `f` runs, so a nested call (none today:
/// the correlations run no parallel work of their own) would just make its
/// own.
fn with_correlator<R>(
    settings: CorrelateSettings,
    n: usize,
    f: impl FnOnce(&mut Correlator) -> R,
) -> R {
    let mut c = CORRELATOR
        .take()
        .filter(|c| c.settings() == &settings)
        .unwrap_or_else(|| Correlator::new(settings));
    let out = f(&mut c);
    if n <= KEEP_MAX_SAMPLES {
        CORRELATOR.set(Some(c));
    }
    out
}

/// Longest record whose correlator a thread keeps: its FFT has at most
/// 2^19 points, whose seven buffers of 2^18 complex values (three signals'
/// spectra, two work spectra, the inverse's input, scratch) hold ~28 MB; a
/// longer record's would stay with the thread for the rest of the run.
const KEEP_MAX_SAMPLES: usize = 1 << 18;

/// The series present (each signal and pair) and absent (with the reason;
/// a pair is absent when either of its signals is).
pub(crate) fn series_info(signals: &[Signal], absent: &[(Signal, String)]) -> SeriesInfo {
    let present = pairs_for(signals)
        .into_iter()
        .map(|(x, y)| pair_name(x, y))
        .collect();
    let mut absent_series: Vec<Absent> = Vec::new();
    for (s, reason) in absent {
        absent_series.push(Absent {
            name: s.name().into(),
            reason: reason.clone(),
        });
        for (x, y) in super::CROSS_PAIRS {
            if x == *s || y == *s {
                let name = pair_name(x, y);
                if !absent_series.iter().any(|a| a.name == name) {
                    absent_series.push(Absent {
                        name,
                        reason: reason.clone(),
                    });
                }
            }
        }
    }
    SeriesInfo {
        signals: signals.to_vec(),
        present,
        absent: absent_series,
    }
}

#[cfg(test)]
mod staged_tests;
