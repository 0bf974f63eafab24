//! Loading a thesis-sized recording: 30 s at 1 kHz, `time_s` plus three
//! channels written at full precision by `write_csv` (about 2 MB of text).
//!
//! Compare with `tools/bench_scipy_load.py`, which times `numpy.loadtxt` on a
//! file of the same shape.
//!
//! Every other format: `tools/bench_formats_load.py DIR` writes the same
//! 30 s record as CSV, MAT v5, v7 (zlib), v7.3 (HDF5), TDMS and MF4 with each
//! format's own writer into `DIR` (default `target/format-bench`) and times
//! each format's own reader (numpy, scipy.io, h5py, npTDMS, asammdf); the
//! "load <format>" benchmarks here read the same files (set
//! `BALLPASS_FORMAT_BENCH_DIR` for another folder; missing files are
//! skipped with a note).
//!
//! Measured on the shared 2-core machine (load average 4-5 from other
//! builds; criterion's mean beside the reference's best of 7, which favours
//! the reference), 30 000 samples x 3 channels plus time:
//!
//! | format        | file    | ballpass          | reference                  |
//! |---------------|---------|-------------------|----------------------------|
//! | CSV           | 1.89 MB | 4.08 ms, 465 MB/s | numpy.loadtxt 43.8 ms      |
//! | MAT v5        | 0.96 MB | 0.235 ms          | scipy.io.loadmat 0.21 ms   |
//! | MAT v7 (zlib) | 0.71 MB | 2.48 ms           | scipy.io.loadmat 3.30 ms   |
//! | MAT v7.3      | 0.96 MB | 0.229 ms          | h5py 0.67 ms               |
//! | TDMS          | 0.72 MB | 0.099 ms          | npTDMS 0.27 ms             |
//! | MF4           | 0.96 MB | 0.495 ms          | asammdf 1.58 ms            |
//!
//! ballpass also derives and checks the time base, finiteness and gaps; the
//! references only read the arrays.

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

fn bench_formats(c: &mut Criterion) {
    let dir = std::env::var_os("BALLPASS_FORMAT_BENCH_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| {
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/format-bench")
        });
    let opts = LoadOptions::default();
    for (what, file) in [
        ("csv", "rec.csv"),
        ("mat v5", "rec_v5.mat"),
        ("mat v7 (zlib)", "rec_v7.mat"),
        ("mat v7.3 (hdf5)", "rec_v73.mat"),
        ("tdms", "rec.tdms"),
        ("mf4", "rec.mf4"),
    ] {
        let path = dir.join(file);
        if !path.exists() {
            eprintln!(
                "note: {} missing; run tools/bench_formats_load.py to write it",
                path.display()
            );
            continue;
        }
        let n = load(&path, &opts).expect("load").len();
        assert_eq!(n, 30_000, "{}", path.display());
        c.bench_function(&format!("load {what} 30 s 1 kHz 3 channels"), |b| {
            b.iter(|| load(black_box(&path), &opts).expect("load"))
        });
    }
}

/// The benchmark group (written out: `criterion_group!` makes an undocumented fn).
fn benches() {
    let mut c = Criterion::default().configure_from_args();
    bench_load(&mut c);
    bench_formats(&mut c);
}

criterion_main!(benches);
