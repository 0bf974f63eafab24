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

use ballpass_dsp::{DetrendType, Welch, WelchSettings, ZeroPhaseFilter};
use serde::Serialize;

use super::confidence::{psd_band, PsdBand};
use super::{AnalyzeSettings, Signal};
use crate::error::{Error, Result};
use crate::recording::Recording;
use crate::stats::welch_dof;

mod grid;
mod lines;
mod walk;

use grid::resample_record;
pub(crate) use grid::{grid_step, Lowpassed};
use lines::lines;
pub(crate) use lines::LineScan;

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

/// One record for [`compute`]: the record, a replacement friction, the
/// samples analysed.
pub(crate) type RecordPart<'a> = (&'a Recording, Option<&'a [f64]>, std::ops::Range<usize>);

/// Welch segment lengths tried, longest first (module docs).
pub(crate) const SEGMENT_CHOICES: [usize; 3] = [
    PERIODS_PER_SEGMENT * POINTS_PER_PERIOD,
    PERIODS_PER_SEGMENT / 2 * POINTS_PER_PERIOD,
    PERIODS_PER_SEGMENT / 4 * POINTS_PER_PERIOD,
];

/// The Welch segment length for runs whose longest has `longest` grid
/// points: the longest of [`SEGMENT_CHOICES`] that fits.
///
/// # Errors
/// [`Error::InvalidRecording`] (naming `names`) when none fits.
pub(crate) fn choose_nperseg(longest: usize, names: &str, d_avg_mm: f64) -> Result<usize> {
    let dx = 2.0 * d_avg_mm / POINTS_PER_PERIOD as f64;
    SEGMENT_CHOICES
        .into_iter()
        .find(|&n| n <= longest)
        .ok_or_else(|| Error::InvalidRecording {
            source_name: names.into(),
            reason: format!(
                "no run of one direction covers {} ball-pass periods ({:.1} mm of travel beyond \
                 one period for the velocity error's mean); longest {:.1} mm: no \
                 position-domain spectrum",
                PERIODS_PER_SEGMENT / 4,
                (PERIODS_PER_SEGMENT / 4) as f64 * 2.0 * d_avg_mm,
                longest as f64 * dx
            ),
        })
}

/// What the runs gave, summed over their Welch segments, for [`assemble`].
pub(crate) struct Accumulated {
    /// Per signal, the sum over segments of each segment's PSD.
    pub sums: Vec<(Signal, Vec<f64>)>,
    pub freq: Vec<f64>,
    pub n_segments: usize,
    pub dof: f64,
    pub runs: Vec<DirectionRun>,
    pub travel: f64,
    pub min_speed: f64,
}

/// The spectra of `acc` (segments of `nperseg` grid points of `d_avg_mm / 32`),
/// averaged, with their lines (located with `scan` when given).
pub(crate) fn assemble(
    mut acc: Accumulated,
    d_avg_mm: f64,
    nperseg: usize,
    n_records: usize,
    settings: &AnalyzeSettings,
    scan: Option<&LineScan>,
) -> PositionSpectra {
    let dx = 2.0 * d_avg_mm / POINTS_PER_PERIOD as f64;
    for (_, s) in &mut acc.sums {
        s.iter_mut().for_each(|a| *a /= acc.n_segments as f64);
    }
    acc.sums.sort_by_key(|(s, _)| *s);
    let mut out = PositionSpectra {
        d_avg_mm,
        line_per_mm: 1.0 / (2.0 * d_avg_mm),
        dx_mm: dx,
        nperseg,
        n_segments: acc.n_segments,
        n_records,
        resolution_per_mm: (1.0 / dx) / nperseg as f64,
        dof: acc.dof,
        band: psd_band(acc.dof, settings.band_confidence),
        travel_used_mm: acc.travel,
        min_speed_mm_s: acc.min_speed,
        runs: acc.runs,
        lines: Vec::new(),
        freq_per_mm: acc.freq,
        auto: acc.sums,
    };
    out.lines = lines(&out, settings.harmonics, scan);
    out
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

/// [`compute`] with each record's friction and optical channels (over its
/// range) already low-passed with `filter`, when `lowpassed[i]` holds them.
///
/// # Errors
/// As [`compute`].
pub(crate) fn compute_lowpassed(
    recs: &[RecordPart<'_>],
    lowpassed: &[Option<&Lowpassed>],
    settings: &AnalyzeSettings,
    filter: Option<&ZeroPhaseFilter>,
    d_avg_mm: f64,
) -> Result<PositionSpectra> {
    compute_given(recs, lowpassed, settings, filter, d_avg_mm, Detail::Full)
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
    compute_given(recs, &[], settings, filter, d_avg_mm, detail)
}

/// [`compute_with`], record `i`'s signals in `lowpassed[i]` (when there)
/// low-passed already.
fn compute_given(
    recs: &[RecordPart<'_>],
    lowpassed: &[Option<&Lowpassed>],
    settings: &AnalyzeSettings,
    filter: Option<&ZeroPhaseFilter>,
    d_avg_mm: f64,
    detail: Detail,
) -> Result<PositionSpectra> {
    let full = detail == Detail::Full;
    let dx = 2.0 * d_avg_mm / POINTS_PER_PERIOD as f64;
    let mut all = Vec::new();
    for (i, (rec, fr, range)) in recs.iter().enumerate() {
        all.push(resample_record(
            rec,
            range.clone(),
            *fr,
            lowpassed.get(i).copied().flatten(),
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
    let names = recs
        .iter()
        .map(|(r, _, _)| r.source_name())
        .collect::<Vec<_>>()
        .join(", ");
    let nperseg = choose_nperseg(longest, &names, d_avg_mm)?;
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
    let acc = Accumulated {
        sums,
        freq,
        n_segments,
        dof,
        runs,
        travel,
        min_speed,
    };
    Ok(assemble(
        acc,
        d_avg_mm,
        nperseg,
        recs.len(),
        settings,
        full.then_some(&scan),
    ))
}

/// Position-domain spectra of records of one bearing with average ball
/// pitch `d_avg_mm`, with the analysis' low-pass and window (module docs).
///
/// # Errors
/// As `compute`; [`Error::InvalidSetting`] for a bad low-pass.
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

/// The method note of computed spectra (`analysis.json`'s notes).
pub(crate) fn note(p: &PositionSpectra) -> String {
    format!(
        "position-domain spectra: {} runs of one direction, {:.0} mm of travel on a \
         {:.4} mm grid, {}-point Hann segments (resolution {:.5} cycles/mm), line at \
         1/(2 d_avg) = {:.5} cycles/mm",
        p.runs.iter().filter(|r| r.segments > 0).count(),
        p.travel_used_mm,
        p.dx_mm,
        p.nperseg,
        p.resolution_per_mm,
        p.line_per_mm
    )
}

/// The warning when the spectra could not be made.
pub(crate) fn failure(e: &Error) -> String {
    format!("no position-domain spectra: {e}")
}
