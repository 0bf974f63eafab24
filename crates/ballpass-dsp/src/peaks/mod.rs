//! Peak finding, prominences and widths, matching `scipy.signal.find_peaks`,
//! `peak_prominences` and `peak_widths` (SciPy 1.17).
//!
//! A *peak* is one or more samples of equal value with a strictly smaller
//! sample on each side; the first and last samples are never peaks. A flat
//! peak (plateau) is reported at its middle index, rounded down:
//!
//! ```text
//! peak = (left_edge + right_edge) / 2        (integer division)
//! ```
//!
//! [`find_peaks`] applies its criteria in SciPy's order, each one to the
//! peaks left by the previous ones: plateau size, height, threshold,
//! distance, prominence, width. A property is computed (and returned) only
//! when its criterion is given; a [`Bound::any`] computes it without removing
//! peaks, as SciPy's `(None, None)`.
//!
//! Differences from SciPy, all on inputs where SciPy's answer is undefined
//! or an accident of the platform:
//! - a NaN or infinite sample is an `Err` (SciPy: "may return unexpected
//!   results");
//! - with `distance`, peaks of *exactly equal* height closer than `distance`
//!   are ranked by position, the later one first (NumPy's `kind="stable"`
//!   argsort). SciPy uses NumPy's default argsort, whose order of ties is not
//!   stable and differs between CPUs (SIMD sorting networks);
//! - a NaN bound, a non-finite `distance`, `wlen` or `rel_height` is an
//!   `Err`, and settings are checked even when the criterion that uses them
//!   is off.
//!
//! ```
//! use ballpass_dsp::{find_peaks, Bound, FindPeaksSettings};
//! let x = [0.0, 1.0, 0.0, 3.0, 1.0, 3.0, 0.0, 4.0, 0.0];
//! let settings = FindPeaksSettings { prominence: Some(Bound::at_least(2.5)), ..Default::default() };
//! let peaks = find_peaks(&x, &settings)?;
//! assert_eq!(peaks.indices, [3, 5, 7]);
//! assert_eq!(peaks.properties.prominences, Some(vec![3.0, 3.0, 4.0]));
//! # Ok::<(), ballpass_dsp::DspError>(())
//! ```

use crate::error::{invalid, Result};

mod bases;
mod distance;
mod prominence;
mod widths;

pub(crate) use bases::{run_left, run_right, Runs};
use distance::{local_maxima, peaks_by_distance, select_by_distance};
pub use prominence::peak_prominences;
use prominence::{may_be_prominent, prominences_unchecked};
use widths::widths_unchecked;
pub use widths::{peak_widths, peak_widths_with_prominences};

/// An interval `[min, max]` a peak property must lie in; either end may be
/// open (`None`). SciPy's `(min, max)` tuple, or a bare number for `min`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Bound {
    /// Smallest accepted value (inclusive), or no lower limit.
    pub min: Option<f64>,
    /// Largest accepted value (inclusive), or no upper limit.
    pub max: Option<f64>,
}

impl Bound {
    /// No limit: the property is computed and returned, no peak is removed
    /// (SciPy's `(None, None)`).
    pub const fn any() -> Self {
        Bound {
            min: None,
            max: None,
        }
    }

    /// `value >= min`.
    pub const fn at_least(min: f64) -> Self {
        Bound {
            min: Some(min),
            max: None,
        }
    }

    /// `value <= max`.
    pub const fn at_most(max: f64) -> Self {
        Bound {
            min: None,
            max: Some(max),
        }
    }

    /// `min <= value <= max`.
    pub const fn between(min: f64, max: f64) -> Self {
        Bound {
            min: Some(min),
            max: Some(max),
        }
    }

    /// Whether `value` lies in the bound (SciPy's `_select_by_property`).
    pub fn contains(&self, value: f64) -> bool {
        self.min.is_none_or(|m| m <= value) && self.max.is_none_or(|m| value <= m)
    }

    fn validate(&self, name: &'static str) -> Result<()> {
        for end in [self.min, self.max].into_iter().flatten() {
            if end.is_nan() {
                return Err(invalid(name, "bound is NaN"));
            }
        }
        Ok(())
    }
}

/// Settings of [`find_peaks`]; every criterion is off by default.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FindPeaksSettings {
    /// Required peak height `x[peak]`.
    pub height: Option<Bound>,
    /// Required vertical distance to both neighbouring samples: `min` is
    /// compared with the smaller of `x[p] - x[p-1]` and `x[p] - x[p+1]`,
    /// `max` with the larger.
    pub threshold: Option<Bound>,
    /// Minimal horizontal distance in samples (>= 1, rounded up) between
    /// peaks; lower peaks are removed first.
    pub distance: Option<f64>,
    /// Required prominence (see [`peak_prominences`]).
    pub prominence: Option<Bound>,
    /// Required width in samples (see [`peak_widths`]).
    pub width: Option<Bound>,
    /// Window length in samples for the prominence search (> 1, rounded up
    /// to an integer, then the window is `2 * (wlen / 2) + 1` samples
    /// centred on the peak); `None` searches the whole signal.
    pub wlen: Option<f64>,
    /// Height at which widths are measured, as a fraction of the prominence
    /// below the peak (>= 0). Default 0.5.
    pub rel_height: f64,
    /// Required number of samples in the flat top of a peak.
    pub plateau_size: Option<Bound>,
}

impl Default for FindPeaksSettings {
    fn default() -> Self {
        FindPeaksSettings {
            height: None,
            threshold: None,
            distance: None,
            prominence: None,
            width: None,
            wlen: None,
            rel_height: 0.5,
            plateau_size: None,
        }
    }
}

/// Properties of the peaks returned by [`find_peaks`], one entry per peak.
/// A field is `Some` only when the criterion that computes it was given.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PeakProperties {
    /// `x[peak]`; with `height`.
    pub peak_heights: Option<Vec<f64>>,
    /// `x[peak] - x[peak - 1]`; with `threshold`.
    pub left_thresholds: Option<Vec<f64>>,
    /// `x[peak] - x[peak + 1]`; with `threshold`.
    pub right_thresholds: Option<Vec<f64>>,
    /// Prominences; with `prominence` or `width`.
    pub prominences: Option<Vec<f64>>,
    /// Left bases (sample indices); with `prominence` or `width`.
    pub left_bases: Option<Vec<usize>>,
    /// Right bases (sample indices); with `prominence` or `width`.
    pub right_bases: Option<Vec<usize>>,
    /// Widths in samples; with `width`.
    pub widths: Option<Vec<f64>>,
    /// Heights at which the widths were measured; with `width`.
    pub width_heights: Option<Vec<f64>>,
    /// Interpolated left intersection positions (samples); with `width`.
    pub left_ips: Option<Vec<f64>>,
    /// Interpolated right intersection positions (samples); with `width`.
    pub right_ips: Option<Vec<f64>>,
    /// Samples in the flat top, `right_edge - left_edge + 1`; with `plateau_size`.
    pub plateau_sizes: Option<Vec<usize>>,
    /// First sample of the flat top; with `plateau_size`.
    pub left_edges: Option<Vec<usize>>,
    /// Last sample of the flat top; with `plateau_size`.
    pub right_edges: Option<Vec<usize>>,
}

impl PeakProperties {
    fn retain(&mut self, keep: &[bool]) {
        fn f<T: Copy>(v: &mut Option<Vec<T>>, keep: &[bool]) {
            if let Some(v) = v {
                retain_mask(v, keep);
            }
        }
        f(&mut self.peak_heights, keep);
        f(&mut self.left_thresholds, keep);
        f(&mut self.right_thresholds, keep);
        f(&mut self.prominences, keep);
        f(&mut self.left_bases, keep);
        f(&mut self.right_bases, keep);
        f(&mut self.widths, keep);
        f(&mut self.width_heights, keep);
        f(&mut self.left_ips, keep);
        f(&mut self.right_ips, keep);
        f(&mut self.plateau_sizes, keep);
        f(&mut self.left_edges, keep);
        f(&mut self.right_edges, keep);
    }
}

/// Peaks found by [`find_peaks`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Peaks {
    /// Sample indices of the peaks, increasing.
    pub indices: Vec<usize>,
    /// Their properties, in the same order.
    pub properties: PeakProperties,
}

/// Result of [`peak_prominences`], one entry per peak.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Prominences {
    /// `x[peak] - max(x[left_base], x[right_base])`, >= 0.
    pub prominences: Vec<f64>,
    /// Index of the minimum between the peak and the nearest higher sample
    /// (or window edge) on the left; the one nearest the peak on ties.
    pub left_bases: Vec<usize>,
    /// The same on the right.
    pub right_bases: Vec<usize>,
}

/// Result of [`peak_widths`], one entry per peak.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Widths {
    /// `right_ips - left_ips`, in samples.
    pub widths: Vec<f64>,
    /// `x[peak] - prominence * rel_height`.
    pub width_heights: Vec<f64>,
    /// Interpolated position where the signal crosses `width_heights` left
    /// of the peak (or the left base), in samples.
    pub left_ips: Vec<f64>,
    /// The same on the right.
    pub right_ips: Vec<f64>,
}

/// Settings of [`peak_widths`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeakWidthsSettings {
    /// Height at which the width is measured, as a fraction of the
    /// prominence below the peak (>= 0): 0.5 is the width at half
    /// prominence, 1.0 at the lowest contour line. Default 0.5.
    pub rel_height: f64,
    /// Window length for the prominence search, as
    /// [`FindPeaksSettings::wlen`].
    pub wlen: Option<f64>,
}

impl Default for PeakWidthsSettings {
    fn default() -> Self {
        PeakWidthsSettings {
            rel_height: 0.5,
            wlen: None,
        }
    }
}

/// Keeps `v[i]` where `keep[i]` (branch-free compaction; entries beyond
/// `keep` are dropped).
fn retain_mask<T: Copy>(v: &mut Vec<T>, keep: &[bool]) {
    debug_assert_eq!(v.len(), keep.len());
    let n = v.len().min(keep.len());
    let mut w = 0;
    for i in 0..n {
        v[w] = v[i];
        w += usize::from(keep[i]);
    }
    v.truncate(w);
}

/// Rejects NaN and infinite samples; an empty signal is allowed.
fn check_signal(x: &[f64]) -> Result<()> {
    if x.is_empty() {
        Ok(())
    } else {
        crate::error::check_finite("x", x)
    }
}

/// `wlen` as SciPy's `_arg_wlen_as_expected`: `None` → no window, else
/// `ceil(wlen)` which must be > 1. Returns the half window `wlen // 2`.
fn half_window(wlen: Option<f64>) -> Result<Option<usize>> {
    match wlen {
        None => Ok(None),
        Some(w) if w.is_finite() && w > 1.0 => {
            // Saturating: any window longer than the signal is the whole signal.
            let w = w.ceil().min(usize::MAX as f64) as usize;
            Ok(Some(w / 2))
        }
        Some(w) => Err(invalid(
            "wlen",
            format!("must be a finite number larger than 1, was {w}"),
        )),
    }
}

fn check_rel_height(rel_height: f64) -> Result<()> {
    if rel_height.is_finite() && rel_height >= 0.0 {
        Ok(())
    } else {
        Err(invalid(
            "rel_height",
            format!("must be finite and >= 0, was {rel_height}"),
        ))
    }
}

fn check_peaks(x: &[f64], peaks: &[usize]) -> Result<()> {
    match peaks.iter().find(|&&p| p >= x.len()) {
        Some(&p) => Err(invalid(
            "peaks",
            format!("peak {p} is not a valid index for x of length {}", x.len()),
        )),
        None => Ok(()),
    }
}

/// Finds peaks of `x` that satisfy the criteria in `settings`, as
/// `scipy.signal.find_peaks`.
///
/// The criteria apply in this order, each to the peaks that survived the
/// previous ones (SciPy's order): `plateau_size`, `height`, `threshold`,
/// `distance`, `prominence`, `width`. Prominences (and bases) are computed
/// when `prominence` or `width` is given, after the distance criterion.
///
/// ```text
/// threshold:   min <= min(x[p]-x[p-1], x[p]-x[p+1]),  max(...) <= max
/// distance:    keep the highest peak, drop every peak closer than
///              ceil(distance) samples to it, repeat with the next highest kept
/// ```
///
/// An empty (or shorter than 3 samples) signal has no peaks; this is not an
/// error (SciPy returns empty arrays).
///
/// # Errors
/// [`DspError::NonFinite`](crate::DspError::NonFinite) if `x` holds a NaN or infinity;
/// [`DspError::InvalidSetting`](crate::DspError::InvalidSetting) for `distance < 1` or
/// non-finite, `wlen <= 1` or non-finite, `rel_height < 0` or non-finite, or a NaN in a bound.
pub fn find_peaks(x: &[f64], settings: &FindPeaksSettings) -> Result<Peaks> {
    check_signal(x)?;
    let distance = match settings.distance {
        None => None,
        Some(d) if d.is_finite() && d >= 1.0 => Some(d.ceil().min(usize::MAX as f64) as usize),
        Some(d) => {
            return Err(invalid(
                "distance",
                format!("must be a finite number >= 1, was {d}"),
            ))
        }
    };
    let half = half_window(settings.wlen)?;
    check_rel_height(settings.rel_height)?;
    for (name, bound) in [
        ("height", settings.height),
        ("threshold", settings.threshold),
        ("prominence", settings.prominence),
        ("width", settings.width),
        ("plateau_size", settings.plateau_size),
    ] {
        if let Some(b) = bound {
            b.validate(name)?;
        }
    }

    // Without the filters that precede it, the distance criterion runs
    // fused with the search for maxima.
    let fused = distance.filter(|&d| {
        d > 1
            && settings.plateau_size.is_none()
            && settings.height.is_none()
            && settings.threshold.is_none()
    });
    let (mut peaks, flats) = match fused {
        Some(d) => (peaks_by_distance(x, d), Vec::new()),
        None => local_maxima(x),
    };
    let mut props = PeakProperties::default();
    let mut keep: Vec<bool> = Vec::new();

    if let Some(bound) = settings.plateau_size {
        let (mut left_edges, mut right_edges) = (peaks.clone(), peaks.clone());
        for &(k, l, r) in &flats {
            left_edges[k] = l;
            right_edges[k] = r;
        }
        let sizes: Vec<usize> = left_edges
            .iter()
            .zip(&right_edges)
            .map(|(l, r)| r - l + 1)
            .collect();
        keep.clear();
        keep.extend(sizes.iter().map(|&s| bound.contains(s as f64)));
        props.plateau_sizes = Some(sizes);
        props.left_edges = Some(left_edges);
        props.right_edges = Some(right_edges);
        apply(&mut peaks, &mut props, &keep);
    }

    if let Some(bound) = settings.height {
        let heights: Vec<f64> = peaks.iter().map(|&p| x[p]).collect();
        keep.clear();
        keep.extend(heights.iter().map(|&h| bound.contains(h)));
        props.peak_heights = Some(heights);
        apply(&mut peaks, &mut props, &keep);
    }

    if let Some(bound) = settings.threshold {
        let left: Vec<f64> = peaks.iter().map(|&p| x[p] - x[p - 1]).collect();
        let right: Vec<f64> = peaks.iter().map(|&p| x[p] - x[p + 1]).collect();
        keep.clear();
        keep.extend(left.iter().zip(&right).map(|(&l, &r)| {
            bound.min.is_none_or(|m| m <= l.min(r)) && bound.max.is_none_or(|m| l.max(r) <= m)
        }));
        props.left_thresholds = Some(left);
        props.right_thresholds = Some(right);
        apply(&mut peaks, &mut props, &keep);
    }

    if let (Some(distance), None) = (distance, fused) {
        let heights: Vec<f64> = peaks.iter().map(|&p| x[p]).collect();
        let keep = select_by_distance(&peaks, &heights, distance);
        apply(&mut peaks, &mut props, &keep);
    }

    if let Some(min) = settings.prominence.and_then(|b| b.min) {
        // Most maxima of a noisy signal end their base search within a few
        // samples on one side, too shallow for `min`: dropped before the
        // (branchy) exact search, as the criterion would drop them.
        let keep = may_be_prominent(x, &peaks, half, min);
        apply(&mut peaks, &mut props, &keep);
    }

    if settings.prominence.is_some() || settings.width.is_some() {
        let prom = prominences_unchecked(x, &peaks, half);
        props.prominences = Some(prom.prominences);
        props.left_bases = Some(prom.left_bases);
        props.right_bases = Some(prom.right_bases);
    }

    if let (Some(bound), Some(prom)) = (settings.prominence, &props.prominences) {
        keep.clear();
        keep.extend(prom.iter().map(|&p| bound.contains(p)));
        apply(&mut peaks, &mut props, &keep);
    }

    if let (Some(bound), Some(prom), Some(lb), Some(rb)) = (
        settings.width,
        &props.prominences,
        &props.left_bases,
        &props.right_bases,
    ) {
        let w = widths_unchecked(x, &peaks, settings.rel_height, prom, lb, rb);
        keep.clear();
        keep.extend(w.widths.iter().map(|&v| bound.contains(v)));
        props.widths = Some(w.widths);
        props.width_heights = Some(w.width_heights);
        props.left_ips = Some(w.left_ips);
        props.right_ips = Some(w.right_ips);
        apply(&mut peaks, &mut props, &keep);
    }

    Ok(Peaks {
        indices: peaks,
        properties: props,
    })
}

fn apply(peaks: &mut Vec<usize>, props: &mut PeakProperties, keep: &[bool]) {
    if keep.iter().all(|&k| k) {
        return;
    }
    retain_mask(peaks, keep);
    props.retain(keep);
}

#[cfg(test)]
mod tests;
