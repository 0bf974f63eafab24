//! Peak widths ([`peak_widths`], [`peak_widths_with_prominences`]).

use super::bases::{bases_sorted, scan_left, scan_right};
use super::prominence::prominences_unchecked;
use super::{
    check_peaks, check_rel_height, check_signal, half_window, PeakWidthsSettings, Prominences,
    Widths,
};
use crate::biquad::Baseline;
use crate::error::{invalid, DspError, Result};
use crate::simd::Wide;

/// Width of each peak at `rel_height` of its prominence, as
/// `scipy.signal.peak_widths`; prominences are computed with
/// `settings.wlen` (see [`peak_prominences`](super::peak_prominences)).
///
/// ```text
/// width_height = x[peak] - prominence * rel_height
/// left_ip      = i + (width_height - x[i]) / (x[i+1] - x[i])
///                (i: first sample left of the peak not above width_height,
///                 or the left base; no interpolation at the base or if
///                 x[i] == width_height)
/// right_ip     = mirror image;   width = right_ip - left_ip   (samples)
/// ```
///
/// ```
/// use ballpass_dsp::{peak_widths, PeakWidthsSettings};
/// let x = [0.0, 1.0, 2.0, 1.0, 0.0];
/// let w = peak_widths(&x, &[2], &PeakWidthsSettings::default())?;
/// assert_eq!((w.widths[0], w.width_heights[0], w.left_ips[0], w.right_ips[0]), (2.0, 1.0, 1.0,
/// 3.0));
/// # Ok::<(), ballpass_dsp::DspError>(())
/// ```
///
/// # Errors
/// As [`peak_prominences`](super::peak_prominences), and
/// [`DspError::InvalidSetting`](crate::DspError::InvalidSetting) for `rel_height < 0` or
/// non-finite.
pub fn peak_widths(x: &[f64], peaks: &[usize], settings: &PeakWidthsSettings) -> Result<Widths> {
    check_rel_height(settings.rel_height)?;
    check_signal(x)?;
    check_peaks(x, peaks)?;
    let half = half_window(settings.wlen)?;
    if let Some(w) = widths_sorted(x, peaks, half, settings.rel_height) {
        return Ok(w);
    }
    let prom = prominences_unchecked(x, peaks, half);
    Ok(widths_unchecked(
        x,
        peaks,
        settings.rel_height,
        &prom.prominences,
        &prom.left_bases,
        &prom.right_bases,
    ))
}

/// [`peak_widths`] with prominence data computed beforehand (SciPy's
/// `prominence_data` argument), e.g. from [`find_peaks`](super::find_peaks).
///
/// # Errors
/// [`DspError::NonFinite`](crate::DspError::NonFinite) for a NaN or infinity in `x`;
/// [`DspError::LengthMismatch`] if the arrays of `prominences` are not as
/// long as `peaks`; [`DspError::InvalidSetting`](crate::DspError::InvalidSetting) unless
/// `0 <= left_base <= peak <= right_base < x.len()` and the prominence is
/// finite and >= 0 for every peak (SciPy reads out of bounds on a negative
/// prominence at the signal's edge), or for `rel_height < 0` or non-finite.
pub fn peak_widths_with_prominences(
    x: &[f64],
    peaks: &[usize],
    rel_height: f64,
    prominences: &Prominences,
) -> Result<Widths> {
    check_signal(x)?;
    check_rel_height(rel_height)?;
    for (what, len) in [
        ("peaks and prominences", prominences.prominences.len()),
        ("peaks and left_bases", prominences.left_bases.len()),
        ("peaks and right_bases", prominences.right_bases.len()),
    ] {
        if len != peaks.len() {
            return Err(DspError::LengthMismatch {
                what,
                expected: peaks.len(),
                found: len,
            });
        }
    }
    for (i, &p) in peaks.iter().enumerate() {
        let (lb, rb, pr) = (
            prominences.left_bases[i],
            prominences.right_bases[i],
            prominences.prominences[i],
        );
        if !(lb <= p && p <= rb && rb < x.len()) {
            return Err(invalid(
                "prominences",
                format!(
                    "bases ({lb}, {rb}) are invalid for peak {p} in x of length {}",
                    x.len()
                ),
            ));
        }
        if !(pr.is_finite() && pr >= 0.0) {
            return Err(invalid(
                "prominences",
                format!("prominence {pr} of peak {p} is not finite and >= 0"),
            ));
        }
    }
    Ok(widths_unchecked(
        x,
        peaks,
        rel_height,
        &prominences.prominences,
        &prominences.left_bases,
        &prominences.right_bases,
    ))
}

/// [`peak_widths`] of strictly increasing peaks (validated input) for
/// `rel_height < 1`, with the bases located only where the width search
/// could reach them; `None` where [`prominences_unchecked`] would not take
/// its sorted path (or `rel_height >= 1`).
///
/// The search for the crossing left of a peak stops at the first sample
/// `<= width_height`; it cannot pass the left base when
/// `x[left_base] <= width_height` (the base lies between the peak and the
/// window's edge), so there the base only bounds a search that stops
/// anyway, and the signal's first sample is as good a bound. Only the
/// bases' values are needed for the prominences; a base's index is
/// searched for (SciPy's scan) only when `width_height` is below it (by
/// rounding) or when it and the peak are both zero (whose signs the
/// prominence keeps). Same results as with every base located.
pub(super) fn widths_sorted(
    x: &[f64],
    peaks: &[usize],
    half: Option<usize>,
    rel_height: f64,
) -> Option<Widths> {
    let (n, k) = (x.len(), peaks.len());
    let h = half.unwrap_or(n).min(n);
    // At `rel_height >= 1` rounding often puts the width height below a
    // base, whose index would then be scanned for peak by peak (quadratic
    // without a window): the located path is linear there.
    if k == 0
        || rel_height >= 1.0
        || k.saturating_mul(2 * h + 1) < n
        || !peaks.windows(2).all(|w| w[0] < w[1])
    {
        return None;
    }
    let (left, right) = match crate::simd::detect() {
        Some(Wide::Avx512(w)) => bases_sorted::<false>(x, peaks, h, w),
        Some(Wide::Avx2(w)) => bases_sorted::<false>(x, peaks, h, w),
        None => bases_sorted::<false>(x, peaks, h, Baseline),
    };
    let mut prom = Vec::with_capacity(k);
    let mut left_bases = Vec::with_capacity(k);
    let mut right_bases = Vec::with_capacity(k);
    for ((&p, &(lmin, lb)), &(rmin, rb)) in peaks.iter().zip(&left).zip(&right) {
        // A zero's sign (the value of the sample SciPy reads) changes the
        // prominence `x[p] - max(l, r)` only when the peak is zero too.
        let zero_peak = x[p] == 0.0;
        let lb = if zero_peak && lmin == 0.0 && lb == usize::MAX {
            scan_left(x, p, p.saturating_sub(h)).1
        } else {
            lb
        };
        let rb = if zero_peak && rmin == 0.0 && rb == usize::MAX {
            scan_right(x, p, (p + h).min(n - 1)).1
        } else {
            rb
        };
        let lv = if lb == usize::MAX { lmin } else { x[lb] };
        let rv = if rb == usize::MAX { rmin } else { x[rb] };
        let pr = x[p] - lv.max(rv);
        let height = x[p] - pr * rel_height;
        left_bases.push(if lb != usize::MAX {
            lb
        } else if lv <= height {
            0
        } else {
            scan_left(x, p, p.saturating_sub(h)).1
        });
        right_bases.push(if rb != usize::MAX {
            rb
        } else if rv <= height {
            n - 1
        } else {
            scan_right(x, p, (p + h).min(n - 1)).1
        });
        prom.push(pr);
    }
    Some(widths_unchecked(
        x,
        peaks,
        rel_height,
        &prom,
        &left_bases,
        &right_bases,
    ))
}

/// SciPy's `_peak_widths` on validated input (bases bracket the peak,
/// prominence >= 0, so `x[peak] >= height` and the neighbours read exist).
pub(super) fn widths_unchecked(
    x: &[f64],
    peaks: &[usize],
    rel_height: f64,
    prominences: &[f64],
    left_bases: &[usize],
    right_bases: &[usize],
) -> Widths {
    let k = peaks.len();
    let mut out = Widths {
        widths: Vec::with_capacity(k),
        width_heights: Vec::with_capacity(k),
        left_ips: Vec::with_capacity(k),
        right_ips: Vec::with_capacity(k),
    };
    for (j, &peak) in peaks.iter().enumerate() {
        let (i_min, i_max) = (left_bases[j], right_bases[j]);
        let height = x[peak] - prominences[j] * rel_height;

        let mut i = peak;
        while i_min < i && height < x[i] {
            i -= 1;
        }
        let mut left_ip = i as f64;
        if x[i] < height && x[i + 1] != x[i] {
            left_ip += (height - x[i]) / (x[i + 1] - x[i]);
        }

        let mut i = peak;
        while i < i_max && height < x[i] {
            i += 1;
        }
        let mut right_ip = i as f64;
        if x[i] < height && x[i - 1] != x[i] {
            right_ip -= (height - x[i]) / (x[i - 1] - x[i]);
        }

        out.widths.push(right_ip - left_ip);
        out.width_heights.push(height);
        out.left_ips.push(left_ip);
        out.right_ips.push(right_ip);
    }
    out
}
