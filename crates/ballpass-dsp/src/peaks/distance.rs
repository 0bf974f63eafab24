//! Local maxima and the `distance` criterion of [`super::find_peaks`].

use super::retain_mask;

/// Local maxima as SciPy's `_local_maxima_1d`: the midpoints, and
/// `(position in midpoints, left_edge, right_edge)` for the flat ones (a
/// strict maximum is its own edges).
///
/// Every sample is tested on its own (SciPy skips the samples right of a
/// maximum, none of which can start one, so the results are equal): 64
/// samples at a time into bit masks of strict maxima and plateau starts,
/// branch-free, which matters on noise where a third of the samples are
/// maxima; only plateau starts take SciPy's look-ahead.
pub(super) fn local_maxima(x: &[f64]) -> (Vec<usize>, Vec<(usize, usize, usize)>) {
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
pub(super) fn ranks_above(priority: &[f64], a: usize, b: usize) -> bool {
    priority[a] > priority[b] || (priority[a] == priority[b] && a > b)
}

/// SciPy's `_select_by_peak_distance`: walk the peaks from the highest
/// priority down; each one still kept removes its neighbours closer than
/// `distance` samples.
pub(super) fn greedy_distance(peaks: &[usize], priority: &[f64], distance: usize) -> Vec<bool> {
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
pub(super) fn select_by_distance(peaks: &[usize], priority: &[f64], distance: usize) -> Vec<bool> {
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
pub(super) fn outranks(a: (f64, usize), b: (f64, usize)) -> bool {
    a.0 > b.0 || (a.0 == b.0 && a.1 > b.1)
}

/// Lanes of [`strict_top`] over `w` (samples `1..w.len() - 1` tested, a
/// multiple of [`PEAK_LANES`] of them): per lane the largest strict local
/// maximum (`-inf` if none) and 1.0 if a plateau starts there (else 0.0).
/// Exact maxima, so every instance (baseline, or compiled with AVX2 /
/// AVX-512F through `crate::simd::widest`) returns the same bits.
#[inline(always)]
pub(super) fn peak_lanes(w: &[f64]) -> ([f64; PEAK_LANES], [f64; PEAK_LANES]) {
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
pub(super) const PEAK_LANES: usize = 8;

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
pub(super) fn strict_top(x: &[f64], lo: usize, hi: usize) -> (Option<(f64, usize)>, bool) {
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
pub(super) fn plateaus_in(x: &[f64], lo: usize, hi: usize, flats: &mut Vec<(usize, usize, usize)>) {
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
pub(super) fn flats_in(
    flats: &[(usize, usize, usize)],
    lo: usize,
    hi: usize,
) -> &[(usize, usize, usize)] {
    let start = flats.partition_point(|f| f.0 < lo);
    let end = flats.partition_point(|f| f.0 <= hi);
    &flats[start..end.max(start)]
}

/// The top-ranked local maximum (strict, or a plateau's middle) in
/// `lo..=hi`.
pub(super) fn top_in(
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
pub(super) fn peaks_by_distance(x: &[f64], distance: usize) -> Vec<usize> {
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
