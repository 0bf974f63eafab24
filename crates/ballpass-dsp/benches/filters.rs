//! Filter kernels on the thesis' workload: 30 s at 1 kHz.
//!
//! SciPy 1.17 for the same work: `tools/bench_scipy_filters.py`.
//!
//! Measured back to back on the shared 2-core build machine under heavy load
//! (load average ~10, so absolute numbers are noisy; SciPy on a quiet
//! machine in brackets):
//!
//! | kernel                     | ballpass               | SciPy 1.17           |
//! |----------------------------|------------------------|----------------------|
//! | butter(5, 20 Hz) design    | 1.8 us                 | 823 us (277 us)      |
//! | sosfiltfilt, 30 000 samples| 423 us                 | 1324 us (457 us)     |
//! | decimate q=20, 30 000      | 684 us planned, 905 us | 2214 us (879 us)     |
//!
//! The filtering itself is a serial recurrence (each output sample needs the
//! previous one), the same loop SciPy runs in Cython, so it is ~3x, not 10x.
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
