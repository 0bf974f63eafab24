//! Sticking events: friction spikes far above a bearing's robust level, and
//! whether they come at ball-pass multiples (thesis ch. 8, Fig. 66).
//!
//! ```text
//! baseline  = linear interpolation of block medians (blocks of tau_c / 2)
//! residual  = friction − baseline               (removes load-cell drift)
//! level     = 1.4826 · median(|residual − median(residual)|)   (robust σ)
//! event     = local maximum of residual with residual > spike_factor · level,
//!             at least min_separation · tau_c after the previous event
//! timing    = fraction of intervals between successive events within
//!             ±tolerance · tau_c of a whole number of periods
//! ```
//!
//! Random spikes would give a timing fraction of about `2 · tolerance` (0.4
//! with the default 0.2); spikes caused by the balls give close to 1.

use serde::{Deserialize, Serialize};

use ballpass_dsp::{find_peaks, Bound, FindPeaksSettings};

use crate::error::{Error, Result};
use crate::stats::{median_with, robust_sigma_with};

/// Settings of the sticking-event detector.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StickingSettings {
    /// A spike counts when it stands this many robust σ above the baseline.
    pub spike_factor: f64,
    /// Fewest ball periods between two counted spikes.
    pub min_separation_periods: f64,
    /// Half-width of the window around whole periods, in periods.
    pub timing_tolerance_periods: f64,
}

impl Default for StickingSettings {
    fn default() -> Self {
        Self {
            spike_factor: 8.0,
            min_separation_periods: 0.5,
            timing_tolerance_periods: 0.2,
        }
    }
}

/// Sticking events of one record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StickingEvents {
    /// Robust level (σ) of the friction about its baseline, N.
    pub robust_level_n: f64,
    /// Threshold used, N above the baseline.
    pub threshold_n: f64,
    /// Times of the events, s from the record start.
    pub times_s: Vec<f64>,
    /// Heights above the baseline, N.
    pub heights_n: Vec<f64>,
    /// Largest height over the robust level.
    pub max_height_over_level: Option<f64>,
    /// Events per second.
    pub rate_per_s: f64,
    /// Fraction of intervals that are whole numbers of ball periods
    /// (`None` with fewer than two events).
    pub timing_fraction: Option<f64>,
}

/// Finds the sticking events of a friction record.
///
/// # Errors
/// [`Error::InvalidSetting`] for a non-positive period, rate or setting;
/// [`Error::Dsp`] if the peak finder rejects the signal (non-finite samples).
pub fn sticking_events(
    friction_n: &[f64],
    fs_hz: f64,
    tau_c_s: f64,
    settings: &StickingSettings,
) -> Result<StickingEvents> {
    for (name, v) in [
        ("tau_c", tau_c_s),
        ("fs", fs_hz),
        ("spike factor", settings.spike_factor),
        ("min separation", settings.min_separation_periods),
        ("timing tolerance", settings.timing_tolerance_periods),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::setting(
                name,
                format!("must be a positive number, got {v}"),
            ));
        }
    }
    let n = friction_n.len();
    let block = ((tau_c_s * fs_hz / 2.0).round() as usize).max(8);
    let residual = detrend_by_block_medians(friction_n, block);
    let level = robust_sigma_with(&residual, &mut Vec::new()).unwrap_or(0.0);
    let threshold = settings.spike_factor * level;
    let distance = (settings.min_separation_periods * tau_c_s * fs_hz).max(1.0);
    let found = find_peaks(
        &residual,
        &FindPeaksSettings {
            height: Some(Bound::at_least(threshold.max(f64::MIN_POSITIVE))),
            distance: Some(distance),
            ..Default::default()
        },
    )
    .map_err(|e| Error::dsp("sticking events", e))?;
    let times_s: Vec<f64> = found.indices.iter().map(|&i| i as f64 / fs_hz).collect();
    let heights_n: Vec<f64> = found.indices.iter().map(|&i| residual[i]).collect();
    let timing_fraction = (times_s.len() >= 2).then(|| {
        let near = times_s
            .windows(2)
            .filter(|w| {
                let k = (w[1] - w[0]) / tau_c_s;
                (k - k.round()).abs() <= settings.timing_tolerance_periods && k.round() >= 1.0
            })
            .count();
        near as f64 / (times_s.len() - 1) as f64
    });
    let max_height_over_level = (level > 0.0)
        .then(|| heights_n.iter().copied().fold(f64::NEG_INFINITY, f64::max) / level)
        .filter(|v| v.is_finite());
    Ok(StickingEvents {
        robust_level_n: level,
        threshold_n: threshold,
        rate_per_s: times_s.len() as f64 / (n as f64 / fs_hz),
        times_s,
        heights_n,
        max_height_over_level,
        timing_fraction,
    })
}

/// `x` minus a baseline made of the medians of consecutive blocks of `block`
/// samples, linearly interpolated between block centres (robust to spikes,
/// follows the load cell's slow drift).
fn detrend_by_block_medians(x: &[f64], block: usize) -> Vec<f64> {
    let n = x.len();
    let mut scratch = Vec::with_capacity(block);
    let centres_and_medians: Vec<(f64, f64)> = x
        .chunks(block)
        .enumerate()
        .map(|(b, c)| {
            let centre = (b * block) as f64 + (c.len() as f64 - 1.0) / 2.0;
            (centre, median_with(c, &mut scratch).unwrap_or(0.0))
        })
        .collect();
    let mut out = Vec::with_capacity(n);
    let mut j = 0;
    for (i, &v) in x.iter().enumerate() {
        let t = i as f64;
        while j + 1 < centres_and_medians.len() && centres_and_medians[j + 1].0 <= t {
            j += 1;
        }
        let (c0, m0) = centres_and_medians[j];
        let base = match centres_and_medians.get(j + 1) {
            Some(&(c1, m1)) if t >= c0 => m0 + (m1 - m0) * (t - c0) / (c1 - c0),
            _ => m0,
        };
        out.push(v - base);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn noise(n: usize, seed: u64) -> Vec<f64> {
        // splitmix64 → two uniforms → Box–Muller; fixed seed.
        let mut s = seed;
        let mut next = || {
            s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = s;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| {
                let (u, v) = (next().max(1e-300), next());
                (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
            })
            .collect()
    }

    /// The selection median and robust σ (`crate::stats`, by order keys)
    /// equal the sorting ones bit for bit (odd and even counts, ties, NaN
    /// and infinities dropped, signed zeros, empty input).
    #[test]
    fn selection_median_equals_the_sorting_median() {
        fn sorting_median(x: &[f64]) -> Option<f64> {
            let mut v: Vec<f64> = x.iter().copied().filter(|x| x.is_finite()).collect();
            v.sort_by(f64::total_cmp);
            let n = v.len();
            (n > 0).then(|| {
                if n % 2 == 1 {
                    v[n / 2]
                } else {
                    0.5 * (v[n / 2 - 1] + v[n / 2])
                }
            })
        }
        let mut scratch = Vec::new();
        let mut cases: Vec<Vec<f64>> = vec![
            vec![],
            vec![f64::NAN],
            vec![1.0],
            vec![2.0, 1.0],
            vec![0.0, -0.0, 0.0, -0.0],
            vec![3.0, f64::NAN, 1.0, f64::INFINITY, 2.0, 2.0],
        ];
        for n in [7, 8, 450, 451, 30_000] {
            cases.push(noise(n, n as u64));
            cases.push(noise(n, 3).iter().map(|v| (v * 4.0).round()).collect());
        }
        for x in &cases {
            let want = sorting_median(x);
            assert_eq!(
                median_with(x, &mut scratch).map(f64::to_bits),
                want.map(f64::to_bits),
                "{} values",
                x.len()
            );
            let want_sigma = want.and_then(|m| {
                let dev: Vec<f64> = x.iter().map(|v| (v - m).abs()).collect();
                sorting_median(&dev).map(|d| 1.482_602_218_505_602 * d)
            });
            assert_eq!(
                robust_sigma_with(x, &mut scratch).map(f64::to_bits),
                want_sigma.map(f64::to_bits),
                "{} values",
                x.len()
            );
        }
    }

    #[test]
    fn noise_and_drift_alone_give_no_events() {
        let fs = 1000.0;
        let x: Vec<f64> = noise(30_000, 1)
            .iter()
            .enumerate()
            .map(|(i, e)| 3.0 * (-(i as f64) / fs / 10.0).exp() + 0.05 * e)
            .collect();
        let ev = sticking_events(&x, fs, 0.4056, &StickingSettings::default()).unwrap();
        // 8 robust σ: the chance of one Gaussian sample above it in 30 000 is ~2e-11.
        assert!(ev.times_s.is_empty(), "{:?}", ev.times_s);
        assert!(
            (ev.robust_level_n - 0.05).abs() < 0.005,
            "{}",
            ev.robust_level_n
        );
    }

    #[test]
    fn spikes_at_ball_pass_multiples_are_found_and_timed() {
        let (fs, tau) = (1000.0, 0.4056);
        let mut x: Vec<f64> = noise(30_000, 2).iter().map(|e| 2.0 + 0.05 * e).collect();
        // Spikes on every other or third passage, as a sticking bearing does.
        let mut want = Vec::new();
        let mut k = 1usize;
        while (k as f64 * tau + 0.1) * fs < 29_900.0 {
            let c = ((k as f64 * tau + 0.1) * fs) as usize;
            for d in 0..30usize {
                let g = (-((d as f64 - 15.0) / 5.0).powi(2) / 2.0).exp();
                x[c - 15 + d] += 10.0 * g;
            }
            want.push(c as f64 / fs);
            k += if k % 2 == 0 { 3 } else { 2 };
        }
        let ev = sticking_events(&x, fs, tau, &StickingSettings::default()).unwrap();
        assert_eq!(ev.times_s.len(), want.len());
        for (a, b) in ev.times_s.iter().zip(&want) {
            assert!((a - b).abs() <= 0.002, "{a} vs {b}");
        }
        assert_eq!(ev.timing_fraction, Some(1.0));
        assert!(ev.max_height_over_level.unwrap() > 100.0);
    }

    #[test]
    fn bad_settings_are_errors() {
        let x = vec![0.0; 100];
        assert!(sticking_events(&x, 1000.0, 0.0, &StickingSettings::default()).is_err());
        assert!(sticking_events(&x, -1.0, 0.4, &StickingSettings::default()).is_err());
        let s = StickingSettings {
            spike_factor: f64::NAN,
            ..Default::default()
        };
        assert!(sticking_events(&x, 1000.0, 0.4, &s).is_err());
    }
}
