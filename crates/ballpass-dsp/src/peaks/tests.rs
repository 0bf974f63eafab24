use super::bases::*;
use super::distance::*;
use super::prominence::*;
use super::widths::*;
use super::*;
use crate::biquad::Baseline;
use crate::error::DspError;
use crate::simd::Wide;

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
                        let picku = |v: &[usize]| keep.iter().map(|&i| v[i]).collect::<Vec<_>>();
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
