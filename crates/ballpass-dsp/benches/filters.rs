//! Filter kernels on the thesis' workload: 30 s at 1 kHz.
//!
//! SciPy 1.17 for the same work: `tools/bench_scipy_filters.py`.
//!
//! Measured back to back on the shared 2-core build machine (AMD EPYC with
//! AVX-512F), one core, best of 2000 single calls; SciPy best of 7 timeit
//! repeats. "before" is the previous commit's build run in the same session
//! as "ballpass" (load average ~5); the SciPy column is the quiet-machine
//! figure (load ~2); SciPy under load ~5 in that session took 538-702 us
//! (sosfiltfilt) and 929-1339 us (decimate), so the ratios are the
//! conservative ones:
//!
//! | kernel                          | first  | before | ballpass | SciPy 1.17 | ratio |
//! |---------------------------------|--------|--------|----------|------------|-------|
//! | sosfiltfilt, 30 000 samples     | 172 us | 77 us  | 37 us    | 452 us     | 12x   |
//! | apply_many, 3 x 30 000 (each)   | -      | 73 us  | 57 us *  | 452 us     | 7.9x  |
//! | decimate q=20, 30 000 (planned) | 301 us | 154 us | 75 us    | 894 us     | 12x   |
//! | butter(5, 20 Hz) design (crit.) | 1.1 us | 1.1 us | 1.1 us   | 271 us     | 250x  |
//! | final s3 main, quiet (load ~1.5), criterion mean, SciPy the same minutes: |
//! | sosfiltfilt, 30 000 samples     |        |        | 42.5 us  | 477 us     | 11.2x |
//! | decimate q=20, 30 000 (planned) |        |        | 82.3 us  | 936 us     | 11.4x |
//! | butter(5, 20 Hz) design         |        |        | 0.84 us  | 289 us     | 340x  |
//!
//! \* criterion mean, as `apply x3`: three fresh 240 kB outputs per call,
//! which glibc may hand back to the OS between calls (it did in this
//! session: ~170 000 page faults over 2000 calls of `apply x3`), so the call
//! is bound by page faults, not filtering (37 us a signal).
//!
//! The filtering is a recurrence SciPy runs as the same Cython loop. Where
//! the time went: the regrouped recurrence (each feedback term subtracted
//! last: half the latency chain), one signal split into chunks run as SIMD
//! lanes with a free-response correction at the seams, and 2-4 instead of 5
//! multiplies per section for low-pass layouts (see `src/biquad.rs`). The
//! chunk count follows the CPU, detected at run time (`src/simd.rs`, the
//! crate's one `unsafe` module): 8 chunks in AVX-512F registers (both
//! filters here; the decimation filter's free responses outlast its 3 750-
//! sample chunks and carry across seams), 4 with AVX2, 2 on the SSE2
//! baseline. Beyond the filter: the padded buffer is laid out
//! `[x | right | left]` so the result is trimmed by truncation instead of a
//! copy, and the input is copied and checked for NaN/inf in one blocked pass.
#![allow(missing_docs)] // criterion_group! generates an undocumented `pub fn benches`

use ballpass_dsp::{
    butter, decimate, DecimateSettings, Decimator, FiltFiltSettings, FilterBand, ZeroPhaseFilter,
};
use criterion::{black_box, criterion_group, criterion_main, Criterion};

fn signal(n: usize) -> Vec<f64> {
    signal_seeded(n, 0x2545_f491_4f6c_dd1d)
}

fn signal_seeded(n: usize, seed: u64) -> Vec<f64> {
    // Deterministic broadband test signal (LCG noise plus a 1.1 Hz tone).
    let mut state = seed;
    (0..n)
        .map(|i| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let u = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            u + (2.0 * std::f64::consts::PI * 1.1 * i as f64 / 1000.0).sin()
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let x = signal(30_000);
    let lp = FilterBand::LowPass { cutoff_hz: 20.0 };

    c.bench_function("butter(5, 20 Hz, fs 1 kHz) design", |b| {
        b.iter(|| butter(black_box(5), black_box(lp), black_box(1000.0)).unwrap())
    });

    let filt =
        ZeroPhaseFilter::new(butter(5, lp, 1000.0).unwrap(), FiltFiltSettings::default()).unwrap();
    let mut out = Vec::new();
    c.bench_function("sosfiltfilt butter5 20 Hz, 30k samples (planned)", |b| {
        b.iter(|| filt.apply_into(black_box(&x), &mut out).unwrap())
    });

    let (x2, x3) = (signal_seeded(30_000, 2), signal_seeded(30_000, 3));
    c.bench_function(
        "sosfiltfilt butter5 20 Hz, 3 x 30k samples (apply_many)",
        |b| b.iter(|| filt.apply_many(black_box(&[&x, &x2, &x3])).unwrap()),
    );
    c.bench_function(
        "sosfiltfilt butter5 20 Hz, 3 x 30k samples (apply x3)",
        |b| b.iter(|| [&x, &x2, &x3].map(|s| filt.apply(black_box(s)).unwrap())),
    );

    let dec = Decimator::new(DecimateSettings {
        q: 20,
        ..DecimateSettings::default()
    })
    .unwrap();
    c.bench_function("decimate q=20, 30k samples (planned)", |b| {
        b.iter(|| dec.apply(black_box(&x)).unwrap())
    });
    c.bench_function("decimate q=20, 30k samples (incl. design)", |b| {
        b.iter(|| decimate(black_box(&x), 20).unwrap())
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
