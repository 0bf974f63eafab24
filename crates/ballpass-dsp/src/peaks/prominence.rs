//! Prominences ([`peak_prominences`](super::peak_prominences)) and the prefilter that lets
//! [`super::find_peaks`] skip peaks that cannot be prominent enough.

use super::bases::{bases_sorted, scan_left, scan_right, MinMaxTree};
use super::{check_peaks, check_signal, half_window, Prominences};
use crate::biquad::Baseline;
use crate::error::Result;
use crate::simd::Wide;

/// Samples read on each side of a peak by [`may_be_prominent`].
pub(super) const NEAR: usize = 8;

/// Whether a side of a peak of height `v` rules out a prominence of
/// `min`: `c` holds the [`NEAR`] samples next to the peak on that side,
/// nearest first, all inside the window. If one of them is higher than the
/// peak, SciPy's base search on that side stops there and its minimum is
/// the lowest of `v` and the samples before the stop: exactly known. The
/// prominence, `v` less the higher of the two sides' minima, is then at
/// most `v` less this side's minimum (rounding is monotonic), so
/// `v - side_min < min` means the prominence criterion removes the peak.
#[inline(always)]
pub(super) fn side_rules_out(c: &[f64; NEAR], v: f64, min: f64) -> bool {
    let mut higher = 0u32;
    for (k, &y) in c.iter().enumerate() {
        higher |= u32::from(y > v) << k;
    }
    let stop = higher.trailing_zeros() as usize; // 32 when none is higher
                                                 // The samples before the stop (+inf after it), then their minimum by
                                                 // halves (exact: any order gives the same value).
    let mut m: [f64; NEAR] = std::array::from_fn(|k| if k < stop { c[k] } else { f64::INFINITY });
    let mut half = NEAR / 2;
    while half > 0 {
        for k in 0..half {
            m[k] = if m[k + half] < m[k] {
                m[k + half]
            } else {
                m[k]
            };
        }
        half /= 2;
    }
    let side_min = if m[0] < v { m[0] } else { v };
    stop < NEAR && v - side_min < min
}

/// Mask of the `peaks` that may reach a prominence of `min` (window of
/// half width `half`, see [`peak_prominences`](super::peak_prominences)): `false` only for peaks
/// whose prominence is certainly below `min` (`x[p]` less the signal's
/// lowest sample is below `min`, or [`side_rules_out`] on either side),
/// which the prominence criterion would remove. Branch-free
/// per peak (a noise maximum's short searches are what makes SciPy's scan,
/// and the exact search here, slow: their ends are unpredictable), compiled
/// through `crate::simd::widest`. Peaks nearer than [`NEAR`] samples to the
/// signal's ends, or all peaks when the window is shorter than that, are
/// tested against the lowest sample only.
pub(super) fn may_be_prominent(
    x: &[f64],
    peaks: &[usize],
    half: Option<usize>,
    min: f64,
) -> Vec<bool> {
    let n = x.len();
    crate::simd::widest(
        #[inline(always)]
        || {
            // No side's minimum is below the signal's: `v - lowest < min`
            // rules a peak out as a side's minimum does.
            let mut lanes = [f64::INFINITY; NEAR];
            for c in x.chunks_exact(NEAR) {
                for (m, &y) in lanes.iter_mut().zip(c) {
                    *m = if y < *m { y } else { *m };
                }
            }
            let lowest = x
                .chunks_exact(NEAR)
                .remainder()
                .iter()
                .chain(&lanes)
                .fold(f64::INFINITY, |a, &y| if y < a { y } else { a });
            let near = half.is_none_or(|h| h >= NEAR);
            peaks
                .iter()
                .map(|&p| {
                    let v = x[p];
                    if v - lowest < min {
                        return false;
                    }
                    if !near || p < NEAR || p + NEAR >= n {
                        return true;
                    }
                    let before: &[f64; NEAR] = x[p - NEAR..p].try_into().expect("NEAR samples");
                    let after: &[f64; NEAR] =
                        x[p + 1..p + 1 + NEAR].try_into().expect("NEAR samples");
                    let left: [f64; NEAR] = std::array::from_fn(|k| before[NEAR - 1 - k]);
                    !(side_rules_out(&left, v, min) | side_rules_out(after, v, min))
                })
                .collect()
        },
    )
}

/// Prominence of each peak, as `scipy.signal.peak_prominences`.
///
/// From each peak a horizontal line is extended left and right until it
/// meets a strictly higher sample or the window edge; the lowest sample on
/// each side (the one nearest the peak on ties) is that side's base:
///
/// ```text
/// prominence = x[peak] - max(x[left_base], x[right_base])
/// window     = [peak - wlen/2, peak + wlen/2] ∩ [0, n-1],  wlen = ceil(wlen)
/// ```
///
/// `peaks` need not be local maxima, sorted or unique (a sample that is not
/// a maximum gets prominence 0 and itself as bases, SciPy warns). SciPy
/// scans sample by sample up to the next higher sample, O(n) per peak on a
/// periodic signal. Here strictly increasing peaks (as [`find_peaks`](super::find_peaks)
/// returns them) reuse the searches of the peaks before them: a search
/// reaching a neighbour's searched stretch (all samples `<=` that peak)
/// takes its minimum whole or stops at that peak, so each sample is read
/// about once per side, in vector chunks (O(n + k)). Other peak lists step
/// over blocks of 16, 256, ... samples (O(n) to build, O(log n) per
/// peak). Both visit the samples in SciPy's order with its strict `<`, so
/// the results are identical.
///
/// ```
/// use ballpass_dsp::peak_prominences;
/// let x = [0.0, 1.0, 0.0, 3.0, 1.0, 3.0, 0.0, 4.0, 0.0];
/// let p = peak_prominences(&x, &[5], None)?;
/// assert_eq!((p.prominences[0], p.left_bases[0], p.right_bases[0]), (3.0, 2, 6));
/// let p = peak_prominences(&x, &[5], Some(3.1))?;
/// assert_eq!((p.prominences[0], p.left_bases[0], p.right_bases[0]), (2.0, 4, 6));
/// # Ok::<(), ballpass_dsp::DspError>(())
/// ```
///
/// # Errors
/// [`DspError::NonFinite`](crate::DspError::NonFinite) for a NaN or infinity in `x`;
/// [`DspError::InvalidSetting`](crate::DspError::InvalidSetting) for a peak index `>= x.len()` or
/// `wlen <= 1` (or non-finite).
pub fn peak_prominences(x: &[f64], peaks: &[usize], wlen: Option<f64>) -> Result<Prominences> {
    check_signal(x)?;
    check_peaks(x, peaks)?;
    let half = half_window(wlen)?;
    Ok(prominences_unchecked(x, peaks, half))
}

/// Prominences with validated input; `half` is `wlen // 2`.
pub(super) fn prominences_unchecked(
    x: &[f64],
    peaks: &[usize],
    half: Option<usize>,
) -> Prominences {
    let k = peaks.len();
    let mut out = Prominences {
        prominences: Vec::with_capacity(k),
        left_bases: Vec::with_capacity(k),
        right_bases: Vec::with_capacity(k),
    };
    if k == 0 {
        return out;
    }
    let n = x.len();
    let h = half.unwrap_or(n).min(n);
    let window = |p: usize| (p.saturating_sub(h), (p + h).min(n - 1));
    if k.saturating_mul(2 * h + 1) < n {
        // Short windows: SciPy's scans are cheaper than building the tree.
        for &p in peaks {
            let (lo, hi) = window(p);
            let (lmin, lb) = scan_left(x, p, lo);
            let (rmin, rb) = scan_right(x, p, hi);
            out.prominences.push(x[p] - lmin.max(rmin));
            out.left_bases.push(lb);
            out.right_bases.push(rb);
        }
    } else if peaks.windows(2).all(|w| w[0] < w[1]) {
        let (left, right) = match crate::simd::detect() {
            Some(Wide::Avx512(w)) => bases_sorted::<true>(x, peaks, h, w),
            Some(Wide::Avx2(w)) => bases_sorted::<true>(x, peaks, h, w),
            None => bases_sorted::<true>(x, peaks, h, Baseline),
        };
        for ((&p, (lmin, lb)), (rmin, rb)) in peaks.iter().zip(left).zip(right) {
            out.prominences.push(x[p] - lmin.max(rmin));
            out.left_bases.push(lb);
            out.right_bases.push(rb);
        }
    } else {
        let tree = MinMaxTree::new(x);
        for &p in peaks {
            let (lo, hi) = window(p);
            let (lmin, lb) = tree.base_left(p, lo);
            let (rmin, rb) = tree.base_right(p, hi);
            out.prominences.push(x[p] - lmin.max(rmin));
            out.left_bases.push(lb);
            out.right_bases.push(rb);
        }
    }
    out
}
