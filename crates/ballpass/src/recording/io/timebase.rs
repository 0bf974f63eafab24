//! Sampling rate from a time column, and the uniform-sampling check.
//!
//! A time column `t[0..n]` is accepted when every step `t[i] - t[i-1]` is
//! positive and close to the median step `h`:
//!
//! ```text
//! |t[i] - t[i-1] - h| <= tol * h + min(2 r, h / 2)       (tol = 1e-3 by default)
//! r = (half a unit of the last printed digit of the time column) + 4 eps max|t|
//! ```
//!
//! The `2 r` term lets through the rounding of a printed time (3 kHz printed
//! with 4 decimals steps by 0.0003 and 0.0004); it is capped at half a step so
//! that a missing sample (a step of `2 h`) is always caught.
//!
//! When gaps are allowed, a step of `k h` (k >= 2, within `k tol h + min(2 r,
//! h / 2)`) is a gap of `k - 1` missing samples rather than an error.
//!
//! The rate is then taken from the whole span, which is more accurate than the
//! median step by a factor `m` (the steps of the uniform grid, `n - 1` plus
//! the missing samples):
//!
//! ```text
//! fs = m / (t[n-1] - t[0])
//! ```
//!
//! snapped to the decimal with the fewest significant digits whose span
//! `(n - 1) / fs` is within `2 r` of the observed span: a column printed from
//! `i / 1000` gives exactly `1000.0`, not `999.9999999999999`.

/// Default largest relative deviation of one step from the median step.
pub const DEFAULT_STEP_TOLERANCE: f64 = 1e-3;

/// What a valid time column gives.
#[derive(Debug, Clone, PartialEq)]
pub struct Timebase {
    /// Sampling rate, Hz.
    pub fs_hz: f64,
    /// Time of the first sample, s.
    pub start_time_s: f64,
    /// Median step, s; the mean step when every step is within the tolerance
    /// of the smallest (it then differs from the median by less than the
    /// tolerance, and finding the median is skipped).
    pub median_step_s: f64,
    /// Missing samples (only when gaps are allowed), in time order.
    pub gaps: Vec<TimeGap>,
}

/// Samples missing from a time column: the step before `index` spans
/// `missing + 1` sampling periods.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TimeGap {
    /// 0-based index of the time stamp after the gap.
    pub index: usize,
    /// Samples missing before it.
    pub missing: usize,
}

impl Timebase {
    /// Steps of the uniform grid from the first to the last time stamp.
    pub fn grid_steps(&self, n: usize) -> usize {
        self.gaps
            .iter()
            .fold(n.saturating_sub(1), |a, g| a.saturating_add(g.missing))
    }
}

/// Where a time column is wrong and how.
#[derive(Debug, Clone, PartialEq)]
pub struct TimeError {
    /// 0-based index of the offending sample.
    pub index: usize,
    /// What was found and what was expected.
    pub reason: String,
}

fn err(index: usize, reason: String) -> TimeError {
    TimeError { index, reason }
}

fn rounding(times: &[f64], resolution: f64) -> f64 {
    let tmax = times.iter().fold(0.0_f64, |m, t| m.max(t.abs()));
    resolution.max(0.0) + 4.0 * f64::EPSILON * tmax
}

/// Checks that `times` is uniformly sampled and derives the rate.
///
/// `resolution` is half a unit of the last printed digit of the times
/// (0 for binary data); `step_tolerance` is relative to the median step.
///
/// With `allow_gaps`, a step of a whole number of median steps is a gap
/// (listed in [`Timebase::gaps`]) instead of an error.
///
/// # Errors
/// A [`TimeError`] at the first sample whose step is not positive (duplicate
/// or decreasing time) or deviates from the median step beyond tolerance,
/// or at sample 0 for fewer than two times or a non-finite one.
pub fn derive(
    times: &[f64],
    resolution: f64,
    step_tolerance: f64,
    allow_gaps: bool,
) -> Result<Timebase, TimeError> {
    let n = times.len();
    if n < 2 {
        return Err(err(
            0,
            format!("{n} time stamp(s); at least 2 are needed to know the sampling rate"),
        ));
    }
    if let Some(i) = times.iter().position(|t| !t.is_finite()) {
        return Err(err(i, format!("time {} is not a finite number", times[i])));
    }
    // One pass: every step positive, and the smallest and largest step.
    let (mut dmin, mut dmax) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 1..n {
        let d = times[i] - times[i - 1];
        if d <= 0.0 {
            let r = rounding(times, resolution);
            return Err(if d == 0.0 {
                err(
                    i,
                    format!(
                        "duplicate time stamp {} (same as the row before); expected increasing time{}",
                        times[i],
                        coarse_hint(r, times)
                    ),
                )
            } else {
                err(
                    i,
                    format!(
                        "time goes backwards from {} to {}; expected increasing time",
                        times[i - 1],
                        times[i]
                    ),
                )
            });
        }
        dmin = dmin.min(d);
        dmax = dmax.max(d);
    }
    // Increasing: the largest magnitude is at an end.
    let r = resolution.max(0.0) + 4.0 * f64::EPSILON * times[0].abs().max(times[n - 1].abs());
    let span = times[n - 1] - times[0];
    // Every step within the tolerance of the smallest: every step is within
    // the tolerance of the median too (it lies between them, and the
    // tolerance grows with the step), so the grid is uniform and the median
    // need not be found.
    if let Some(base) = uniform(
        times[0],
        times[n - 1],
        n,
        (dmin, dmax),
        resolution,
        step_tolerance,
    ) {
        return Ok(base);
    }
    let mut steps: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    let mid = steps.len() / 2;
    let h = *steps.select_nth_unstable_by(mid, f64::total_cmp).1;
    let slack = (2.0 * r).min(0.5 * h);
    let tol = step_tolerance * h + slack;
    let mut gaps = Vec::new();
    for i in 1..n {
        let d = times[i] - times[i - 1];
        if (d - h).abs() > tol {
            let k = (d / h).round();
            let whole = k >= 2.0 && (d - k * h).abs() <= step_tolerance * k * h + slack;
            if whole && allow_gaps && k < 1e12 {
                gaps.push(TimeGap {
                    index: i,
                    missing: k as usize - 1,
                });
                continue;
            }
            let hint = if whole {
                format!(" ({} sample(s) missing?)", k - 1.0)
            } else {
                String::new()
            };
            return Err(err(
                i,
                format!(
                    "time step {d} s (from {} to {}) differs from the median step {h} s \
                     by more than {tol:.3e} s: sampling is not uniform{hint}",
                    times[i - 1],
                    times[i]
                ),
            ));
        }
    }
    let steps_n = gaps.iter().fold(n - 1, |a, g| a.saturating_add(g.missing)) as f64;
    let fs_raw = steps_n / span;
    let fs_hz = snap(fs_raw, |fs| (steps_n / fs - span).abs() <= 2.0 * r);
    Ok(Timebase {
        fs_hz,
        start_time_s: times[0],
        median_step_s: h,
        gaps,
    })
}

/// The fast path of [`derive()`] for a time column known by its first and
/// last stamps, its length `n >= 2` and its smallest and largest step
/// (all positive): the timebase when every step is within the tolerance
/// of the smallest, else `None` (the column needs [`derive()`] itself).
/// What a column read in pieces can check without holding it.
pub fn uniform(
    first: f64,
    last: f64,
    n: usize,
    (dmin, dmax): (f64, f64),
    resolution: f64,
    step_tolerance: f64,
) -> Option<Timebase> {
    // Increasing: the largest magnitude is at an end.
    let r = resolution.max(0.0) + 4.0 * f64::EPSILON * first.abs().max(last.abs());
    let span = last - first;
    if n < 2
        || dmin.is_nan()
        || dmin <= 0.0
        || dmax - dmin > step_tolerance * dmin + (2.0 * r).min(0.5 * dmin)
    {
        return None;
    }
    let steps_n = (n - 1) as f64;
    let fs_hz = snap(steps_n / span, |fs| (steps_n / fs - span).abs() <= 2.0 * r);
    Some(Timebase {
        fs_hz,
        start_time_s: first,
        median_step_s: span / steps_n,
        gaps: Vec::new(),
    })
}

/// A time column's steps scanned piece by piece, for [`uniform`]: what a
/// streamed reader checks without holding the column.
#[derive(Debug, Clone)]
pub(crate) struct Steps {
    /// Stamps seen.
    pub n: usize,
    first: f64,
    prev: f64,
    dmin: f64,
    dmax: f64,
    /// A step not positive, or a stamp not finite.
    pub broken: bool,
}

impl Default for Steps {
    fn default() -> Self {
        Self {
            n: 0,
            first: 0.0,
            prev: 0.0,
            dmin: f64::INFINITY,
            dmax: f64::NEG_INFINITY,
            broken: false,
        }
    }
}

impl Steps {
    /// Takes the next stamps (in seconds); stops at the first broken one.
    pub fn extend(&mut self, times: impl IntoIterator<Item = f64>) {
        if self.broken {
            return;
        }
        for v in times {
            if !v.is_finite() {
                self.broken = true;
                return;
            }
            if self.n > 0 {
                let d = v - self.prev;
                if d <= 0.0 {
                    self.broken = true;
                    return;
                }
                self.dmin = self.dmin.min(d);
                self.dmax = self.dmax.max(d);
            } else {
                self.first = v;
            }
            self.prev = v;
            self.n += 1;
        }
    }

    /// The timebase [`derive`] gives the whole column when it is uniform
    /// (the same to the bit), else `None`.
    pub fn uniform(&self, resolution: f64, step_tolerance: f64) -> Option<Timebase> {
        if self.broken {
            return None;
        }
        uniform(
            self.first,
            self.prev,
            self.n,
            (self.dmin, self.dmax),
            resolution,
            step_tolerance,
        )
    }
}

/// Checks a given rate against a uniform time column of `steps` grid steps
/// (`n - 1` without gaps): over the whole span the two may differ by less
/// than one sample.
///
/// # Errors
/// A [`TimeError`] at the last sample saying both rates.
pub fn check_given_rate(
    times: &[f64],
    resolution: f64,
    fs_hz: f64,
    steps: usize,
) -> Result<(), TimeError> {
    let n = times.len();
    if n < 2 {
        return Ok(());
    }
    let span = times[n - 1] - times[0];
    let expected = steps as f64 / fs_hz;
    let r = rounding(times, resolution);
    let apart = (expected - span).abs() * fs_hz;
    if (expected - span).abs() > 2.0 * r + 0.5 / fs_hz {
        return Err(err(
            n - 1,
            format!(
                "given sampling rate {fs_hz} Hz disagrees with the time column, which spans \
                 {span} s over {steps} steps ({} Hz): {apart:.1} samples apart by the end",
                steps as f64 / span
            ),
        ));
    }
    Ok(())
}

fn coarse_hint(r: f64, times: &[f64]) -> String {
    let n = times.len();
    let h = (times[n - 1] - times[0]) / (n - 1) as f64;
    if 2.0 * r >= 0.5 * h.abs() {
        " (the time column seems printed with too few digits for its rate: give the \
         sampling rate and ignore the time column)"
            .into()
    } else {
        String::new()
    }
}

/// The decimal with the fewest significant digits near `x` that `ok` accepts;
/// `x` itself when none with up to 17 digits is.
fn snap(x: f64, ok: impl Fn(f64) -> bool) -> f64 {
    for digits in 1..=17 {
        let s = format!("{:.*e}", digits - 1, x);
        if let Ok(c) = s.parse::<f64>() {
            if c > 0.0 && ok(c) {
                return c;
            }
        }
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: usize, t0: f64, fs: f64) -> Vec<f64> {
        (0..n).map(|i| t0 + i as f64 / fs).collect()
    }

    #[test]
    fn exact_grid_gives_exact_rate() {
        for (fs, t0) in [(1000.0, 0.0), (1234.5, 12.5), (2500.0, -3.0), (1.0, 0.0)] {
            let b = derive(&grid(30_000, t0, fs), 0.0, DEFAULT_STEP_TOLERANCE, false).unwrap();
            assert_eq!(b.fs_hz.to_bits(), fs.to_bits(), "fs {fs}");
            assert_eq!(b.start_time_s, t0);
        }
    }

    #[test]
    fn printed_rounding_is_tolerated_but_a_missing_sample_is_not() {
        // 3 kHz printed with 4 decimals: steps of 0.0003 and 0.0004.
        let t: Vec<f64> = grid(3000, 0.0, 3000.0)
            .iter()
            .map(|x| (x * 1e4).round() / 1e4)
            .collect();
        let b = derive(&t, 0.5e-4, DEFAULT_STEP_TOLERANCE, false).unwrap();
        // The span is 0.9997 printed (0.99966... true): the rate is known to
        // within 2 r / span = 1e-4 relative, and 3000 is the shortest decimal there.
        assert_eq!(b.fs_hz, 3000.0);
        // 1 kHz printed with 3 decimals, sample 500 missing.
        let mut t: Vec<f64> = grid(1000, 0.0, 1000.0);
        t.remove(500);
        let e = derive(&t, 0.5e-3, DEFAULT_STEP_TOLERANCE, false).unwrap_err();
        assert_eq!(e.index, 500);
        assert!(e.reason.contains("1 sample(s) missing"), "{}", e.reason);
        // Allowed, it is a gap and the rate counts the missing sample.
        let b = derive(&t, 0.5e-3, DEFAULT_STEP_TOLERANCE, true).unwrap();
        assert_eq!(
            b.gaps,
            vec![TimeGap {
                index: 500,
                missing: 1
            }]
        );
        assert_eq!(b.fs_hz, 1000.0);
        assert_eq!(b.grid_steps(t.len()), 999);
    }

    #[test]
    fn duplicate_and_decreasing_times_name_the_sample() {
        let mut t = grid(100, 0.0, 1000.0);
        t[40] = t[39];
        let e = derive(&t, 0.0, DEFAULT_STEP_TOLERANCE, false).unwrap_err();
        assert_eq!(e.index, 40);
        assert!(e.reason.contains("duplicate"), "{}", e.reason);
        let mut t = grid(100, 0.0, 1000.0);
        t.swap(60, 61);
        let e = derive(&t, 0.0, DEFAULT_STEP_TOLERANCE, false).unwrap_err();
        assert_eq!(e.index, 61);
        assert!(e.reason.contains("backwards"), "{}", e.reason);
    }

    #[test]
    fn jitter_beyond_tolerance_is_rejected() {
        let mut t = grid(100, 0.0, 1000.0);
        // 2e-3 of a step off: over the 1e-3 tolerance, far above float rounding.
        t[70] += 2e-6;
        let e = derive(&t, 0.0, DEFAULT_STEP_TOLERANCE, false).unwrap_err();
        assert_eq!(e.index, 70);
        // 0.5e-3 of a step: within tolerance.
        let mut t = grid(100, 0.0, 1000.0);
        t[70] += 0.5e-6;
        assert!(derive(&t, 0.0, DEFAULT_STEP_TOLERANCE, false).is_ok());
    }

    #[test]
    fn steps_spread_beyond_the_fast_check_are_still_judged_against_the_median() {
        // Sample 30 late by 0.9e-3 of a step: steps 30 and 31 differ by
        // 1.8e-3 (beyond the shortcut that skips the median), yet each is
        // within the 1e-3 tolerance of the median step: accepted.
        let mut t = grid(1000, 0.0, 1000.0);
        t[30] += 0.9e-6;
        let b = derive(&t, 0.0, DEFAULT_STEP_TOLERANCE, false).unwrap();
        assert_eq!(b.fs_hz, 1000.0);
        assert!(
            (b.median_step_s - 1e-3).abs() < 1e-15,
            "{}",
            b.median_step_s
        );
        // (1e-15: a step is a difference of times below 1 s, exact to ~1e-16.)
        // 0.3e-3: the shortcut; the same rate, the mean step.
        let mut t = grid(1000, 0.0, 1000.0);
        t[30] += 0.3e-6;
        let b = derive(&t, 0.0, DEFAULT_STEP_TOLERANCE, false).unwrap();
        assert_eq!(b.fs_hz, 1000.0);
        // Mean step 0.999/999 s: equal to 1e-3 within float rounding.
        assert!(
            (b.median_step_s - 1e-3).abs() < 1e-15,
            "{}",
            b.median_step_s
        );
    }

    #[test]
    fn given_rate_must_agree_within_a_sample() {
        let t = grid(30_000, 0.0, 1000.0);
        assert!(check_given_rate(&t, 0.0, 1000.0, t.len() - 1).is_ok());
        // 1000.01 Hz drifts 0.3 samples over 30 s: accepted.
        assert!(check_given_rate(&t, 0.0, 1000.01, t.len() - 1).is_ok());
        let e = check_given_rate(&t, 0.0, 1001.0, t.len() - 1).unwrap_err();
        assert!(e.reason.contains("1001 Hz"), "{}", e.reason);
    }
}
