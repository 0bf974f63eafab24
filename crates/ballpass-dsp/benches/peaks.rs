//! find_peaks (distance + prominence) and peak_widths on 30 000 samples of a
//! noisy Gaussian pulse train at 1 kHz, the same signal and work as
//! `tools/bench_scipy_peaks.py` (same splitmix64 stream).
//!
//! Measured on the 2-core dev box (shared with other builds, load average
//! ~2), one core, best of 2000 single calls (SciPy: best of 7 timeit
//! repeats, same session):
//!
//! | work                       | before | ballpass | SciPy 1.17.1 | ratio |
//! |----------------------------|--------|----------|--------------|-------|
//! | find_peaks + peak_widths   | 205 us | 117 us   | 491 us       | 4.2x  |
//! | find_peaks                 | 166 us | 88 us    | 307 us       | 3.5x  |
//! | ... block-top distance test (later), load ~2.4:                     |
//! | find_peaks + peak_widths   | 117 us | 111 us   | 454 us       | 4.1x  |
//! | find_peaks                 | 88 us  | 82 us    | 293 us       | 3.6x  |
//! | ... fused distance scan + AVX lanes, load ~1.2 (old/new alternating): |
//! | find_peaks + peak_widths   | 156 us | 69 us    | 427 us       | 6.2x  |
//! | find_peaks                 | 83 us  | 44 us    | 293 us       | 6.7x  |
//! | ... prominence bases of the sorted peaks by a stack, load ~1.1:     |
//! | find_peaks + peak_widths   | 71 us  | 50 us    | 451 us       | 9.0x  |
//! | find_peaks                 | 46 us  | 37 us    | 306 us       | 8.3x  |
//! | ... wide finite check, block loop through `widest`, unlocated bases in peak_widths, load ~4.3: |
//! | find_peaks + peak_widths   | 50.6 us | 42.0 us | 452 us       | 10.8x |
//! | find_peaks                 | 35.4 us | 35-37 us | 304 us      | 8.3x  |
//! | ... same binaries, the box's slow phase a minute later, load ~4.4:  |
//! | find_peaks + peak_widths   | 74-76 us | 63.6-64.5 us | 851 us  | 13.3x |
//! | find_peaks                 | 54-55 us | 44-46 us | 565 us      | 12.6x |
//! | ... final s3 main, quiet machine (load ~1.5), criterion mean:         |
//! | find_peaks + peak_widths   |        | 41.9 us  | 451 us       | 10.8x |
//! | find_peaks                 |        | 29.9 us  | 304 us       | 10.1x |
//!
//! (The last rows: criterion's estimate, old (main 889051f) and new
//! binaries alternating, SciPy's best repeat just before and after; the
//! box switched between a fast and a slow phase under the other builds,
//! SciPy slowing more than the kernels. Best of 3000 single calls, old/new
//! alternating: 46.7 -> 38.9 us with peak_widths, 31.9 -> 27.6 us for
//! find_peaks, i.e. 11.6x and 11.0x against SciPy's fast-phase 452 / 304 us.)
//! What changed: `check_finite` sums in 32 accumulators compiled through
//! `simd::widest` (was one chain of 8 on SSE2: ~2 us per call -> ~0.6);
//! the block-top loop of `peaks_by_distance` runs once through `widest`
//! with `strict_top` and the lane loop inlined (was one dispatched call per
//! block of `distance` samples); `peak_widths` on sorted peaks with
//! `rel_height <= 1` takes the bases' values from the stack runs and
//! locates a base only where the width search could reach it (the
//! equality search over each run is skipped).
//!
//! (The later rows: criterion's fastest sample, SciPy's best repeat just
//! before. An A/B of best-of-2000 single calls, old and new binaries
//! alternating, gave -8 % for find_peaks and -5 % with peak_widths.)
//! The distance test now compares each block's top peak with the top
//! peaks of the two neighbouring blocks and scans their peaks only when
//! such a top peak ranks above it but is out of reach; the masks are
//! compacted branch-free. Per call, roughly: input check ~5 us, local
//! maxima ~28 us, distance selection ~27 us (blocks 8, neighbour marking
//! 10, greedy walk on the ~200 undecided peaks 8), heights and the final
//! compaction ~10 us, prominence tree ~25 us in find_peaks and again in
//! peak_widths. Reaching 10x (~45 us) needs the distance selection fused
//! into the local-maximum scan (never materialising the ~9 500 noise
//! maxima) and one prominence tree shared by find_peaks and peak_widths.
//!
//! (The old binary measured 156 us with peak_widths in this session, not
//! the 111 us above: the figures of one row are from one session.)
//! The distance criterion now runs fused with the search for maxima
//! (`peaks_by_distance`): per block of `distance` samples only the top
//! strict maximum is found (8 running maxima per lane loop, instantiated
//! with AVX2 / AVX-512F in `simd.rs`, then a backward search for the
//! value), the undominated block tops are kept, and only the maxima at
//! least `distance` from all of them are listed for SciPy's greedy walk;
//! the 9 478 maxima (226 left after `distance`) are never materialised.
//! Per call now, from a perf profile: lane loop ~4 us, the rest of the
//! block-top search ~5 us, input check ~2 us.
//!
//! The prominence tree queries (~70 ns per peak, ~17 us in find_peaks for
//! the 226 peaks after `distance`, ~9 us again in peak_widths for 149, plus
//! ~4 us per tree build; 8-ary and 4-ary trees and the tree levels through
//! the AVX dispatch gave nothing) are replaced for sorted peaks by a stack
//! of finished searches (`bases_left_sorted`): a search that reaches the
//! previous peak's searched stretch takes its minimum whole or stops at
//! that peak, and only samples no search has read are scanned, in chunks
//! of 8 (AVX2 / AVX-512F instances). Old (HEAD before) and new binaries
//! alternating, criterion's estimate: 71-78 -> 50-52 us with peak_widths,
//! 46-47 -> 37 us for find_peaks; SciPy 451-461 / 306-318 us, load ~1.1.
//!
//! Left (before the rows above; still true of the runs): the chunked runs still read
//! nearly every sample once per side and call (4 x 30 000 samples, ~12 us,
//! bound by the 4-cycle minimum chain per chunk of 8), and locating the
//! base in a run is a second chunked search (~5 us). Tried without gain:
//! runs of 32 with 4 chains (+40 %), branch-free stop chunks (+5 %), the
//! equality search through the AVX dispatch (+-0). Ideas: carry the
//! position of the lane minima in the run (no second search); per-block
//! (max, min) summaries so that runs step over blocks whose maximum is
//! `<= v`; share one prominence pass between find_peaks and peak_widths
//! through `peak_widths_with_prominences` where the caller has both.
//! Tried without gain since: carrying the lanes' argmin through the runs
//! (the index lanes are not kept in vector registers: 2x slower); the
//! whole stack search inside one `widest` call (the closure is then not
//! inlined into the AVX function: +20 %).
// criterion_group! generates an undocumented pub fn.
#![allow(missing_docs)]

use ballpass_dsp::{find_peaks, peak_widths, Bound, FindPeaksSettings, PeakWidthsSettings};
use criterion::{black_box, criterion_group, criterion_main, Criterion};

struct SplitMix64(u64);

impl SplitMix64 {
    fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 * 2f64.powi(-53)
    }
}

/// Pulse every 0.2 s +- 10 ms, amplitude 1 +- 0.1, sigma 12 ms, baseline
/// 0.1, Gaussian noise sd 0.05.
fn pulse_train(n: usize, fs_hz: f64, seed: u64) -> Vec<f64> {
    let mut rng = SplitMix64(seed);
    let t_end = (n - 1) as f64 / fs_hz;
    let mut x = vec![0.1; n];
    let mut c = 0.1;
    while c < t_end {
        let a = 1.0 + 0.2 * (rng.next_f64() - 0.5);
        for (i, v) in x.iter_mut().enumerate() {
            let u = (i as f64 / fs_hz - c) / 0.012;
            *v += a * (-0.5 * u * u).exp();
        }
        c += 0.2 + 0.02 * (rng.next_f64() - 0.5);
    }
    for v in &mut x {
        let u1 = 1.0 - rng.next_f64();
        let u2 = rng.next_f64();
        *v += 0.05 * (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos();
    }
    x
}

fn bench(c: &mut Criterion) {
    let x = pulse_train(30_000, 1000.0, 42);
    let settings = FindPeaksSettings {
        distance: Some(100.0),
        prominence: Some(Bound::at_least(0.3)),
        ..Default::default()
    };
    let widths = PeakWidthsSettings::default();
    let peaks = find_peaks(&x, &settings).expect("valid input");
    let w = peak_widths(&x, &peaks.indices, &widths).expect("valid input");
    let mean = w.widths.iter().sum::<f64>() / w.widths.len() as f64;
    eprintln!(
        "{} peaks, mean width {mean:.4} samples",
        peaks.indices.len()
    );

    c.bench_function("find_peaks(distance, prominence) + peak_widths, 30k", |b| {
        b.iter(|| {
            let p = find_peaks(black_box(&x), &settings).expect("valid input");
            peak_widths(&x, &p.indices, &widths).expect("valid input")
        })
    });
    c.bench_function("find_peaks(distance, prominence), 30k", |b| {
        b.iter(|| find_peaks(black_box(&x), &settings).expect("valid input"))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
