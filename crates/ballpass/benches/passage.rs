//! Ball-passage detection speed on a 30 s simulated record (default
//! simulator settings at 9 mm/s, seed 0: 1 kHz, 33 passages): detection
//! alone, and detection plus the whole-record Gaussian (37 parameters) and
//! rectangular (order 20) pulse-train fits. SciPy figure for the same work:
//! `tools/bench_scipy_passage.py` on the same record written by
//! `ballpass simulate -v 9 --seed 0 -o rec.csv`.
//!
//! Measured once on the shared 2-core machine (other builds running):
//!
//! | work                               | ballpass | SciPy 1.17.1 / NumPy 2.4.6 |
//! |------------------------------------|----------|----------------------------|
//! | detect (33 passages)               | 2.6 ms   | 3.5 ms                     |
//! | detect + both whole-record fits    | 92 ms    | 1426 ms (loaded machine; superseded below) |
//!
//! Session 3 (quiet machine, load ~1.5; criterion mean, SciPy best of 5 of
//! the same script, whose `peak_widths` now takes find_peaks' prominences
//! as ballpass does): detect 0.48 ms vs 3.6 ms (7.6x; the Gaussian
//! smoothing by `correlate_valid`, selections on order keys, widths from
//! find_peaks' prominences), detect + fits 78 ms vs 329 ms.
//!
//! Both find the same 33 passages (τ_c 0.90045 s) and the same fits
//! (Gaussian R² 0.9554, rectangular R² 0.8515).
//!
//! Session 17 (widths' excess scatter measured for the withholding rule;
//! shared machine, load ~11, criterion means, two runs each, alternated):
//! detect 16.08 / 16.15 ms against main's 16.18 / 16.16 ms, detect + fits
//! 227.3 / 231.1 ms against 229.3 / 232.2 ms: no change.

use ballpass::analysis::passage::{detect_passages, PassageSettings};
use ballpass::bearing::lookup;
use ballpass::sim::{simulate, SimSettings};
use criterion::{criterion_main, Criterion};

fn bench(c: &mut Criterion) {
    let rec = simulate(&SimSettings {
        velocity_mm_s: 9.0,
        seed: 0,
        ..Default::default()
    })
    .expect("default simulator settings")
    .recording;
    let geometry = Some(lookup("sr25w").expect("catalog").geometry);
    let mut g = c.benchmark_group("passage_30s_1kHz_9mm_s");
    g.sample_size(20);
    for (name, fit_pulses) in [("detect", 0), ("detect_and_fit_whole_record", 200)] {
        let s = PassageSettings {
            geometry,
            fit_pulses,
            ..Default::default()
        };
        g.bench_function(name, |b| {
            b.iter(|| detect_passages(std::hint::black_box(&rec), &s).unwrap())
        });
    }
    g.finish();
}

/// The benchmark group (written out: `criterion_group!` makes an undocumented fn).
fn benches() {
    let mut c = Criterion::default().configure_from_args();
    bench(&mut c);
}

criterion_main!(benches);
