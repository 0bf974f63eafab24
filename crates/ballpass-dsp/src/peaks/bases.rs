//! The base searches shared by prominences and widths: SciPy's scans, the
//! chunked runs (with SIMD variants in `crate::simd`) and the min/max tree.

use crate::biquad::Baseline;

/// SciPy's left base scan over `[lo, p]`: minimum (nearest `p` on ties) of
/// the samples before the first one higher than `x[p]`.
pub(super) fn scan_left(x: &[f64], p: usize, lo: usize) -> (f64, usize) {
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
pub(super) fn scan_right(x: &[f64], p: usize, hi: usize) -> (f64, usize) {
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
pub(super) const RUN: usize = 8;

/// Lane minima of the chunks of `W` samples ending at `end` and going down
/// to `lo` while no sample is `> v`; returns where the chunks stopped.
#[inline(always)]
pub(super) fn lanes_left<const W: usize>(
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
pub(super) fn lanes_right<const W: usize>(
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
pub(super) fn lanes_min(lanes: &[f64]) -> f64 {
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
pub(super) fn last_equal(x: &[f64], a: usize, b: usize, m: f64) -> usize {
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
pub(super) fn first_equal(x: &[f64], a: usize, b: usize, m: f64) -> usize {
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
pub(super) type Bases = Vec<(f64, usize)>;

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
pub(super) fn bases_sorted<const LOCATE: bool>(
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
pub(super) struct Searched {
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
pub(super) fn bases_left_sorted<const LOCATE: bool>(
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
pub(super) fn bases_right_sorted<const LOCATE: bool>(
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
pub(super) const TREE_SHIFT: usize = 4;
/// Branching factor of [`MinMaxTree`]: units of 16, 256, 4096... samples.
pub(super) const TREE_B: usize = 1 << TREE_SHIFT;

/// Maximum and minimum of `x` over units of `B^l` samples (level `l >= 1`;
/// level 0 is `x` itself), so that the base searches step over whole units
/// that hold no sample above the peak. Each search costs O(B log_B n)
/// instead of SciPy's O(distance to the next higher sample), and visits the
/// samples in SciPy's order with the same strict `<`, so bases and ties are
/// identical.
pub(super) struct MinMaxTree<'a> {
    x: &'a [f64],
    /// `levels[l - 1] = (max, min)` per unit of level `l`.
    levels: Vec<(Vec<f64>, Vec<f64>)>,
}

impl<'a> MinMaxTree<'a> {
    pub(super) fn new(x: &'a [f64]) -> Self {
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
    pub(super) fn base_left(&self, p: usize, lo: usize) -> (f64, usize) {
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
    pub(super) fn base_right(&self, p: usize, hi: usize) -> (f64, usize) {
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
