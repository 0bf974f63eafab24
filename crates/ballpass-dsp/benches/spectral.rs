//! Spectral kernels on a 30 000-sample record at 1 kHz (30 s, the thesis'
//! test length). The SciPy figures for the same work come from
//! `tools/bench_scipy_spectral.py`.
//!
//! Measured once (2-core AMD EPYC VM shared with other builds, load 6-13,
//! so best-of figures: criterion's fastest sample, SciPy's best timeit
//! repeat; SciPy 1.17.1 / NumPy 2.4.6):
//!
//! | work                                   | ours     | SciPy    | ratio |
//! | -------------------------------------- | -------- | -------- | ----- |
//! | full-lag xcorr, `correlate_into`       | 361 µs   | 1390 µs  | 3.9x  |
//! | ... with 3-smooth FFT length (later)   | 306 µs   | 1359 µs  | 4.4x  |
//! | full-lag xcorr, `correlate` (allocates)| 678 µs   | 1390 µs  | 2.1x  |
//! | full-lag autocorrelation               | 233 µs   | 1364 µs  | 5.9x  |
//! | welch, nperseg 4096                    | 78 µs    | 747 µs   | 9.6x  |
//! | ... 2 segments per complex FFT (later) | 62 µs    | 731 µs   | 11.8x |
//! | csd, nperseg 4096                      | 159 µs   | 1120 µs  | 7.0x  |
//! | ... x + i y per complex FFT (later)    | 131 µs   | 1106 µs  | 8.4x  |
//! | ... wide input check (s3, fast phase)  | 122 µs   | 1160 µs  | 9.5x  |
//! | ... the same, slow phase               | 180-185 µs | 1866-1960 µs | 10.4x |
//! | xcorr `correlate_into`, fused passes   | 315 µs   | 1426 µs  | 4.5x  |
//! | autocorrelation, fused passes          | 210 µs   | 1447 µs  | 6.9x  |
//! | welch (unchanged code, same minutes)   | 68 µs    | 804 µs   | 11.8x |
//! | csd (unchanged code, same minutes)     | 125 µs   | 1211 µs  | 9.7x  |
//! | final s3 main, quiet (load ~1.5):      |          |          |       |
//! | xcorr `correlate_into`                 | 294 µs   | 1446 µs  | 4.9x  |
//! | xcorr `correlate` (allocates)          | 307 µs   | 1446 µs  | 4.7x  |
//! | autocorrelation                        | 198 µs   | 1437 µs  | 7.3x  |
//! | welch, nperseg 4096                    | 76.5 µs  | 782 µs   | 10.2x |
//! | csd, nperseg 4096                      | 122 µs   | 1185 µs  | 9.7x  |
//!
//! The s3 rows: criterion's estimate, old (main 889051f: 132 / 185-195 µs)
//! and new binaries alternating, load 4.0-4.5, SciPy's best repeat just
//! before and after (the box switched between a fast and a slow phase);
//! best of 1000 single calls, old/new alternating: 113.9 -> 111.8 µs
//! against SciPy's 1170 µs (10.5x). The input checks (`check_finite` on x
//! and y) now sum in 32 accumulators (4 independent AVX-512 chains instead
//! of one latency-bound chain): ~9 -> ~3 µs in a perf profile. Not kept:
//! summing the four 128-leaves of each 512 block of the pairwise mean side
//! by side (bitwise equal), because the larger segment loop was then no
//! longer inlined into the AVX function of `simd::widest` (2x slower). Left
//! (perf, per call): the 13 complex FFTs ~70 % (~80 µs), window/detrend
//! pass ~11 µs, the per-segment pairwise means ~9 µs (one addition chain
//! per leaf of 128), the accumulation of `conj(X) Y` ~5 µs.
//!
//! The "fused passes" rows (load 1.2-1.7, criterion's lower bound; the
//! code before, run back to back: 323 µs and 225 µs; SciPy's best repeat
//! of two runs in the same minutes): the correlator calls RustFFT's
//! half-length complex FFTs itself and does realfft's forward
//! post-processing of both spectra, the product and the inverse
//! pre-processing in one pass over the bin pairs `(k, m-k)` (8 pairs per
//! vector block), and unpacks the lags with vector code. A best-of-1500
//! timing of single calls (load ~4) gave 293-309 µs vs 303-327 µs and
//! 192-202 µs vs 209-224 µs. Still short of 10x: the three complex FFTs
//! of 31 104 points take ~64-75 µs each, and the fused pass ~3.5 ns per
//! bin pair (~55 µs), since the reversed, interleaved pairs vectorise
//! poorly (SLP shuffles; AVX-512 turned the stores into scatters).
//!
//! Where the time goes (perf): the correlations are ~75 % RustFFT/realfft
//! (three real transforms of length 60 000, since then 62 208 = 2^8 3^5,
//! which RustFFT runs 6-17 % faster; SciPy's pocketfft does the same
//! three), so no kernel-side change reaches 10x. (The later row: best of
//! 500 single calls, load ~2.) The allocating
//! `correlate` also pays ~240 page faults per call for its fresh 1 MB of
//! output (glibc returns the blocks to the OS between calls). Welch/csd are
//! ~60 % FFT (13 or 26 transforms of 4096), the rest the per-segment
//! mean/window pass and input checks.
//!
//! The two "(later)" welch/csd rows: best of 1000 single calls, load
//! average 4-6 (two other builds running); the code before the change,
//! timed the same way back to back, took 76 µs and 153 µs, SciPy's best
//! repeat in the same minutes is beside them. Now one complex FFT of
//! `x_seg + i y_seg` per segment, with `conj(X) Y` read straight off it,
//! replaces two real FFTs, their post-processing and the product pass;
//! what is left is the 13 complex FFTs of 4096 (~80 µs, RustFFT's AVX
//! path), the window/detrend pass (~15 µs), the per-segment means (~9 µs),
//! the input checks (~9 µs) and the accumulation (~20 µs). The
//! correlation stays FFT-bound: the three transforms alone (as complex
//! FFTs of 31 104 points, 3 x ~64 µs) exceed a 10x budget of ~136 µs; a
//! fused "pack, multiply, repack" pass around hand-packed complex FFTs was
//! measured and gained only ~4 %, so it was not kept.

use ballpass_dsp::{CorrelateSettings, Correlation, Correlator, Welch, WelchSettings};
use criterion::Criterion;
use std::hint::black_box;

const N: usize = 30_000;
const FS_HZ: f64 = 1000.0;

/// Same signals as the SciPy script: a 1.1096 Hz tone plus a
/// deterministic pseudo-random sequence (an LCG, no RNG crate needed).
fn record(seed: u64) -> Vec<f64> {
    let mut s = seed;
    (0..N)
        .map(|i| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let noise = ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0;
            (2.0 * std::f64::consts::PI * 1.1096 * i as f64 / FS_HZ).sin() + noise
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let x = record(1);
    let y = record(2);

    let mut corr = Correlator::with_lengths(CorrelateSettings::default(), N, N);
    c.bench_function("correlate_full_30000", |b| {
        b.iter(|| corr.correlate(black_box(&x), black_box(&y)).unwrap())
    });
    let mut out = Correlation {
        lags: Vec::new(),
        values: Vec::new(),
    };
    c.bench_function("correlate_full_30000_into", |b| {
        b.iter(|| {
            corr.correlate_into(black_box(&x), black_box(&y), &mut out)
                .unwrap()
        })
    });
    c.bench_function("autocorrelate_full_30000", |b| {
        b.iter(|| corr.autocorrelate(black_box(&x)).unwrap())
    });

    let settings = WelchSettings {
        nperseg: 4096,
        ..Default::default()
    };
    let mut welch = Welch::new(settings).unwrap();
    c.bench_function("welch_30000_nperseg4096", |b| {
        b.iter(|| welch.psd(black_box(&x), FS_HZ).unwrap())
    });
    c.bench_function("csd_30000_nperseg4096", |b| {
        b.iter(|| welch.csd(black_box(&x), black_box(&y), FS_HZ).unwrap())
    });
}

// `criterion_group!` would generate an undocumented `pub fn`, which the
// workspace's `missing_docs` lint rejects; this is what it expands to.
fn main() {
    let mut c = Criterion::default().configure_from_args();
    bench(&mut c);
    c.final_summary();
}
