//! Step 1–2 of the analysis: velocity error, start-transient trim, low-pass
//! and detrend of the three analysed signals.
//!
//! ```text
//! v[n]   = numpy.gradient(position_mm, 1 / fs)        (Eq. 4.1 inside, one-sided at the ends), mm/s
//! v_e[n] = v[n] - V                                    (V the commanded velocity), mm/s
//! s      = detrend(sosfiltfilt(butter(order, f_lp, fs), x), kind)   for friction, v_e, optical
//! ```

use ballpass_dsp::{
    butter, detrend_in_place, gradient, FiltFiltSettings, FilterBand, Spacing, ZeroPhaseFilter,
};
use serde::Serialize;
use std::borrow::Cow;

use super::{AnalyzeSettings, Signal};
use crate::error::{Error, Result};
use crate::recording::{Channel, Recording};

/// One record after step 2: the analysed signals, equal length.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// Sampling rate, Hz.
    pub fs_hz: f64,
    /// Samples per signal (after the trim).
    pub n: usize,
    /// Signals present, in canonical order, low-passed and detrended.
    pub signals: Vec<(Signal, Vec<f64>)>,
    /// Velocity-error statistics, when the position channel is present.
    pub velocity_error: Option<VelocityErrorStats>,
    /// Samples removed at the start.
    pub trimmed_samples: usize,
}

impl Prepared {
    /// The samples of one signal, if present.
    pub fn signal(&self, s: Signal) -> Option<&[f64]> {
        self.signals
            .iter()
            .find(|(k, _)| *k == s)
            .map(|(_, v)| v.as_slice())
    }
}

/// Statistics of the velocity error `v - V`, µm/s.
///
/// Of one record as `prepare` computes them; in an [`super::Analysis`] of
/// several repeats, each field is the mean over the records of that
/// record's value (the thesis' Fig. 29 averages the per-test standard
/// deviations), see [`VelocityErrorStats::mean_of`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VelocityErrorStats {
    /// Records the statistics are the mean of (1 for one record).
    pub records: usize,
    /// Sample standard deviation (ddof 1) over the records of each record's
    /// `std_um_s`, µm/s; `None` for one record.
    pub std_spread_um_s: Option<f64>,
    /// Mean of the raw (after trim) velocity error, µm/s.
    pub mean_um_s: f64,
    /// Standard deviation (ddof 0) of the raw velocity error, µm/s (the
    /// thesis' Fig. 29 quantity).
    pub std_um_s: f64,
    /// Root mean square of the raw velocity error, µm/s.
    pub rms_um_s: f64,
    /// Mean of the low-passed (not detrended) velocity error, µm/s.
    pub lowpassed_mean_um_s: f64,
    /// Standard deviation (ddof 0) of the low-passed velocity error, µm/s.
    pub lowpassed_std_um_s: f64,
    /// Root mean square of the low-passed velocity error, µm/s.
    pub lowpassed_rms_um_s: f64,
    /// Encoder quantisation noise floor `q / (T_s sqrt(24))` of the centred
    /// difference, µm/s (docs/methods.md §2; 20.4 µm/s at 0.1 µm and 1 kHz).
    pub quantisation_floor_um_s: f64,
}

impl VelocityErrorStats {
    /// The mean over records of each statistic, with the spread of the
    /// standard deviations; `None` when `records` is empty.
    pub fn mean_of(records: &[&VelocityErrorStats]) -> Option<VelocityErrorStats> {
        let first = records.first()?;
        let n = records.len() as f64;
        let mean =
            |f: fn(&VelocityErrorStats) -> f64| records.iter().map(|r| f(r)).sum::<f64>() / n;
        let stds: Vec<f64> = records.iter().map(|r| r.std_um_s).collect();
        Some(VelocityErrorStats {
            records: records.len(),
            std_spread_um_s: crate::stats::MeanStd::of(&stds)
                .filter(|m| m.n > 1)
                .map(|m| m.std),
            mean_um_s: mean(|r| r.mean_um_s),
            std_um_s: mean(|r| r.std_um_s),
            rms_um_s: mean(|r| r.rms_um_s),
            lowpassed_mean_um_s: mean(|r| r.lowpassed_mean_um_s),
            lowpassed_std_um_s: mean(|r| r.lowpassed_std_um_s),
            lowpassed_rms_um_s: mean(|r| r.lowpassed_rms_um_s),
            quantisation_floor_um_s: first.quantisation_floor_um_s,
        })
    }
}

fn moments_um_s(x: &[f64]) -> (f64, f64, f64) {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    let var = x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
    let ms = x.iter().map(|v| v * v).sum::<f64>() / n;
    (mean * 1e3, var.sqrt() * 1e3, ms.sqrt() * 1e3)
}

/// The planned step-2 filter for one sampling rate (`None`: no low-pass).
pub(crate) fn lowpass_filter(
    settings: &AnalyzeSettings,
    fs_hz: f64,
) -> Result<Option<ZeroPhaseFilter>> {
    let Some(f_lp) = settings.lowpass_hz else {
        return Ok(None);
    };
    if !(f_lp.is_finite() && f_lp > 0.0) {
        return Err(Error::setting(
            "lowpass",
            format!("cutoff must be a positive number of Hz, got {f_lp}"),
        ));
    }
    if f_lp >= fs_hz / 2.0 {
        return Err(Error::setting(
            "lowpass",
            format!(
                "cutoff {f_lp} Hz is at or above the Nyquist frequency {} Hz (fs = {fs_hz} Hz)",
                fs_hz / 2.0
            ),
        ));
    }
    if settings.order == 0 {
        return Err(Error::setting("order", "filter order must be at least 1"));
    }
    let sos = butter(
        settings.order,
        FilterBand::LowPass { cutoff_hz: f_lp },
        fs_hz,
    )
    .map_err(|e| Error::dsp("low-pass design", e))?;
    let f = ZeroPhaseFilter::new(sos, FiltFiltSettings::default())
        .map_err(|e| Error::dsp("low-pass design", e))?;
    Ok(Some(f))
}

/// Step 1 for one record: the analysed signals trimmed to
/// `trim..trim + n_keep`, before the low-pass (what the full-range spectra
/// of the unfiltered signals are computed from), in canonical order,
/// `signals` only.
///
/// Friction and optical are the record's own samples (borrowed; `friction`,
/// when given, replaces the recorded friction: its load-cell discharge
/// undone, and an owned one is cut in place); the velocity error
/// `gradient(position) - V` is computed over the whole record and then cut,
/// so that the first kept value is a centred difference too.
///
/// # Errors
/// [`Error::InvalidRecording`] if the record is shorter than
/// `trim + n_keep`; [`Error::Dsp`] for a kernel failure (named with the
/// record).
pub(crate) fn raw_signals<'a>(
    rec: &'a Recording,
    velocity_mm_s: f64,
    (trim, n_keep): (usize, usize),
    friction: Option<Cow<'a, [f64]>>,
    signals: &[Signal],
) -> Result<Vec<(Signal, Cow<'a, [f64]>)>> {
    let fs = rec.fs_hz();
    let name = rec.source_name();
    let range = trim..trim + n_keep;
    if range.end > rec.len() {
        return Err(Error::InvalidRecording {
            source_name: name,
            reason: format!(
                "{} samples, fewer than the {} needed after trimming {trim}",
                rec.len(),
                range.end
            ),
        });
    }
    // The range of an owned buffer, in place (no second copy).
    let cut = |c: Cow<'a, [f64]>| match c {
        Cow::Borrowed(x) => Cow::Borrowed(&x[range.clone()]),
        Cow::Owned(mut v) => {
            v.truncate(range.end);
            v.drain(..range.start);
            Cow::Owned(v)
        }
    };
    let mut friction = friction;
    let mut out = Vec::with_capacity(3);
    for s in Signal::ALL.into_iter().filter(|s| signals.contains(s)) {
        let raw = match s {
            Signal::Friction => match friction
                .take()
                .or_else(|| rec.channel(Channel::Friction).map(Cow::Borrowed))
            {
                Some(x) => cut(x),
                None => continue,
            },
            Signal::Optical => match rec.channel(Channel::Optical) {
                Some(x) => Cow::Borrowed(&x[range.clone()]),
                None => continue,
            },
            Signal::VelocityError => match rec.channel(Channel::Position) {
                Some(p) => {
                    let mut v = gradient(p, Spacing::Uniform(1.0 / fs))
                        .map_err(|e| Error::dsp(format!("{name}: velocity (gradient)"), e))?;
                    v.truncate(range.end);
                    v.drain(..range.start);
                    v.iter_mut().for_each(|x| *x -= velocity_mm_s);
                    Cow::Owned(v)
                }
                None => continue,
            },
        };
        out.push((s, raw));
    }
    Ok(out)
}

/// Signals as low-passed, before the detrend ([`prepare_raw_keeping`]).
pub(crate) type Kept = Vec<(Signal, Vec<f64>)>;

/// Step 2 of one record's step-1 signals ([`raw_signals`]), each dropped
/// as soon as it is filtered (an owned one's memory is free before the
/// next signal is filtered); with a copy of each signal of `keep` as
/// low-passed, before its detrend (for the position-domain spectra, which
/// low-pass the same samples with the same filter).
///
/// # Errors
/// [`Error::Dsp`] for a kernel failure (named with the record).
pub(crate) fn prepare_raw_keeping(
    rec: &Recording,
    raw: Vec<(Signal, Cow<'_, [f64]>)>,
    settings: &AnalyzeSettings,
    filter: Option<&ZeroPhaseFilter>,
    (trim, n_keep): (usize, usize),
    keep: &[Signal],
) -> Result<(Prepared, Kept)> {
    let mut kept = Vec::new();
    let fs = rec.fs_hz();
    let name = rec.source_name();
    let ctx = |what: &str| format!("{name}: {what}");
    let mut signals = Vec::with_capacity(3);
    let mut velocity_error = None;
    for (s, raw) in raw {
        let mut y = match filter {
            Some(f) => f
                .apply(&raw)
                .map_err(|e| Error::dsp(ctx(&format!("low-pass of {}", s.name())), e))?,
            None => raw.to_vec(),
        };
        if s == Signal::VelocityError {
            let (m, sd, rms) = moments_um_s(&raw);
            let (lm, lsd, lrms) = moments_um_s(&y);
            velocity_error = Some(VelocityErrorStats {
                records: 1,
                std_spread_um_s: None,
                mean_um_s: m,
                std_um_s: sd,
                rms_um_s: rms,
                lowpassed_mean_um_s: lm,
                lowpassed_std_um_s: lsd,
                lowpassed_rms_um_s: lrms,
                quantisation_floor_um_s: settings.encoder_resolution_um * fs / 24f64.sqrt(),
            });
        }
        drop(raw);
        if keep.contains(&s) {
            kept.push((s, y.clone()));
        }
        detrend_in_place(&mut y, settings.detrend.to_dsp())
            .map_err(|e| Error::dsp(ctx(&format!("detrend of {}", s.name())), e))?;
        signals.push((s, y));
    }
    Ok((
        Prepared {
            fs_hz: fs,
            n: n_keep,
            signals,
            velocity_error,
            trimmed_samples: trim,
        },
        kept,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::{Channels, Metadata};

    #[test]
    fn velocity_error_of_a_ramp_is_zero_and_quantisation_floor_is_errata_value() {
        let fs = 1000.0;
        let v = 9.0;
        let pos: Vec<f64> = (0..2000).map(|i| v * i as f64 / fs).collect();
        let rec = Recording::new(
            fs,
            Channels {
                position_mm: Some(pos),
                ..Default::default()
            },
            Metadata::default(),
        )
        .unwrap();
        let s = AnalyzeSettings::default();
        let f = lowpass_filter(&s, fs).unwrap();
        let raw = raw_signals(&rec, v, (0, 2000), None, &Signal::ALL).unwrap();
        let (p, _) = prepare_raw_keeping(&rec, raw, &s, f.as_ref(), (0, 2000), &[]).unwrap();
        let st = p.velocity_error.unwrap();
        // A ramp differentiates exactly up to rounding of i/fs * 9 (~1e-15 mm
        // relative), amplified by 1/(2 T_s) = 500: far below 1e-6 µm/s.
        assert!(st.std_um_s < 1e-6 && st.mean_um_s.abs() < 1e-6, "{st:?}");
        // docs/methods.md §2: 0.1 µm at 1 kHz gives 20.4 µm/s (printed to 3 digits).
        assert!((st.quantisation_floor_um_s - 20.4).abs() < 0.05);
        assert_eq!(p.signals.len(), 1);
    }

    #[test]
    fn cutoff_at_or_above_nyquist_is_an_error() {
        let s = AnalyzeSettings {
            lowpass_hz: Some(600.0),
            ..Default::default()
        };
        let e = lowpass_filter(&s, 1000.0).unwrap_err().to_string();
        assert!(e.contains("lowpass") && e.contains("Nyquist"), "{e}");
    }
}
