//! Sticking: sporadic friction spikes at ball passages, told from the
//! regular ball-pass ripple every bearing has (thesis ch. 8, Fig. 66).
//!
//! A good bearing's friction rises a little at every ball passage (the
//! ripple); a sticking bearing's jumps, at some passages only, by random
//! amounts up to many times that. So every ball-pass period of a record is
//! measured the same way, and a period counts as a spike only when it stands
//! far above the bearing's *own typical period*, never merely above the
//! noise:
//!
//! ```text
//! smoothed  = friction through three box filters of width w (≈ Gaussian of
//!             σ = 0.01 τc: noise down, spikes of ≥ 0.02 τc kept)
//! baseline  = block medians over τc, linearly interpolated (follows drift
//!             and slow wander, not the passages; a pulse narrower than
//!             τc/2 never fills half a block)
//! height_j  = max over period j (t in [j τc, (j+1) τc)) of smoothed − baseline
//! typical   = median of the heights,  spread = (median − 10th percentile) / 1.2816
//! spike     = a period with height > typical + κ · spread      (κ = 8)
//! ```
//!
//! The spread comes from the lower half of the heights, which spikes (at
//! most half the periods) do not reach. For a good bearing the heights are
//! the ripple's peak plus the largest noise sample of the period: close to
//! a Gumbel distribution, whose chance of exceeding `typical + 8 spread`
//! is 4e-4 (a Gaussian's is far smaller); [`super::diagnose`] turns spike
//! counts into verdicts with that per-period rate and states the resulting
//! false-alarm rate. The first and last half period are left out (a load
//! cell's discharge or a start transient there is not a passage).

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::stats::percentile_of_keys;
use crate::stats::{median_with, order_key};

/// Settings of the per-period heights.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StickingSettings {
    /// A period is a spike when its height exceeds the typical by this many
    /// spreads.
    pub outlier_spreads: f64,
    /// Smoothing (Gaussian-equivalent σ), in ball-pass periods.
    pub smoothing_periods: f64,
}

impl Default for StickingSettings {
    fn default() -> Self {
        Self {
            outlier_spreads: 8.0,
            smoothing_periods: 0.01,
        }
    }
}

/// The friction of each ball-pass period of one record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PassageHeights {
    /// Ball-pass period used, s.
    pub period_s: f64,
    /// Periods measured.
    pub periods: usize,
    /// Height of each period above the baseline, N (not in the tables).
    #[serde(skip)]
    pub heights_n: Vec<f64>,
    /// Time of each period's maximum, s from the record start (not in the tables).
    #[serde(skip)]
    pub times_s: Vec<f64>,
    /// Typical period height (median), N.
    pub typical_n: f64,
    /// Spread of the heights below the median (robust σ), N.
    pub spread_n: f64,
    /// Periods standing above `typical + κ spread`.
    pub spikes: usize,
    /// Their times, s.
    pub spike_times_s: Vec<f64>,
    /// Their heights, N.
    pub spike_heights_n: Vec<f64>,
}

/// `(median − 10th percentile) / 1.2816` of `v`: the robust σ of the lower
/// half (0 for fewer than two values).
pub(crate) fn lower_spread(v: &[f64]) -> (f64, f64) {
    let mut keys: Vec<i64> = v
        .iter()
        .filter(|x| x.is_finite())
        .map(|&x| order_key(x))
        .collect();
    if keys.is_empty() {
        return (0.0, 0.0);
    }
    let med = percentile_of_keys(&mut keys, 50.0);
    let p10 = percentile_of_keys(&mut keys, 10.0);
    (med, (med - p10).max(0.0) / 1.281_551_565_544_600_5)
}

/// Three passes of a centred moving average of `w` samples (edges: the
/// mean of what the window holds), `σ² = 3 (w² − 1) / 12`.
fn triple_box(x: &[f64], w: usize) -> Vec<f64> {
    let mut cur = x.to_vec();
    if w <= 1 {
        return cur;
    }
    let h = w / 2;
    let n = x.len();
    let mut prefix = vec![0.0; n + 1];
    for _ in 0..3 {
        for i in 0..n {
            prefix[i + 1] = prefix[i] + cur[i];
        }
        for (i, c) in cur.iter_mut().enumerate() {
            let lo = i.saturating_sub(h);
            let hi = (i + (w - h)).min(n);
            *c = (prefix[hi] - prefix[lo]) / (hi - lo) as f64;
        }
    }
    cur
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

/// The height of each ball-pass period of a friction record (module docs).
///
/// # Errors
/// [`Error::InvalidSetting`] for a non-positive period, rate or setting.
pub fn passage_heights(
    friction_n: &[f64],
    fs_hz: f64,
    tau_c_s: f64,
    settings: &StickingSettings,
) -> Result<PassageHeights> {
    for (name, v) in [
        ("tau_c", tau_c_s),
        ("fs", fs_hz),
        ("outlier spreads", settings.outlier_spreads),
        ("smoothing", settings.smoothing_periods),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::setting(
                name,
                format!("must be a positive number, got {v}"),
            ));
        }
    }
    let per = tau_c_s * fs_hz;
    // Box width for a Gaussian-equivalent σ: w = sqrt(4 σ² + 1).
    let sigma = settings.smoothing_periods * per;
    let w = ((4.0 * sigma * sigma + 1.0).sqrt().round() as usize).max(1);
    let smooth = triple_box(friction_n, w);
    // Blocks of one period: a ripple pulse narrower than half a period
    // then fills less than half of every block, so the block median stays
    // on the level between pulses (half-period blocks put it on the pulse
    // top wherever a pulse wider than a quarter period filled more than
    // half a block, and the heights then changed with the blocks' phase).
    let block = (per.round() as usize).max(8);
    let residual = detrend_by_block_medians(&smooth, block);
    let n = residual.len();
    // Whole periods centred on the passages: the windows' edges half a
    // period from where the residual folded on the period peaks (else a
    // passage on an edge is seen by both neighbouring windows), starting at
    // least half a period in and ending half a period early.
    let start = {
        let bins = (per.round() as usize).max(1);
        let mut sum = vec![0.0; bins];
        let mut count = vec![0usize; bins];
        for (i, &v) in residual.iter().enumerate() {
            let b = ((i as f64 % per) / per * bins as f64) as usize % bins;
            sum[b] += v;
            count[b] += 1;
        }
        let peak = (0..bins)
            .filter(|&b| count[b] > 0)
            .max_by(|&a, &b| (sum[a] / count[a] as f64).total_cmp(&(sum[b] / count[b] as f64)))
            .unwrap_or(0) as f64
            * per
            / bins as f64;
        let mut edge = (peak + 0.5 * per) % per;
        if edge < 0.5 * per {
            edge += per;
        }
        edge.round() as usize
    };
    let mut heights_n = Vec::new();
    let mut times_s = Vec::new();
    let mut j = 0usize;
    loop {
        let a = start + (j as f64 * per).round() as usize;
        let b = start + ((j + 1) as f64 * per).round() as usize;
        if (b as f64 + 0.5 * per) > n as f64 || b <= a {
            break;
        }
        let (i, h) =
            residual[a..b]
                .iter()
                .enumerate()
                .fold((0, f64::NEG_INFINITY), |(bi, bv), (k, &v)| {
                    if v > bv {
                        (k, v)
                    } else {
                        (bi, bv)
                    }
                });
        heights_n.push(h);
        times_s.push((a + i) as f64 / fs_hz);
        j += 1;
    }
    let (typical_n, spread_n) = lower_spread(&heights_n);
    let limit = typical_n + settings.outlier_spreads * spread_n;
    let (mut spike_times_s, mut spike_heights_n) = (Vec::new(), Vec::new());
    for (&h, &t) in heights_n.iter().zip(&times_s) {
        if spread_n > 0.0 && h > limit {
            spike_times_s.push(t);
            spike_heights_n.push(h);
        }
    }
    Ok(PassageHeights {
        period_s: tau_c_s,
        periods: heights_n.len(),
        spikes: spike_times_s.len(),
        heights_n,
        times_s,
        typical_n,
        spread_n,
        spike_times_s,
        spike_heights_n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::stats::test_noise::gaussian as noise;

    /// A regular ripple far above the noise, on a decaying load cell: no
    /// period is a spike (the old rule called every one of them a spike).
    #[test]
    fn a_regular_ripple_is_not_sticking() {
        let (fs, tau) = (1000.0, 0.4056);
        let x: Vec<f64> = noise(60_000, 1)
            .iter()
            .enumerate()
            .map(|(i, e)| {
                let t = i as f64 / fs;
                let ph = (t / tau).fract() - 0.5;
                let ripple = 0.1 * (-0.5 * (ph / 0.03).powi(2)).exp();
                3.0 * (-t / 10.0).exp() + ripple + 0.01 * e
            })
            .collect();
        let h = passage_heights(&x, fs, tau, &StickingSettings::default()).unwrap();
        assert!(h.periods >= 145, "{}", h.periods);
        assert_eq!(h.spikes, 0, "{:?}", h.spike_heights_n);
        assert!((h.typical_n - 0.1).abs() < 0.03, "{}", h.typical_n);
    }

    /// Spikes three times the ripple on every seventh passage are found, at
    /// their times.
    #[test]
    fn sporadic_spikes_stand_out_of_the_ripple() {
        let (fs, tau) = (1000.0, 0.4056);
        let mut want = Vec::new();
        let x: Vec<f64> = noise(60_000, 2)
            .iter()
            .enumerate()
            .map(|(i, e)| {
                let t = i as f64 / fs;
                let k = (t / tau).floor() as usize;
                let ph = (t / tau).fract() - 0.5;
                let g = (-0.5 * (ph / 0.03).powi(2)).exp();
                let spike = if k % 7 == 3 { 0.3 } else { 0.0 };
                2.0 + (0.1 + spike) * g + 0.01 * e
            })
            .collect();
        for k in (0..148).filter(|k| k % 7 == 3) {
            want.push((k as f64 + 0.5) * tau);
        }
        let h = passage_heights(&x, fs, tau, &StickingSettings::default()).unwrap();
        // The first and the last half periods are not examined.
        let inside: Vec<f64> = want
            .iter()
            .copied()
            .filter(|t| *t > 0.5 * tau && *t < 60.0 - 0.5 * tau)
            .collect();
        assert_eq!(h.spikes, inside.len(), "{:?}", h.spike_times_s);
        for (a, b) in h.spike_times_s.iter().zip(&inside) {
            assert!((a - b).abs() < 0.01, "{a} vs {b}");
        }
    }

    #[test]
    fn bad_settings_are_errors() {
        let x = vec![0.0; 100];
        assert!(passage_heights(&x, 1000.0, 0.0, &StickingSettings::default()).is_err());
        assert!(passage_heights(&x, -1.0, 0.4, &StickingSettings::default()).is_err());
        let s = StickingSettings {
            outlier_spreads: f64::NAN,
            ..Default::default()
        };
        assert!(passage_heights(&x, 1000.0, 0.4, &s).is_err());
    }
}
