//! Signal helpers of the passage detection: robust noise levels,
//! percentiles, the running-percentile baseline, Gaussian smoothing, box
//! decimation and the running integral.

use crate::stats::{from_order_key, order_key, percentile_of_keys};

/// Robust noise standard deviation from lag-`lag` differences:
/// `MAD(x[n+lag] − x[n]) / (0.67449 √2)`.
pub(super) fn noise_sigma(x: &[f64], lag: usize) -> f64 {
    let lag = lag.max(1);
    if x.len() <= lag + 1 {
        return 0.0;
    }
    let mut keys: Vec<i64> = x
        .windows(lag + 1)
        .map(|w| order_key(w[lag] - w[0]))
        .collect();
    let med = percentile_of_keys(&mut keys, 50.0);
    for k in keys.iter_mut() {
        *k = order_key((from_order_key(*k) - med).abs());
    }
    percentile_of_keys(&mut keys, 50.0) / (0.674_489_750_196_081_7 * std::f64::consts::SQRT_2)
}

/// Non-robust fallback of [`noise_sigma`]: `rms(x[n+lag] − x[n]) / √2`.
pub(super) fn rms_difference_sigma(x: &[f64], lag: usize) -> f64 {
    let lag = lag.max(1);
    if x.len() <= lag {
        return 0.0;
    }
    let m = (x.len() - lag) as f64;
    (x.windows(lag + 1)
        .map(|w| (w[lag] - w[0]).powi(2))
        .sum::<f64>()
        / m
        / 2.0)
        .sqrt()
}

pub(super) fn median(v: &[f64]) -> f64 {
    percentile(v, 50.0)
}

/// Linear-interpolated percentile (numpy's default) of `v`.
pub(super) fn percentile(v: &[f64], q: f64) -> f64 {
    let mut keys: Vec<i64> = v.iter().map(|&x| order_key(x)).collect();
    percentile_of_keys(&mut keys, q)
}

/// Running percentile over `window` samples, evaluated every `window / 4`
/// samples and linearly interpolated between.
pub(super) fn running_percentile(x: &[f64], window: usize, q: f64) -> Vec<f64> {
    let n = x.len();
    let window = window.clamp(3, n.max(3));
    let hop = (window / 4).max(1);
    let mut centres: Vec<usize> = (0..n).step_by(hop).collect();
    if *centres.last().unwrap_or(&0) != n - 1 {
        centres.push(n - 1);
    }
    let mut keys = Vec::with_capacity(window);
    let levels: Vec<f64> = centres
        .iter()
        .map(|&c| {
            let lo = c.saturating_sub(window / 2);
            let hi = (c + window / 2 + 1).min(n);
            keys.clear();
            keys.extend(x[lo..hi].iter().map(|&v| order_key(v)));
            percentile_of_keys(&mut keys, q)
        })
        .collect();
    let mut out = vec![0.0; n];
    for w in 0..centres.len().saturating_sub(1) {
        let (c0, c1) = (centres[w], centres[w + 1]);
        for (i, o) in out.iter_mut().enumerate().take(c1 + 1).skip(c0) {
            let f = (i - c0) as f64 / (c1 - c0) as f64;
            *o = levels[w] + f * (levels[w + 1] - levels[w]);
        }
    }
    if centres.len() == 1 {
        out.fill(levels[0]);
    }
    out
}

/// Kernels longer than this many taps are applied by FFT (the same sums,
/// rounded differently; `gaussian_smooth_equals_the_plain_sum` bounds the
/// difference at 1e-13 for unit-scale noise), shorter ones directly.
pub(super) const FFT_TAPS: usize = 64;

/// The unit-area Gaussian of `sigma` samples truncated at 4σ (and to fit a
/// signal of `n` samples): its half-length and its `2 half + 1` taps.
pub(super) fn gaussian_kernel(sigma: f64, n: usize) -> (usize, Vec<f64>) {
    let half = ((4.0 * sigma).ceil() as usize).min(n.saturating_sub(1));
    let mut k: Vec<f64> = (0..=2 * half)
        .map(|i| {
            let u = (i as f64 - half as f64) / sigma;
            (-0.5 * u * u).exp()
        })
        .collect();
    let sum: f64 = k.iter().sum();
    k.iter_mut().for_each(|v| *v /= sum);
    (half, k)
}

/// Longest record smoothed with one whole-record FFT (2^20 samples, 17 min
/// at 1 kHz); longer ones go in blocks of [`FFT_BLOCK`] outputs.
pub(super) const FFT_WHOLE_MAX: usize = 1 << 20;
/// Outputs per block of a long record's FFT smoothing.
pub(super) const FFT_BLOCK: usize = 1 << 16;

/// Convolution with a unit-area Gaussian of `sigma` samples (truncated at
/// 4σ), with the signal mirrored at both ends.
pub(super) fn gaussian_smooth(x: &[f64], sigma: f64) -> Vec<f64> {
    let n = x.len();
    let (half, k) = gaussian_kernel(sigma, n);
    let at = |i: isize| -> f64 {
        let n = n as isize;
        let j = if i < 0 {
            -i
        } else if i >= n {
            2 * (n - 1) - i
        } else {
            i
        };
        x[j.clamp(0, n - 1) as usize]
    };
    let edge = |i: usize| -> f64 {
        k.iter()
            .enumerate()
            .map(|(j, w)| w * at(i as isize + j as isize - half as isize))
            .sum()
    };
    if k.len() > FFT_TAPS && n > k.len() {
        // A long kernel (slow tracking: σ_k = τ_c/200 is 40 samples at
        // 1 mm/s and 1 kHz, 325 taps) by FFT: the mirrored signal
        // correlated with the symmetric kernel, whose lag `i` is output `i`.
        // A long record in blocks of outputs (each needs `k.len() - 1`
        // more samples), so that the transforms stay a few megabytes; a
        // record up to FFT_WHOLE_MAX samples is one block, as it always was.
        let block = if n <= FFT_WHOLE_MAX { n } else { FFT_BLOCK };
        let mut c = ballpass_dsp::Correlator::new(ballpass_dsp::CorrelateSettings::default());
        let mut out = Vec::with_capacity(n);
        let mut a = 0;
        while a < n {
            let b = (a + block).min(n);
            let padded: Vec<f64> = (a..b + k.len() - 1)
                .map(|m| at(m as isize - half as isize))
                .collect();
            let Ok(r) = c.correlate(&padded, &k) else {
                break;
            };
            out.extend_from_slice(&r.values[k.len() - 1..k.len() - 1 + (b - a)]);
            a = b;
        }
        if out.len() == n {
            return out;
        }
    }
    // Where the kernel lies inside the signal, outputs `lo..hi` are the
    // plain sums of `w_j x_(i-half+j)` in the order of `j` (the value `edge`
    // gives), computed side by side with the CPU's vectors.
    let lo = half.min(n);
    let hi = n.saturating_sub(half).max(lo);
    let mut out: Vec<f64> = Vec::with_capacity(n);
    out.extend((0..lo).map(edge));
    if hi > lo {
        // The slice holds `hi - lo + 2 half >= k.len()` samples, neither
        // empty: `correlate_valid` has nothing to reject.
        out.extend(
            ballpass_dsp::correlate_valid(&x[lo - half..hi + half], &k)
                .expect("the kernel fits inside the slice"),
        );
    }
    out.extend((hi..n).map(edge));
    out
}

/// Means of consecutive whole blocks of `q` samples (the last `n mod q`
/// samples are left out): `out[i] = mean(x[i q .. (i + 1) q])`, centred on
/// sample `i q + (q − 1) / 2` of `x`. White noise of std σ becomes white
/// noise of std σ / √q; a pulse of FWHM `w` samples widens by a box of `q`
/// samples (variance `+ q² / 12`: 0.04 % of the FWHM² for `w ≥ 24 q`).
pub(super) fn box_decimate(x: &[f64], q: usize) -> Vec<f64> {
    let q = q.max(1);
    x.chunks_exact(q)
        .map(|c| c.iter().sum::<f64>() / q as f64)
        .collect()
}

/// Running integral by the trapezoidal rule, `I[0] = 0`,
/// `I[i] = I[i−1] + dt (x[i−1] + x[i]) / 2`, of `x − mean(x)` (the mean
/// only adds a ramp, which the baseline takes anyway, and would make the
/// values large; the baseline reported gets it back, `measure.rs`).
pub(super) fn running_integral(x: &[f64], dt: f64) -> Vec<f64> {
    let n = x.len();
    if n == 0 {
        return Vec::new();
    }
    let mean = x.iter().sum::<f64>() / n as f64;
    let mut out = Vec::with_capacity(n);
    let mut acc = 0.0;
    out.push(0.0);
    for w in x.windows(2) {
        acc += 0.5 * dt * ((w[0] - mean) + (w[1] - mean));
        out.push(acc);
    }
    out
}
