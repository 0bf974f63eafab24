//! Finding pulses: the first, coarse search that seeds the template
//! ([`seeds`]), and the matched-filter search with the record's own
//! template and a threshold set for a stated false-detection rate
//! ([`scan`]).
//!
//! # The threshold
//!
//! The search runs on the matched-filter statistic of the baseline-removed
//! signal `d` with the template `h` (sampled at whole samples, `h_j`):
//!
//! ```text
//! t[n] = Σ_j h_j d[n + j] / √(Σ_j h_j²)        (partial sums at the record ends)
//! a[n] = Σ_j h_j d[n + j] / Σ_j h_j²           (the pulse amplitude, least squares)
//! ```
//!
//! Its noise `σ_t` is measured on the statistic of the model's residual
//! (`1.4826 MAD`): the noise of the signal actually searched, white or not.
//! In white Gaussian noise `t/σ_t` is a smooth Gaussian process whose rate
//! of crossings of `±z` is, by Rice's formula,
//!
//! ```text
//! N(z) = 2 n/(2π) √(λ₂/λ₀) exp(−z²/2),   λ₀ = Σ h_j²,  λ₂ = Σ (h_{j+1} − h_j)²
//! ```
//!
//! for `n` samples; the threshold is the `z` with `N(z) = α`, the false
//! detections per record allowed ([`super::PassageSettings::false_detections_per_record`]),
//! and at least [`super::PassageSettings::min_snr`]. Detections are then
//! kept at least 0.7 `τ_c` apart (the strongest first), which on a regular
//! train leaves no room for a noise peak between two passages: false
//! detections can only appear where passages are missing.

use ballpass_dsp::{
    find_peaks, peak_widths_with_prominences, Bound, FindPeaksSettings, Prominences,
};

use super::signal::{
    gaussian_kernel, gaussian_smooth, median, percentile, FFT_BLOCK, FFT_TAPS, FFT_WHOLE_MAX,
};
use super::template::Template;
use crate::error::{Error, Result};

/// Peaks found by `find_peaks` with their half-prominence widths.
pub(super) struct Candidates {
    pub idx: Vec<usize>,
    pub prominence: Vec<f64>,
    pub width: Vec<f64>,
    pub left_ip: Vec<f64>,
    pub right_ip: Vec<f64>,
}

fn dsp(context: &str, e: ballpass_dsp::DspError) -> Error {
    Error::dsp(context.to_string(), e)
}

/// `find_peaks(y, height ≥ height, prominence ≥ prominence, distance, wlen)`
/// with `peak_widths(rel_height = 0.5)` from the same prominences.
pub(super) fn candidates(
    y: &[f64],
    height: Option<f64>,
    prominence: f64,
    distance: Option<f64>,
    wlen: Option<f64>,
) -> Result<Candidates> {
    let peaks = find_peaks(
        y,
        &FindPeaksSettings {
            height: height.map(Bound::at_least),
            prominence: Some(Bound::at_least(prominence)),
            distance,
            wlen,
            ..Default::default()
        },
    )
    .map_err(|e| dsp("optical_V: find_peaks", e))?;
    // The widths at half prominence from the prominences find_peaks just
    // computed with the same `wlen` (what `peak_widths(y, peaks, 0.5, wlen)`
    // would compute again).
    let p = peaks.properties;
    let prominences = Prominences {
        prominences: p.prominences.unwrap_or_default(),
        left_bases: p.left_bases.unwrap_or_default(),
        right_bases: p.right_bases.unwrap_or_default(),
    };
    let w = peak_widths_with_prominences(y, &peaks.indices, 0.5, &prominences)
        .map_err(|e| dsp("optical_V: peak_widths", e))?;
    Ok(Candidates {
        prominence: prominences.prominences,
        idx: peaks.indices,
        width: w.widths,
        left_ip: w.left_ips,
        right_ip: w.right_ips,
    })
}

/// Keeps the candidates whose prominence is at least `rel` × the 75th
/// percentile of all.
pub(super) fn keep_strong(c: Candidates, rel: f64) -> Candidates {
    if c.idx.is_empty() {
        return c;
    }
    let p75 = percentile(&c.prominence, 75.0);
    keep_where(c, |i, c| c.prominence[i] >= rel * p75)
}

/// The candidates `i` for which `keep(i, c)` holds.
fn keep_where(c: Candidates, keep: impl Fn(usize, &Candidates) -> bool) -> Candidates {
    let k: Vec<bool> = (0..c.idx.len()).map(|i| keep(i, &c)).collect();
    let f = |v: &[f64]| -> Vec<f64> {
        v.iter()
            .zip(&k)
            .filter(|(_, k)| **k)
            .map(|(x, _)| *x)
            .collect()
    };
    Candidates {
        idx: c
            .idx
            .iter()
            .zip(&k)
            .filter(|(_, k)| **k)
            .map(|(x, _)| *x)
            .collect(),
        prominence: f(&c.prominence),
        width: f(&c.width),
        left_ip: f(&c.left_ip),
        right_ip: f(&c.right_ip),
    }
}

/// `Φ⁻¹(p)`, the standard normal quantile (`scipy.stats.norm.ppf`), by
/// bisection on `Φ(z) = (1 + sign(z) P(1/2, z²/2)) / 2` with `P` the
/// regularised lower incomplete gamma function ([`crate::stats::gamma_p`]).
fn normal_quantile(p: f64) -> f64 {
    let cdf = |z: f64| 0.5 * (1.0 + z.signum() * crate::stats::gamma_p(0.5, 0.5 * z * z));
    let p = p.clamp(1e-12, 1.0 - 1e-12);
    let (mut lo, mut hi) = (-8.0, 8.0);
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if cdf(mid) < p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The threshold `z` of the module docs: `N(z) = alpha` crossings of `±z`
/// in `n` samples of a process with `√(λ₂/λ₀) = roughness`, at least `floor`.
pub(super) fn rice_threshold(n: usize, roughness: f64, alpha: f64, floor: f64) -> f64 {
    let rate = n as f64 * roughness / (std::f64::consts::PI * alpha);
    let z = if rate > 1.0 {
        (2.0 * rate.ln()).sqrt()
    } else {
        0.0
    };
    z.max(floor)
}

/// The coarse first search: upward pulses of the lightly smoothed,
/// baseline-removed signal.
pub(super) struct Seeds {
    /// Peak samples.
    pub idx: Vec<usize>,
    /// Prominences (of the smoothed signal), V.
    pub prominence: Vec<f64>,
    /// Half-prominence crossings, samples (fractional).
    pub left_ip: Vec<f64>,
    pub right_ip: Vec<f64>,
    /// Smoothing kernel sigma, samples.
    pub sigma_k: f64,
}

/// Seeds: `find_peaks` on `y` (the signal above its running
/// `percentile_q` percentile) smoothed by a Gaussian of `τ_c/100` (at least
/// one sample), height above the noise's own offset there plus, and
/// prominence above, `z` times the smoothed noise
/// (`z` from [`rice_threshold`] for that smoothing), at least 0.7 `τ_c`
/// apart, and at least half the 75th percentile of the prominences: the
/// clear pulses, from which the template is first estimated.
pub(super) fn seeds(
    y: &[f64],
    noise: f64,
    percentile_q: f64,
    tau_samples: f64,
    alpha: f64,
    floor: f64,
) -> Result<Seeds> {
    let n = y.len();
    let sigma_k = (0.01 * tau_samples).max(1.0);
    let ys = gaussian_smooth(y, sigma_k);
    let (_, k) = gaussian_kernel(sigma_k, n);
    let noise_s = noise * k.iter().map(|v| v * v).sum::<f64>().sqrt();
    // √(λ₂/λ₀) of Gaussian-smoothed white noise: 1 / (√2 σ_k).
    let z = rice_threshold(n, 1.0 / (std::f64::consts::SQRT_2 * sigma_k), alpha, floor);
    let thr = (z * noise_s).max(1e-12 * y.iter().fold(0.0f64, |a, v| a.max(v.abs())));
    // `y` is measured from a low running percentile `q` of the signal, so
    // its noise sits `−Φ⁻¹(q/100) σ` above zero (1.28 σ for the 10th
    // percentile): the height threshold starts there.
    let offset = -normal_quantile(percentile_q / 100.0) * noise;
    let c = candidates(
        &ys,
        Some(offset.max(0.0) + thr),
        thr,
        Some((0.7 * tau_samples).max(1.0)),
        Some((2.5 * tau_samples).max(3.0)),
    )?;
    let c = keep_strong(c, 0.5);
    // Between inverted pulses (interference) the level rises back to the
    // baseline: a bump as high as a pulse, but as wide as the gap. Seeds
    // are kept within a factor 1.6 of the median width.
    let c = if c.width.len() >= 3 {
        let med = median(&c.width);
        keep_where(c, |i, c| c.width[i] <= 1.6 * med && c.width[i] >= med / 1.6)
    } else {
        c
    };
    Ok(Seeds {
        idx: c.idx,
        prominence: c.prominence,
        left_ip: c.left_ip,
        right_ip: c.right_ip,
        sigma_k,
    })
}

impl Seeds {
    /// Median half widths left and right of the peaks, corrected for the
    /// smoothing as for a Gaussian (`hw² − (1.1774 σ_k)²`), samples.
    pub fn half_widths(&self) -> Option<(f64, f64)> {
        if self.idx.is_empty() {
            return None;
        }
        let l: Vec<f64> = self
            .idx
            .iter()
            .zip(&self.left_ip)
            .map(|(&i, &lip)| i as f64 - lip)
            .collect();
        let r: Vec<f64> = self
            .idx
            .iter()
            .zip(&self.right_ip)
            .map(|(&i, &rip)| rip - i as f64)
            .collect();
        let smear = 1.177_410_022_515_474_6 * self.sigma_k;
        let fix = |w: f64| (w * w - smear * smear).max(0.25 * w * w).sqrt();
        Some((fix(median(&l)).max(0.5), fix(median(&r)).max(0.5)))
    }
}

/// A pulse found by the matched filter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Found {
    /// Centre (template origin), samples, refined by a parabola.
    pub c: f64,
    /// Amplitude (least squares against the template), signed.
    pub a: f64,
    /// Statistic over its noise, signed.
    pub z: f64,
}

/// The result of a matched-filter search.
pub(super) struct Scan {
    /// The pulses found, in time order.
    pub found: Vec<Found>,
    /// Threshold on the statistic, in its noise std.
    pub z: f64,
    /// Noise std of the amplitude estimate `a[n]` for a whole pulse (the
    /// noise of the signal searched, in signal units).
    pub amplitude_noise: f64,
}

thread_local! {
    /// The correlator (raw sums, as `ballpass_dsp::correlate`) this thread
    /// used last for [`filter`]: its FFT plan and buffers, which a new one
    /// would make and zero again on every call (the statistic is filtered
    /// twice per round of the measurement loop, every round of every
    /// record). Same plan, same sums: the values are a new one's.
    static CORRELATOR: std::cell::Cell<Option<ballpass_dsp::Correlator>> =
        const { std::cell::Cell::new(None) };
}

/// Runs `f` with this thread's kept correlator (a new one the first time)
/// on a record of `n` samples, and keeps it afterwards when `n` is at most
/// [`KEEP_MAX_SAMPLES`].
fn with_correlator<R>(n: usize, f: impl FnOnce(&mut ballpass_dsp::Correlator) -> R) -> R {
    let mut c = CORRELATOR.take().unwrap_or_else(|| {
        ballpass_dsp::Correlator::new(ballpass_dsp::CorrelateSettings::default())
    });
    let out = f(&mut c);
    if n <= KEEP_MAX_SAMPLES {
        CORRELATOR.set(Some(c));
    }
    out
}

/// Longest record whose correlator a thread keeps (its plan's buffers,
/// four of a quarter of the transform length in complex values, hold
/// ~17 MB at 2^18 samples; a longer record's would stay with the thread).
const KEEP_MAX_SAMPLES: usize = 1 << 18;

/// `Σ_j h_j x[n + off + j]` for `n = 0..x.len()`, zero outside `x`.
fn filter(x: &[f64], taps: &[f64], off: isize) -> Vec<f64> {
    let n = x.len();
    let m = taps.len();
    if m > FFT_TAPS && n > FFT_WHOLE_MAX {
        // A long record in blocks of outputs (transforms of a few MB).
        let mut c = ballpass_dsp::Correlator::new(ballpass_dsp::CorrelateSettings::default());
        let mut out = Vec::with_capacity(n);
        let mut a = 0;
        while a < n {
            let b = (a + FFT_BLOCK).min(n);
            // Output i is Σ_j h_j x[i + off + j]: samples from a + off on.
            let start = a as isize + off;
            let seg: Vec<f64> = (0..b - a + m - 1)
                .map(|t| {
                    let k = start + t as isize;
                    if k >= 0 && (k as usize) < n {
                        x[k as usize]
                    } else {
                        0.0
                    }
                })
                .collect();
            let Ok(r) = c.correlate(&seg, taps) else {
                break;
            };
            out.extend_from_slice(&r.values[m - 1..m - 1 + (b - a)]);
            a = b;
        }
        if out.len() == n {
            return out;
        }
    }
    if m > FFT_TAPS && n > m {
        if let Ok(c) = with_correlator(n, |c| c.correlate(x, taps)) {
            // c.values[idx] is lag idx − (m − 1): Σ_j x[j + lag] taps[j].
            return (0..n)
                .map(|i| {
                    let lag = i as isize + off;
                    c.values[(lag + m as isize - 1) as usize]
                })
                .collect();
        }
    }
    (0..n)
        .map(|i| {
            let mut s = 0.0;
            for (j, h) in taps.iter().enumerate() {
                let k = i as isize + off + j as isize;
                if k >= 0 && (k as usize) < n {
                    s += h * x[k as usize];
                }
            }
            s
        })
        .collect()
}

/// Matched-filter search of `d` (baseline removed) with template `t`; the
/// noise is measured on the same statistic of `resid` (the model's
/// residual). Pulses at least `distance` samples apart, strongest first;
/// amplitudes at least `rel` × the 75th percentile of the kept ones.
pub(super) fn scan(
    d: &[f64],
    resid: &[f64],
    t: &Template,
    distance: f64,
    alpha: f64,
    floor: f64,
    rel: f64,
) -> Scan {
    let n = d.len();
    let j0 = t.left().ceil() as isize;
    let j1 = t.right().floor() as isize;
    let taps: Vec<f64> = (j0..=j1).map(|j| t.value(j as f64)).collect();
    let l0: f64 = taps.iter().map(|v| v * v).sum();
    let l2: f64 = taps.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum();
    let empty = Scan {
        found: Vec::new(),
        z: f64::INFINITY,
        amplitude_noise: f64::NAN,
    };
    if l0.is_nan() || l0 <= 0.0 || n < 3 {
        return empty;
    }
    // Partial Σ h² at each n (taps falling outside the record drop out).
    let mut prefix = vec![0.0; taps.len() + 1];
    for (j, v) in taps.iter().enumerate() {
        prefix[j + 1] = prefix[j] + v * v;
    }
    let norm = |i: usize| -> f64 {
        let first = (-(i as isize + j0)).max(0) as usize;
        let last = ((n as isize - 1 - i as isize - j0).min(taps.len() as isize - 1)).max(-1);
        if last < first as isize {
            0.0
        } else {
            prefix[last as usize + 1] - prefix[first]
        }
    };
    let norms: Vec<f64> = (0..n).map(norm).collect();
    let stat = |x: &[f64]| -> Vec<f64> {
        filter(x, &taps, j0)
            .into_iter()
            .zip(&norms)
            .map(|(s, &w)| if w > 0.0 { s / w.sqrt() } else { 0.0 })
            .collect()
    };
    let st = stat(d);
    let sr = stat(resid);
    // Noise of the statistic where the template is (mostly) inside.
    let inner: Vec<f64> = sr
        .iter()
        .zip(&norms)
        .filter(|(_, &w)| w >= 0.5 * l0)
        .map(|(v, _)| *v)
        .collect();
    let sigma_t = crate::stats::robust_sigma(&inner).unwrap_or(0.0);
    if sigma_t.is_nan() || sigma_t <= 0.0 {
        return empty;
    }
    let z = rice_threshold(n, (l2 / l0).sqrt(), alpha, floor);
    let thr = z * sigma_t;
    // Local extremes of |t| above the threshold.
    let mut peaks: Vec<(usize, f64)> = Vec::new();
    for i in 0..n {
        let v = st[i];
        if v.abs() < thr {
            continue;
        }
        let left = if i > 0 { st[i - 1] } else { 0.0 };
        let right = if i + 1 < n { st[i + 1] } else { 0.0 };
        let is_peak = if v > 0.0 {
            v >= left && v > right
        } else {
            v <= left && v < right
        };
        if is_peak {
            peaks.push((i, v));
        }
    }
    peaks.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()).then(a.0.cmp(&b.0)));
    let mut kept: Vec<(usize, f64)> = Vec::new();
    for (i, v) in peaks {
        if kept
            .iter()
            .all(|(k, _)| (*k as f64 - i as f64).abs() >= distance)
        {
            kept.push((i, v));
        }
    }
    kept.sort_by_key(|p| p.0);
    let mut found: Vec<Found> = kept
        .iter()
        .map(|&(i, v)| {
            // Parabola through the statistic's three samples.
            let c = if i > 0 && i + 1 < n {
                let (a, b, cc) = (st[i - 1], st[i], st[i + 1]);
                let den = a - 2.0 * b + cc;
                if den.abs() > 0.0 {
                    i as f64 + (0.5 * (a - cc) / den).clamp(-0.5, 0.5)
                } else {
                    i as f64
                }
            } else {
                i as f64
            };
            let w = norms[i];
            Found {
                c,
                a: v * w.sqrt() / w,
                z: v / sigma_t,
            }
        })
        .collect();
    if !found.is_empty() && rel > 0.0 {
        let amps: Vec<f64> = found.iter().map(|f| f.a.abs()).collect();
        let p75 = percentile(&amps, 75.0);
        found.retain(|f| f.a.abs() >= rel * p75);
    }
    Scan {
        found,
        z,
        amplitude_noise: sigma_t / l0.sqrt(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Seeded values in (-1, 1), no dependency.
    fn noise(n: usize) -> Vec<f64> {
        let mut s = 0x9E37_79B9_7F4A_7C15_u64;
        (0..n)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                (s >> 11) as f64 / (1u64 << 52) as f64 - 1.0
            })
            .collect()
    }

    /// A long record filtered and smoothed in blocks gives the direct sums
    /// at the record's ends and around every block boundary. Tolerance:
    /// sums of ~100–200 products of values below 1 by FFT, rounding
    /// ~1e-15 times the taps' sum; 1e-11 leaves room.
    #[test]
    fn long_records_filtered_in_blocks_give_the_direct_sums() {
        let n = FFT_WHOLE_MAX + 3 * FFT_BLOCK + 777;
        let x = noise(n);
        let taps: Vec<f64> = (0..101).map(|j| ((j as f64) * 0.07).sin()).collect();
        let off = -50isize;
        let got = filter(&x, &taps, off);
        let (half, k) = gaussian_kernel(20.0, n);
        let smooth = gaussian_smooth(&x, 20.0);
        assert_eq!(got.len(), n);
        assert_eq!(smooth.len(), n);
        let mirror = |i: isize| -> f64 {
            let m = n as isize;
            let j = if i < 0 {
                -i
            } else if i >= m {
                2 * (m - 1) - i
            } else {
                i
            };
            x[j as usize]
        };
        let mut at: Vec<usize> = (0..40).chain(n - 40..n).collect();
        for b in 1..=(n / FFT_BLOCK) {
            let e = b * FFT_BLOCK;
            at.extend(e.saturating_sub(3)..(e + 3).min(n));
        }
        for i in at {
            let want: f64 = taps
                .iter()
                .enumerate()
                .map(|(j, h)| {
                    let t = i as isize + off + j as isize;
                    if t >= 0 && (t as usize) < n {
                        h * x[t as usize]
                    } else {
                        0.0
                    }
                })
                .sum();
            assert!(
                (got[i] - want).abs() < 1e-11,
                "filter at {i}: {} vs {want}",
                got[i]
            );
            let want: f64 = k
                .iter()
                .enumerate()
                .map(|(j, w)| w * mirror(i as isize + j as isize - half as isize))
                .sum();
            assert!(
                (smooth[i] - want).abs() < 1e-11,
                "smooth at {i}: {} vs {want}",
                smooth[i]
            );
        }
    }

    #[test]
    fn normal_quantile_matches_scipy() {
        // scipy.stats.norm.ppf(0.1) = -1.2815515655446004; ppf(0.975) = 1.959963984540054.
        assert!((normal_quantile(0.1) + 1.281_551_565_544_600_4).abs() < 1e-9);
        assert!((normal_quantile(0.975) - 1.959_963_984_540_054).abs() < 1e-9);
        assert!(normal_quantile(0.5).abs() < 1e-12);
    }

    #[test]
    fn rice_threshold_gives_the_stated_rate() {
        // N(z) = n r / π · exp(−z²/2) = α at the threshold.
        let (n, r, alpha) = (30_000, 0.05, 0.01);
        let z = rice_threshold(n, r, alpha, 0.0);
        let rate = n as f64 * r / std::f64::consts::PI * (-0.5 * z * z).exp();
        assert!((rate / alpha - 1.0).abs() < 1e-12, "{rate}");
        assert_eq!(rice_threshold(n, r, alpha, 9.0), 9.0);
    }
}
