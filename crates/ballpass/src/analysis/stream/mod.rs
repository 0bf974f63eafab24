//! The analysis of one record read block by block ([`analyze_stream`]), in
//! memory that does not grow with the record's length.
//!
//! [`analyze`](super::analyze) holds the record and, while the
//! correlations and spectra run, its low-passed signals: about 60 bytes
//! per sample of a three-channel record, 5 GB for 24 hours at 1 kHz. Here
//! the record is read from its [`RecordSource`] four times, each time
//! block by block, and every step keeps only running sums or a bounded
//! window of samples:
//!
//! 1. **Load cell** (records with friction): the friction's mean and,
//!    for an estimated τ, its block means (at most 20 000, as
//!    [`load_cell::fit_discharge`] makes them), or for a given τ the sums
//!    of its offset fit; the discharge is then fitted as in memory.
//! 2. **Low-pass and trend**: restoration, velocity error, trim and
//!    low-pass (`chain`); the Welch spectra of the unfiltered signals;
//!    the sums of each low-passed signal's least-squares line; the
//!    velocity error's sums; the lines of the untrimmed restored friction
//!    and velocity error for the stage identification (`stage`).
//! 3. **Correlations and spectra**: the same chain, each low-passed signal
//!    detrended with its line, into the lag-window correlations
//!    ([`ballpass_dsp::WindowCorrelation`]), the full-range Welch spectra
//!    ([`ballpass_dsp::WelchStream`]), and the decimation (a
//!    [`ballpass_dsp::ZeroPhaseStream`] of the anti-alias filter, every
//!    `q`-th sample kept) into the high-resolution Welch spectra; the
//!    stage identification's spectra. Then the period, harmonics and
//!    coherence, and the stage fit, exactly as in memory.
//! 4. **Phases**: the same chain into the segment DFTs at the measured
//!    `f_c` (one pair of numbers per segment of three periods).
//!
//! The report's signals figures are gathered on the way
//! ([`SignalGatherer`]): the envelopes in pass 2, the detail (a few ball
//! periods at the measured period) in pass 4; the same samples the
//! in-memory report takes from the record.
//!
//! Memory: the blocks of the source, about `2 B + 4 L` samples per signal
//! for the correlations (`L` the lag window), one Welch segment per
//! signal and spectrum, `2^16` samples plus the filter overlap per signal
//! and filter, 20 000 block means, and 16 bytes per signal and segment of
//! three ball periods for the phases: for a 24-hour record at 1 kHz and
//! 9 mm/s, about 2 MB of per-segment summaries beside a fixed ~100 MB.
//! The stage identification adds one Welch segment (16 s) per signal, the
//! signals figures 2000 stretches of up to 4 samples per channel and 5
//! ball periods of samples (measured peak: 170 MB at 2 hours, 166 MB at
//! 24 hours).
//!
//! Equal to the in-memory analysis: restoration, velocity error, Welch
//! spectra and segment DFTs to the bit given the same input; the
//! low-pass to 1e-12 of the whole-record filter; the line to compensated
//! summation; the correlations to rounding. Tested on records forced
//! through small blocks (`tests`): every table within 1e-12 of its
//! series' peak (measured: 1.1e-14), the period, harmonic verdicts and
//! phases the same; the stage's spectra within 1e-12, its estimates
//! within 1e-9 relative (measured 1.7e-13), its intervals within 1e-6
//! (measured 1.3e-8: central differences of step 1e-6); the signals
//! figures' samples to the bit.
//!
//! The position-domain spectra (`position`) ride along: the exact
//! median speed over the first three passes, the resampling and Welch
//! segments in the fourth (a fifth pass, of its own, for a record without
//! friction, which has no load-cell pass); the same numbers as in memory
//! (their tests). The ball passages are detected in pass 2 on overlapping
//! windows of the optical signal ([`passages`]): a different method from
//! the whole-record detection, the same on a record of one window.
//!
//! The synchronous average keyed to those passages is summed in pass 3
//! (`sync`); without passages it is keyed on the encoder at the
//! predicted ball pitch, as in memory, the keys found in pass 2
//! (`EncoderKeys`). Not computed on a streamed record: only one
//! record (no repeats), the decimating high-resolution spectrum (not the
//! polyphase zoom), and a lag window shorter than the record (not
//! `--max-lag full`).

mod chain;
pub mod file;
pub mod passages;
mod position;
mod stage;
mod support;
mod sync;

use ballpass_dsp::{WelchStream, WindowCorrelation, ZeroPhaseStream};
use serde::Serialize;

use self::chain::{Output, TrendSums};
use self::support::{channel_of, load_cell_pass, Moments, PassKit};
use super::correlation::{pairs_for, Correlations};
use super::load_cell;
use super::phase::LineStream;
use super::preprocess::{self, VelocityErrorStats};
use super::repeats::series_info;
use super::repeats::{evaluate_findings, fill_line_phases, verdict_of};
use super::spectra::{self, Spectra};
use super::sync::{records::encoder_note, EncoderKeys, SyncKey};
use super::{
    Analysis, AnalyzeSettings, HiresMethod, InputInfo, MaxLag, PassageSummary, Signal, SCHEMA,
};
use crate::bearing::{check_velocity, Prediction};
use crate::error::{Error, Result};
use crate::recording::stream::{Block, RecordSource};
use crate::report::envelope::{SignalGatherer, SignalSamples};

/// How a streamed analysis ran (`analysis.json`'s `stream`; absent when
/// the record was analysed in memory).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StreamInfo {
    /// Times the record was read.
    pub passes: usize,
    /// Samples the low-pass's backward pass reruns past each block
    /// (twice its slowest pole's decay to 1e-16).
    pub lowpass_overlap_samples: Option<usize>,
    /// The same for the high-resolution decimation's anti-alias filter.
    pub decimation_overlap_samples: Option<usize>,
    /// What a streamed record does not give, and why.
    pub not_computed: Vec<String>,
    /// The samples of the report's signals figures (its envelopes and
    /// detail), gathered while streaming; not written to `analysis.json`.
    #[serde(skip)]
    pub signals: Option<SignalSamples>,
}

/// Analyses one record read block by block (module docs).
///
/// `progress` is told which pass runs and how far it is.
///
/// # Errors
/// As [`analyze`](super::analyze); [`Error::InvalidSetting`] for a setting
/// a streamed record cannot take (`--zoom`, `--max-lag full`); the
/// source's read errors.
pub fn analyze_stream(
    src: &mut dyn RecordSource,
    pred: &Prediction,
    settings: &AnalyzeSettings,
    progress: &mut dyn FnMut(&str),
) -> Result<Analysis> {
    analyze_stream_blocks(src, pred, settings, progress, FILTER_BLOCK)
}

/// Samples the zero-phase filters settle at a time.
const FILTER_BLOCK: usize = 1 << 16;

/// [`analyze_stream`] with the filters settling `filter_block` samples at
/// a time (the tests use small blocks, to make many block joins).
pub(crate) fn analyze_stream_blocks(
    src: &mut dyn RecordSource,
    pred: &Prediction,
    settings: &AnalyzeSettings,
    progress: &mut dyn FnMut(&str),
    filter_block: usize,
) -> Result<Analysis> {
    settings.validate()?;
    check_velocity(pred.velocity_mm_s)?;
    let name = src.source_name();
    if let HiresMethod::PolyphaseZoom { .. } = settings.hires {
        return Err(Error::setting(
            "zoom",
            format!("{name} is streamed: its high-resolution spectrum is by decimation only (read it whole for --zoom)"),
        ));
    }
    if settings.max_lag == MaxLag::Full {
        return Err(Error::setting(
            "max-lag",
            format!("{name} is streamed: every lag of a long record does not fit in bounded memory; give a window in seconds (or read it whole)"),
        ));
    }
    let fs = src.fs_hz();
    let len = src.len();
    let trim = (settings.trim_start_s * fs).round() as usize;
    if len <= trim {
        return Err(Error::InvalidRecording {
            source_name: name,
            reason: format!(
                "{len} samples; trimming {} s ({trim} samples) leaves none",
                settings.trim_start_s
            ),
        });
    }
    let n = len - trim;
    let mut warnings = Vec::new();
    let mut notes = Vec::new();
    let (duration, periods, max_lag) =
        super::repeats::span_checks(&name, n, fs, pred, settings, &mut warnings)?;
    let channels = src.channels();
    let mut signals = Vec::new();
    let mut absent = Vec::new();
    for s in Signal::ALL {
        let ch = channel_of(s);
        if channels.contains(&ch) {
            signals.push(s);
        } else {
            let reason = format!("channel {} missing in {name}", ch.column_name());
            warnings.push(format!("{} not analysed: {reason}", s.words()));
            absent.push((s, reason));
        }
    }
    if signals.is_empty() {
        return Err(Error::MissingChannel {
            channel: "friction_N",
            source_name: name,
            needed_for: "analyze (no friction, position or optical channel)",
        });
    }
    let filter = preprocess::lowpass_filter(settings, fs)?;
    let mut plan_warnings = Vec::new();
    let plan = spectra::plan_hires(settings, fs, n, pred.f_c_hz, &mut plan_warnings)?;
    let has_friction = signals.contains(&Signal::Friction);
    // The position-domain spectra: three passes select the median speed,
    // the next resamples (`position`); without the load-cell pass, one
    // pass more.
    let stage_filters = position::StageFilters::new()?;
    let mut pos = signals.contains(&Signal::VelocityError).then(|| {
        position::PositionPass::new(
            &name,
            fs,
            (trim, n),
            &signals,
            pred.d_avg_mm,
            filter.as_ref(),
            filter_block,
            &stage_filters,
            settings,
        )
    });
    let extra = pos.is_some() && !has_friction;
    let mut passes = 3 + usize::from(has_friction) + usize::from(extra);
    let mut pass_no = 0;
    let mut next_pass = |what: &str, progress: &mut dyn FnMut(&str)| {
        pass_no += 1;
        let s = format!("streaming {name}: pass {pass_no}/{passes}, {what}");
        progress(&s);
        s
    };

    let mut stage = stage::StageStream::new(&signals, len, fs, trim)?;
    let stage_of = stage.as_ref().map_or(Vec::new(), |s| s.untrimmed());
    let kit = |restore| PassKit {
        signals: &signals,
        fs,
        velocity: pred.velocity_mm_s,
        trim_n: (trim, n),
        len,
        restore,
        filter: filter.as_ref(),
        filter_block,
        name: &name,
        untrimmed: &stage_of,
    };

    // Pass 1: the load cell.
    let (restore, mut dc, friction_mean) = if has_friction {
        let what = next_pass("load cell", progress);
        position::begin(&mut pos, None);
        let (undo, dc, mean) = load_cell_pass(src, pred, settings, &what, progress, &mut |b| {
            position::push(&mut pos, b);
        })?;
        position::end(&mut pos);
        (undo, Some(dc), Some(mean))
    } else {
        (None, None, None)
    };

    // Pass 2: unfiltered spectra, lines, velocity sums.
    let k = signals.len();
    let (_, cross_idx) = spectra::cross_pairs(&signals);
    let (nperseg, noverlap) = spectra::full_segments(settings, n)?;
    let welch = |np: usize, no: usize| {
        WelchStream::new(spectra::welch_settings(settings, np, no), k, &cross_idx)
            .map_err(|e| Error::dsp("Welch settings", e))
    };
    let vi = signals.iter().position(|&s| s == Signal::VelocityError);
    let mut unfiltered = welch(nperseg, noverlap)?;
    let mut lines: Vec<TrendSums> = vec![TrendSums::new(n); k];
    let (mut raw_v, mut low_v) = (Moments::new(), Moments::new());
    let mut friction_dev = -0.0;
    let mut gather = SignalGatherer::new(name.clone(), len, fs, src.meta().start_time_s, &channels);
    // The passages, window by window in pass 2 (`passages`).
    let mut found = passages::StreamPassages::new(
        &name,
        fs,
        src.meta().start_time_s,
        len,
        pred,
        channels.contains(&crate::recording::Channel::Optical),
    );
    // The encoder keys at the predicted ball pitch, for a synchronous
    // average without optical passages (as in memory): the analysed
    // positions, in pass 2.
    let pitch_mm = 2.0 * pred.d_avg_mm;
    let mut encoder = channels
        .contains(&crate::recording::Channel::Position)
        .then(|| (0usize, EncoderKeys::new(fs, pitch_mm)));
    {
        let what = next_pass("low-pass and trend", progress);
        let mut eat = |out: &mut Output, _last: bool| -> Result<()> {
            if !out.raw.is_empty() && !out.raw[0].is_empty() {
                let xs: Vec<&[f64]> = out.raw.iter().map(Vec::as_slice).collect();
                unfiltered
                    .push(&xs)
                    .map_err(|e| Error::dsp(format!("{name}: unfiltered spectra"), e))?;
                if let Some(v) = vi {
                    for &x in &out.raw[v] {
                        raw_v.sum += x;
                        raw_v.sq += x * x;
                    }
                }
            }
            for (t, y) in lines.iter_mut().zip(&out.filtered) {
                t.add(out.filtered_at, y);
            }
            if let Some(st) = stage.as_mut() {
                st.add_lines(out);
            }
            if let Some(v) = vi {
                if let Some(y) = out.filtered.get(v) {
                    for &x in y {
                        low_v.sum += x;
                        low_v.sq += x * x;
                    }
                }
            }
            Ok(())
        };
        position::begin(&mut pos, restore);
        let mut on_block = |b: Block<'_>| {
            gather.push(b);
            found.push(b);
            if let (Some((at, keys)), Some(p)) = (encoder.as_mut(), b.position_mm) {
                let part = |i: usize| i.saturating_sub(*at).min(p.len());
                keys.push(&p[part(trim)..part(trim + n)]);
                *at += p.len();
            }
            position::push(&mut pos, b);
            if let (Some(m), Some(f)) = (friction_mean, b.friction_n) {
                for &y in f {
                    friction_dev += (y - m) * (y - m);
                }
            }
        };
        kit(restore).run(src, what, progress, &mut on_block, &mut eat)?;
        position::end(&mut pos);
    }
    if let (Some(dc), Some(mean)) = (dc.as_mut(), friction_mean) {
        // The mean over the standard deviation (ddof 1) of the recorded
        // friction, as `MeanStd::of` takes them.
        let std = if len > 1 {
            (friction_dev / (len - 1) as f64).sqrt()
        } else {
            0.0
        };
        dc.level_over_spread = if std > 0.0 { mean / std } else { f64::INFINITY };
        dc.unknown_high_pass = dc.source == "none"
            && settings.load_cell == load_cell::LoadCellCorrection::Auto
            && dc.level_over_spread.abs() < 3.0;
    }
    let trends: Vec<_> = lines.iter().map(|t| t.trend(settings.detrend)).collect();
    // The passages (pass 2), then the synchronous average keyed to them
    // (pass 3).
    let (passage_times, passage_summary) = match found.finish(&name) {
        Some((times, summary, note)) => {
            notes.extend(note);
            (times, summary)
        }
        None => (
            Err("no optical channel".to_string()),
            PassageSummary::without(name.clone(), "no optical channel".into()),
        ),
    };
    let mut not_computed = Vec::new();
    let no_sync = |warnings: &mut Vec<String>| {
        warnings.push(format!(
            "no synchronous average: {name}: neither friction nor velocity error present"
        ));
    };
    // The average's key, and the note an encoder key adds to it.
    let mut encoder_keyed = None;
    let mut sync = match (&passage_times, encoder) {
        (Ok(t), _) if t.len() >= 3 => {
            let t0 = src.meta().start_time_s + trim as f64 / fs;
            let keys: Vec<f64> = t.iter().map(|t| t - t0).collect();
            let s = sync::SyncStream::new(
                SyncKey::OpticalPassage,
                &keys,
                n,
                fs,
                &signals,
                pred.balls_in_race,
            );
            if s.is_none() {
                no_sync(&mut warnings);
            }
            s
        }
        (other, encoder) => {
            let why = match other {
                Ok(t) => format!("{} passages", t.len()),
                Err(e) => e.clone(),
            };
            match encoder {
                Some((_, keys)) => {
                    let keys = keys.finish();
                    let s = sync::SyncStream::new(
                        SyncKey::EncoderPitch,
                        &keys,
                        n,
                        fs,
                        &signals,
                        pred.balls_in_race,
                    );
                    if s.is_none() {
                        no_sync(&mut warnings);
                    }
                    encoder_keyed = Some(encoder_note(pitch_mm, &[format!("{name}: {why}")]));
                    s
                }
                None => {
                    not_computed.push(format!(
                        "synchronous average ({why}, and no encoder position to key it on)"
                    ));
                    None
                }
            }
        }
    };
    let nf = n as f64;
    let (raw_mean, low_mean) = (raw_v.sum / nf, low_v.sum / nf);

    // Pass 3: correlations and spectra.
    let pairs = pairs_for(&signals);
    let idx = |s: Signal| signals.iter().position(|&x| x == s).expect("present");
    let index_pairs: Vec<(usize, usize)> = pairs.iter().map(|&(x, y)| (idx(x), idx(y))).collect();
    let mut corr = WindowCorrelation::new(k, &index_pairs, n, max_lag, settings.corr_norm.to_dsp())
        .map_err(|e| Error::dsp("correlations", e))?;
    let mut full = welch(nperseg, noverlap)?;
    let mut hires = WelchStream::new(
        spectra::welch_settings(settings, plan.nperseg, plan.noverlap),
        k,
        &cross_idx,
    )
    .map_err(|e| Error::dsp("Welch settings", e))?;
    let dec_filter = plan.decimator.as_ref().and_then(|d| d.zero_phase_filter());
    {
        let what = next_pass("correlations and spectra", progress);
        let mut dec: Vec<Option<ZeroPhaseStream<'_>>> = (0..k)
            .map(|_| dec_filter.map(|f| ZeroPhaseStream::new(f, filter_block)))
            .collect();
        let mut dec_held: Vec<Vec<f64>> = vec![Vec::new(); k];
        let mut dec_at = 0usize;
        let q = plan.q.max(1);
        let mut detrended: Vec<Vec<f64>> = vec![Vec::new(); k];
        let mut eat = |out: &mut Output, last: bool| -> Result<()> {
            if let Some(v) = vi {
                for &x in out.raw.get(v).map_or(&[][..], Vec::as_slice) {
                    raw_v.dev += (x - raw_mean) * (x - raw_mean);
                }
                for &x in out.filtered.get(v).map_or(&[][..], Vec::as_slice) {
                    low_v.dev += (x - low_mean) * (x - low_mean);
                }
            }
            for ((d, y), t) in detrended.iter_mut().zip(&out.filtered).zip(&trends) {
                d.clear();
                d.extend(
                    y.iter()
                        .enumerate()
                        .map(|(i, v)| v - t.at(out.filtered_at + i)),
                );
            }
            if let Some(st) = stage.as_mut() {
                st.push(out)?;
            }
            if let Some(s) = sync.as_mut() {
                s.push(out.filtered_at, &detrended);
            }
            let xs: Vec<&[f64]> = detrended.iter().map(Vec::as_slice).collect();
            if xs.first().is_some_and(|x| !x.is_empty()) {
                corr.push(&xs).map_err(|e| Error::dsp("correlations", e))?;
                full.push(&xs)
                    .map_err(|e| Error::dsp(format!("{name}: full-range spectra"), e))?;
            }
            // Decimation: the anti-alias filter, then every q-th sample.
            let mut settled: Vec<Vec<f64>> = vec![Vec::new(); k];
            for (j, (s, x)) in settled.iter_mut().zip(&xs).enumerate() {
                match &mut dec[j] {
                    Some(f) => f.push(x, s),
                    None => {
                        s.extend_from_slice(x);
                        Ok(())
                    }
                }
                .map_err(|e| Error::dsp(format!("decimation of {}", signals[j].name()), e))?;
                if last {
                    if let Some(f) = dec[j].take() {
                        f.finish(s).map_err(|e| {
                            Error::dsp(format!("decimation of {}", signals[j].name()), e)
                        })?;
                    }
                }
                dec_held[j].append(s);
            }
            let m = dec_held.iter().map(Vec::len).min().unwrap_or(0);
            let picked: Vec<Vec<f64>> = dec_held
                .iter_mut()
                .map(|h| {
                    let p = (0..m)
                        .filter(|i| (dec_at + i) % q == 0)
                        .map(|i| h[i])
                        .collect();
                    h.drain(..m);
                    p
                })
                .collect();
            dec_at += m;
            let ps: Vec<&[f64]> = picked.iter().map(Vec::as_slice).collect();
            if ps.first().is_some_and(|x| !x.is_empty()) {
                hires
                    .push(&ps)
                    .map_err(|e| Error::dsp(format!("{name}: high-resolution spectra"), e))?;
            }
            Ok(())
        };
        position::begin(&mut pos, restore);
        let mut on_block = |b: Block<'_>| position::push(&mut pos, b);
        kit(restore).run(src, what, progress, &mut on_block, &mut eat)?;
        position::end(&mut pos);
    }
    let correlations = {
        let mut out = corr.finish().map_err(|e| Error::dsp("correlations", e))?;
        let lags = out
            .first_mut()
            .map(|c| std::mem::take(&mut c.lags))
            .unwrap_or_default();
        let lag_s = lags.iter().map(|&m| m as f64 / fs).collect();
        Correlations {
            fs_hz: fs,
            samples: n,
            lags,
            lag_s,
            series: pairs
                .iter()
                .copied()
                .zip(out.into_iter().map(|c| c.values))
                .collect(),
        }
    };
    let finish = |w: WelchStream, f: f64, what: &str| -> Result<Spectra> {
        let set = w
            .finish(f)
            .map_err(|e| Error::dsp(format!("{name}: {what}"), e))?;
        Ok(spectra::of_set(&signals, set))
    };
    let nseg_u = unfiltered.n_segments();
    let mut unfiltered = finish(unfiltered, fs, "unfiltered spectra")?;
    spectra::complete(
        &mut unfiltered,
        "welch",
        settings,
        fs,
        1,
        nperseg,
        noverlap,
        nseg_u,
    )?;
    let nseg_f = full.n_segments();
    let mut full = finish(full, fs, "full-range spectra")?;
    spectra::complete(
        &mut full, "welch", settings, fs, 1, nperseg, noverlap, nseg_f,
    )?;
    let nseg_h = hires.n_segments();
    let mut hr = finish(hires, plan.fs_hz, "high-resolution spectra")?;
    spectra::complete(
        &mut hr,
        "decimate+welch",
        settings,
        plan.fs_hz,
        plan.q,
        plan.nperseg,
        plan.noverlap,
        nseg_h,
    )?;
    for s in [&mut unfiltered, &mut full, &mut hr] {
        super::confidence::finish(s, settings);
    }
    let (stage, stage_spectra) = match (stage, &dc) {
        (Some(st), Some(dc)) => {
            let (id, sp) = st.finish(fs, pred.velocity_mm_s, dc)?;
            (Some(id), Some(sp))
        }
        _ => (None, None),
    };
    let load_cell: Vec<_> = dc.into_iter().collect();
    if let Some(w) = load_cell.iter().find_map(|d| d.warning(pred.f_c_hz)) {
        warnings.push(w);
    }
    for d in &load_cell {
        notes.push(format!("{name}: {}", d.note));
    }
    warnings.extend(plan_warnings);
    if hr.info.n_segments < 2 {
        warnings.push(format!(
            "high-resolution spectrum has {} segment: coherence is 1 by construction and the \
             harmonic tests are weak",
            hr.info.n_segments
        ));
    }
    let mut findings = evaluate_findings(&correlations, &hr, pred, settings, &mut warnings);

    // Pass 4: the phases at the measured f_c.
    let mut line = LineStream::new(&signals, fs, n, findings.f_used);
    // The report's detail figure: ball periods at the period it marks.
    gather.detail_at(findings.measured.period_s.unwrap_or(pred.tau_c_s));
    {
        let what = next_pass("phases", progress);
        let mut eat = |out: &mut Output, _last: bool| -> Result<()> {
            let d: Vec<Vec<f64>> = out
                .filtered
                .iter()
                .zip(&trends)
                .map(|(y, t)| {
                    y.iter()
                        .enumerate()
                        .map(|(i, v)| v - t.at(out.filtered_at + i))
                        .collect()
                })
                .collect();
            let xs: Vec<&[f64]> = d.iter().map(Vec::as_slice).collect();
            if xs.first().is_some_and(|x| !x.is_empty()) {
                line.push(&xs);
            }
            Ok(())
        };
        position::begin(&mut pos, restore);
        let mut on_block = |b: Block<'_>| {
            gather.push_detail(b);
            position::push(&mut pos, b);
        };
        let kit = PassKit {
            untrimmed: &[],
            ..kit(restore)
        };
        kit.run(src, what, progress, &mut on_block, &mut eat)?;
        position::end(&mut pos);
    }
    if extra {
        let what = next_pass("position-domain spectra", progress);
        if !position::extra_pass(&mut pos, src, restore, what, progress)? {
            // The spectra had already failed: the pass was not made.
            passes -= 1;
        }
    }
    let position = position::finish(pos, &mut notes, &mut warnings);
    fill_line_phases(
        &mut findings.phases,
        &line.finish(),
        findings.f_used,
        settings.confidence,
    );

    let velocity_error = vi.map(|_| {
        let um = |m: f64| m * 1e3;
        VelocityErrorStats {
            records: 1,
            std_spread_um_s: None,
            mean_um_s: um(raw_mean),
            std_um_s: um((raw_v.dev / nf).sqrt()),
            rms_um_s: um((raw_v.sq / nf).sqrt()),
            lowpassed_mean_um_s: um(low_mean),
            lowpassed_std_um_s: um((low_v.dev / nf).sqrt()),
            lowpassed_rms_um_s: um((low_v.sq / nf).sqrt()),
            quantisation_floor_um_s: settings.encoder_resolution_um * fs / 24f64.sqrt(),
        }
    });
    super::repeats::common_notes(&mut notes, &hr, &plan, &correlations, settings, pred, n, fs);
    let stream = StreamInfo {
        passes,
        lowpass_overlap_samples: filter.as_ref().map(ZeroPhaseStream::overlap_for),
        decimation_overlap_samples: dec_filter.map(ZeroPhaseStream::overlap_for),
        not_computed: not_computed.clone(),
        signals: Some(gather.finish()),
    };
    notes.push(format!(
        "record streamed: read {passes} times block by block in bounded memory; low-pass and \
         decimation filtered forward exactly and backward in blocks rerun over {} and {} samples \
         (within 1e-12 of the whole-record filter)",
        stream
            .lowpass_overlap_samples
            .map_or("no".into(), |p| p.to_string()),
        stream
            .decimation_overlap_samples
            .map_or("no".into(), |p| p.to_string()),
    ));
    warnings.push(format!(
        "{name} was streamed (too long to hold in memory){}",
        if not_computed.is_empty() {
            "; its ball passages were detected window by window".to_string()
        } else {
            format!("; not computed: {}", not_computed.join("; "))
        }
    ));
    let sync = sync.and_then(|s| match s.finish(&name) {
        Ok(mut a) => {
            if let Some(note) = encoder_keyed {
                a.pitch_mm = Some(pitch_mm);
                a.notes.insert(0, note);
            }
            Some(a)
        }
        Err(e) => {
            warnings.push(format!("no synchronous average: {e}"));
            None
        }
    });
    let verdict = verdict_of(pred, &findings);
    let stage = super::stage_for_lines(stage, stage_spectra.as_ref(), &verdict);
    let correlation_window =
        super::CorrelationWindow::of(&correlations, settings.max_lag, pred.tau_c_s);
    let meta = src.meta();
    Ok(Analysis {
        schema: SCHEMA,
        version: crate::VERSION,
        inputs: vec![InputInfo {
            source: name.clone(),
            test_id: meta.test_id.clone(),
            fs_hz: fs,
            samples: len,
            duration_s: len as f64 / fs,
            channels: channels
                .iter()
                .map(|c| c.column_name().to_string())
                .collect(),
        }],
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
        repeats: None,
        verdict,
        passages: vec![passage_summary],
        sync,
        warnings,
        correlations,
        spectra: full,
        spectra_hires: hr,
        spectra_unfiltered: unfiltered,
        position,
        stream: Some(stream),
    })
}

#[cfg(test)]
mod tests;
