//! What a user must know about a recording before analysing it.
//!
//! Per channel: range, mean, standard deviation, and three checks, each with
//! a threshold in [`InspectSettings`]:
//!
//! - **clipping**: a run of at least `clip_run` consecutive samples exactly
//!   at the channel's minimum or maximum (an input stuck at a rail of the
//!   converter: a clean noisy signal touches its extreme once);
//! - **dropouts**: a run of at least `dropout_run` identical consecutive
//!   samples away from the extremes (a frozen or disconnected input);
//! - **drift** (friction only, the quartz load cell's DC drift): the least
//!   squares line through the samples,
//!   ```text
//!   x(t) ≈ a + b t,   change over the record = b · duration
//!   ```
//!   flagged when the change exceeds `drift_ratio` times the standard
//!   deviation of what is left after removing the line.
//!
//! With a position channel, the mean stage velocity is the slope of the same
//! fit; it is compared with the stated tracking velocity (`velocity_ratio`).
//! With velocity and geometry known, the number of ball-pass periods spanned.
//!
//! [`inspect_file`] reads a file as it is, without refusing what analyses
//! refuse: it reports gaps (time stamps missing from the uniform grid,
//! samples without a finite value) with their positions, and values beyond
//! ±[`Recording::MAX_ABS`]; the statistics skip them.
//!
//! The statistics stay finite wherever their true value is (a channel of
//! values near 1e308 has a finite mean and deviation): the samples are
//! scaled by a power of two near their largest magnitude before any sum,
//! and the sums are compensated (Neumaier), so no intermediate overflows.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::io::{Gap, LoadOptions, Prepared};
use super::{Channel, Recording};
use crate::bearing::Geometry;
use crate::error::Result;

/// Thresholds of the checks of [`inspect`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct InspectSettings {
    /// Fewest consecutive samples at an extreme that count as clipping.
    pub clip_run: usize,
    /// Fewest identical consecutive samples (not at an extreme) that count as a dropout.
    pub dropout_run: usize,
    /// Friction drift over the record, in detrended standard deviations, that is flagged.
    pub drift_ratio: f64,
    /// Largest relative difference between the position's slope and the stated velocity.
    pub velocity_ratio: f64,
}

impl Default for InspectSettings {
    fn default() -> Self {
        Self {
            clip_run: 5,
            dropout_run: 20,
            drift_ratio: 2.0,
            velocity_ratio: 0.02,
        }
    }
}

/// How serious a finding is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    /// Worth knowing.
    Info,
    /// Likely to spoil an analysis.
    Warning,
}

/// One thing the checks found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Finding {
    /// How serious.
    pub severity: Severity,
    /// Channel concerned, canonical name, if one.
    pub channel: Option<String>,
    /// One line for a person.
    pub message: String,
}

/// A run of identical samples.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Run {
    /// The repeated value, in the channel's unit.
    pub value: f64,
    /// First sample of the run (0-based).
    pub start: usize,
    /// Length in samples.
    pub len: usize,
    /// Start time, s.
    pub start_time_s: f64,
}

/// Summary of one channel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChannelSummary {
    /// Canonical name (`friction_N`, ...).
    pub channel: String,
    /// Unit.
    pub unit: String,
    /// Smallest sample.
    pub min: f64,
    /// Largest sample.
    pub max: f64,
    /// Mean.
    pub mean: f64,
    /// Standard deviation (population, `ddof = 0`).
    pub std: f64,
    /// Samples exactly at the minimum or maximum in runs of at least `clip_run`.
    pub clipped_samples: usize,
    /// Longest run at an extreme.
    pub longest_clip: Option<Run>,
    /// Runs of identical samples away from the extremes, at least `dropout_run` long.
    pub dropouts: Vec<Run>,
    /// Slope of the least-squares line, unit per second.
    pub slope_per_s: f64,
    /// Slope times duration, in the channel's unit.
    pub change_over_record: f64,
    /// Standard deviation after removing the line.
    pub detrended_std: f64,
}

/// Everything [`inspect`] reports about one recording.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Inspection {
    /// Source file or test id.
    pub source: String,
    /// Test id.
    pub test_id: Option<String>,
    /// Samples per channel.
    pub samples: usize,
    /// Sampling rate, Hz.
    pub fs_hz: f64,
    /// Duration `samples / fs`, s.
    pub duration_s: f64,
    /// Time of the first sample, s.
    pub start_time_s: f64,
    /// Stated tracking velocity, mm/s.
    pub velocity_mm_s: Option<f64>,
    /// Bearing name.
    pub bearing: Option<String>,
    /// Mean stage velocity from the position channel, mm/s.
    pub position_velocity_mm_s: Option<f64>,
    /// Predicted ball-pass period at the stated velocity, s.
    pub tau_c_s: Option<f64>,
    /// Ball-pass periods spanned, `duration / tau_c`.
    pub periods: Option<f64>,
    /// Channels present, canonical order.
    pub channels: Vec<ChannelSummary>,
    /// Channels absent (analyses that need them will refuse).
    pub missing: Vec<String>,
    /// Clipping, dropouts, drift, velocity mismatch, gaps, values out of range.
    pub findings: Vec<Finding>,
    /// Gaps, in time order (at most [`MAX_GAPS_LISTED`]; `gap_count` has them all).
    pub gaps: Vec<Gap>,
    /// Number of gaps.
    pub gap_count: usize,
    /// Samples in all gaps.
    pub gap_samples: usize,
    /// What loading did to the numbers (units converted, lines skipped).
    pub notes: Vec<String>,
}

/// Most gaps an [`Inspection`] lists one by one.
pub const MAX_GAPS_LISTED: usize = 100;

/// What [`inspect_view`] looks at: channels on a uniform grid, perhaps with gaps.
struct View<'a> {
    source: String,
    test_id: Option<String>,
    fs_hz: f64,
    start_time_s: f64,
    /// Samples on the grid, missing ones included.
    grid_len: usize,
    channels: Vec<(Channel, &'a [f64])>,
    /// Grid sample of each value, when samples are missing.
    grid: Option<&'a [usize]>,
    velocity_mm_s: Option<f64>,
    bearing: Option<String>,
}

impl View<'_> {
    fn pos(&self, i: usize) -> usize {
        self.grid.map_or(i, |g| g[i])
    }
    fn time_s(&self, i: usize) -> f64 {
        self.start_time_s + self.pos(i) as f64 / self.fs_hz
    }
    fn duration_s(&self) -> f64 {
        self.grid_len as f64 / self.fs_hz
    }
}

/// Inspects a recording file as it is, gaps and all (see the module doc).
///
/// # Errors
/// As [`super::load`] for a file that cannot be read or placed on a time
/// base (a bad cell, a time column that is not uniform); never for gaps or
/// values out of range.
pub fn inspect_file(path: &Path, opts: &LoadOptions, s: &InspectSettings) -> Result<Inspection> {
    opts.validate()?;
    // `FILE#GROUP`: read the file, name the record.
    let (file, opts) = super::io::resolve(path, opts)?;
    let bytes = std::fs::read(&file).map_err(|source| crate::Error::Io {
        path: file.clone(),
        source,
    })?;
    let p = super::io::prepare_for_inspection(&file, &bytes, &opts)?;
    Ok(inspect_prepared(path, &p, &opts, s))
}

/// [`inspect_file`] of a file in memory; `path` names it and gives the
/// format when none is set.
///
/// # Errors
/// As [`inspect_file`].
pub fn inspect_bytes(
    path: &Path,
    bytes: &[u8],
    opts: &LoadOptions,
    s: &InspectSettings,
) -> Result<Inspection> {
    let p = super::io::prepare_for_inspection(path, bytes, opts)?;
    Ok(inspect_prepared(path, &p, opts, s))
}

fn inspect_prepared(
    path: &Path,
    p: &Prepared,
    opts: &LoadOptions,
    s: &InspectSettings,
) -> Inspection {
    let view = View {
        source: crate::error::shown_path(path),
        test_id: opts
            .test_id
            .clone()
            .or_else(|| path.file_stem().map(|s| s.to_string_lossy().into_owned())),
        fs_hz: p.fs_hz,
        start_time_s: p.start_time_s,
        grid_len: p.grid_len,
        channels: p.channels.iter().map(|(c, v)| (*c, v.as_slice())).collect(),
        grid: p.grid.as_deref(),
        velocity_mm_s: opts.velocity_mm_s,
        bearing: opts.bearing.clone(),
    };
    let mut out = inspect_view(&view, opts.geometry.as_ref(), s);
    if p.grid_len < Recording::MIN_SAMPLES {
        out.findings.push(Finding {
            severity: Severity::Warning,
            channel: None,
            message: format!(
                "only {} samples; analyses need at least {}",
                p.grid_len,
                Recording::MIN_SAMPLES
            ),
        });
    }
    out.gap_count = p.gaps.len();
    out.gap_samples = p.gaps.iter().map(|g| g.len).sum();
    out.gaps = p.gaps.iter().take(MAX_GAPS_LISTED).cloned().collect();
    out.notes = p.notes.clone();
    if let Some(first) = p.gaps.first() {
        out.findings.push(Finding {
            severity: Severity::Warning,
            channel: None,
            message: format!(
                "{} gap(s), {} sample(s) missing or without a value (the first: {} sample(s) \
                 at t = {:.6} s, {}, {}); analyses refuse them unless told to fill or split",
                p.gaps.len(),
                out.gap_samples,
                first.len,
                first.start_time_s,
                first.place,
                first.channels.join(", ")
            ),
        });
    }
    if let (n, Some((c, g, x))) = p.out_of_range {
        out.findings.push(Finding {
            severity: Severity::Warning,
            channel: Some(c.column_name().into()),
            message: format!(
                "{n} value(s) beyond ±{:e} (the first: {x:e} at t = {:.6} s); analyses refuse them",
                Recording::MAX_ABS,
                p.start_time_s + g as f64 / p.fs_hz
            ),
        });
    }
    out
}

/// Inspects a recording (see the module doc for what is checked).
pub fn inspect(rec: &Recording, geometry: Option<&Geometry>, s: &InspectSettings) -> Inspection {
    let view = View {
        source: rec.source_name(),
        test_id: rec.meta.test_id.clone(),
        fs_hz: rec.fs_hz(),
        start_time_s: rec.meta.start_time_s,
        grid_len: rec.len(),
        channels: rec
            .channels()
            .into_iter()
            .filter_map(|c| rec.channel(c).map(|v| (c, v)))
            .collect(),
        grid: None,
        velocity_mm_s: rec.meta.velocity_mm_s,
        bearing: rec.meta.bearing.clone(),
    };
    let mut out = inspect_view(&view, geometry, s);
    out.notes = rec.meta.notes.clone();
    out
}

fn inspect_view(rec: &View<'_>, geometry: Option<&Geometry>, s: &InspectSettings) -> Inspection {
    let mut findings = Vec::new();
    let mut channels = Vec::new();
    let mut position_velocity_mm_s = None;
    for &(c, x) in &rec.channels {
        let sum = summarise(rec, c, x, s);
        let name = c.column_name().to_string();
        if let Some(run) = &sum.longest_clip {
            findings.push(Finding {
                severity: Severity::Warning,
                channel: Some(name.clone()),
                message: format!(
                    "clipped: {} samples stuck at {} {} (longest run {} samples from t = {:.3} s)",
                    sum.clipped_samples,
                    run.value,
                    c.unit(),
                    run.len,
                    run.start_time_s
                ),
            });
        }
        if let Some(first) = sum.dropouts.first() {
            let total: usize = sum.dropouts.iter().map(|r| r.len).sum();
            findings.push(Finding {
                severity: Severity::Warning,
                channel: Some(name.clone()),
                message: format!(
                    "{} dropout(s): {total} samples frozen at one value (first: {} {} for {} samples from t = {:.3} s)",
                    sum.dropouts.len(),
                    first.value,
                    c.unit(),
                    first.len,
                    first.start_time_s
                ),
            });
        }
        if c == Channel::Friction
            && sum.change_over_record.abs() > s.drift_ratio * sum.detrended_std
        {
            findings.push(Finding {
                severity: Severity::Warning,
                channel: Some(name.clone()),
                message: format!(
                    "load-cell DC drift: {:+.4} N over the record ({:+.4} N/s), {:.1} times the \
                     detrended standard deviation",
                    sum.change_over_record,
                    sum.slope_per_s,
                    sum.change_over_record.abs() / sum.detrended_std.max(f64::MIN_POSITIVE)
                ),
            });
        }
        if c == Channel::Position {
            position_velocity_mm_s = Some(sum.slope_per_s);
        }
        channels.push(sum);
    }
    let v = rec.velocity_mm_s;
    if let (Some(v), Some(pv)) = (v, position_velocity_mm_s) {
        if (pv.abs() - v).abs() > s.velocity_ratio * v {
            findings.push(Finding {
                severity: Severity::Warning,
                channel: Some(Channel::Position.column_name().into()),
                message: format!(
                    "the stage moves at {:.4} mm/s by the position channel, not the stated {v} mm/s",
                    pv.abs()
                ),
            });
        }
    }
    let tau_c_s = match (v, geometry) {
        (Some(v), Some(g)) if v > 0.0 => Some(2.0 * g.d_avg_mm() / v),
        _ => None,
    };
    let periods = tau_c_s.map(|t| rec.duration_s() / t);
    if let (Some(p), Some(t)) = (periods, tau_c_s) {
        findings.push(Finding {
            severity: Severity::Info,
            channel: None,
            message: format!("spans {p:.1} ball-pass periods (tau_c = {t:.4} s)"),
        });
    }
    if v.is_none() {
        findings.push(Finding {
            severity: Severity::Info,
            channel: None,
            message: "tracking velocity unknown: give it to get predictions".into(),
        });
    }
    let missing = Channel::ALL
        .into_iter()
        .filter(|&c| rec.channels.iter().all(|(d, _)| *d != c))
        .map(|c| c.column_name().to_string())
        .collect();
    Inspection {
        source: rec.source.clone(),
        test_id: rec.test_id.clone(),
        samples: rec.grid_len,
        fs_hz: rec.fs_hz,
        duration_s: rec.duration_s(),
        start_time_s: rec.start_time_s,
        velocity_mm_s: v,
        bearing: rec.bearing.clone(),
        position_velocity_mm_s,
        tau_c_s,
        periods,
        channels,
        missing,
        findings,
        gaps: Vec::new(),
        gap_count: 0,
        gap_samples: 0,
        notes: Vec::new(),
    }
}

/// Neumaier-compensated sum.
fn sum(values: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut c) = (0.0_f64, 0.0_f64);
    for x in values {
        let t = s + x;
        c += if s.abs() >= x.abs() {
            (s - t) + x
        } else {
            (x - t) + s
        };
        s = t;
    }
    s + c
}

/// A power of two near the largest magnitude of `x` (at most it), so that
/// `x / scale` lies within ±2 and its squares neither overflow nor vanish.
fn scale_of(largest: f64) -> f64 {
    if largest >= f64::MIN_POSITIVE && largest.is_finite() {
        f64::from_bits(largest.to_bits() & 0x7FF0_0000_0000_0000)
    } else {
        f64::MIN_POSITIVE
    }
}

fn summarise(rec: &View<'_>, c: Channel, x: &[f64], s: &InspectSettings) -> ChannelSummary {
    let ok = |v: &f64| v.is_finite();
    let valid: Vec<(f64, f64)> = x
        .iter()
        .enumerate()
        .filter(|(_, v)| ok(v))
        .map(|(i, &v)| (rec.pos(i) as f64, v))
        .collect();
    let n = valid.len() as f64;
    let min = valid.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let max = valid.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
    let k = scale_of(min.abs().max(max.abs()));
    // Moments of y = x / k, then scaled back.
    let my = sum(valid.iter().map(|p| p.1 / k)) / n;
    let std_y = (sum(valid.iter().map(|p| (p.1 / k - my).powi(2))) / n).sqrt();
    let (mean, std) = (my * k, std_y * k);
    // Least-squares line against the grid position (centred, so the sums stay small).
    let tm = sum(valid.iter().map(|p| p.0)) / n;
    let sxx = sum(valid.iter().map(|p| (p.0 - tm).powi(2)));
    let sxy = sum(valid.iter().map(|p| (p.0 - tm) * (p.1 / k - my)));
    let slope_y = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    let resid_y = (sum(valid
        .iter()
        .map(|p| (p.1 / k - my - slope_y * (p.0 - tm)).powi(2)))
        / n)
        .sqrt();
    let slope_per_s = slope_y * rec.fs_hz * k;
    let change_over_record = slope_y * rec.grid_len as f64 * k;
    let resid = resid_y * k;
    let mut clipped = 0;
    let mut longest_clip: Option<Run> = None;
    let mut dropouts = Vec::new();
    let mut i = 0;
    while i < x.len() {
        if !x[i].is_finite() {
            i += 1;
            continue;
        }
        let mut j = i + 1;
        while j < x.len() && x[j] == x[i] {
            j += 1;
        }
        let len = j - i;
        let run = Run {
            value: x[i],
            start: i,
            len,
            start_time_s: rec.time_s(i),
        };
        let at_rail = (x[i] == min || x[i] == max) && max > min;
        if at_rail && len >= s.clip_run {
            clipped += len;
            if longest_clip.is_none_or(|r| len > r.len) {
                longest_clip = Some(run);
            }
        } else if !at_rail && len >= s.dropout_run {
            dropouts.push(run);
        }
        i = j;
    }
    ChannelSummary {
        channel: c.column_name().into(),
        unit: c.unit().into(),
        min,
        max,
        mean,
        std,
        clipped_samples: clipped,
        longest_clip,
        dropouts,
        slope_per_s,
        change_over_record,
        detrended_std: resid,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::{Channels, Metadata};

    fn rec(f: Vec<f64>, p: Vec<f64>, o: Vec<f64>, v: Option<f64>) -> Recording {
        Recording::new(
            1000.0,
            Channels {
                friction_n: Some(f),
                position_mm: Some(p),
                optical_v: Some(o),
            },
            Metadata {
                velocity_mm_s: v,
                ..Default::default()
            },
        )
        .unwrap()
    }

    use crate::stats::test_noise::uniform as noise;

    #[test]
    fn clean_recording_has_no_warnings_and_right_velocity() {
        let n = 10_000;
        let f: Vec<f64> = noise(n, 1).iter().map(|e| 2.0 + 0.1 * e).collect();
        let p: Vec<f64> = (0..n).map(|i| 9.0 * i as f64 / 1000.0).collect();
        let o = noise(n, 2);
        let g = crate::bearing::lookup("sr25w").unwrap().geometry;
        let r = inspect(
            &rec(f, p, o, Some(9.0)),
            Some(&g),
            &InspectSettings::default(),
        );
        assert!(
            r.findings.iter().all(|f| f.severity == Severity::Info),
            "{:?}",
            r.findings
        );
        // An exact ramp: the fitted slope is 9 mm/s to rounding (1e-9 relative is
        // far above the ~1e-13 accumulated in the sums of 1e4 terms).
        assert!((r.position_velocity_mm_s.unwrap() - 9.0).abs() < 9e-9);
        // 10 s / 0.90123 s.
        assert!((r.periods.unwrap() - 10.0 / 0.901234567901).abs() < 1e-6);
        assert_eq!(r.channels[0].channel, "friction_N");
        assert!(r.missing.is_empty());
    }

    #[test]
    fn clipping_dropout_drift_and_velocity_mismatch_are_found() {
        let n = 10_000;
        // Friction drifts by 1 N over 10 s with 0.01 N noise.
        let f: Vec<f64> = noise(n, 3)
            .iter()
            .enumerate()
            .map(|(i, e)| 2.0 + 0.1 * i as f64 / 1000.0 + 0.01 * e)
            .collect();
        // Position at 8 mm/s (stated 9).
        let p: Vec<f64> = (0..n).map(|i| 8.0 * i as f64 / 1000.0).collect();
        // Optical clipped at 10 V for 50 samples, frozen at 0.123 for 100.
        let mut o = noise(n, 4);
        for v in &mut o[2000..2050] {
            *v = 10.0;
        }
        for v in &mut o[5000..5100] {
            *v = 0.123;
        }
        let r = inspect(&rec(f, p, o, Some(9.0)), None, &InspectSettings::default());
        let msgs: Vec<&str> = r.findings.iter().map(|f| f.message.as_str()).collect();
        assert!(
            msgs.iter()
                .any(|m| m.contains("clipped: 50 samples stuck at 10 V")),
            "{msgs:?}"
        );
        assert!(
            msgs.iter().any(|m| m.contains("1 dropout(s): 100 samples")),
            "{msgs:?}"
        );
        assert!(
            msgs.iter().any(|m| m.contains("load-cell DC drift: +")),
            "{msgs:?}"
        );
        // 0.1 N/s for 10 s; the 0.01 N noise moves the fitted change by ~1e-4 N.
        assert!((r.channels[0].change_over_record - 1.0).abs() < 1e-3);
        assert!(
            msgs.iter()
                .any(|m| m.contains("8.0000 mm/s") && m.contains("stated 9")),
            "{msgs:?}"
        );
        let o = &r.channels[2];
        assert_eq!(o.longest_clip.unwrap().start, 2000);
        assert_eq!(o.dropouts[0].start, 5000);
    }

    /// Issue 18, item 12: a channel alternating 1e308 and 1.7e308 has a
    /// finite mean and deviation (1.35e308 and 0.35e308), not inf.
    #[test]
    fn inspect_statistics_overflow() {
        let n = 1000;
        let big: Vec<f64> = (0..n)
            .map(|i| if i % 2 == 0 { 1e308 } else { 1.7e308 })
            .collect();
        let view = View {
            source: "big".into(),
            test_id: None,
            fs_hz: 1000.0,
            start_time_s: 0.0,
            grid_len: n,
            channels: vec![(Channel::Friction, &big)],
            grid: None,
            velocity_mm_s: None,
            bearing: None,
        };
        let r = inspect_view(&view, None, &InspectSettings::default());
        let c = &r.channels[0];
        // Scaling by a power of two is exact and the compensated sums of
        // 1000 terms are good to a few ulps: 1e-12 relative is ample.
        assert!((c.mean / 1.35e308 - 1.0).abs() < 1e-12, "{}", c.mean);
        assert!((c.std / 0.35e308 - 1.0).abs() < 1e-12, "{}", c.std);
        assert!(c.detrended_std.is_finite() && c.slope_per_s.is_finite());
        // Tiny values keep their deviation too (their squares would underflow).
        let tiny: Vec<f64> = (0..n)
            .map(|i| if i % 2 == 0 { 1e-300 } else { 3e-300 })
            .collect();
        let view = View {
            channels: vec![(Channel::Friction, &tiny)],
            ..view
        };
        let c = &inspect_view(&view, None, &InspectSettings::default()).channels[0];
        assert!((c.std / 1e-300 - 1.0).abs() < 1e-12, "{}", c.std);
    }

    /// Gaps are skipped by the statistics and positioned by the grid.
    #[test]
    fn statistics_skip_gaps_and_use_grid_positions() {
        // A ramp 0, 1, 2, ... with samples 3 and 4 missing from the grid and
        // sample 7 without a value: mean of the finite values, slope 1 per sample.
        let x = [0.0, 1.0, 2.0, 5.0, 6.0, f64::NAN, 8.0, 9.0];
        let grid = [0, 1, 2, 5, 6, 7, 8, 9];
        let view = View {
            source: "g".into(),
            test_id: None,
            fs_hz: 10.0,
            start_time_s: 0.0,
            grid_len: 10,
            channels: vec![(Channel::Position, &x)],
            grid: Some(&grid),
            velocity_mm_s: None,
            bearing: None,
        };
        let r = inspect_view(&view, None, &InspectSettings::default());
        let c = &r.channels[0];
        assert_eq!(c.min, 0.0);
        assert_eq!(c.max, 9.0);
        assert!((c.mean - 31.0 / 7.0).abs() < 1e-12);
        // 1 mm per sample at 10 Hz: 10 mm/s, exact to rounding.
        assert!((c.slope_per_s - 10.0).abs() < 1e-9, "{}", c.slope_per_s);
        assert!(c.detrended_std < 1e-12);
    }
}
