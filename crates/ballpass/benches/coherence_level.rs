//! The coherence rows' calibrated significance level
//! (`confidence::coherence_row_level`), alone:
//!
//! ```sh
//! cargo bench -p ballpass --bench coherence_level -- [--repeat 200]
//! ```
//!
//! First every level one `analyze` of the record `tools/bench_python.py`
//! times computes (`ballpass.simulate(9.0, seed=1)`: 30 s at 1 kHz, the
//! default settings): the drawn level of its three spectra and one level
//! per coherence row, at the row's offset from its bin. Then one level at
//! a time for periodic Hann at 50 % and a spread of segment counts, a line
//! on a bin and a quarter of a bin off. Best wall time of `--repeat` runs.
//!
//! Measured (session 20, shared 2-core machine, load about 2): see
//! `crates/ballpass-py/README.md`, the speed section.

use std::hint::black_box;
use std::time::{Duration, Instant};

use ballpass::analysis::confidence::coherence_row_level;
use ballpass::analysis::preflight::{check, PreflightSettings};
use ballpass::analysis::{analyze, AnalyzeSettings, SpectrumInfo};
use ballpass::sim::{simulate, SimSettings};
use ballpass::stats::welch_dof;
use ballpass_dsp::Window;

fn arg(name: &str, default: usize) -> usize {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .map_or(default, |v| v.parse().expect("a whole number"))
}

fn best<T>(repeat: usize, mut f: impl FnMut() -> T) -> Duration {
    (0..repeat)
        .map(|_| {
            let t = Instant::now();
            black_box(f());
            t.elapsed()
        })
        .min()
        .expect("repeat >= 1")
}

fn main() {
    let repeat = arg("--repeat", 200).max(1);
    let sim = simulate(&SimSettings {
        velocity_mm_s: 9.0,
        seed: 1,
        ..SimSettings::default()
    })
    .expect("the default simulation runs");
    let geometry = sim.truth.settings.geometry;
    let settings = AnalyzeSettings::default();
    let checked = check(
        vec![sim.recording],
        Some(9.0),
        &geometry,
        &PreflightSettings::default(),
    )
    .expect("the simulated record passes the checks");
    let pred = geometry
        .predict(checked.velocity_mm_s, settings.harmonics)
        .expect("a prediction");
    let a = analyze(&checked.recordings, &pred, &settings).expect("the record analyses");
    let confidence = settings.confidence;
    // (info, window, offset in bins) of every level analyze computes.
    let mut calls: Vec<(SpectrumInfo, Vec<f64>, f64)> = Vec::new();
    for s in [&a.spectra_unfiltered, &a.spectra, &a.spectra_hires] {
        let w = Window::Hann.values(s.info.nperseg).expect("a window");
        calls.push((s.info.clone(), w, 0.0));
    }
    let hr = &a.spectra_hires;
    let w_hr = Window::Hann.values(hr.info.nperseg).expect("a window");
    for row in &a.coherence {
        let i = hr.nearest_bin(row.f_hz).expect("a bin");
        let d = (row.f_hz - hr.freq_hz[i]) / hr.info.resolution_hz;
        calls.push((hr.info.clone(), w_hr.clone(), d));
    }
    let us = |d: Duration| d.as_secs_f64() * 1e6;
    println!("coherence_row_level, best of {repeat} runs");
    for (name, s) in [
        ("unfiltered", &a.spectra_unfiltered),
        ("full", &a.spectra),
        ("hires", &a.spectra_hires),
    ] {
        println!(
            "  {name}: nperseg {}, noverlap {}, {} segments x {} records",
            s.info.nperseg, s.info.noverlap, s.info.n_segments, s.info.n_records
        );
    }
    let t = best(repeat, || {
        calls
            .iter()
            .map(|(info, w, d)| coherence_row_level(info, w, *d, confidence))
            .collect::<Vec<_>>()
    });
    println!(
        "  one analyze's {} levels ({} spectra + {} coherence rows): {:.1} us",
        calls.len(),
        3,
        a.coherence.len(),
        us(t)
    );
    let w = Window::Hann.values(64).expect("a window");
    for k in [3usize, 12, 58, 150, 512] {
        let info = SpectrumInfo {
            nperseg: 64,
            noverlap: 32,
            n_segments: k,
            n_records: 1,
            dof: welch_dof(&w, 32, k),
            ..Default::default()
        };
        for d in [0.0, 0.25] {
            let t = best(repeat, || coherence_row_level(&info, &w, d, confidence));
            println!("  Hann 50 %, K = {k:3}, offset {d:.2} bin: {:.2} us", us(t));
        }
    }
}
