//! Loading a thesis-sized recording: 30 s at 1 kHz, `time_s` plus three
//! channels written at full precision by `write_csv` (about 2 MB of text).
//!
//! Compare with `tools/bench_scipy_load.py`, which times `numpy.loadtxt` on a
//! file of the same shape.

use std::hint::black_box;

use ballpass::recording::{load, write_csv, Channels, LoadOptions, Metadata, Recording};
use criterion::{criterion_main, Criterion};

fn thesis_sized() -> Recording {
    let fs = 1000.0;
    let n = 30_000;
    let t = |i: usize| i as f64 / fs;
    // Smooth signals plus a deterministic pseudo-random term, so that every
    // number prints with 15-17 significant digits as measured data would.
    let mut s: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut noise = move || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1);
        (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let friction = (0..n)
        .map(|i| 2.0 + 0.05 * (2.0 * std::f64::consts::PI * 1.10959 * t(i)).sin() + 0.01 * noise())
        .collect();
    let position = (0..n).map(|i| 9.0 * t(i) + 1e-4 * noise()).collect();
    let optical = (0..n).map(|_| 0.3 + 0.2 * noise()).collect();
    Recording::new(
        fs,
        Channels {
            friction_n: Some(friction),
            position_mm: Some(position),
            optical_v: Some(optical),
        },
        Metadata::default(),
    )
    .expect("valid recording")
}

fn bench_load(c: &mut Criterion) {
    let dir = std::env::temp_dir().join(format!("ballpass-bench-load-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("thesis_30s_1kHz.csv");
    write_csv(&thesis_sized(), &path).expect("write");
    let opts = LoadOptions::default();
    c.bench_function("load csv 30 s 1 kHz 4 columns", |b| {
        b.iter(|| load(black_box(&path), &opts).expect("load"))
    });
    let rec = thesis_sized();
    let out = dir.join("out.csv");
    c.bench_function("write_csv 30 s 1 kHz 4 columns", |b| {
        b.iter(|| write_csv(black_box(&rec), &out).expect("write"))
    });
    let _ = std::fs::remove_dir_all(&dir);
}

/// The benchmark group (written out: `criterion_group!` makes an undocumented fn).
fn benches() {
    let mut c = Criterion::default().configure_from_args();
    bench_load(&mut c);
}

criterion_main!(benches);
