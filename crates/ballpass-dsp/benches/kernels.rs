//! The seven `ballpass.signal` kernels that were below 5x SciPy in
//! `tools/bench_python.py`, timed in Rust alone (no Python call overhead)
//! on 30 000 samples shaped like that script's inputs: a uniform-noise
//! sine (`correlate`, `lfilter`, `gradient`), a noisy Gaussian pulse train
//! with 8 000-odd local maxima (`find_peaks` with `prominence` and
//! `width`, no `distance`), 30 000 response frequencies (`freqs`,
//! `freqz`) and the 60 000 lags of two 30 000-sample records.
//!
//! ```sh
//! cargo bench -p ballpass-dsp --bench kernels -- [--repeat 400] [name ...]
//! ```
//!
//! Prints the best single-call wall time of `--repeat` calls per kernel
//! (one thread). The SciPy figures to set beside these are
//! `tools/bench_python.py`'s (SciPy 1.17.1 in one Python process, CPU
//! time: correlate 1669 us, correlation_lags 17.3, lfilter 181, find_peaks
//! 1011, freqs 469, freqz 974, numpy.gradient 31.7).
//!
//! Measured on the shared 2-core machine (load average 8-10), best of 400,
//! main 2db691d and this change:
//!
//! | kernel | before | after | what changed |
//! |---|---:|---:|---|
//! | correlate | 443.5 us | 400.1 us | product pass in split re/im lanes |
//! | correlation_lags | 8.2 us | 4.1 us | half-open range, wide vectors |
//! | lfilter | 163.6 us | 163.2 us | (latency of SciPy's recurrence) |
//! | find_peaks | 582.1 us | 570.0 us | (unchanged) |
//! | freqs | 161.4 us | 162.1 us | (unchanged) |
//! | freqz | 185.4 us | 185.4 us | (unchanged) |
//! | gradient | 20.4 us | 11.4 us | interior in wide vectors |
//!
//! `segment_powers10` / `segment_powers16` time `analyze`'s line search
//! in the position-domain spectra (8 segments of 1024 points; 10
//! frequencies, a golden-section step of five lines, and 16, a grid
//! chunk): 20.5 us both (session 10), since 10 frequencies run in a chunk
//! of 16 lanes. A 12-lane chunk for 9-12 frequencies (bitwise the same)
//! compiled to 66.8 us here (the compiler does not keep 12 lanes in
//! registers), so it was not kept.
//!
//! `floor_fill_480kB` and `floor_scale_240kB` (session 15) are the floors
//! of the two kernels that mostly write their output: a new `Vec` of the
//! lags' size (59 999 i64) filled with a constant, and one of the
//! gradient's size (30 000 f64) holding each sample of `x` times a
//! constant. Best of 300-500, load 7-11: correlation_lags 4.1 us against
//! 8.2 us for the plain fill (the range is already written as fast as this
//! core stores to L2); gradient 6.5-6.8 us against 4.1 us for the
//! read-scale-write pass (the stencil and its finiteness check cost the
//! rest; computing the interior by that plain pass and checking it after
//! measured 7.8-8.0 us, slower).
//!
//! Session 16 (`freqz_scipy_grid`, `floor_memset_480kB`, `fft_31104`,
//! `fft_15552`): freqs 92 -> 81 us and freqz 209 -> 171 us (a block
//! without a zero denominator skips the zero case's divisions; freqz in
//! blocks of 64 lanes), gradient 7.3-7.6 -> 5.2-5.4 us (groups of 32
//! outputs), load 6-10. The FFTs of correlate: 31 104 points 97 us, 15 552
//! points 45 us (so splitting each forward transform of zero-padded input
//! into two half-length ones would save ~7 us of the ~290), and the
//! memset of an existing 480 kB buffer is the lags' store floor.
//!
//! Session 17 (`freqz_grid_sp0` .. `freqz_grid_sp48`: `freqz_scipy_grid`
//! called from four stack offsets modulo 64). The freqz blocks were 8-byte
//! aligned arrays on the stack, so the speed depended on where the
//! process's stack started. Main's binary measured freqz 169 or 205 us and
//! freqz_scipy_grid 182 or 226 us, depending on the process. With the blocks
//! 64-byte aligned: freqz 163-165 us, and freqz_scipy_grid 172-173 us at all
//! four offsets (best of 300, load 7-8).
//!
//! Of correlate's 400 us, the three FFTs of 31 104 complex points (the real
//! transforms of 62 208) take ~290 us (96 us each; RustFFT was no faster
//! at 30 000, 30 720, 31 250, 32 000 or 32 768 points, measured), so 5x
//! SciPy (~334 us with the call) is out of reach while RustFFT does them.

use std::hint::black_box;
use std::time::{Duration, Instant};

use ballpass_dsp as dsp;

/// splitmix64 uniforms in [0, 1).
fn uniforms(n: usize, mut state: u64) -> Vec<f64> {
    (0..n)
        .map(|_| {
            state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^= z >> 31;
            (z >> 11) as f64 / (1u64 << 53) as f64
        })
        .collect()
}

/// `f()` with the stack pointer moved down by `PAD` bytes: the same call
/// from a stack that starts elsewhere modulo 64, as in different processes
/// (the kernel places the stack top at a random 16-byte multiple).
#[inline(never)]
fn with_stack_pad<const PAD: usize>(f: &mut dyn FnMut()) {
    let pad = [0u8; PAD];
    black_box(&pad);
    f();
    black_box(&pad);
}

fn best(repeat: usize, mut f: impl FnMut()) -> Duration {
    (0..repeat)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed()
        })
        .min()
        .expect("repeat >= 1")
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let repeat = args
        .iter()
        .position(|a| a == "--repeat")
        .and_then(|i| args.get(i + 1))
        .map_or(400, |v| v.parse().expect("a whole number"));
    let wanted: Vec<&String> = args
        .iter()
        .filter(|a| !a.starts_with("--") && a.parse::<usize>().is_err())
        .collect();
    let n = 30_000;
    let fs = 1000.0;
    let u = uniforms(n, 1);
    let x: Vec<f64> = (0..n)
        .map(|i| u[i] - 0.5 + (2.0 * std::f64::consts::PI * 1.1 * i as f64 / fs).sin())
        .collect();
    let v = uniforms(n, 2);
    let y: Vec<f64> = (0..n)
        .map(|i| x[(i + n - 25) % n] + 0.3 * (v[i] - 0.5))
        .collect();
    let noise = uniforms(n, 3);
    let pulses: Vec<f64> = (0..n)
        .map(|i| {
            let d = ((i + 100) % 200) as f64 - 100.0;
            (-0.5 * (d / 12.0) * (d / 12.0)).exp() + 0.035 * (noise[i] - 0.5)
        })
        .collect();
    // scipy.signal.butter(5, 20.0, fs=1000.0) (b, a), as printed by SciPy 1.17.1.
    let b = [
        8.042356421971168e-07,
        4.021178210985584e-06,
        8.042356421971168e-06,
        8.042356421971168e-06,
        4.021178210985584e-06,
        8.042356421971168e-07,
    ];
    let a = [
        1.0,
        -4.593421399807688,
        8.455115223510134,
        -7.794918318044447,
        3.5989027680539127,
        -0.665652538171361,
    ];
    let f: Vec<f64> = (0..n).map(|i| 500.0 * i as f64 / (n - 1) as f64).collect();
    let w: Vec<f64> = (0..n)
        .map(|i| 10f64.powf(-2.0 + 5.0 * i as f64 / (n - 1) as f64))
        .collect();
    let peaks_settings = dsp::FindPeaksSettings {
        prominence: Some(dsp::Bound {
            min: Some(0.5),
            max: None,
        }),
        width: Some(dsp::Bound {
            min: Some(1.0),
            max: None,
        }),
        ..dsp::FindPeaksSettings::default()
    };
    let mut correlator = dsp::Correlator::new(dsp::CorrelateSettings::default());
    let mut corr = dsp::Correlation {
        lags: Vec::new(),
        values: Vec::new(),
    };
    // `analyze`'s line search in the position-domain spectra: 8 Welch
    // segments of 1024 points, 10 frequencies (a golden-section step of
    // five lines) and 16 (a grid chunk).
    let segs: Vec<&[f64]> = x.chunks_exact(1024).take(8).collect();
    let f10: Vec<f64> = (0..10).map(|j| 0.01 + 0.003 * j as f64).collect();
    let f16: Vec<f64> = (0..16).map(|j| 0.01 + 0.002 * j as f64).collect();
    // The single 30 s record at 9 mm/s has 3 segments (and 5 at 15 mm/s),
    // 5 frequencies a golden-section step (one new point per line).
    let segs3: Vec<&[f64]> = segs[..3].to_vec();
    let f5: Vec<f64> = f10[..5].to_vec();
    let mut lags_buf = vec![0i64; 2 * n - 1];
    // Zeros: an FFT's time does not depend on the values (no subnormals),
    // and repeated transforms of zeros never overflow.
    let mut planner = rustfft::FftPlanner::<f64>::new();
    let (fft_long, fft_short) = (
        planner.plan_fft_forward(31_104),
        planner.plan_fft_forward(15_552),
    );
    let zero = rustfft::num_complex::Complex::new(0.0, 0.0);
    let mut fft_buf = vec![zero; 31_104];
    let mut fft_scratch = vec![zero; fft_long.get_inplace_scratch_len()];
    let mut fft_buf_short = vec![zero; 15_552];
    let mut fft_scratch_short = vec![zero; fft_short.get_inplace_scratch_len()];
    type Kernel<'a> = (&'static str, Box<dyn FnMut() + 'a>);
    let kernels: Vec<Kernel> = vec![
        (
            "segment_powers10",
            Box::new(|| {
                black_box(dsp::segment_powers(&segs, 0.1, &f10).expect("ok"));
            }),
        ),
        (
            "segment_powers16",
            Box::new(|| {
                black_box(dsp::segment_powers(&segs, 0.1, &f16).expect("ok"));
            }),
        ),
        (
            "segment_powers16x3",
            Box::new(|| {
                black_box(dsp::segment_powers(&segs3, 0.1, &f16).expect("ok"));
            }),
        ),
        (
            "segment_powers5x3",
            Box::new(|| {
                black_box(dsp::segment_powers(&segs3, 0.1, &f5).expect("ok"));
            }),
        ),
        (
            "correlate",
            Box::new(|| {
                correlator.correlate_into(&x, &y, &mut corr).expect("ok");
                black_box(std::mem::take(&mut corr.values));
            }),
        ),
        (
            "correlation_lags",
            Box::new(|| {
                black_box(dsp::correlation_lags(n, n));
            }),
        ),
        (
            "lfilter",
            Box::new(|| {
                black_box(dsp::lfilter(&b, &a, &x).expect("ok"));
            }),
        ),
        (
            "lfilter_fast",
            Box::new(|| {
                black_box(dsp::lfilter_fast(&b, &a, &x).expect("ok"));
            }),
        ),
        (
            "find_peaks",
            Box::new(|| {
                black_box(dsp::find_peaks(&pulses, &peaks_settings).expect("ok"));
            }),
        ),
        (
            "freqs",
            Box::new(|| {
                black_box(dsp::freqs_values(&b, &a, &w).expect("ok"));
            }),
        ),
        (
            "freqz",
            Box::new(|| {
                black_box(dsp::freqz_values(&b, &a, &f, fs).expect("ok"));
            }),
        ),
        (
            "freqz_scipy_grid",
            Box::new(|| {
                black_box(dsp::freqz_values_scipy_grid(&b, &a, &f, fs).expect("ok"));
            }),
        ),
        // The Python path of freqz at four stack offsets modulo 64 (session
        // 17): a kernel whose blocks sit on the stack unaligned runs at
        // two speeds depending on where the stack starts.
        (
            "freqz_grid_sp0",
            Box::new(|| {
                with_stack_pad::<64>(&mut || {
                    black_box(dsp::freqz_values_scipy_grid(&b, &a, &f, fs).expect("ok"));
                })
            }),
        ),
        (
            "freqz_grid_sp16",
            Box::new(|| {
                with_stack_pad::<80>(&mut || {
                    black_box(dsp::freqz_values_scipy_grid(&b, &a, &f, fs).expect("ok"));
                })
            }),
        ),
        (
            "freqz_grid_sp32",
            Box::new(|| {
                with_stack_pad::<96>(&mut || {
                    black_box(dsp::freqz_values_scipy_grid(&b, &a, &f, fs).expect("ok"));
                })
            }),
        ),
        (
            "freqz_grid_sp48",
            Box::new(|| {
                with_stack_pad::<112>(&mut || {
                    black_box(dsp::freqz_values_scipy_grid(&b, &a, &f, fs).expect("ok"));
                })
            }),
        ),
        (
            "gradient",
            Box::new(|| {
                black_box(dsp::gradient(&x, dsp::Spacing::Uniform(1.0 / fs)).expect("ok"));
            }),
        ),
        // Floors of the two kernels bound by writing their output: a new
        // buffer of the same size filled by the plainest loop (the lags'
        // 59 999 i64, 480 kB: a constant; the gradient's 30 000 f64,
        // 240 kB: each sample of `x` read and scaled once).
        (
            "floor_fill_480kB",
            Box::new(|| {
                black_box(vec![black_box(7i64); 2 * n - 1]);
            }),
        ),
        (
            "floor_scale_240kB",
            Box::new(|| {
                let s = black_box(2.0);
                black_box(x.iter().map(|v| v * s).collect::<Vec<f64>>());
            }),
        ),
        // The C library's memset of an existing 480 kB buffer (the lags'
        // size), no allocation: the store bandwidth correlation_lags is
        // held to.
        (
            "floor_memset_480kB",
            Box::new(|| {
                lags_buf.fill(0);
                black_box(&mut lags_buf);
            }),
        ),
        // Correlate's transforms: one complex RustFFT of 31 104 points (the
        // half-length transform of the real 62 208-point FFTs; correlate
        // makes three), and of 15 552 (two of which would make one of
        // 31 104 when its input's second half is zero).
        (
            "fft_31104",
            Box::new(|| {
                fft_long.process_with_scratch(&mut fft_buf, &mut fft_scratch);
                black_box(&mut fft_buf);
            }),
        ),
        (
            "fft_15552",
            Box::new(|| {
                fft_short.process_with_scratch(&mut fft_buf_short, &mut fft_scratch_short);
                black_box(&mut fft_buf_short);
            }),
        ),
    ];
    for (name, mut call) in kernels {
        if !wanted.is_empty() && !wanted.iter().any(|w| w.as_str() == name) {
            continue;
        }
        let t = best(repeat, &mut call);
        println!("{name:18} {:9.1} us", t.as_secs_f64() * 1e6);
    }
}
