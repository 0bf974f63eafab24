//! Spectra in the position domain: friction, velocity error and the
//! optical sensor against the distance travelled, in cycles per mm.
//!
//! The balls pass at fixed points of the travel (every `2 d_avg` of stage
//! travel, the balls moving at half the stage's speed), so in the position
//! domain the ball-pass line sits at `1 / (2 d_avg)` cycles/mm at every
//! speed: records at different speeds, and runs whose speed varies, share
//! one axis and can be averaged and compared.
//!
//! # Method
//!
//! ```text
//! v        = gradient(position, 1/fs), low-passed as the analysis (step 2)
//! runs     = maximal stretches where v keeps one sign and |v| ≥ 0.1 median|v|
//!            (stops, turn-arounds and slow creep are left out; a backward
//!            run is mirrored, its position negated)
//! dx       = 2 d_avg / 64                     (grid, mm; 64 points per period)
//! fine     = dx / q, q = a power of two with dx/q ≤ v_min / (2 f_b)
//!            (f_b the low-pass, or fs/2 without; v_min the slowest speed kept:
//!            the time band maps below the fine grid's Nyquist at every speed)
//! resample the running maximum of the (mirrored) position onto the fine grid,
//!            signals (friction, velocity, optical; low-passed as step 2) by
//!            linear interpolation in time at each grid point
//! decimate by q in stages of at most 8 (scipy.signal.decimate, zero phase)
//! v_e(x)   = v(x) − mean of v over one period (2 d_avg) centred on x:
//!            V on a constant-speed run, the speed itself through ramps; its
//!            nulls at k/(2 d_avg) leave every ball-pass line untouched
//! Welch    per run: Hann, 1024 points (16 periods; 8 or 4 periods when no run
//!            is that long), half overlap, linear detrend per segment; runs
//!            averaged weighted by their segments; ν = Σ runs' Welch dof
//! line k   = largest PSD bin within ±25 % of k/(2 d_avg), then the maximum
//!            of the segment-averaged power |DFT(f)|² (the Welch PSD at any f,
//!            zero-padded) within ±1 bin of it; its power Σ (PSD − floor) Δk
//!            over the peak ±2 bins (Hann's main lobe), floor = median of the
//!            bins within ±50 % of k/(2 d_avg) more than 2 bins from the peak
//!            and from the neighbouring harmonics
//! ```
//!
//! The PSD is one-sided, in unit² per (cycle/mm) = unit²·mm (column names
//! `psd_friction_n2_mm`); its integral over cycles/mm is the variance. A
//! line's rms is `sqrt(power)`, a sinusoid's amplitude `sqrt(2 power)`.

use ballpass_dsp::{
    gradient, DecimateSettings, Decimator, DetrendType, Spacing, Welch, WelchSettings,
    ZeroPhaseFilter,
};
use rayon::prelude::*;
use serde::Serialize;

use super::confidence::{psd_band, PsdBand};
use super::{AnalyzeSettings, Signal};
use crate::error::{Error, Result};
use crate::recording::{Channel, Recording};
use crate::stats::{median, welch_dof};

/// Grid points per ball-pass period of travel (`2 d_avg`).
pub const POINTS_PER_PERIOD: usize = 64;
/// Periods per Welch segment (16: resolution `1/(32 d_avg)`, a sixteenth
/// of the line's frequency); 8, then 4, when no run is long enough.
pub const PERIODS_PER_SEGMENT: usize = 16;
/// Runs slower than this fraction of the median speed are left out.
pub const STOP_FRACTION: f64 = 0.1;

/// One stretch of travel in one direction that was used.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DirectionRun {
    /// First sample's time, s (from the record's first sample).
    pub start_s: f64,
    /// Last sample's time, s.
    pub end_s: f64,
    /// `forward` (position increasing) or `backward`.
    pub direction: &'static str,
    /// Travel, mm.
    pub travel_mm: f64,
    /// Mean speed `travel / duration`, mm/s.
    pub mean_speed_mm_s: f64,
    /// Welch segments it gave (0: shorter than one segment, not used).
    pub segments: usize,
}

/// The ball-pass line of one signal in the position domain.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PositionLine {
    /// Signal.
    pub signal: Signal,
    /// Harmonic `k`.
    pub k: usize,
    /// `k / (2 d_avg)`, cycles/mm.
    pub predicted_per_mm: f64,
    /// Interpolated peak, cycles/mm.
    pub measured_per_mm: f64,
    /// `(measured − predicted) / predicted`, %.
    pub deviation_percent: f64,
    /// Power above the floor, unit².
    pub power: f64,
    /// `sqrt(power)`, the line's rms (N or mm/s).
    pub rms: f64,
    /// Unit of `rms` (`N`, `mm/s`).
    pub unit: &'static str,
    /// PSD at the peak over the floor, dB.
    pub ratio_db: f64,
    /// The floor's share of the summed bins, `floor · bins · Δk`, unit²
    /// (0 when no bin was left to measure the floor, see `floor_bins`).
    pub floor_power: f64,
    /// Bins the floor's median was taken over (0: the spectrum is too
    /// coarse to tell the line from its floor; `power` then includes it).
    pub floor_bins: usize,
    /// Amplitude of the line as a sinusoid, `sqrt(2 power)` (N or mm/s).
    pub amplitude: f64,
    /// Lower end of the amplitude's confidence interval (the PSD band's
    /// confidence, [`line_amplitude_band`]); 0 when the line does not stand
    /// above the floor at that confidence.
    pub amplitude_lower: Option<f64>,
    /// Upper end of the amplitude's confidence interval.
    pub amplitude_upper: Option<f64>,
}

/// Confidence interval `[lower, upper]` of a line's sinusoid amplitude from
/// the chi-square factors `[lower_factor, upper_factor]` of its PSD
/// ([`super::confidence::psd_band_factors`]): the bins summed hold
/// `power + floor_power`, which the factors bound; the floor, taken as known
/// (a median over many bins), is subtracted:
/// `sqrt(2 max(0, (power + floor_power) · factor − floor_power))`.
///
/// The factors are those of one bin: the sum of the ±2 Hann bins around a
/// line carries at least one bin's degrees of freedom, so the interval is on
/// the wide (conservative) side.
pub fn line_amplitude_band(power: f64, floor_power: f64, factors: [f64; 2]) -> [f64; 2] {
    factors.map(|f| (2.0 * ((power + floor_power) * f - floor_power).max(0.0)).sqrt())
}

/// Friction and velocity-error spectra against the travel.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PositionSpectra {
    /// `d_avg` used, mm.
    pub d_avg_mm: f64,
    /// `1 / (2 d_avg)`, cycles/mm.
    pub line_per_mm: f64,
    /// Grid spacing, mm.
    pub dx_mm: f64,
    /// Points per Welch segment.
    pub nperseg: usize,
    /// Segments averaged (all runs and records).
    pub n_segments: usize,
    /// Records averaged.
    pub n_records: usize,
    /// Bin spacing, cycles/mm.
    pub resolution_per_mm: f64,
    /// Equivalent degrees of freedom of a bin.
    pub dof: f64,
    /// Confidence band of the PSDs.
    pub band: Option<PsdBand>,
    /// Travel used, mm (sum over the runs with segments).
    pub travel_used_mm: f64,
    /// Slowest speed kept, mm/s.
    pub min_speed_mm_s: f64,
    /// The runs of one direction found (all records).
    pub runs: Vec<DirectionRun>,
    /// The line and its harmonics, per signal.
    pub lines: Vec<PositionLine>,
    /// Bin frequencies, cycles/mm (exported as CSV).
    #[serde(skip)]
    pub freq_per_mm: Vec<f64>,
    /// One-sided PSDs, unit²·mm (exported as CSV).
    #[serde(skip)]
    pub auto: Vec<(Signal, Vec<f64>)>,
}

impl PositionSpectra {
    /// The PSD of a signal, if present.
    pub fn auto_of(&self, s: Signal) -> Option<&[f64]> {
        self.auto
            .iter()
            .find(|(k, _)| *k == s)
            .map(|(_, v)| v.as_slice())
    }

    /// The line `k` of a signal, if measured.
    pub fn line(&self, s: Signal, k: usize) -> Option<&PositionLine> {
        self.lines.iter().find(|l| l.signal == s && l.k == k)
    }
}

/// Unit token of a position-domain PSD (`n2_mm`; `mm3_s2` = (mm/s)²·mm).
fn position_unit(s: Signal) -> &'static str {
    match s {
        Signal::Friction => "n2_mm",
        Signal::VelocityError => "mm3_s2",
        Signal::Optical => "v2_mm",
    }
}

/// Column name of a position-domain PSD: `psd_friction_n2_mm`.
pub fn position_psd_column(s: Signal) -> String {
    format!("psd_{}_{}", s.name(), position_unit(s))
}

/// Columns of `spectra_position.csv` (without `freq_per_mm`): the PSDs,
/// then each one's band (`psd_friction_lower_n2_mm`, `..._upper_...`).
pub fn position_columns(p: &PositionSpectra) -> Vec<(String, Vec<f64>)> {
    let mut cols: Vec<(String, Vec<f64>)> = p
        .auto
        .iter()
        .map(|(s, v)| (position_psd_column(*s), v.clone()))
        .collect();
    if let Some(b) = p.band {
        for (s, v) in &p.auto {
            let unit = position_unit(*s);
            cols.push((
                format!("psd_{}_lower_{unit}", s.name()),
                v.iter().map(|x| x * b.lower_factor).collect(),
            ));
            cols.push((
                format!("psd_{}_upper_{unit}", s.name()),
                v.iter().map(|x| x * b.upper_factor).collect(),
            ));
        }
    }
    cols
}

/// One record's runs resampled on the common grid.
struct Resampled {
    /// Each run, with its friction (if any) and velocity error on the grid
    /// when it was long enough to resample.
    runs: Vec<(DirectionRun, Option<Series>)>,
}

/// Signals on the position grid.
type Series = Vec<(Signal, Vec<f64>)>;

/// One record for [`compute`]: the record, a replacement friction, the
/// samples analysed.
pub(crate) type RecordPart<'a> = (&'a Recording, Option<&'a [f64]>, std::ops::Range<usize>);

/// Index ranges of the runs of one direction above `v_stop`.
fn direction_runs(v: &[f64], v_stop: f64) -> Vec<(usize, usize, bool)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < v.len() {
        if v[i].abs() < v_stop {
            i += 1;
            continue;
        }
        let fwd = v[i] > 0.0;
        let start = i;
        while i < v.len() && v[i].abs() >= v_stop && (v[i] > 0.0) == fwd {
            i += 1;
        }
        out.push((start, i, fwd));
    }
    out
}

/// Values of `y` where the non-decreasing `p` first reaches each grid point
/// `x0 + j dx`, `j = 0..m` (linear interpolation between samples).
fn resample(p: &[f64], ys: &[&[f64]], x0: f64, dx: f64, m: usize) -> Vec<Vec<f64>> {
    let mut out: Vec<Vec<f64>> = ys.iter().map(|_| Vec::with_capacity(m)).collect();
    let mut i = 1;
    for j in 0..m {
        let x = x0 + j as f64 * dx;
        while i + 1 < p.len() && p[i] < x {
            i += 1;
        }
        let (a, b) = (p[i - 1], p[i]);
        let t = if b > a {
            ((x - a) / (b - a)).clamp(0.0, 1.0)
        } else {
            1.0
        };
        for (o, y) in out.iter_mut().zip(ys) {
            o.push(y[i - 1] + t * (y[i] - y[i - 1]));
        }
    }
    out
}

/// Centred moving average over `w` points (odd); the ends, where the
/// window is not full, are dropped: the output is `len − w + 1` long.
fn moving_average_valid(x: &[f64], w: usize) -> Vec<f64> {
    if x.len() < w {
        return Vec::new();
    }
    let mut s: f64 = x[..w].iter().sum();
    let mut out = Vec::with_capacity(x.len() - w + 1);
    out.push(s / w as f64);
    for i in w..x.len() {
        s += x[i] - x[i - w];
        out.push(s / w as f64);
    }
    out
}

/// Decimates by `q` (a power of two) in stages of at most 8.
fn decimate_pow2(mut x: Vec<f64>, mut q: usize, what: &str) -> Result<Vec<f64>> {
    while q > 1 {
        let step = q.min(8);
        let d = Decimator::new(DecimateSettings {
            q: step,
            ..DecimateSettings::default()
        })
        .map_err(|e| Error::dsp(format!("{what}: position-domain decimator"), e))?;
        x = d
            .apply(&x)
            .map_err(|e| Error::dsp(format!("{what}: position-domain decimation"), e))?;
        q /= step;
    }
    Ok(x)
}

/// Shortest stretch (fine points) the zero-phase decimation stages take:
/// SciPy's `padlen` of an order-8 Chebyshev in 4 sections is 27 per stage.
const MIN_FINE_POINTS: usize = 64;

/// Resamples one record's friction and velocity on the grid `dx` (module
/// docs).
fn resample_record(
    rec: &Recording,
    range: std::ops::Range<usize>,
    friction: Option<&[f64]>,
    filter: Option<&ZeroPhaseFilter>,
    settings: &AnalyzeSettings,
    dx: f64,
    with_optical: bool,
) -> Result<Resampled> {
    let name = rec.source_name();
    let fs = rec.fs_hz();
    let Some(pos) = rec.channel(Channel::Position) else {
        return Err(Error::MissingChannel {
            channel: "position_mm",
            source_name: name,
            needed_for: "position-domain spectra",
        });
    };
    let lowpass = |x: Vec<f64>, what: &str| -> Result<Vec<f64>> {
        match filter {
            Some(f) => f
                .apply(&x)
                .map_err(|e| Error::dsp(format!("{name}: low-pass of {what}"), e)),
            None => Ok(x),
        }
    };
    let v_all = gradient(pos, Spacing::Uniform(1.0 / fs))
        .map_err(|e| Error::dsp(format!("{name}: velocity (gradient)"), e))?;
    let v = lowpass(v_all[range.clone()].to_vec(), "velocity")?;
    let f = match friction.or_else(|| rec.channel(Channel::Friction)) {
        Some(x) => Some(lowpass(x[range.clone()].to_vec(), "friction")?),
        None => None,
    };
    let o = match rec.channel(Channel::Optical).filter(|_| with_optical) {
        Some(x) => Some(lowpass(x[range.clone()].to_vec(), "optical")?),
        None => None,
    };
    let p = &pos[range.clone()];
    let speeds: Vec<f64> = v.iter().map(|x| x.abs()).collect();
    let med = median(&speeds).unwrap_or(0.0);
    if med.is_nan() || med <= 0.0 {
        return Err(Error::InvalidRecording {
            source_name: name,
            reason: "the stage does not move (median speed 0): no position-domain spectrum".into(),
        });
    }
    let v_stop = STOP_FRACTION * med;
    let f_b = settings.lowpass_hz.unwrap_or(fs / 2.0).min(fs / 2.0);
    // Fine spacing dx/q ≤ v_stop / (2 f_b): alias-free at every kept speed.
    let mut q = 1usize;
    while dx / q as f64 > v_stop / (2.0 * f_b) {
        q *= 2;
    }
    let fine = dx / q as f64;
    let period_pts = POINTS_PER_PERIOD | 1; // odd window for a centred mean
    let mut runs = Vec::new();
    for (a, b, fwd) in direction_runs(&v, v_stop) {
        let sign = if fwd { 1.0 } else { -1.0 };
        // Running maximum of the mirrored position: a monotone travel axis.
        let mut run_max = f64::NEG_INFINITY;
        let mono: Vec<f64> = p[a..b]
            .iter()
            .map(|x| {
                run_max = run_max.max(sign * x);
                run_max
            })
            .collect();
        let travel = mono[mono.len() - 1] - mono[0];
        let duration = (b - a) as f64 / fs;
        let run = DirectionRun {
            start_s: a as f64 / fs,
            end_s: (b - 1) as f64 / fs,
            direction: if fwd { "forward" } else { "backward" },
            travel_mm: travel,
            mean_speed_mm_s: travel / duration,
            segments: 0,
        };
        let x0 = (mono[0] / fine).ceil() * fine;
        let m = if travel > 0.0 {
            ((mono[mono.len() - 1] - x0) / fine).floor() as usize + 1
        } else {
            0
        };
        if b - a < 2 || m < MIN_FINE_POINTS * q {
            runs.push((run, None));
            continue;
        }
        let mut ys: Vec<&[f64]> = vec![&v[a..b]];
        if let Some(f) = &f {
            ys.push(&f[a..b]);
        }
        if let Some(o) = &o {
            ys.push(&o[a..b]);
        }
        let mut fine_series = resample(&mono, &ys, x0, fine, m).into_iter();
        let vel = decimate_pow2(fine_series.next().expect("velocity"), q, &name)?;
        let fr = match f.is_some() {
            true => Some(decimate_pow2(
                fine_series.next().expect("friction"),
                q,
                &name,
            )?),
            false => None,
        };
        let op = match o.is_some() {
            true => Some(decimate_pow2(
                fine_series.next().expect("optical"),
                q,
                &name,
            )?),
            false => None,
        };
        // Velocity error: v minus its mean over one period, centred.
        let mean = moving_average_valid(&vel, period_pts);
        let h = period_pts / 2;
        let mut sigs = Vec::new();
        if mean.is_empty() {
            runs.push((run, None));
            continue;
        }
        if let Some(fr) = fr {
            sigs.push((Signal::Friction, fr[h..h + mean.len()].to_vec()));
        }
        let ve: Vec<f64> = vel[h..h + mean.len()]
            .iter()
            .zip(&mean)
            .map(|(x, m)| x - m)
            .collect();
        sigs.push((Signal::VelocityError, ve));
        if let Some(op) = op {
            sigs.push((Signal::Optical, op[h..h + mean.len()].to_vec()));
        }
        runs.push((run, Some(sigs)));
    }
    Ok(Resampled { runs })
}

/// Position-domain spectra of one or more records of one bearing (module
/// docs). `friction`: per record, a replacement friction (load-cell
/// discharge undone), else the recorded one; `filter`: the analysis'
/// low-pass; `range`: the samples analysed of each record.
///
/// # Errors
/// [`Error::MissingChannel`] without a position channel;
/// [`Error::InvalidRecording`] when no run of one direction covers four
/// ball-pass periods.
pub(crate) fn compute(
    recs: &[RecordPart<'_>],
    settings: &AnalyzeSettings,
    filter: Option<&ZeroPhaseFilter>,
    d_avg_mm: f64,
) -> Result<PositionSpectra> {
    compute_with(recs, settings, filter, d_avg_mm, Detail::Full)
}

/// How much [`compute_with`] does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Detail {
    /// Friction, velocity error and optical; each line located between the
    /// bins (the zero-padded Welch maximum).
    Full,
    /// Friction and velocity error only, each line's frequency left at its
    /// largest bin: what the lines' powers and amplitudes need (they are
    /// summed over the bins), at a fraction of the cost (a sweep's records).
    Amplitudes,
}

/// [`compute`] in the detail asked for.
///
/// # Errors
/// As [`compute`].
pub(crate) fn compute_with(
    recs: &[RecordPart<'_>],
    settings: &AnalyzeSettings,
    filter: Option<&ZeroPhaseFilter>,
    d_avg_mm: f64,
    detail: Detail,
) -> Result<PositionSpectra> {
    let full = detail == Detail::Full;
    let line = 1.0 / (2.0 * d_avg_mm);
    let dx = 2.0 * d_avg_mm / POINTS_PER_PERIOD as f64;
    let mut all = Vec::new();
    for (rec, fr, range) in recs {
        all.push(resample_record(
            rec,
            range.clone(),
            *fr,
            filter,
            settings,
            dx,
            full,
        )?);
    }
    let longest = all
        .iter()
        .flat_map(|r| r.runs.iter().filter_map(|(_, s)| s.as_ref()))
        .flat_map(|s| s.iter().map(|(_, x)| x.len()))
        .max()
        .unwrap_or(0);
    let nperseg = [
        PERIODS_PER_SEGMENT,
        PERIODS_PER_SEGMENT / 2,
        PERIODS_PER_SEGMENT / 4,
    ]
    .into_iter()
    .map(|k| k * POINTS_PER_PERIOD)
    .find(|&n| n <= longest)
    .ok_or_else(|| Error::InvalidRecording {
        source_name: recs
            .iter()
            .map(|(r, _, _)| r.source_name())
            .collect::<Vec<_>>()
            .join(", "),
        reason: format!(
            "no run of one direction covers {} ball-pass periods ({:.1} mm of travel beyond \
                 one period for the velocity error's mean); longest {:.1} mm: no \
                 position-domain spectrum",
            PERIODS_PER_SEGMENT / 4,
            (PERIODS_PER_SEGMENT / 4) as f64 * 2.0 * d_avg_mm,
            longest as f64 * dx
        ),
    })?;
    let mut welch = Welch::new(WelchSettings {
        window: settings.window.to_dsp(),
        nperseg,
        noverlap: Some(nperseg / 2),
        detrend: DetrendType::Linear,
        ..WelchSettings::default()
    })
    .map_err(|e| Error::dsp("position-domain Welch", e))?;
    let w = settings
        .window
        .to_dsp()
        .values(nperseg)
        .map_err(|e| Error::dsp("window", e))?;
    let fs_x = 1.0 / dx;
    let mut sums: Vec<(Signal, Vec<f64>)> = Vec::new();
    let mut freq = Vec::new();
    let mut n_segments = 0usize;
    let mut dof = 0.0;
    let mut runs = Vec::new();
    let mut travel = 0.0;
    let mut min_speed = f64::INFINITY;
    let mut scan = LineScan::new(&w, dx);
    for r in all {
        for (mut run, sigs) in r.runs {
            let len = sigs
                .as_ref()
                .and_then(|s| s.first())
                .map_or(0, |(_, x)| x.len());
            if let (Some(sigs), true) = (sigs, len >= nperseg) {
                let mut k = 0;
                for (s, x) in &sigs {
                    let p = welch
                        .psd(x, fs_x)
                        .map_err(|e| Error::dsp("position-domain Welch", e))?;
                    k = p.n_segments;
                    freq = p.freq_hz;
                    match sums.iter_mut().find(|(t, _)| t == s) {
                        Some((_, acc)) => acc
                            .iter_mut()
                            .zip(&p.pxx)
                            .for_each(|(a, b)| *a += k as f64 * b),
                        None => sums.push((*s, p.pxx.iter().map(|b| k as f64 * b).collect())),
                    }
                }
                if full {
                    for (sig, x) in &sigs {
                        scan.add(*sig, x);
                    }
                }
                run.segments = k;
                n_segments += k;
                dof += welch_dof(&w, nperseg / 2, k);
                travel += len as f64 * dx;
                min_speed = min_speed.min(run.mean_speed_mm_s);
            }
            runs.push(run);
        }
    }
    for (_, acc) in &mut sums {
        acc.iter_mut().for_each(|a| *a /= n_segments as f64);
    }
    sums.sort_by_key(|(s, _)| *s);
    let mut out = PositionSpectra {
        d_avg_mm,
        line_per_mm: line,
        dx_mm: dx,
        nperseg,
        n_segments,
        n_records: recs.len(),
        resolution_per_mm: fs_x / nperseg as f64,
        dof,
        band: psd_band(dof, settings.band_confidence),
        travel_used_mm: travel,
        min_speed_mm_s: min_speed,
        runs,
        lines: Vec::new(),
        freq_per_mm: freq,
        auto: sums,
    };
    out.lines = lines(&out, settings.harmonics, full.then_some(&scan));
    Ok(out)
}

/// The windowed, detrended Welch segments of every signal, for locating a
/// line between the bins: the mean of `|Σ w[n] x[n] e^{−2πi f n dx}|²` over
/// the segments is the Welch PSD at any `f` (up to its scale), so its
/// maximum near a peak bin is the zero-padded Welch peak, free of an
/// interpolation formula's bias.
struct LineScan {
    window: Vec<f64>,
    dx: f64,
    segments: Vec<(Signal, Vec<f64>)>,
}

impl LineScan {
    fn new(window: &[f64], dx: f64) -> Self {
        LineScan {
            window: window.to_vec(),
            dx,
            segments: Vec::new(),
        }
    }

    /// Adds the segments of `x` as Welch cuts them (step `n/2`, linear
    /// detrend, window).
    fn add(&mut self, s: Signal, x: &[f64]) {
        let n = self.window.len();
        let mut start = 0;
        while start + n <= x.len() {
            let mut seg = x[start..start + n].to_vec();
            ballpass_dsp::detrend_in_place(&mut seg, DetrendType::Linear)
                .expect("a finite segment detrends");
            seg.iter_mut().zip(&self.window).for_each(|(v, w)| *v *= w);
            self.segments.push((s, seg));
            start += n / 2;
        }
    }

    /// Mean power of the segments of `s` at each frequency of `freqs`
    /// (cycles/mm), `L` frequencies in lock step.
    ///
    /// Per frequency, exactly the arithmetic of one frequency alone
    /// ([`tests::power_alone`] is the reference, checked bit for bit): a
    /// phasor `e^{−i step n}` rotated sample by sample and renormalised
    /// every 256 points, and per segment `Σ v·pr`, `−Σ v·pi` in sample
    /// order. The phasor does not depend on the segment, so it is made
    /// once for all of them, and `L` independent frequencies keep the
    /// processor busy where one is a chain of dependent multiplications.
    fn powers<const L: usize>(&self, s: Signal, freqs: &[f64]) -> Vec<f64> {
        let n = self.window.len();
        let segs: Vec<&[f64]> = self
            .segments
            .iter()
            .filter(|(t, _)| *t == s)
            .map(|(_, v)| v.as_slice())
            .collect();
        let count = segs.len().max(1) as f64;
        let mut table = vec![([0.0f64; L], [0.0f64; L]); n];
        let mut out = Vec::with_capacity(freqs.len());
        for chunk in freqs.chunks(L) {
            // Unused lanes rotate by zero (cos 1, sin 0) and are dropped.
            let (mut c, mut sn) = ([1.0f64; L], [0.0f64; L]);
            for (j, f) in chunk.iter().enumerate() {
                let step = std::f64::consts::TAU * f * self.dx;
                (c[j], sn[j]) = (step.cos(), step.sin());
            }
            let (mut pr, mut pi) = ([1.0f64; L], [0.0f64; L]);
            for (k, slot) in table.iter_mut().enumerate() {
                *slot = (pr, pi);
                for j in 0..L {
                    let t = pr[j] * c[j] - pi[j] * sn[j];
                    pi[j] = pr[j] * sn[j] + pi[j] * c[j];
                    pr[j] = t;
                }
                if k % 256 == 255 {
                    for j in 0..L {
                        let a = (pr[j] * pr[j] + pi[j] * pi[j]).sqrt();
                        pr[j] /= a;
                        pi[j] /= a;
                    }
                }
            }
            let mut total = [0.0f64; L];
            for seg in &segs {
                let (mut re, mut im) = ([0.0f64; L], [0.0f64; L]);
                for (v, (pr, pi)) in seg.iter().zip(&table) {
                    for j in 0..L {
                        re[j] += v * pr[j];
                        im[j] -= v * pi[j];
                    }
                }
                for j in 0..L {
                    total[j] += re[j] * re[j] + im[j] * im[j];
                }
            }
            out.extend(total[..chunk.len()].iter().map(|t| t / count));
        }
        out
    }

    /// Frequency of the largest mean power in `[lo, hi]`: a grid of 64
    /// steps, then golden-section refinement of the best step to 1e-4 of
    /// a step.
    fn peak(&self, s: Signal, lo: f64, hi: f64) -> f64 {
        let n = 64;
        let h = (hi - lo) / n as f64;
        let grid: Vec<f64> = (0..=n).map(|j| lo + j as f64 * h).collect();
        let p = self.powers::<8>(s, &grid);
        // The last of equal maxima, as `Iterator::max_by` picks.
        let best = (0..=n)
            .max_by(|&a, &b| p[a].total_cmp(&p[b]))
            .map(|j| grid[j])
            .expect("grid");
        let (mut a, mut b) = ((best - h).max(lo), (best + h).min(hi));
        let g = 0.5 * (5f64.sqrt() - 1.0);
        while b - a > 1e-4 * h {
            let (c, d) = (b - g * (b - a), a + g * (b - a));
            let p = self.powers::<2>(s, &[c, d]);
            if p[0] >= p[1] {
                b = d;
            } else {
                a = c;
            }
        }
        0.5 * (a + b)
    }
}

/// Median of `χ²_ν / ν` (0.693 at ν = 2, 0.934 at 10, → 1); 1 without
/// degrees of freedom.
fn chi2_median_over_nu(nu: f64) -> f64 {
    let m = crate::stats::chi2_ppf(0.5, nu) / nu;
    if nu > 0.0 && m.is_finite() && m > 0.0 {
        m
    } else {
        1.0
    }
}

/// The line and harmonics of every signal (module docs), each line in
/// parallel (rayon; the order is that of a sequential pass). Without
/// `scan`, each line's frequency is its largest bin's.
fn lines(p: &PositionSpectra, harmonics: usize, scan: Option<&LineScan>) -> Vec<PositionLine> {
    let df = p.resolution_per_mm;
    let wanted: Vec<(Signal, &[f64], usize)> = p
        .auto
        .iter()
        .flat_map(|(s, psd)| (1..=harmonics).map(move |k| (*s, psd.as_slice(), k)))
        .collect();
    wanted
        .into_par_iter()
        .filter_map(|(s, psd, k)| {
            let s = &s;
            let f = k as f64 * p.line_per_mm;
            let lo = ((0.75 * f / df).ceil() as usize).max(1);
            let hi = ((1.25 * f / df).floor() as usize).min(psd.len().saturating_sub(3));
            if lo + 2 > hi {
                return None;
            }
            let i = (lo..=hi)
                .max_by(|&a, &b| psd[a].total_cmp(&psd[b]))
                .expect("non-empty");
            if psd[i] <= 0.0 {
                return None;
            }
            let measured = match scan {
                Some(scan) => scan.peak(*s, (i as f64 - 1.0) * df, (i as f64 + 1.0) * df),
                None => i as f64 * df,
            };
            // The power is summed around the predicted line's bin, not the
            // largest one: where the line is weak, the largest bin of a
            // ±25 % search is often a peak of the floor's scatter, and
            // summing around it would bias the power up.
            let i0 = ((f / df).round() as usize).clamp(lo, hi);
            // Floor: the bins within ±50 % of k·f_line, more than 2 bins
            // from the line and from the neighbouring harmonics.
            let flo = ((0.5 * f / df).ceil() as usize).max(1);
            let fhi = ((1.5 * f / df).floor() as usize).min(psd.len() - 1);
            let rest: Vec<f64> = (flo..=fhi)
                .filter(|&j| {
                    let h = (j as f64 * df / p.line_per_mm).round();
                    j.abs_diff(i0) > 2 && (j as f64 * df - h * p.line_per_mm).abs() > 2.0 * df
                })
                .map(|j| psd[j])
                .collect();
            // The median of bins distributed S·χ²_ν/ν is S times the median
            // of χ²_ν/ν: divided by it, the floor is the mean level S the
            // line's bins carry too.
            let floor = median(&rest).unwrap_or(0.0) / chi2_median_over_nu(p.dof);
            let summed = i0.saturating_sub(2)..=(i0 + 2).min(psd.len() - 1);
            let floor_power = floor * summed.clone().count() as f64 * df;
            // Unclamped per bin (a bin below the floor is the floor's
            // scatter, and clamping it would bias the power up).
            let power = summed.map(|j| (psd[j] - floor) * df).sum::<f64>().max(0.0);
            let band = p
                .band
                .map(|b| line_amplitude_band(power, floor_power, [b.lower_factor, b.upper_factor]));
            Some(PositionLine {
                signal: *s,
                k,
                predicted_per_mm: f,
                measured_per_mm: measured,
                deviation_percent: 100.0 * (measured - f) / f,
                power,
                rms: power.sqrt(),
                unit: s.unit(),
                ratio_db: if floor > 0.0 {
                    10.0 * (psd[i] / floor).log10()
                } else {
                    f64::INFINITY
                },
                floor_power,
                floor_bins: rest.len(),
                amplitude: (2.0 * power).sqrt(),
                amplitude_lower: band.map(|b| b[0]),
                amplitude_upper: band.map(|b| b[1]),
            })
        })
        .collect()
}

/// Position-domain spectra of records of one bearing with average ball
/// pitch `d_avg_mm`, with the analysis' low-pass and window (module docs).
///
/// # Errors
/// As [`compute`]; [`Error::InvalidSetting`] for a bad low-pass.
pub fn position_spectra(
    recs: &[Recording],
    d_avg_mm: f64,
    settings: &AnalyzeSettings,
) -> Result<PositionSpectra> {
    if !(d_avg_mm.is_finite() && d_avg_mm > 0.0) {
        return Err(Error::setting(
            "d_avg",
            format!("ball pitch must be a positive number of mm, got {d_avg_mm}"),
        ));
    }
    let Some(first) = recs.first() else {
        return Err(Error::setting("records", "no records"));
    };
    let filter = super::preprocess::lowpass_filter(settings, first.fs_hz())?;
    let mut all = Vec::new();
    for r in recs {
        if r.fs_hz() != first.fs_hz() {
            return Err(Error::InvalidRecording {
                source_name: r.source_name(),
                reason: format!(
                    "sampled at {} Hz, the first record at {} Hz",
                    r.fs_hz(),
                    first.fs_hz()
                ),
            });
        }
        let trim = ((settings.trim_start_s * r.fs_hz()).round() as usize).min(r.len());
        all.push((r, None, trim..r.len()));
    }
    compute(&all, settings, filter.as_ref(), d_avg_mm)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mean power of the segments of `s` at `f`, one frequency and one
    /// segment at a time: the reference [`LineScan::powers`] must equal
    /// bit for bit.
    pub(super) fn power_alone(scan: &LineScan, s: Signal, f: f64) -> f64 {
        let step = std::f64::consts::TAU * f * scan.dx;
        let (c, sn) = (step.cos(), step.sin());
        let mut total = 0.0;
        let mut count = 0usize;
        for (_, seg) in scan.segments.iter().filter(|(t, _)| *t == s) {
            let (mut re, mut im) = (0.0, 0.0);
            let (mut pr, mut pi) = (1.0f64, 0.0f64);
            for (n, v) in seg.iter().enumerate() {
                re += v * pr;
                im -= v * pi;
                let t = pr * c - pi * sn;
                pi = pr * sn + pi * c;
                pr = t;
                if n % 256 == 255 {
                    let a = (pr * pr + pi * pi).sqrt();
                    pr /= a;
                    pi /= a;
                }
            }
            total += re * re + im * im;
            count += 1;
        }
        total / count.max(1) as f64
    }

    #[test]
    fn powers_in_lock_step_equal_one_frequency_at_a_time_bit_for_bit() {
        // Two signals, runs of 2600 and 1100 points (several segments of
        // 1024, one run with one): a line near 0.123 cycles/mm plus
        // deterministic noise.
        let dx = 0.127;
        let w = ballpass_dsp::Window::Hann.values(1024).unwrap();
        let mut scan = LineScan::new(&w, dx);
        let mut state = 7u64;
        let mut noise = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for (s, len) in [
            (Signal::Friction, 2600),
            (Signal::VelocityError, 2600),
            (Signal::Friction, 1100),
        ] {
            let x: Vec<f64> = (0..len)
                .map(|i| (std::f64::consts::TAU * 0.123 * i as f64 * dx).sin() + 0.3 * noise())
                .collect();
            scan.add(s, &x);
        }
        let freqs: Vec<f64> = (0..37).map(|j| 0.05 + 0.0071 * j as f64).collect();
        for s in [Signal::Friction, Signal::VelocityError, Signal::Optical] {
            let alone: Vec<u64> = freqs
                .iter()
                .map(|&f| power_alone(&scan, s, f).to_bits())
                .collect();
            let eight: Vec<u64> = scan
                .powers::<8>(s, &freqs)
                .iter()
                .map(|p| p.to_bits())
                .collect();
            let two: Vec<u64> = scan
                .powers::<2>(s, &freqs)
                .iter()
                .map(|p| p.to_bits())
                .collect();
            assert_eq!(eight, alone, "{s:?}");
            assert_eq!(two, alone, "{s:?}");
        }
        // The peak search finds the line (the grid is 1/(1024 dx) wide per bin).
        let f = scan.peak(Signal::Friction, 0.11, 0.135);
        assert!((f - 0.123).abs() < 0.1 / (1024.0 * dx), "{f}");
    }
}
