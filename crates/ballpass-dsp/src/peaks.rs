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

use crate::biquad::Baseline;
use crate::error::{invalid, DspError, Result};
use crate::simd::Wide;

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

/// Local maxima as SciPy's `_local_maxima_1d`: the midpoints, and
/// `(position in midpoints, left_edge, right_edge)` for the flat ones (a
/// strict maximum is its own edges).
///
/// Every sample is tested on its own (SciPy skips the samples right of a
/// maximum, none of which can start one, so the results are equal): 64
/// samples at a time into bit masks of strict maxima and plateau starts,
/// branch-free, which matters on noise where a third of the samples are
/// maxima; only plateau starts take SciPy's look-ahead.
fn local_maxima(x: &[f64]) -> (Vec<usize>, Vec<(usize, usize, usize)>) {
    let n = x.len();
    if n < 3 {
        return (Vec::new(), Vec::new());
    }
    let i_max = n - 1;
    let mut mids = Vec::with_capacity(n / 2 + 1);
    let mut flats = Vec::new();
    let mut base = 1;
    while base < i_max {
        let end = (base + 64).min(i_max);
        let (mut strict, mut flat) = (0u64, 0u64);
        for (j, w) in x[base - 1..=end].windows(3).enumerate() {
            let up = w[0] < w[1];
            strict |= u64::from(up & (w[1] > w[2])) << j;
            flat |= u64::from(up & (w[1] == w[2])) << j;
        }
        let mut bits = strict | flat;
        while bits != 0 {
            let j = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let i = base + j;
            if (flat >> j) & 1 == 0 {
                mids.push(i);
            } else {
                let b = x[i];
                let mut ahead = i + 1;
                while ahead < i_max && x[ahead] == b {
                    ahead += 1;
                }
                if x[ahead] < b {
                    flats.push((mids.len(), i, ahead - 1));
                    mids.push((i + ahead - 1) / 2);
                }
            }
        }
        base = end;
    }
    (mids, flats)
}

/// `priority[a]` ranks above `priority[b]`: higher, or equal and later
/// (NumPy `argsort(kind="stable")` walked from the end).
#[inline]
fn ranks_above(priority: &[f64], a: usize, b: usize) -> bool {
    priority[a] > priority[b] || (priority[a] == priority[b] && a > b)
}

/// SciPy's `_select_by_peak_distance`: walk the peaks from the highest
/// priority down; each one still kept removes its neighbours closer than
/// `distance` samples.
fn greedy_distance(peaks: &[usize], priority: &[f64], distance: usize) -> Vec<bool> {
    let n = peaks.len();
    let mut keep = vec![true; n];
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_unstable_by(|&a, &b| priority[a].total_cmp(&priority[b]).then_with(|| a.cmp(&b)));
    for &j in order.iter().rev() {
        if !keep[j] {
            continue;
        }
        let mut k = j;
        while k > 0 && peaks[j] - peaks[k - 1] < distance {
            keep[k - 1] = false;
            k -= 1;
        }
        let mut k = j + 1;
        while k < n && peaks[k] - peaks[j] < distance {
            keep[k] = false;
            k += 1;
        }
    }
    keep
}

/// Mask of the peaks kept by the distance criterion, equal to
/// [`greedy_distance`] but without sorting every peak.
///
/// A peak that ranks above every other peak closer than `distance` is kept
/// by the greedy walk, and removes all those neighbours (found in O(k) with
/// two sliding-window maxima). The peaks left undecided are farther than
/// `distance` from every such peak, so only undecided peaks can remove each
/// other: the greedy walk on them alone decides them as on the full set.
fn select_by_distance(peaks: &[usize], priority: &[f64], distance: usize) -> Vec<bool> {
    let k = peaks.len();
    if distance <= 1 || k < 2 {
        return vec![true; k];
    }
    // dominated[j]: some peak closer than `distance` ranks above j. Cut the
    // samples into blocks of `distance`: any two peaks in one block are
    // closer than `distance`, so only the top-ranked peak of a block can be
    // undominated, and it is if it also outranks the peaks within reach,
    // all of which lie in the two neighbouring blocks. A neighbouring
    // block whose own top peak ranks below it holds no such peak; only
    // when that top peak ranks above but is out of reach are the peaks
    // within reach scanned.
    struct Block {
        id: usize,
        start: usize,
        end: usize,
        best: usize,
    }
    let mut blocks = Vec::new();
    let mut j = 0;
    while j < k {
        let id = peaks[j] / distance;
        let block_end = (id + 1).saturating_mul(distance);
        let mut best = j;
        let mut e = j + 1;
        while e < k && peaks[e] < block_end {
            if ranks_above(priority, e, best) {
                best = e;
            }
            e += 1;
        }
        blocks.push(Block {
            id,
            start: j,
            end: e,
            best,
        });
        j = e;
    }
    let mut dominated = vec![true; k];
    for (i, b) in blocks.iter().enumerate() {
        let p = peaks[b.best];
        let outranks =
            |n: &Block| n.id.abs_diff(b.id) == 1 && ranks_above(priority, n.best, b.best);
        let left = i.checked_sub(1).map(|i| &blocks[i]).is_some_and(|n| {
            outranks(n)
                && (p - peaks[n.best] < distance
                    || peaks[n.start..b.start]
                        .iter()
                        .enumerate()
                        .rev()
                        .take_while(|&(_, &q)| p - q < distance)
                        .any(|(o, _)| ranks_above(priority, n.start + o, b.best)))
        });
        let right = || {
            blocks.get(i + 1).is_some_and(|n| {
                outranks(n)
                    && (peaks[n.best] - p < distance
                        || peaks[b.end..n.end]
                            .iter()
                            .enumerate()
                            .take_while(|&(_, &q)| q - p < distance)
                            .any(|(o, _)| ranks_above(priority, b.end + o, b.best)))
            })
        };
        if !left && !right() {
            dominated[b.best] = false;
        }
    }
    // 0 = undecided, 1 = kept, 2 = removed
    let mut state = vec![0u8; k];
    for j in 0..k {
        if dominated[j] {
            continue;
        }
        state[j] = 1;
        let mut i = j;
        while i > 0 && peaks[j] - peaks[i - 1] < distance {
            state[i - 1] = 2;
            i -= 1;
        }
        let mut i = j + 1;
        while i < k && peaks[i] - peaks[j] < distance {
            state[i] = 2;
            i += 1;
        }
    }
    let rest: Vec<usize> = (0..k).filter(|&j| state[j] == 0).collect();

    if !rest.is_empty() {
        let p: Vec<usize> = rest.iter().map(|&j| peaks[j]).collect();
        let h: Vec<f64> = rest.iter().map(|&j| priority[j]).collect();
        for (&j, kept) in rest.iter().zip(greedy_distance(&p, &h, distance)) {
            state[j] = if kept { 1 } else { 2 };
        }
    }
    state.iter().map(|&s| s == 1).collect()
}

/// `(value, index)` ranks above `other`: higher, or equal and later (the
/// order of [`ranks_above`]).
#[inline]
fn outranks(a: (f64, usize), b: (f64, usize)) -> bool {
    a.0 > b.0 || (a.0 == b.0 && a.1 > b.1)
}

/// Lanes of [`strict_top`] over `w` (samples `1..w.len() - 1` tested, a
/// multiple of [`PEAK_LANES`] of them): per lane the largest strict local
/// maximum (`-inf` if none) and 1.0 if a plateau starts there (else 0.0).
/// Exact maxima, so every instance (baseline, or compiled with AVX2 /
/// AVX-512F through `crate::simd::widest`) returns the same bits.
#[inline(always)]
fn peak_lanes(w: &[f64]) -> ([f64; PEAK_LANES], [f64; PEAK_LANES]) {
    const L: usize = PEAK_LANES;
    let mut acc = [f64::NEG_INFINITY; L];
    let mut flat = [0.0f64; L];
    for s in w.windows(L + 2).step_by(L) {
        for l in 0..L {
            let (a, v, z) = (s[l], s[l + 1], s[l + 2]);
            // `&`, not `&&`: no branches.
            let up = a < v;
            let mv = if up & (v > z) { v } else { f64::NEG_INFINITY };
            acc[l] = if mv > acc[l] { mv } else { acc[l] };
            let fl = if up & (v == z) { 1.0 } else { 0.0 };
            flat[l] = if fl > flat[l] { fl } else { flat[l] };
        }
    }
    (acc, flat)
}

/// Lanes of [`peak_lanes`].
const PEAK_LANES: usize = 8;

/// The top-ranked strict local maximum (`x[i-1] < x[i] > x[i+1]`; highest,
/// the later on ties) among the samples `lo..=hi`, and whether a plateau
/// starts there (`x[i-1] < x[i] == x[i+1]`). Needs `1 <= lo` and
/// `hi + 1 < x.len()`.
///
/// Two passes over groups of 8 samples. The first is branch-free: non-maxima
/// enter as `-inf` (which no finite sample is) into 8 running maxima (exact
/// in any order), and plateau starts as 1.0 into 8 more (flags kept as
/// floats, so that every lane operation is a vector compare, select or
/// maximum); the block's best value
/// is the largest of the 8. The second walks the groups back from the end to
/// the last maximum of that value, the top (the later one on ties).
/// Inlined into the block loop of [`peaks_by_distance`], which runs
/// through `crate::simd::widest` (one call per signal, not per block).
#[inline(always)]
fn strict_top(x: &[f64], lo: usize, hi: usize) -> (Option<(f64, usize)>, bool) {
    const L: usize = PEAK_LANES;
    if lo > hi {
        return (None, false);
    }
    let w = &x[lo - 1..=hi + 1];
    let m = hi + 1 - lo;
    let full = m / L * L;
    let peak_value = |j: usize| {
        let (a, v, z) = (w[j], w[j + 1], w[j + 2]);
        if a < v && v > z {
            v
        } else {
            f64::NEG_INFINITY
        }
    };
    let (acc, flat) = peak_lanes(&w[..full + 2]);
    let mut best = acc.iter().fold(f64::NEG_INFINITY, |m, &v| m.max(v));
    let mut any_flat = flat.iter().any(|&f| f != 0.0);
    let mut at = None;
    for j in full..m {
        let (a, v, z) = (w[j], w[j + 1], w[j + 2]);
        any_flat |= (a < v) & (v == z);
        let mv = peak_value(j);
        if mv >= best && mv != f64::NEG_INFINITY {
            best = mv;
            at = Some(j);
        }
    }
    if at.is_none() && best != f64::NEG_INFINITY {
        // Most groups hold no sample equal to `best`: test that first,
        // all 8 at once.
        at = (0..full / L).rev().find_map(|g| {
            let s = &w[g * L + 1..g * L + 1 + L];
            let eq: [bool; L] = std::array::from_fn(|l| s[l] == best);
            if !eq.iter().fold(false, |a, &e| a | e) {
                return None;
            }
            (g * L..g * L + L).rev().find(|&j| peak_value(j) == best)
        });
    }
    (at.map(|j| (best, lo + j)), any_flat)
}

/// Appends the flat maxima starting in `lo..=hi` as `(middle, left_edge,
/// right_edge)`, with SciPy's look-ahead (see [`local_maxima`]); needs
/// `1 <= lo` and `hi + 1 < x.len()`.
fn plateaus_in(x: &[f64], lo: usize, hi: usize, flats: &mut Vec<(usize, usize, usize)>) {
    let i_max = x.len() - 1;
    for i in lo..=hi {
        let b = x[i];
        if x[i - 1] < b && x[i + 1] == b {
            let mut ahead = i + 1;
            while ahead < i_max && x[ahead] == b {
                ahead += 1;
            }
            if x[ahead] < b {
                flats.push(((i + ahead - 1) / 2, i, ahead - 1));
            }
        }
    }
}

/// The flat maxima of `flats` (sorted by middle) whose middle lies in
/// `lo..=hi`.
fn flats_in(flats: &[(usize, usize, usize)], lo: usize, hi: usize) -> &[(usize, usize, usize)] {
    let start = flats.partition_point(|f| f.0 < lo);
    let end = flats.partition_point(|f| f.0 <= hi);
    &flats[start..end.max(start)]
}

/// The top-ranked local maximum (strict, or a plateau's middle) in
/// `lo..=hi`.
fn top_in(
    x: &[f64],
    flats: &[(usize, usize, usize)],
    lo: usize,
    hi: usize,
) -> Option<(f64, usize)> {
    let mut top = strict_top(x, lo, hi).0;
    for &(mid, _, _) in flats_in(flats, lo, hi) {
        if top.is_none_or(|t| outranks((x[mid], mid), t)) {
            top = Some((x[mid], mid));
        }
    }
    top
}

/// [`local_maxima`] followed by [`select_by_distance`] on their heights,
/// without listing the maxima that `distance` removes (`distance >= 2`).
///
/// The samples are cut into blocks of `distance`; only the top-ranked
/// maximum of a block can outrank every maximum closer than `distance`,
/// and it does if it outranks those within reach in the two neighbouring
/// blocks (a neighbour whose own top ranks below it holds none above it).
/// Such an undominated maximum is kept by SciPy's greedy walk and removes
/// every maximum closer than `distance`, so the maxima listed are only the
/// block tops and those at least `distance` from every undominated one;
/// the latter can only remove each other, and the greedy walk on them
/// alone decides them (as in [`select_by_distance`]).
fn peaks_by_distance(x: &[f64], distance: usize) -> Vec<usize> {
    let n = x.len();
    if n < 3 {
        return Vec::new();
    }
    let last = n - 2;
    let block = |id: usize| {
        let lo = id.saturating_mul(distance).max(1);
        let hi = (id + 1)
            .saturating_mul(distance)
            .saturating_sub(1)
            .min(last);
        (lo, hi)
    };
    let blocks = last / distance + 1;
    let mut tops = Vec::with_capacity(blocks);
    let mut flats = Vec::new();
    crate::simd::widest(|| {
        for id in 0..blocks {
            let (lo, hi) = block(id);
            let (top, flat) = strict_top(x, lo, hi);
            if flat {
                plateaus_in(x, lo, hi, &mut flats);
            }
            tops.push(top);
        }
    });
    for &(mid, _, _) in &flats {
        let t = &mut tops[mid / distance];
        if t.is_none_or(|t| outranks((x[mid], mid), t)) {
            *t = Some((x[mid], mid));
        }
    }

    let mut sure = Vec::new();
    for (id, &top) in tops.iter().enumerate() {
        let Some(t) = top else { continue };
        let p = t.1;
        let left = id.checked_sub(1).and_then(|i| tops[i]).is_some_and(|l| {
            outranks(l, t)
                && (p - l.1 < distance
                    || top_in(x, &flats, p + 1 - distance, block(id).0 - 1)
                        .is_some_and(|m| outranks(m, t)))
        });
        let right = || {
            tops.get(id + 1).copied().flatten().is_some_and(|r| {
                outranks(r, t)
                    && (r.1 - p < distance
                        || top_in(x, &flats, block(id + 1).0, (p + distance - 1).min(last))
                            .is_some_and(|m| outranks(m, t)))
            })
        };
        if !left && !right() {
            sure.push(p);
        }
    }

    // The maxima at least `distance` from every undominated one.
    let mut rest = Vec::new();
    let mut from = 1;
    for &s in sure.iter().chain(std::iter::once(&usize::MAX)) {
        let to = if s == usize::MAX {
            last
        } else {
            match s.checked_sub(distance) {
                Some(to) => to,
                None => {
                    from = s.saturating_add(distance);
                    continue;
                }
            }
        };
        if from <= to {
            let start = rest.len();
            for i in from..=to {
                if x[i - 1] < x[i] && x[i] > x[i + 1] {
                    rest.push(i);
                }
            }
            let flat = flats_in(&flats, from, to);
            if !flat.is_empty() {
                rest.extend(flat.iter().map(|f| f.0));
                rest[start..].sort_unstable();
            }
        }
        from = s.saturating_add(distance);
    }
    if !rest.is_empty() {
        let h: Vec<f64> = rest.iter().map(|&p| x[p]).collect();
        let keep = greedy_distance(&rest, &h, distance);
        retain_mask(&mut rest, &keep);
        // Both increasing: merge.
        let mut all = Vec::with_capacity(sure.len() + rest.len());
        let (mut a, mut b) = (sure.iter().peekable(), rest.iter().peekable());
        while let (Some(&&i), Some(&&j)) = (a.peek(), b.peek()) {
            if i < j {
                all.push(i);
                a.next();
            } else {
                all.push(j);
                b.next();
            }
        }
        all.extend(a.chain(b));
        return all;
    }
    sure
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
/// [`DspError::NonFinite`] if `x` holds a NaN or infinity;
/// [`DspError::InvalidSetting`] for `distance < 1` or non-finite, `wlen <= 1`
/// or non-finite, `rel_height < 0` or non-finite, or a NaN in a bound.
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

/// Samples read on each side of a peak by [`may_be_prominent`].
const NEAR: usize = 8;

/// Whether a side of a peak of height `v` rules out a prominence of
/// `min`: `c` holds the [`NEAR`] samples next to the peak on that side,
/// nearest first, all inside the window. If one of them is higher than the
/// peak, SciPy's base search on that side stops there and its minimum is
/// the lowest of `v` and the samples before the stop: exactly known. The
/// prominence, `v` less the higher of the two sides' minima, is then at
/// most `v` less this side's minimum (rounding is monotonic), so
/// `v - side_min < min` means the prominence criterion removes the peak.
#[inline(always)]
fn side_rules_out(c: &[f64; NEAR], v: f64, min: f64) -> bool {
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
/// half width `half`, see [`peak_prominences`]): `false` only for peaks
/// whose prominence is certainly below `min` (`x[p]` less the signal's
/// lowest sample is below `min`, or [`side_rules_out`] on either side),
/// which the prominence criterion would remove. Branch-free
/// per peak (a noise maximum's short searches are what makes SciPy's scan,
/// and the exact search here, slow: their ends are unpredictable), compiled
/// through `crate::simd::widest`. Peaks nearer than [`NEAR`] samples to the
/// signal's ends, or all peaks when the window is shorter than that, are
/// tested against the lowest sample only.
fn may_be_prominent(x: &[f64], peaks: &[usize], half: Option<usize>, min: f64) -> Vec<bool> {
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

fn apply(peaks: &mut Vec<usize>, props: &mut PeakProperties, keep: &[bool]) {
    if keep.iter().all(|&k| k) {
        return;
    }
    retain_mask(peaks, keep);
    props.retain(keep);
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
/// periodic signal. Here strictly increasing peaks (as [`find_peaks`]
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
/// [`DspError::NonFinite`] for a NaN or infinity in `x`;
/// [`DspError::InvalidSetting`] for a peak index `>= x.len()` or
/// `wlen <= 1` (or non-finite).
pub fn peak_prominences(x: &[f64], peaks: &[usize], wlen: Option<f64>) -> Result<Prominences> {
    check_signal(x)?;
    check_peaks(x, peaks)?;
    let half = half_window(wlen)?;
    Ok(prominences_unchecked(x, peaks, half))
}

/// Prominences with validated input; `half` is `wlen // 2`.
fn prominences_unchecked(x: &[f64], peaks: &[usize], half: Option<usize>) -> Prominences {
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

/// SciPy's left base scan over `[lo, p]`: minimum (nearest `p` on ties) of
/// the samples before the first one higher than `x[p]`.
fn scan_left(x: &[f64], p: usize, lo: usize) -> (f64, usize) {
    let xp = x[p];
    let (mut vmin, mut base) = (xp, p);
    for i in (lo..=p).rev() {
        let v = x[i];
        if v > xp {
            break;
        }
        if v < vmin {
            vmin = v;
            base = i;
        }
    }
    (vmin, base)
}

/// SciPy's right base scan over `[p, hi]`.
fn scan_right(x: &[f64], p: usize, hi: usize) -> (f64, usize) {
    let xp = x[p];
    let (mut vmin, mut base) = (xp, p);
    for (i, &v) in x.iter().enumerate().take(hi + 1).skip(p) {
        if v > xp {
            break;
        }
        if v < vmin {
            vmin = v;
            base = i;
        }
    }
    (vmin, base)
}

/// Lanes of the chunked runs in [`run_left`] and [`run_right`] (and of
/// [`last_equal`], [`first_equal`]).
const RUN: usize = 8;

/// Lane minima of the chunks of `W` samples ending at `end` and going down
/// to `lo` while no sample is `> v`; returns where the chunks stopped.
#[inline(always)]
fn lanes_left<const W: usize>(
    x: &[f64],
    lo: usize,
    mut end: usize,
    v: f64,
    lanes: &mut [f64; W],
) -> usize {
    while end >= lo + W {
        let c: &[f64; W] = x[end - W..end].try_into().expect("W samples");
        if c.iter().fold(false, |a, &y| a | (y > v)) {
            break;
        }
        for (m, &y) in lanes.iter_mut().zip(c) {
            *m = if y < *m { y } else { *m };
        }
        end -= W;
    }
    end
}

/// [`lanes_left`] mirrored: chunks from `start` up to `end` (exclusive).
#[inline(always)]
fn lanes_right<const W: usize>(
    x: &[f64],
    mut start: usize,
    end: usize,
    v: f64,
    lanes: &mut [f64; W],
) -> usize {
    while start + W <= end {
        let c: &[f64; W] = x[start..start + W].try_into().expect("W samples");
        if c.iter().fold(false, |a, &y| a | (y > v)) {
            break;
        }
        for (m, &y) in lanes.iter_mut().zip(c) {
            *m = if y < *m { y } else { *m };
        }
        start += W;
    }
    start
}

/// Smallest of lane minima (exact: the order does not matter).
#[inline(always)]
fn lanes_min(lanes: &[f64]) -> f64 {
    lanes
        .iter()
        .fold(f64::INFINITY, |a, &m| if m < a { m } else { a })
}

/// Backward run over `[lo, hi]` as SciPy's left scan with threshold `v`:
/// the first sample `> v` met from `hi` downwards (`None` if all are
/// `<= v`) and the minimum of the samples after it (`+inf` if none).
/// Chunks of [`RUN`] samples without a sample `> v` only update lane
/// minima (vectorises); the rest, from the chunk holding the stop, is
/// scanned sample by sample.
#[inline(always)]
pub(crate) fn run_left(x: &[f64], lo: usize, hi: usize, v: f64) -> (Option<usize>, f64) {
    let mut lanes = [f64::INFINITY; RUN];
    let end = lanes_left(x, lo, hi + 1, v, &mut lanes);
    let mut vmin = lanes_min(&lanes);
    for i in (lo..end).rev() {
        if x[i] > v {
            return (Some(i), vmin);
        }
        vmin = if x[i] < vmin { x[i] } else { vmin };
    }
    (None, vmin)
}

/// [`run_left`] mirrored: forward run over `[lo, hi]`.
#[inline(always)]
pub(crate) fn run_right(x: &[f64], lo: usize, hi: usize, v: f64) -> (Option<usize>, f64) {
    let mut lanes = [f64::INFINITY; RUN];
    let start = lanes_right(x, lo, hi + 1, v, &mut lanes);
    let mut vmin = lanes_min(&lanes);
    for (i, &y) in x.iter().enumerate().take(hi + 1).skip(start) {
        if y > v {
            return (Some(i), vmin);
        }
        vmin = if y < vmin { y } else { vmin };
    }
    (None, vmin)
}

/// The last sample of `[a, b]` equal to `m` (`b` if none), by chunks of
/// [`RUN`] compared at once.
#[inline(always)]
fn last_equal(x: &[f64], a: usize, b: usize, m: f64) -> usize {
    let mut end = b + 1;
    while end >= a + RUN {
        let c: &[f64; RUN] = x[end - RUN..end].try_into().expect("RUN samples");
        if c.iter().fold(false, |f, &y| f | (y == m)) {
            break;
        }
        end -= RUN;
    }
    (a..end).rev().find(|&i| x[i] == m).unwrap_or(b)
}

/// The first sample of `[a, b]` equal to `m` (`a` if none).
#[inline(always)]
fn first_equal(x: &[f64], a: usize, b: usize, m: f64) -> usize {
    let mut start = a;
    while start + RUN <= b + 1 {
        let c: &[f64; RUN] = x[start..start + RUN].try_into().expect("RUN samples");
        if c.iter().fold(false, |f, &y| f | (y == m)) {
            break;
        }
        start += RUN;
    }
    (start..=b).find(|&i| x[i] == m).unwrap_or(a)
}

/// Per peak, the base's value and index.
type Bases = Vec<(f64, usize)>;

/// [`run_left`] and [`run_right`], instantiated with AVX2 / AVX-512F in
/// `crate::simd` (the same results: exact minima, same comparisons).
pub(crate) trait Runs: Copy {
    /// [`run_left`].
    fn run_left(self, x: &[f64], lo: usize, hi: usize, v: f64) -> (Option<usize>, f64);
    /// [`run_right`].
    fn run_right(self, x: &[f64], lo: usize, hi: usize, v: f64) -> (Option<usize>, f64);
}

impl Runs for Baseline {
    fn run_left(self, x: &[f64], lo: usize, hi: usize, v: f64) -> (Option<usize>, f64) {
        run_left(x, lo, hi, v)
    }
    fn run_right(self, x: &[f64], lo: usize, hi: usize, v: f64) -> (Option<usize>, f64) {
        run_right(x, lo, hi, v)
    }
}

/// Left and right bases ([`bases_left_sorted`], [`bases_right_sorted`]) of
/// strictly increasing `peaks`, the runs by `runs`.
///
/// Without `LOCATE` only the bases' values are exact: the index of a base
/// that is the minimum of a run is not searched for (reported as
/// `usize::MAX`), and the value is the run's minimum (`-0.0` and `0.0`
/// not told apart).
fn bases_sorted<const LOCATE: bool>(
    x: &[f64],
    peaks: &[usize],
    h: usize,
    runs: impl Runs,
) -> (Bases, Bases) {
    (
        bases_left_sorted::<LOCATE>(x, peaks, h, runs),
        bases_right_sorted::<LOCATE>(x, peaks, h, runs),
    )
}

/// A peak's finished base search, kept on the stack of
/// [`bases_left_sorted`] / [`bases_right_sorted`]: every sample of
/// `[lo, hi]` is `<= x[peak]` (the end at the peak), `min` is their
/// minimum, found at `at` (nearest the peak on ties).
#[derive(Clone, Copy)]
struct Searched {
    lo: usize,
    hi: usize,
    max: f64,
    min: f64,
    at: usize,
}

/// Left bases ([`scan_left`] within the window of half width `h`) of
/// strictly increasing `peaks`, with a stack of the finished searches: a
/// search reaching the previous peak's searched stretch, whose samples are
/// all `<= ` that peak, takes its minimum whole if that peak is not higher
/// (and the stretch lies in the window), else stops at that peak. Only
/// samples no earlier search covered are read, in chunked runs, so the
/// cost is O(n + k) instead of the tree's O(k log n). Same visiting order
/// and strict `<` as SciPy, so the bases are identical.
fn bases_left_sorted<const LOCATE: bool>(
    x: &[f64],
    peaks: &[usize],
    h: usize,
    runs: impl Runs,
) -> Bases {
    let mut stack: Vec<Searched> = Vec::new();
    let mut out = Vec::with_capacity(peaks.len());
    for &p in peaks {
        let v = x[p];
        let wlo = p.saturating_sub(h);
        // (min, where: a sample, or a run [a, b] holding its last copy)
        let (mut vmin, mut at, mut run) = (v, p, None::<(usize, usize)>);
        let mut pos = p; // samples [pos, p] are done
        while pos > wlo {
            match stack.last().copied() {
                Some(s) if s.hi + 1 == pos => {
                    if s.max > v {
                        break;
                    }
                    // With the window's edge inside it, the stretch is
                    // dropped and its samples in the window are read again
                    // as a run on the next turn (all <= v, no stop).
                    stack.pop();
                    if s.lo >= wlo {
                        if s.min < vmin {
                            (vmin, at, run) = (s.min, s.at, None);
                        }
                        pos = s.lo;
                    }
                }
                top => {
                    let lo = top.map_or(wlo, |s| (s.hi + 1).max(wlo));
                    let (stop, m) = runs.run_left(x, lo, pos - 1, v);
                    let first = stop.map_or(lo, |i| i + 1);
                    if m < vmin {
                        (vmin, run) = (m, Some((first, pos - 1)));
                    }
                    pos = first;
                    if stop.is_some() {
                        break;
                    }
                }
            }
        }
        if let Some((a, b)) = run {
            at = if LOCATE {
                last_equal(x, a, b, vmin)
            } else {
                usize::MAX
            };
        }
        stack.push(Searched {
            lo: pos,
            hi: p,
            max: v,
            min: vmin,
            at,
        });
        // x[at] rather than vmin: the same sample SciPy reads (signed zeros)
        out.push(if LOCATE { (x[at], at) } else { (vmin, at) });
    }
    out
}

/// [`bases_left_sorted`] mirrored: right bases ([`scan_right`]), the
/// peaks taken from the last.
fn bases_right_sorted<const LOCATE: bool>(
    x: &[f64],
    peaks: &[usize],
    h: usize,
    runs: impl Runs,
) -> Bases {
    let n = x.len();
    let mut stack: Vec<Searched> = Vec::new();
    let mut out = vec![(0.0, 0); peaks.len()];
    for (j, &p) in peaks.iter().enumerate().rev() {
        let v = x[p];
        let whi = (p + h).min(n - 1);
        let (mut vmin, mut at, mut run) = (v, p, None::<(usize, usize)>);
        let mut pos = p; // samples [p, pos] are done
        while pos < whi {
            match stack.last().copied() {
                Some(s) if s.lo == pos + 1 => {
                    if s.max > v {
                        break;
                    }
                    stack.pop();
                    if s.hi <= whi {
                        if s.min < vmin {
                            (vmin, at, run) = (s.min, s.at, None);
                        }
                        pos = s.hi;
                    }
                }
                top => {
                    let hi = top.map_or(whi, |s| (s.lo - 1).min(whi));
                    let (stop, m) = runs.run_right(x, pos + 1, hi, v);
                    let last = stop.map_or(hi, |i| i - 1);
                    if m < vmin {
                        (vmin, run) = (m, Some((pos + 1, last)));
                    }
                    pos = last;
                    if stop.is_some() {
                        break;
                    }
                }
            }
        }
        if let Some((a, b)) = run {
            at = if LOCATE {
                first_equal(x, a, b, vmin)
            } else {
                usize::MAX
            };
        }
        stack.push(Searched {
            lo: p,
            hi: pos,
            max: v,
            min: vmin,
            at,
        });
        out[j] = if LOCATE { (x[at], at) } else { (vmin, at) };
    }
    out
}

/// log2 of the branching factor of [`MinMaxTree`].
const TREE_SHIFT: usize = 4;
/// Branching factor of [`MinMaxTree`]: units of 16, 256, 4096... samples.
const TREE_B: usize = 1 << TREE_SHIFT;

/// Maximum and minimum of `x` over units of `B^l` samples (level `l >= 1`;
/// level 0 is `x` itself), so that the base searches step over whole units
/// that hold no sample above the peak. Each search costs O(B log_B n)
/// instead of SciPy's O(distance to the next higher sample), and visits the
/// samples in SciPy's order with the same strict `<`, so bases and ties are
/// identical.
struct MinMaxTree<'a> {
    x: &'a [f64],
    /// `levels[l - 1] = (max, min)` per unit of level `l`.
    levels: Vec<(Vec<f64>, Vec<f64>)>,
}

impl<'a> MinMaxTree<'a> {
    fn new(x: &'a [f64]) -> Self {
        fn reduce(mx: &[f64], mn: &[f64]) -> (Vec<f64>, Vec<f64>) {
            // Finite values (checked), so max and min do not depend on the
            // order of comparison: full units reduce pairwise (SIMD), the
            // short last unit by a fold.
            fn unit<const MAX: bool>(c: &[f64]) -> f64 {
                let pick = |a: f64, b: f64| if (b > a) == MAX { b } else { a };
                match <&[f64; TREE_B]>::try_from(c) {
                    Ok(c) => {
                        let h: [f64; 8] = std::array::from_fn(|i| pick(c[i], c[i + 8]));
                        let q: [f64; 4] = std::array::from_fn(|i| pick(h[i], h[i + 4]));
                        pick(pick(q[0], q[2]), pick(q[1], q[3]))
                    }
                    Err(_) => c.iter().fold(c[0], |m, &v| pick(m, v)),
                }
            }
            (
                mx.chunks(TREE_B).map(unit::<true>).collect(),
                mn.chunks(TREE_B).map(unit::<false>).collect(),
            )
        }
        let mut levels: Vec<(Vec<f64>, Vec<f64>)> = Vec::new();
        if x.len() > TREE_B {
            levels.push(reduce(x, x));
            while let Some((mx, mn)) = levels.last().filter(|(mx, _)| mx.len() > TREE_B) {
                let next = reduce(mx, mn);
                levels.push(next);
            }
        }
        MinMaxTree { x, levels }
    }

    #[inline]
    fn count(&self, l: usize) -> usize {
        if l == 0 {
            self.x.len()
        } else {
            self.levels[l - 1].0.len()
        }
    }

    #[inline]
    fn max(&self, l: usize, u: usize) -> f64 {
        if l == 0 {
            self.x[u]
        } else {
            self.levels[l - 1].0[u]
        }
    }

    #[inline]
    fn min(&self, l: usize, u: usize) -> f64 {
        if l == 0 {
            self.x[u]
        } else {
            self.levels[l - 1].1[u]
        }
    }

    /// First and last sample of unit `u` of level `l`.
    #[inline]
    fn span(&self, l: usize, u: usize) -> (usize, usize) {
        let start = u << (TREE_SHIFT * l);
        let end = ((u + 1) << (TREE_SHIFT * l)).min(self.x.len()) - 1;
        (start, end)
    }

    /// [`scan_left`] over `[lo, p]`.
    fn base_left(&self, p: usize, lo: usize) -> (f64, usize) {
        let xp = self.x[p];
        let mut vmin = xp;
        let mut hit = (0, p);
        let top = self.levels.len();
        // Ascend: samples [span(l, u).0, p] are done; take units leftwards,
        // moving up a level whenever u starts its parent.
        let (mut l, mut u) = (0, p);
        let mut stop = loop {
            if self.span(l, u).0 <= lo {
                break None;
            }
            if u % TREE_B == 0 && l < top {
                u /= TREE_B;
                l += 1;
                continue;
            }
            let c = u - 1;
            if self.span(l, c).0 < lo || self.max(l, c) > xp {
                break Some((l, c));
            }
            let m = self.min(l, c);
            if m < vmin {
                vmin = m;
                hit = (l, c);
            }
            u = c;
        };
        // Descend into the unit holding the higher sample or `lo`.
        'outer: while let Some((l, c)) = stop {
            if l == 0 {
                break;
            }
            let cl = l - 1;
            let first = c * TREE_B;
            let last = (first + TREE_B).min(self.count(cl)) - 1;
            for ch in (first..=last).rev() {
                let (start, end) = self.span(cl, ch);
                if end < lo {
                    break 'outer;
                }
                if start < lo || self.max(cl, ch) > xp {
                    stop = Some((cl, ch));
                    continue 'outer;
                }
                let m = self.min(cl, ch);
                if m < vmin {
                    vmin = m;
                    hit = (cl, ch);
                }
            }
            break;
        }
        // The base is the rightmost sample equal to vmin in the unit hit.
        let (mut l, mut u) = hit;
        while l > 0 {
            let cl = l - 1;
            let first = u * TREE_B;
            let last = (first + TREE_B).min(self.count(cl)) - 1;
            u = (first..=last)
                .rev()
                .find(|&ch| self.min(cl, ch) == vmin)
                .expect("a unit's minimum is one of its children's");
            l = cl;
        }
        (vmin, u)
    }

    /// [`scan_right`] over `[p, hi]`, the mirror image of [`Self::base_left`].
    fn base_right(&self, p: usize, hi: usize) -> (f64, usize) {
        let xp = self.x[p];
        let mut vmin = xp;
        let mut hit = (0, p);
        let top = self.levels.len();
        let (mut l, mut u) = (0, p);
        let mut stop = loop {
            if self.span(l, u).1 >= hi {
                break None;
            }
            if (u + 1) % TREE_B == 0 && l < top {
                u /= TREE_B;
                l += 1;
                continue;
            }
            let c = u + 1;
            if self.span(l, c).1 > hi || self.max(l, c) > xp {
                break Some((l, c));
            }
            let m = self.min(l, c);
            if m < vmin {
                vmin = m;
                hit = (l, c);
            }
            u = c;
        };
        'outer: while let Some((l, c)) = stop {
            if l == 0 {
                break;
            }
            let cl = l - 1;
            let first = c * TREE_B;
            let last = (first + TREE_B).min(self.count(cl)) - 1;
            for ch in first..=last {
                let (start, end) = self.span(cl, ch);
                if start > hi {
                    break 'outer;
                }
                if end > hi || self.max(cl, ch) > xp {
                    stop = Some((cl, ch));
                    continue 'outer;
                }
                let m = self.min(cl, ch);
                if m < vmin {
                    vmin = m;
                    hit = (cl, ch);
                }
            }
            break;
        }
        let (mut l, mut u) = hit;
        while l > 0 {
            let cl = l - 1;
            let first = u * TREE_B;
            let last = (first + TREE_B).min(self.count(cl)) - 1;
            u = (first..=last)
                .find(|&ch| self.min(cl, ch) == vmin)
                .expect("a unit's minimum is one of its children's");
            l = cl;
        }
        (vmin, u)
    }
}

/// Width of each peak at `rel_height` of its prominence, as
/// `scipy.signal.peak_widths`; prominences are computed with
/// `settings.wlen` (see [`peak_prominences`]).
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
/// assert_eq!((w.widths[0], w.width_heights[0], w.left_ips[0], w.right_ips[0]), (2.0, 1.0, 1.0, 3.0));
/// # Ok::<(), ballpass_dsp::DspError>(())
/// ```
///
/// # Errors
/// As [`peak_prominences`], and [`DspError::InvalidSetting`] for
/// `rel_height < 0` or non-finite.
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
/// `prominence_data` argument), e.g. from [`find_peaks`].
///
/// # Errors
/// [`DspError::NonFinite`] for a NaN or infinity in `x`;
/// [`DspError::LengthMismatch`] if the arrays of `prominences` are not as
/// long as `peaks`; [`DspError::InvalidSetting`] unless
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
fn widths_sorted(
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
fn widths_unchecked(
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

#[cfg(test)]
mod tests {
    use super::*;

    /// SciPy's scan, the reference for the tree search.
    fn naive(x: &[f64], peaks: &[usize], half: usize) -> Prominences {
        let mut out = Prominences::default();
        for &p in peaks {
            let (l, lb) = scan_left(x, p, p.saturating_sub(half));
            let (r, rb) = scan_right(x, p, (p + half).min(x.len() - 1));
            out.prominences.push(x[p] - l.max(r));
            out.left_bases.push(lb);
            out.right_bases.push(rb);
        }
        out
    }

    fn lcg_levels(s: &mut u64, len: usize, levels: u64) -> Vec<f64> {
        (0..len)
            .map(|_| {
                *s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((*s >> 33) % levels) as f64
            })
            .collect()
    }

    #[test]
    fn tree_search_matches_scipy_scan_with_ties_and_windows() {
        // Small integer alphabets => many equal values (the hard case for
        // ties); lengths across several tree levels; a random walk for long
        // searches.
        let mut s = 12345u64;
        for len in (1..80).chain([255, 256, 257, 1000, 4097, 5000]) {
            for levels in [2, 4, 1000] {
                let mut x = lcg_levels(&mut s, len, levels);
                if levels == 1000 {
                    for i in 1..len {
                        x[i] = x[i - 1] + x[i] - 499.5;
                    }
                }
                // every index (or a stride), unsorted, with a duplicate
                let step = 1 + len / 300;
                let mut peaks: Vec<usize> = (0..len).rev().step_by(step).collect();
                peaks.push(len / 2);
                for half in [len, 1, 7, 100] {
                    let tree = MinMaxTree::new(&x);
                    let mut fast = Prominences::default();
                    for &p in &peaks {
                        let (l, lb) = tree.base_left(p, p.saturating_sub(half));
                        let (r, rb) = tree.base_right(p, (p + half).min(len - 1));
                        fast.prominences.push(x[p] - l.max(r));
                        fast.left_bases.push(lb);
                        fast.right_bases.push(rb);
                    }
                    assert_eq!(
                        fast,
                        naive(&x, &peaks, half),
                        "len {len} levels {levels} half {half}"
                    );
                }
            }
        }
    }

    /// Pseudo-random integers below the argument (the LCG of
    /// [`lcg_levels`]), seeded with `seed`.
    fn lcg(seed: u64) -> impl FnMut(u64) -> u64 {
        let mut s = seed;
        move |m| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 33) % m
        }
    }

    /// Sorted peak sets of `x` for the stack-search tests: every sample, a
    /// random quarter of them, the local maxima.
    fn peak_sets(x: &[f64], next: &mut impl FnMut(u64) -> u64) -> [Vec<usize>; 3] {
        let len = x.len();
        let some = (0..len).filter(|_| next(4) == 0).collect();
        [(0..len).collect(), some, local_maxima(x).0]
    }

    /// A test signal of `len` samples with ties: kind 0 a small alphabet,
    /// 1 runs of equal values (plateaus), 2 the same alphabet with signed
    /// zeros and -1 when `signed_zeros`, 3 a random walk
    /// `x[i] = x[i-1] + a u[i] + b` of `walk = (a, b)`.
    fn tricky_signal(
        len: usize,
        kind: u64,
        walk: (f64, f64),
        signed_zeros: bool,
        next: &mut impl FnMut(u64) -> u64,
    ) -> Vec<f64> {
        let mut x: Vec<f64> = (0..len).map(|_| next(3 + 3 * kind) as f64).collect();
        match kind {
            1 => {
                for i in 1..len {
                    if next(3) > 0 {
                        x[i] = x[i - 1];
                    }
                }
            }
            2 if signed_zeros => {
                for v in &mut x {
                    *v = match *v as u64 {
                        0 => -0.0,
                        1 => 0.0,
                        2 => -1.0,
                        _ => *v,
                    };
                }
            }
            3 => {
                for i in 1..len {
                    x[i] = x[i - 1] + walk.0 * x[i] + walk.1;
                }
            }
            _ => {}
        }
        x
    }

    #[test]
    fn prominence_prefilter_keeps_every_peak_the_criterion_keeps() {
        // find_peaks with a prominence bound (which drops the shallow
        // maxima before the exact search) against every local maximum's
        // prominence by SciPy's scan, filtered afterwards: the same peaks,
        // prominences and bases, on noise, pulse trains with noise, ties
        // and plateaus, windows shorter and longer than the prefilter's
        // reach, bounds at and around the prominences that occur.
        let mut next = lcg(777u64);
        for len in [3, 9, 17, 40, 300, 3000] {
            for kind in 0..5u64 {
                let x: Vec<f64> = match kind {
                    0..=3 => tricky_signal(len, kind, (0.7, -0.2), true, &mut next),
                    _ => (0..len)
                        .map(|i| {
                            let d = (i % 50) as f64 - 25.0;
                            (-0.5 * d * d / 16.0).exp() + 0.02 * (next(1000) as f64 - 500.0) / 500.0
                        })
                        .collect(),
                };
                let (maxima, _) = local_maxima(&x);
                for half in [None, Some(3), Some(8), Some(20)] {
                    let all = naive(&x, &maxima, half.unwrap_or(len));
                    let mut proms = all.prominences.clone();
                    proms.sort_by(f64::total_cmp);
                    let picks = [0.0, 0.05, 0.5, 1.0]
                        .into_iter()
                        .chain(proms.iter().copied().step_by(1 + proms.len() / 5));
                    for min in picks {
                        for min in [min, min * (1.0 + 1e-15), min * (1.0 - 1e-15)] {
                            let settings = FindPeaksSettings {
                                prominence: Some(Bound::at_least(min)),
                                wlen: half.map(|h| (2 * h + 1) as f64),
                                ..Default::default()
                            };
                            let got = find_peaks(&x, &settings).unwrap();
                            let keep: Vec<usize> = (0..maxima.len())
                                .filter(|&i| all.prominences[i] >= min)
                                .collect();
                            let want: Vec<usize> = keep.iter().map(|&i| maxima[i]).collect();
                            let ctx = format!("len {len} kind {kind} half {half:?} min {min}");
                            assert_eq!(got.indices, want, "{ctx}");
                            let p = got.properties;
                            let pick = |v: &[f64]| keep.iter().map(|&i| v[i]).collect::<Vec<_>>();
                            let picku =
                                |v: &[usize]| keep.iter().map(|&i| v[i]).collect::<Vec<_>>();
                            assert_eq!(p.prominences.unwrap(), pick(&all.prominences), "{ctx}");
                            assert_eq!(p.left_bases.unwrap(), picku(&all.left_bases), "{ctx}");
                            assert_eq!(p.right_bases.unwrap(), picku(&all.right_bases), "{ctx}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn sorted_stack_search_matches_tree_and_scan() {
        // Random sorted peak sets (all samples, random subsets, local maxima
        // only) on signals with ties and plateaus (small alphabets, runs of
        // equal values) and random walks, for windows from 1 sample to none.
        let mut next = lcg(4242u64);
        for len in (1..60).chain([200, 1000, 3000]) {
            for kind in 0..4 {
                let x = tricky_signal(len, kind, (1.0, -5.0), false, &mut next);
                for peaks in peak_sets(&x, &mut next) {
                    for half in [len, 1, 2, 3, 7, 16, 100, 1 + next(len as u64) as usize] {
                        let h = half.min(len);
                        let (left, right) = bases_sorted::<true>(&x, &peaks, h, Baseline);
                        let wide = match crate::simd::detect() {
                            Some(Wide::Avx512(w)) => {
                                assert_eq!(
                                    bases_sorted::<true>(&x, &peaks, h, w.avx2()),
                                    (left.clone(), right.clone())
                                );
                                Some(bases_sorted::<true>(&x, &peaks, h, w))
                            }
                            Some(Wide::Avx2(w)) => Some(bases_sorted::<true>(&x, &peaks, h, w)),
                            None => None,
                        };
                        assert!(wide.is_none_or(|w| w == (left.clone(), right.clone())));
                        let mut fast = Prominences::default();
                        for ((&p, (l, lb)), (r, rb)) in peaks.iter().zip(left).zip(right) {
                            fast.prominences.push(x[p] - l.max(r));
                            fast.left_bases.push(lb);
                            fast.right_bases.push(rb);
                        }
                        let tree = MinMaxTree::new(&x);
                        let mut slow = Prominences::default();
                        for &p in &peaks {
                            let (l, lb) = tree.base_left(p, p.saturating_sub(h));
                            let (r, rb) = tree.base_right(p, (p + h).min(len - 1));
                            slow.prominences.push(x[p] - l.max(r));
                            slow.left_bases.push(lb);
                            slow.right_bases.push(rb);
                        }
                        let what = format!("len {len} kind {kind} half {half} peaks {peaks:?}");
                        assert_eq!(fast, slow, "tree: {what}");
                        assert_eq!(fast, naive(&x, &peaks, h), "scan: {what}");
                    }
                }
            }
        }
    }

    #[test]
    fn widths_with_unlocated_bases_equal_the_located_path() {
        // Ties, plateaus, signed zeros, random walks; windows from 1 sample
        // to none; rel_height 0 to 1 (1: rounding can put the width height
        // below a base).
        let mut next = lcg(2718u64);
        for len in (3..40).chain([200, 1000, 3000]) {
            for kind in 0..4 {
                let x = tricky_signal(len, kind, (0.37, -2.0), true, &mut next);
                for peaks in peak_sets(&x, &mut next) {
                    for half in [
                        None,
                        Some(1),
                        Some(3),
                        Some(16),
                        Some(1 + next(len as u64) as usize),
                    ] {
                        for rel in [0.0, 0.25, 0.5, 0.999, 1.0 - f64::EPSILON / 2.0, 1.0] {
                            let Some(fast) = widths_sorted(&x, &peaks, half, rel) else {
                                continue;
                            };
                            let prom = prominences_unchecked(&x, &peaks, half);
                            let slow = widths_unchecked(
                                &x,
                                &peaks,
                                rel,
                                &prom.prominences,
                                &prom.left_bases,
                                &prom.right_bases,
                            );
                            let bits = |w: &Widths| {
                                [&w.widths, &w.width_heights, &w.left_ips, &w.right_ips]
                                    .map(|v| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>())
                            };
                            assert_eq!(
                                bits(&fast),
                                bits(&slow),
                                "len {len} kind {kind} half {half:?} rel {rel} peaks {peaks:?}"
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn distance_selection_matches_the_greedy_walk() {
        let mut s = 777u64;
        for len in [3, 10, 50, 300, 3000] {
            for levels in [2, 5, 1000] {
                let x = lcg_levels(&mut s, len, levels);
                let (peaks, _) = local_maxima(&x);
                let h: Vec<f64> = peaks.iter().map(|&p| x[p]).collect();
                for d in [1, 2, 3, 5, 17, 100, 10_000] {
                    assert_eq!(
                        select_by_distance(&peaks, &h, d),
                        greedy_distance(&peaks, &h, d),
                        "len {len} levels {levels} d {d}"
                    );
                }
            }
        }
    }

    #[test]
    fn fused_distance_matches_maxima_then_selection() {
        let mut s = 4242u64;
        for len in [0, 1, 2, 3, 4, 10, 50, 300, 3000] {
            for levels in [2, 3, 5, 1000] {
                let mut x = lcg_levels(&mut s, len, levels);
                if levels == 3 && len > 20 {
                    // long plateaus, one at the end
                    for v in &mut x[len / 3..len / 2] {
                        *v = 7.0;
                    }
                    for v in &mut x[len - 10..] {
                        *v = 9.0;
                    }
                }
                let (peaks, _) = local_maxima(&x);
                let h: Vec<f64> = peaks.iter().map(|&p| x[p]).collect();
                for d in [2, 3, 5, 17, 100, 10_000, usize::MAX] {
                    let mut expect = peaks.clone();
                    retain_mask(&mut expect, &greedy_distance(&peaks, &h, d));
                    assert_eq!(
                        peaks_by_distance(&x, d),
                        expect,
                        "len {len} levels {levels} d {d}"
                    );
                }
            }
        }
    }

    #[test]
    fn wide_peak_lanes_equal_the_baseline() {
        let Some(wide) = crate::simd::detect() else {
            eprintln!("no AVX2 on this CPU: only the baseline runs");
            return;
        };
        let mut s = 99u64;
        for levels in [2, 3, 1000] {
            let x = lcg_levels(&mut s, 8 * 500 + 2, levels);
            let base = peak_lanes(&x);
            let mut wides = vec![];
            if let crate::simd::Wide::Avx512(p) = wide {
                wides.push(p.run(|| peak_lanes(&x)));
                wides.push(p.avx2().run(|| peak_lanes(&x)));
            }
            if let crate::simd::Wide::Avx2(p) = wide {
                wides.push(p.run(|| peak_lanes(&x)));
            }
            let bits = |(a, f): ([f64; PEAK_LANES], [f64; PEAK_LANES])| {
                (a.map(f64::to_bits), f.map(f64::to_bits))
            };
            for w in wides {
                assert_eq!(bits(w), bits(base), "levels {levels}");
            }
        }
    }

    #[test]
    fn flat_peaks_report_middle_rounded_down_and_edges() {
        let x = [0.0, 1.0, 1.0, 0.0, 2.0, 2.0, 2.0, 0.0, 3.0, 3.0];
        let x2 = [0.0, 2.0, 1.0, 1.0, 3.0, 0.0];
        assert_eq!(local_maxima(&x), (vec![1, 5], vec![(0, 1, 2), (1, 4, 6)]));
        assert_eq!(local_maxima(&x2), (vec![1, 4], vec![]));
    }

    #[test]
    fn distance_ties_keep_the_later_peak() {
        let x = [0.0, 1.0, 0.0, 1.0, 0.0];
        let s = FindPeaksSettings {
            distance: Some(3.0),
            ..Default::default()
        };
        assert_eq!(find_peaks(&x, &s).unwrap().indices, [3]);
    }

    #[test]
    fn bad_settings_are_errors() {
        let x = [0.0, 1.0, 0.0];
        let bad = [
            FindPeaksSettings {
                distance: Some(0.5),
                ..Default::default()
            },
            FindPeaksSettings {
                wlen: Some(1.0),
                ..Default::default()
            },
            FindPeaksSettings {
                rel_height: -0.1,
                ..Default::default()
            },
            FindPeaksSettings {
                height: Some(Bound::at_least(f64::NAN)),
                ..Default::default()
            },
        ];
        for s in bad {
            assert!(matches!(
                find_peaks(&x, &s),
                Err(DspError::InvalidSetting { .. })
            ));
        }
        assert!(matches!(
            find_peaks(&[0.0, f64::NAN, 0.0], &FindPeaksSettings::default()),
            Err(DspError::NonFinite { index: 1, .. })
        ));
        assert!(peak_prominences(&x, &[3], None).is_err());
        let prom = Prominences {
            prominences: vec![-1.0],
            left_bases: vec![0],
            right_bases: vec![2],
        };
        assert!(peak_widths_with_prominences(&x, &[2], 0.5, &prom).is_err());
    }

    #[test]
    fn empty_and_tiny_signals_have_no_peaks() {
        let s = FindPeaksSettings {
            prominence: Some(Bound::any()),
            width: Some(Bound::any()),
            ..Default::default()
        };
        for x in [&[][..], &[1.0], &[1.0, 2.0]] {
            let p = find_peaks(x, &s).unwrap();
            assert!(p.indices.is_empty());
            assert_eq!(p.properties.widths, Some(vec![]));
        }
    }
}
