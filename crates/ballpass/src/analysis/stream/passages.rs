//! Ball passages of a streamed record, detected window by window
//! ([`WindowedPassages`]): a different method from the whole-record
//! detection ([`detect_passages`] on the record), documented in
//! docs/methods.md ("Passages of a streamed record").
//!
//! ```text
//! windows   W = max(300 s, 10 O) long, overlapping by O = 20 τ_c (predicted),
//!           stepping by W − O; the last one ends at the record's end
//! each      detect_passages on the window alone: its own period guide, noise,
//!           template, baseline, AC coupling and threshold, with the false
//!           detections allowed per record shared out over the windows
//! merge     a window keeps the passages whose centre lies in its core: from
//!           O/2 after its start (the first window: from the record's start)
//!           to O/2 before its end (the last: to the record's end)
//! summary   periods between consecutive kept passages, widths and their
//!           ratios, f_c from the regular periods: the same formulas as the
//!           whole-record detection, over all kept passages
//! ```
//!
//! A record no longer than one window is one window: the same passages as
//! the whole-record detection. Memory: one window of optical samples and
//! the detection's buffers of it, plus 40 bytes per passage kept (8 MB at
//! 24 hours at 9 mm/s).

use crate::analysis::passage::{detect_passages, Condition, Passage, PassageAnalysis, TrainStats};
use crate::analysis::PassageSettings;
use crate::error::{Error, Result};
use crate::recording::{Channels, Metadata, Recording};

/// Shortest window, s.
pub const MIN_WINDOW_S: f64 = 300.0;
/// Overlap of consecutive windows, in predicted ball-pass periods.
pub const OVERLAP_PERIODS: f64 = 20.0;
/// Windows at least this many overlaps long.
pub const WINDOW_OVERLAPS: f64 = 10.0;

/// One passage kept, in the few numbers the summary needs.
#[derive(Debug, Clone, Copy)]
struct Kept {
    time_s: f64,
    peak_time_s: f64,
    tau_p_s: f64,
    sigma_s: f64,
    amplitude_v: f64,
    polarity: i8,
    edge: bool,
    width_used: bool,
}

/// Passages detected window by window over a record given in pieces
/// (module docs).
pub struct WindowedPassages {
    name: String,
    fs: f64,
    start_time_s: f64,
    len: usize,
    window: usize,
    overlap: usize,
    settings: PassageSettings,
    buf: Vec<f64>,
    buf_start: usize,
    kept: Vec<Kept>,
    windows: usize,
    failed: Vec<String>,
    conditions: Vec<Condition>,
    first: Option<PassageAnalysis>,
}

impl WindowedPassages {
    /// Windows of `window_s` overlapping by `overlap_s` over a record of
    /// `len` samples at `fs` whose first sample is at `start_time_s`;
    /// `settings` as for [`detect_passages`] on the whole record (its
    /// false detections per record are shared out over the windows).
    pub fn new(
        name: &str,
        fs: f64,
        start_time_s: f64,
        len: usize,
        (window_s, overlap_s): (f64, f64),
        settings: &PassageSettings,
    ) -> Self {
        let window = ((window_s * fs).round() as usize).max(2);
        let overlap = ((overlap_s * fs).round() as usize).min(window / 2);
        let step = window - overlap;
        let windows = if len <= window {
            1
        } else {
            (len - window).div_ceil(step) + 1
        };
        let settings = PassageSettings {
            false_detections_per_record: settings.false_detections_per_record / windows as f64,
            ..settings.clone()
        };
        WindowedPassages {
            name: name.into(),
            fs,
            start_time_s,
            len,
            window,
            overlap,
            settings,
            buf: Vec::new(),
            buf_start: 0,
            kept: Vec::new(),
            windows: 0,
            failed: Vec::new(),
            conditions: Vec::new(),
            first: None,
        }
    }

    /// The window and overlap a streamed analysis uses for a predicted
    /// ball-pass period `tau_c_s`, s.
    pub fn sizes(tau_c_s: f64) -> (f64, f64) {
        let overlap = OVERLAP_PERIODS * tau_c_s;
        (MIN_WINDOW_S.max(WINDOW_OVERLAPS * overlap), overlap)
    }

    /// The next optical samples.
    pub fn push(&mut self, x: &[f64]) -> Result<()> {
        self.buf.extend_from_slice(x);
        let step = self.window - self.overlap;
        while self.buf.len() >= self.window && self.buf_start + self.window < self.len {
            let w: Vec<f64> = self.buf[..self.window].to_vec();
            self.detect(w, false)?;
            self.buf.drain(..step);
            self.buf_start += step;
        }
        Ok(())
    }

    /// Detects the passages of the window starting at `buf_start`.
    fn detect(&mut self, x: Vec<f64>, last: bool) -> Result<()> {
        let n = x.len();
        let t0 = self.start_time_s + self.buf_start as f64 / self.fs;
        let lo = if self.buf_start == 0 {
            f64::NEG_INFINITY
        } else {
            t0 + (self.overlap / 2) as f64 / self.fs
        };
        let hi = if last {
            f64::INFINITY
        } else {
            t0 + (n - self.overlap / 2) as f64 / self.fs
        };
        self.windows += 1;
        let rec = Recording::new(
            self.fs,
            Channels {
                optical_v: Some(x),
                ..Channels::default()
            },
            Metadata {
                start_time_s: t0,
                test_id: Some(self.name.clone()),
                ..Metadata::default()
            },
        )?;
        match detect_passages(&rec, &self.settings) {
            Ok(a) => {
                for p in &a.passages {
                    if p.time_s >= lo && p.time_s < hi {
                        self.kept.push(Kept {
                            time_s: p.time_s,
                            peak_time_s: p.peak_time_s,
                            tau_p_s: p.tau_p_s,
                            sigma_s: p.sigma_s,
                            amplitude_v: p.amplitude_v,
                            polarity: p.polarity,
                            edge: p.edge,
                            width_used: p.width_used,
                        });
                    }
                }
                for c in &a.conditions {
                    if !self.conditions.iter().any(|d| d.kind == c.kind) {
                        self.conditions.push(c.clone());
                    }
                }
                if self.first.is_none() {
                    self.first = Some(a);
                }
            }
            Err(e @ Error::NoPassages { .. }) => {
                self.failed.push(format!(
                    "{:.1}–{:.1} s: {e}",
                    t0 - self.start_time_s,
                    t0 - self.start_time_s + n as f64 / self.fs
                ));
            }
            Err(e) => return Err(e),
        }
        Ok(())
    }

    /// Ends the record: the last window, then the merged passages as one
    /// analysis (the first window's detection settings and noise, the
    /// passages, their statistics and the conditions of every window).
    ///
    /// # Errors
    /// [`Error::NoPassages`] when no window gave two passages; a window's
    /// other errors.
    pub fn finish(mut self) -> Result<(PassageAnalysis, Windows)> {
        if !self.buf.is_empty() || self.windows == 0 {
            // The last window: from where the previous one stepped to (its
            // overlap included) to the record's end.
            let x = std::mem::take(&mut self.buf);
            self.detect(x, true)?;
        }
        let windows = Windows {
            count: self.windows,
            window_s: self.window as f64 / self.fs,
            overlap_s: self.overlap as f64 / self.fs,
            failed: self.failed.clone(),
        };
        let no = |reason: String| Error::NoPassages {
            source_name: self.name.clone(),
            reason,
        };
        let Some(mut a) = self.first.take() else {
            return Err(no(format!(
                "no window of {:.0} s held passages ({})",
                windows.window_s,
                windows.failed.join("; ")
            )));
        };
        let k = &self.kept;
        let times: Vec<f64> = k.iter().map(|p| p.time_s).collect();
        let v = a.velocity_mm_s;
        a.passages = k
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let tau_c = times.get(i + 1).map(|t| t - times[i]);
                Passage {
                    index: i,
                    time_s: p.time_s,
                    peak_time_s: p.peak_time_s,
                    polarity: p.polarity,
                    tau_c_s: tau_c,
                    tau_p_s: p.tau_p_s,
                    sigma_s: p.sigma_s,
                    amplitude_v: p.amplitude_v,
                    height_v: p.amplitude_v,
                    tau_p_over_tau_c: tau_c.map(|t| p.tau_p_s / t),
                    spacing_mm: tau_c.zip(v).map(|(t, v)| v * t / 2.0),
                    edge: p.edge,
                    width_used: p.width_used,
                }
            })
            .collect();
        a.source = self.name.clone();
        a.duration_s = self.len as f64 / self.fs;
        a.count = a.passages.len();
        a.count_inverted = a.passages.iter().filter(|p| p.polarity < 0).count();
        // The whole-record detection's statistics (passage::detect_passages).
        let stats = TrainStats::of(&a.passages)
            .ok_or_else(|| no("no period between the passages of the windows".into()))?;
        let tau_c_stats = stats.tau_c;
        a.tau_c_s = tau_c_stats;
        a.tau_p_s = stats.tau_p;
        a.sigma_s = stats.sigma;
        a.tau_p_over_tau_c = stats.tau_p_over_tau_c;
        a.amplitude_v = stats.amplitude;
        a.f_c_measured_hz = 1.0 / tau_c_stats.mean;
        a.f_c_relative_error = a.f_c_predicted_hz.map(|p| (a.f_c_measured_hz - p) / p);
        a.d_avg_implied_mm = v.map(|v| v * tau_c_stats.mean / 2.0);
        a.spacing = None;
        a.fits = None;
        a.baseline_v = Vec::new();
        a.conditions = std::mem::take(&mut self.conditions);
        Ok((a, windows))
    }
}

/// How a record's passages were windowed.
#[derive(Debug, Clone, PartialEq)]
pub struct Windows {
    /// Windows detected.
    pub count: usize,
    /// Window length, s.
    pub window_s: f64,
    /// Overlap, s.
    pub overlap_s: f64,
    /// Windows without passages, with why.
    pub failed: Vec<String>,
}

/// What [`StreamPassages::finish`] gives: the passage times (or why
/// there are none), the summary, the method note.
pub(super) type Found = (
    std::result::Result<Vec<f64>, String>,
    crate::analysis::PassageSummary,
    Option<String>,
);

/// The passages of a streamed analysis: its windows fed from the blocks of
/// one pass, a read error kept for the end.
pub(super) struct StreamPassages {
    inner: Option<WindowedPassages>,
    error: Option<Error>,
}

impl StreamPassages {
    /// For a record with an optical channel; `None` inside without one.
    pub(super) fn new(
        name: &str,
        fs: f64,
        start_time_s: f64,
        len: usize,
        pred: &crate::bearing::Prediction,
        optical: bool,
    ) -> Self {
        let settings = PassageSettings {
            velocity_mm_s: Some(pred.velocity_mm_s),
            fit_pulses: 0,
            ..PassageSettings::default()
        };
        StreamPassages {
            inner: optical.then(|| {
                WindowedPassages::new(
                    name,
                    fs,
                    start_time_s,
                    len,
                    WindowedPassages::sizes(pred.tau_c_s),
                    &settings,
                )
            }),
            error: None,
        }
    }

    pub(super) fn push(&mut self, b: crate::recording::stream::Block<'_>) {
        if let (Some(w), None, Some(x)) = (self.inner.as_mut(), &self.error, b.optical_v) {
            if let Err(e) = w.push(x) {
                self.error = Some(e);
            }
        }
    }

    /// The summary (as the in-memory analysis gives it), the method note
    /// and the passage times (s, the record's clock) or why there are none;
    /// `None` without an optical channel.
    pub(super) fn finish(self, name: &str) -> Option<Found> {
        let w = self.inner?;
        let empty = |note: String| crate::analysis::PassageSummary::without(name.into(), note);
        let r = match self.error {
            Some(e) => Err(e),
            None => w.finish(),
        };
        Some(match r {
            Ok((p, win)) => (
                Ok(p.passages.iter().map(|q| q.time_s).collect()),
                crate::analysis::PassageSummary::of(name.into(), &p),
                Some(format!(
                    "passages of the streamed record detected window by window ({} windows of \
                     {:.0} s overlapping by {:.1} s, each with its own template, baseline and \
                     threshold; merged by centre time){}",
                    win.count,
                    win.window_s,
                    win.overlap_s,
                    if win.failed.is_empty() {
                        String::new()
                    } else {
                        format!(
                            "; {} window(s) without passages: {}",
                            win.failed.len(),
                            win.failed.join("; ")
                        )
                    }
                )),
            ),
            Err(e) => (Err(e.to_string()), empty(e.to_string()), None),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::{analyze, AnalyzeSettings, MaxLag};
    use crate::bearing::lookup;
    use crate::recording::stream::RecordingSource;
    use crate::recording::Channel;

    fn record(seed: u64, duration_s: f64) -> Recording {
        crate::sim::test_record(seed, duration_s)
    }

    #[test]
    fn a_record_of_one_window_gives_the_in_memory_passages() {
        let rec = record(4, 40.0);
        let settings = AnalyzeSettings {
            max_lag: MaxLag::Seconds(5.0),
            ..Default::default()
        };
        let pred = lookup("sr25w")
            .unwrap()
            .geometry
            .predict(9.0, settings.harmonics)
            .unwrap();
        let mem = analyze(std::slice::from_ref(&rec), &pred, &settings).unwrap();
        let mut src = RecordingSource::new(&rec, 999);
        let st = super::super::analyze_stream(&mut src, &pred, &settings, &mut |_| {}).unwrap();
        assert!(mem.passages[0].count.unwrap() > 10);
        // One window holds the whole record: the same detection.
        assert_eq!(
            serde_json::to_string(&mem.passages).unwrap(),
            serde_json::to_string(&st.passages).unwrap()
        );
        let not = &st.stream.as_ref().unwrap().not_computed;
        assert!(not.iter().all(|s| !s.contains("passages")), "{not:?}");
    }

    #[test]
    fn windows_merge_without_doubles_or_gaps() {
        // 120 s cut into windows of 20 s overlapping by 5 periods: each
        // join crossed by passages.
        let rec = record(9, 120.0);
        let pred = lookup("sr25w").unwrap().geometry.predict(9.0, 1).unwrap();
        let settings = PassageSettings {
            velocity_mm_s: Some(9.0),
            fit_pulses: 0,
            ..PassageSettings::default()
        };
        let whole = detect_passages(&rec, &settings).unwrap();
        let mut w = WindowedPassages::new(
            "test",
            rec.fs_hz(),
            0.0,
            rec.len(),
            (20.0, 5.0 * pred.tau_c_s),
            &settings,
        );
        for c in rec.channel(Channel::Optical).unwrap().chunks(777) {
            w.push(c).unwrap();
        }
        let (a, win) = w.finish().unwrap();
        assert!(win.count >= 6, "{win:?}");
        // No passage twice (a double would make a period near 0) and none
        // lost at a join (a gap would make one near 2 τ_c): every period
        // within the whole-record detection's range.
        let periods: Vec<f64> = a.passages.iter().filter_map(|p| p.tau_c_s).collect();
        let lo = whole
            .passages
            .iter()
            .filter_map(|p| p.tau_c_s)
            .fold(f64::INFINITY, f64::min);
        let hi = whole
            .passages
            .iter()
            .filter_map(|p| p.tau_c_s)
            .fold(0.0, f64::max);
        let (plo, phi) = periods
            .iter()
            .fold((f64::INFINITY, 0.0_f64), |(a, b), &t| (a.min(t), b.max(t)));
        assert!(
            plo >= 0.9 * lo && phi <= 1.1 * hi,
            "{plo} {phi} vs {lo} {hi}"
        );
        assert_eq!(
            a.count, whole.count,
            "windowed {} whole {}",
            a.count, whole.count
        );
        let dw = (a.tau_p_s.mean / whole.tau_p_s.mean - 1.0).abs();
        assert!(dw < 0.02, "widths differ by {dw}");
    }
}
