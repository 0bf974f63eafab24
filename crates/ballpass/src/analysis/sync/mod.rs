//! Synchronous averaging keyed to the ball passages: the mean friction and
//! velocity-error waveform over one ball-pass period, with a confidence
//! band from the spread between periods.
//!
//! # Method
//!
//! ```text
//! keys      t_k: the optical passages (phase 0 = a ball's pulse centre), or
//!           without an optical channel the times the encoder crosses
//!           x_0 + k·2·d_avg (phase 0 = the record's first position)
//! periods   [t_k, t_k+1) with 0.5 T_med ≤ t_k+1 − t_k ≤ 1.5 T_med (T_med the
//!           median interval); others are rejected (a missed or spurious key)
//! resample  y_p[j] = x(t_k + (j / B)(t_k+1 − t_k)),  j = 0..B−1, linear
//!           interpolation between samples (B bins per period, default 64)
//! mean      m[j] = Σ_p y_p[j] / P
//! band      m[j] ± t_{(1+c)/2, P−1} · s[j] / √P     (s[j] sample std, ddof 1;
//!           the c = 95 % Student-t interval of the mean, periods taken as
//!           independent draws)
//! p-p       max m − min m
//! fund.     c_1 = (1/B) Σ_j m[j] e^(−2πi j/B);  m(φ) ≈ m̄ + A cos(2πφ + θ),
//!           A = 2|c_1|, θ = arg c_1; the fundamental peaks at φ = −θ/2π mod 1
//! explained 1 − Σ_i (x_i − m(φ_i))² / Σ_i (x_i − x̄)² over the samples of the
//!           used periods, m(φ) interpolated periodically between bins
//! ```
//!
//! A signal that holds nothing periodic "explains" about `1/P` of its
//! variance (the mean of `P` noisy periods keeps `1/P` of the noise);
//! [`SyncWaveform::noise_fraction`] states that level beside the value.
//!
//! Balls are told apart when the circuit's ball count `N_B` is known and no
//! period of a record was rejected: passage `k` of a record is then ball
//! `k mod N_B`, numbered from the record's first passage (ball 0). With a
//! rejected period the count after it is unknown and the split is not made;
//! [`SyncAverage::per_ball_note`] says why. Numbers are per record (two
//! records do not start on the same ball), so the split is made for a
//! single record only.
//!
//! The signals are those of the analysis after its low-pass and detrend
//! (zero-phase, so the waveform is not shifted), friction in N and velocity
//! error in µm/s.

use serde::Serialize;

use super::Signal;
use crate::error::{Error, Result};
use crate::stats::{student_t_quantile, MeanStd};

pub(crate) mod records;
#[cfg(test)]
mod tests;

/// Settings of the synchronous average.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SyncSettings {
    /// Phase bins per period. Default 64.
    pub bins: usize,
    /// Confidence of the band. Default 0.95.
    pub confidence: f64,
}

impl Default for SyncSettings {
    fn default() -> Self {
        Self {
            bins: 64,
            confidence: 0.95,
        }
    }
}

impl SyncSettings {
    /// Checks the ranges.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming the setting.
    pub fn validate(&self) -> Result<()> {
        if !(8..=4096).contains(&self.bins) {
            return Err(Error::setting(
                "bins",
                format!("must be between 8 and 4096 per period, got {}", self.bins),
            ));
        }
        if !(self.confidence > 0.5 && self.confidence < 1.0) {
            return Err(Error::setting(
                "confidence",
                format!(
                    "must be between 0.5 and 1 (exclusive), got {}",
                    self.confidence
                ),
            ));
        }
        Ok(())
    }
}

/// What marks phase 0 of each period.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SyncKey {
    /// The optical ball passages (pulse centres).
    OpticalPassage,
    /// The encoder position at the predicted ball pitch `2 d_avg` of
    /// travel (no optical channel, or no passages found).
    EncoderPitch,
}

/// One record's signals and keys.
#[derive(Debug, Clone)]
pub struct SyncInput<'a> {
    /// Record name.
    pub source: String,
    /// Sampling rate, Hz.
    pub fs_hz: f64,
    /// Friction, N (`None`: absent).
    pub friction_n: Option<&'a [f64]>,
    /// Velocity error, mm/s (`None`: absent).
    pub velocity_error_mm_s: Option<&'a [f64]>,
    /// Times of phase 0, s from the signals' first sample, increasing.
    pub key_times_s: Vec<f64>,
}

/// The mean waveform of one signal over one period.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SyncWaveform {
    /// Which signal.
    pub signal: Signal,
    /// Unit of every value below (`N`, `µm/s`).
    pub unit: &'static str,
    /// Mean per bin (bin `j` at phase `j / B`).
    pub mean: Vec<f64>,
    /// Lower edge of the band per bin.
    pub band_low: Vec<f64>,
    /// Upper edge of the band per bin.
    pub band_high: Vec<f64>,
    /// `max mean − min mean`.
    pub peak_to_peak: f64,
    /// Amplitude `A` of the fundamental (one cycle per period).
    pub fundamental_amplitude: f64,
    /// Phase `θ` of the fundamental, `m ≈ m̄ + A cos(2πφ + θ)`, degrees in (−180, 180].
    pub fundamental_phase_deg: f64,
    /// Where the fundamental peaks, fraction of the period after phase 0, [0, 1).
    pub fundamental_peak_phase: f64,
    /// Fraction of the signal's variance the mean waveform explains.
    pub variance_explained: f64,
    /// What a signal without any periodic part would give, `1/P`.
    pub noise_fraction: f64,
}

/// One ball's periods (the period that starts at its passage).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BallRow {
    /// Ball number, 0 = the record's first passage.
    pub ball: usize,
    /// Periods averaged.
    pub periods: usize,
    /// Peak-to-peak of the ball's mean friction, N.
    pub friction_peak_to_peak_n: Option<f64>,
    /// Peak-to-peak of the ball's mean velocity error, µm/s.
    pub velocity_error_peak_to_peak_um_s: Option<f64>,
    /// Largest friction of the ball's mean, N (a sticking ball stands out).
    pub friction_max_n: Option<f64>,
}

/// The synchronous average of one or more records (part of `analysis.json`;
/// the waveforms are also written as `sync_average.csv`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SyncAverage {
    /// What marks phase 0.
    pub key: SyncKey,
    /// Phase 0 in words.
    pub key_text: String,
    /// Phase bins per period.
    pub bins: usize,
    /// Confidence of the band.
    pub confidence: f64,
    /// The band in words.
    pub band: String,
    /// Periods averaged (all records).
    pub periods_used: usize,
    /// Periods rejected (interval outside half to 1.5 times the median).
    pub periods_rejected: usize,
    /// Length of the periods used, s.
    pub period_s: MeanStd,
    /// Travel per period when keyed on the encoder, mm (`2 d_avg`).
    pub pitch_mm: Option<f64>,
    /// Friction and velocity-error waveforms (those present).
    pub waveforms: Vec<SyncWaveform>,
    /// Per-ball rows, when the balls can be told apart.
    pub per_ball: Vec<BallRow>,
    /// Whether and why not the balls were told apart.
    pub per_ball_note: String,
    /// Everything else the reader should know.
    pub notes: Vec<String>,
}

impl SyncAverage {
    /// The waveform of one signal.
    pub fn waveform(&self, s: Signal) -> Option<&SyncWaveform> {
        self.waveforms.iter().find(|w| w.signal == s)
    }

    /// Phase of each bin, fraction of a period.
    pub fn phases(&self) -> Vec<f64> {
        (0..self.bins)
            .map(|j| j as f64 / self.bins as f64)
            .collect()
    }
}

/// Times at which the encoder position first crosses `x_0 + k·pitch`
/// (`x_0` the first sample; `k = 1, 2, …` forward, or `−1, −2, …` when the
/// stage moves backwards), linear interpolation between samples, s from the
/// first sample. The level `x_0` itself is key 0 at time 0.
pub fn encoder_keys(position_mm: &[f64], fs_hz: f64, pitch_mm: f64) -> Vec<f64> {
    let mut keys = EncoderKeys::new(fs_hz, pitch_mm);
    keys.push(position_mm);
    keys.finish()
}

/// [`encoder_keys`] fed the positions block by block (a streamed record),
/// the same keys to the bit. The direction of travel is known only at the
/// last sample, so the crossings are followed both ways; the way not
/// travelled holds few keys (key 0, and a few more only where the stage
/// first backs up by more than a pitch).
#[derive(Debug, Clone)]
pub(crate) struct EncoderKeys {
    fs_hz: f64,
    pitch_mm: f64,
    /// First and latest position.
    ends: Option<(f64, f64)>,
    /// Samples read.
    at: usize,
    /// Forward, then backward: the next level and the keys so far.
    ways: [(f64, Vec<f64>); 2],
}

impl EncoderKeys {
    pub(crate) fn new(fs_hz: f64, pitch_mm: f64) -> Self {
        EncoderKeys {
            fs_hz,
            pitch_mm,
            ends: None,
            at: 0,
            ways: [(pitch_mm, vec![0.0]), (pitch_mm, vec![0.0])],
        }
    }

    /// The next positions, in order.
    pub(crate) fn push(&mut self, position_mm: &[f64]) {
        let pitch = self.pitch_mm;
        // (No crossings at a pitch that is not a positive length: `finish`
        // gives no keys then, and a zero step would never end.)
        let valid = pitch > 0.0;
        for &x in position_mm {
            let Some((x0, prev)) = self.ends else {
                self.ends = Some((x, x));
                self.at = 1;
                continue;
            };
            let i = self.at - 1;
            for ((level, keys), dir) in self.ways.iter_mut().zip([1.0, -1.0]) {
                if !valid {
                    break;
                }
                let (a, b) = ((prev - x0) * dir, (x - x0) * dir);
                while b >= *level && a < *level {
                    let frac = if b > a { (*level - a) / (b - a) } else { 0.0 };
                    keys.push((i as f64 + frac) / self.fs_hz);
                    *level += pitch;
                }
                // A crossing missed by a backward step is taken at the next
                // forward one.
                while b >= *level + pitch {
                    *level += pitch;
                }
            }
            self.ends = Some((x0, x));
            self.at += 1;
        }
    }

    /// The keys in the direction of travel (first to last position); none
    /// without travel or a valid pitch.
    pub(crate) fn finish(self) -> Vec<f64> {
        let Some((x0, x1)) = self.ends else {
            return Vec::new();
        };
        if self.pitch_mm.is_nan() || self.pitch_mm <= 0.0 || x0 == x1 {
            return Vec::new();
        }
        let [fwd, back] = self.ways;
        if x1 > x0 {
            fwd.1
        } else {
            back.1
        }
    }
}

/// Linear interpolation of `x` (sampled at `fs`) at `t` seconds.
fn interp(x: &[f64], fs: f64, t: f64) -> f64 {
    let u = (t * fs).clamp(0.0, (x.len() - 1) as f64);
    // `u >= 0` (or NaN): the cast truncates to the floor, without the
    // library call `floor` is on the x86_64 baseline.
    let i = (u as usize).min(x.len().saturating_sub(2));
    let f = u - i as f64;
    x[i] + f * (x[i + 1] - x[i])
}

/// Accepted periods of one record: `(start_s, end_s, key index)`, and the
/// count rejected.
pub(crate) fn periods(keys: &[f64], n: usize, fs: f64) -> (Vec<(f64, f64, usize)>, usize) {
    let t_end = (n.saturating_sub(1)) as f64 / fs;
    let intervals: Vec<f64> = keys.windows(2).map(|w| w[1] - w[0]).collect();
    let Some(med) = crate::stats::median(&intervals) else {
        return (Vec::new(), 0);
    };
    let mut out = Vec::new();
    let mut rejected = 0;
    for (k, w) in keys.windows(2).enumerate() {
        if w[0] < 0.0 || w[1] > t_end {
            continue;
        }
        let d = w[1] - w[0];
        if d >= 0.5 * med && d <= 1.5 * med {
            out.push((w[0], w[1], k));
        } else {
            rejected += 1;
        }
    }
    (out, rejected)
}

/// Rows of resampled periods of one signal.
fn resample(
    x: &[f64],
    fs: f64,
    per: &[(f64, f64, usize)],
    bins: usize,
    scale: f64,
) -> Vec<Vec<f64>> {
    per.iter()
        .map(|&(a, b, _)| {
            (0..bins)
                .map(|j| scale * interp(x, fs, a + (b - a) * j as f64 / bins as f64))
                .collect()
        })
        .collect()
}

/// Mean, band and sample std per bin of `rows` (at least two).
fn mean_band(rows: &[&Vec<f64>], bins: usize, tq: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let p = rows.len() as f64;
    let mut mean = vec![0.0; bins];
    for r in rows {
        mean.iter_mut().zip(r.iter()).for_each(|(m, v)| *m += v / p);
    }
    let mut lo = vec![0.0; bins];
    let mut hi = vec![0.0; bins];
    for j in 0..bins {
        let ss: f64 = rows.iter().map(|r| (r[j] - mean[j]).powi(2)).sum();
        let half = tq * (ss / (p - 1.0)).sqrt() / p.sqrt();
        lo[j] = mean[j] - half;
        hi[j] = mean[j] + half;
    }
    (mean, lo, hi)
}

/// `max − min`.
fn peak_to_peak(m: &[f64]) -> f64 {
    m.iter().copied().fold(f64::NEG_INFINITY, f64::max)
        - m.iter().copied().fold(f64::INFINITY, f64::min)
}

/// Fourier coefficient `c_k = (1/B) Σ m[j] e^(−2πi k j/B)` as (re, im).
pub(crate) fn coefficient(m: &[f64], k: usize) -> (f64, f64) {
    let b = m.len() as f64;
    m.iter().enumerate().fold((0.0, 0.0), |(re, im), (j, v)| {
        let a = std::f64::consts::TAU * (k * j) as f64 / b;
        (re + v * a.cos() / b, im - v * a.sin() / b)
    })
}

/// The periodic interpolation of the bins at phase `phi` in [0, 1).
pub(crate) fn at_phase(m: &[f64], phi: f64) -> f64 {
    let b = m.len();
    // A phase already in [0, 1) is its own remainder (`fmod` is exact):
    // the library call `rem_euclid` makes is left to the others.
    let phi = if (0.0..1.0).contains(&phi) {
        phi
    } else {
        phi.rem_euclid(1.0)
    };
    let u = phi * b as f64;
    // `u >= 0` (or NaN): the cast is the floor (see `interp`).
    let i = (u as usize).min(b - 1);
    let f = u - i as f64;
    // `(i + 1) % b` without the integer division.
    let next = if i + 1 == b { 0 } else { i + 1 };
    m[i] + f * (m[next] - m[i])
}

/// `1 − Σ (x − m(φ))² / Σ (x − x̄)²` over the samples of the periods.
fn explained(x: &[f64], fs: f64, per: &[(f64, f64, usize)], m: &[f64], scale: f64) -> f64 {
    let mut xs = Vec::new();
    let mut res = 0.0;
    for &(a, b, _) in per {
        let i0 = (a * fs).ceil() as usize;
        let i1 = ((b * fs).ceil() as usize).min(x.len());
        for (i, v) in x.iter().enumerate().take(i1).skip(i0) {
            let phi = (i as f64 / fs - a) / (b - a);
            let v = scale * v;
            res += (v - at_phase(m, phi)).powi(2);
            xs.push(v);
        }
    }
    let mean = xs.iter().sum::<f64>() / xs.len().max(1) as f64;
    let tot: f64 = xs.iter().map(|v| (v - mean).powi(2)).sum();
    if tot > 0.0 {
        1.0 - res / tot
    } else {
        0.0
    }
}

/// The synchronous average of `inputs` (one or more records) keyed on
/// `key`; `balls_in_circuit` is `N_B` when known.
///
/// # Errors
/// [`Error::InvalidSetting`] for bad settings; [`Error::InvalidRecording`]
/// naming the records when fewer than two periods remain, or when neither
/// friction nor velocity error is given.
pub fn synchronous_average(
    inputs: &[SyncInput<'_>],
    key: SyncKey,
    balls_in_circuit: Option<u32>,
    settings: &SyncSettings,
) -> Result<SyncAverage> {
    settings.validate()?;
    let names = || {
        inputs
            .iter()
            .map(|i| i.source.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let bins = settings.bins;
    let mut rows: [(Signal, &str, f64, Vec<Vec<f64>>); 2] = [
        (Signal::Friction, "N", 1.0, Vec::new()),
        (Signal::VelocityError, "µm/s", 1e3, Vec::new()),
    ];
    let mut present = [false, false];
    let mut all_periods = Vec::new();
    let mut per_record = Vec::new();
    let mut rejected = 0;
    for (ii, inp) in inputs.iter().enumerate() {
        let sig = [inp.friction_n, inp.velocity_error_mm_s];
        let Some(n) = sig.iter().flatten().map(|x| x.len()).min() else {
            continue;
        };
        if n < 2 {
            continue;
        }
        let (per, rej) = periods(&inp.key_times_s, n, inp.fs_hz);
        rejected += rej;
        for (k, x) in sig.iter().enumerate() {
            if let Some(x) = x {
                present[k] = true;
                let (_, _, scale, r) = &mut rows[k];
                r.extend(resample(x, inp.fs_hz, &per, bins, *scale));
            }
        }
        all_periods.extend(per.iter().map(|&(a, b, _)| b - a));
        per_record.push((ii, per, rej));
    }
    if !present.iter().any(|&p| p) {
        return Err(Error::InvalidRecording {
            source_name: names(),
            reason: "synchronous average: neither friction nor velocity error present".into(),
        });
    }
    let p = all_periods.len();
    if p < 2 {
        return Err(Error::InvalidRecording {
            source_name: names(),
            reason: format!(
                "synchronous average: {p} whole period(s) between the keys; at least 2 are needed"
            ),
        });
    }
    let tq = student_t_quantile(0.5 + settings.confidence / 2.0, (p - 1) as f64);
    let mut waveforms = Vec::new();
    for (k, (signal, unit, scale, r)) in rows.iter().enumerate() {
        if !present[k] || r.len() != p {
            continue;
        }
        let refs: Vec<&Vec<f64>> = r.iter().collect();
        let (mean, band_low, band_high) = mean_band(&refs, bins, tq);
        // Variance explained over every record's samples.
        let mut num = 0.0;
        let mut den = 0.0;
        for (ii, per, _) in &per_record {
            let inp = &inputs[*ii];
            let x = if k == 0 {
                inp.friction_n
            } else {
                inp.velocity_error_mm_s
            };
            if let Some(x) = x {
                let samples: usize = per
                    .iter()
                    .map(|&(a, b, _)| ((b * inp.fs_hz).ceil() - (a * inp.fs_hz).ceil()) as usize)
                    .sum();
                num += explained(x, inp.fs_hz, per, &mean, *scale) * samples as f64;
                den += samples as f64;
            }
        }
        waveforms.push(waveform(
            *signal,
            unit,
            [mean, band_low, band_high],
            if den > 0.0 { num / den } else { 0.0 },
            p,
        ));
    }
    let (per_ball, per_ball_note) = split_balls(inputs, &per_record, &rows, balls_in_circuit, key);
    Ok(finish(
        key,
        settings,
        rejected,
        &all_periods,
        waveforms,
        (per_ball, per_ball_note),
    ))
}

/// One signal's waveform from its `[mean, band_low, band_high]` per bin,
/// the variance it explains and the periods `p` averaged.
pub(crate) fn waveform(
    signal: Signal,
    unit: &'static str,
    [mean, band_low, band_high]: [Vec<f64>; 3],
    variance_explained: f64,
    p: usize,
) -> SyncWaveform {
    let c1 = coefficient(&mean, 1);
    let theta = c1.1.atan2(c1.0);
    SyncWaveform {
        signal,
        unit,
        peak_to_peak: peak_to_peak(&mean),
        fundamental_amplitude: 2.0 * c1.0.hypot(c1.1),
        fundamental_phase_deg: theta.to_degrees(),
        fundamental_peak_phase: (-theta / std::f64::consts::TAU).rem_euclid(1.0),
        variance_explained,
        noise_fraction: 1.0 / p as f64,
        mean,
        band_low,
        band_high,
    }
}

/// The average from its waveforms: the periods used (`all_periods`, at
/// least two) and rejected, the per-ball rows and note.
pub(crate) fn finish(
    key: SyncKey,
    settings: &SyncSettings,
    rejected: usize,
    all_periods: &[f64],
    waveforms: Vec<SyncWaveform>,
    (per_ball, per_ball_note): (Vec<BallRow>, String),
) -> SyncAverage {
    let p = all_periods.len();
    let bins = settings.bins;
    let key_text = match key {
        SyncKey::OpticalPassage => {
            "phase 0 = the optical ball passage (pulse centre); a period runs to the next passage"
                .to_string()
        }
        SyncKey::EncoderPitch => "phase 0 = the record's first encoder position, then every \
            2·d_avg of travel (the predicted ball pitch; no optical passages): the phase is not \
            tied to a ball"
            .to_string(),
    };
    let mut notes = Vec::new();
    if rejected > 0 {
        notes.push(format!(
            "{rejected} period(s) rejected: interval outside 0.5–1.5 times the median (a missed \
             or spurious key)"
        ));
    }
    SyncAverage {
        key,
        key_text,
        bins,
        confidence: settings.confidence,
        band: format!(
            "{:.0} % Student-t interval of the mean per bin (t with P − 1 = {} dof times the \
             sample std over √P), periods taken as independent",
            settings.confidence * 100.0,
            p - 1
        ),
        periods_used: p,
        periods_rejected: rejected,
        period_s: MeanStd::of(all_periods).expect("at least two periods"),
        pitch_mm: None,
        waveforms,
        per_ball,
        per_ball_note,
        notes,
    }
}

/// A record's index, accepted periods `(start_s, end_s, key index)` and
/// rejected count.
type RecordPeriods = (usize, Vec<(f64, f64, usize)>, usize);

type Rows<'r> = [(Signal, &'r str, f64, Vec<Vec<f64>>); 2];

/// Per-ball rows of a single record with no rejected period.
fn split_balls(
    inputs: &[SyncInput<'_>],
    per_record: &[RecordPeriods],
    rows: &Rows<'_>,
    balls: Option<u32>,
    key: SyncKey,
) -> (Vec<BallRow>, String) {
    let none = |why: String| (Vec::new(), format!("balls not told apart: {why}"));
    if key != SyncKey::OpticalPassage {
        return none("no optical passages (keyed on the encoder)".into());
    }
    let Some(nb) = balls.map(|b| b as usize).filter(|&b| b > 0) else {
        return none(
            "the number of balls in the circuit is unknown (bearing not in the catalog)".into(),
        );
    };
    if inputs.len() != 1 || per_record.len() != 1 {
        return none(format!(
            "{} records: ball numbers do not carry from one record to another",
            inputs.len()
        ));
    }
    let (_, per, rej) = &per_record[0];
    if *rej > 0 {
        return none(format!(
            "{rej} period(s) rejected (a passage missed or spurious), so the count after it is \
             not the ball's"
        ));
    }
    let mut out = Vec::new();
    for ball in 0..nb {
        let idx: Vec<usize> = per
            .iter()
            .enumerate()
            .filter(|(_, &(_, _, k))| k % nb == ball)
            .map(|(i, _)| i)
            .collect();
        if idx.is_empty() {
            continue;
        }
        let mean_of = |r: &Vec<Vec<f64>>| -> Option<Vec<f64>> {
            if r.len() != per.len() {
                return None;
            }
            let sel: Vec<&Vec<f64>> = idx.iter().map(|&i| &r[i]).collect();
            let b = sel[0].len();
            Some(
                (0..b)
                    .map(|j| sel.iter().map(|v| v[j]).sum::<f64>() / sel.len() as f64)
                    .collect(),
            )
        };
        let f = mean_of(&rows[0].3);
        let v = mean_of(&rows[1].3);
        out.push(BallRow {
            ball,
            periods: idx.len(),
            friction_peak_to_peak_n: f.as_deref().map(peak_to_peak),
            velocity_error_peak_to_peak_um_s: v.as_deref().map(peak_to_peak),
            friction_max_n: f
                .as_deref()
                .map(|m| m.iter().copied().fold(f64::NEG_INFINITY, f64::max)),
        });
    }
    let note = ball_note(&out, nb);
    (out, note)
}

/// The note of rows `out` of `nb` balls told apart.
pub(crate) fn ball_note(out: &[BallRow], nb: usize) -> String {
    let min = out.iter().map(|r| r.periods).min().unwrap_or(0);
    if out.len() < nb {
        format!(
            "balls told apart (passage index mod N_B = {nb}, ball 0 = the first passage): only {} \
             of the {nb} balls passed in the record",
            out.len()
        )
    } else {
        format!(
            "balls told apart (passage index mod N_B = {nb}, ball 0 = the first passage), at \
             least {min} period(s) each"
        )
    }
}

/// Unit token of a waveform's columns (`n`, `um_s`).
fn unit_token(s: Signal) -> &'static str {
    match s {
        Signal::Friction => "n",
        _ => "um_s",
    }
}

impl SyncAverage {
    /// Columns of `sync_average.csv` (without `phase`): per waveform
    /// `<signal>_mean_<unit>`, `<signal>_band_low_<unit>`,
    /// `<signal>_band_high_<unit>` (`friction_mean_n`,
    /// `velocity_error_mean_um_s`, ...).
    pub fn csv_columns(&self) -> Vec<(String, Vec<f64>)> {
        let mut out = Vec::new();
        for w in &self.waveforms {
            let (s, u) = (w.signal.name(), unit_token(w.signal));
            out.push((format!("{s}_mean_{u}"), w.mean.clone()));
            out.push((format!("{s}_band_low_{u}"), w.band_low.clone()));
            out.push((format!("{s}_band_high_{u}"), w.band_high.clone()));
        }
        out
    }

    /// Writes `sync_average.csv`: `phase` (fraction of the period after
    /// phase 0, bin starts), then [`SyncAverage::csv_columns`].
    ///
    /// # Errors
    /// [`Error::Io`] naming the file.
    pub fn write_csv(&self, path: &std::path::Path) -> Result<()> {
        let phase = self.phases();
        super::export::write_csv(
            path,
            &super::export::Table {
                index_name: "phase",
                index: &phase,
                columns: self.csv_columns(),
            },
        )
    }
}
