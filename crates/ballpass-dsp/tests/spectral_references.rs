//! Spectral and correlation kernels against slow obviously-correct
//! references (direct-sum correlation, naive DFT Welch) and against laws
//! (Parseval, `R_xy[m] = R_yx[-m]`, linearity) with proptest. The SciPy
//! fixtures are in `spectral.rs`.

mod common;

use ballpass_dsp::{
    correlate, csd, detrend, periodogram, welch, Average, Complex64, CorrelateSettings, Correlator,
    DetrendType, Normalization, PeriodogramSettings, Scaling, Welch, WelchSettings, Window,
};
use common::{assert_close, assert_close_complex, assert_close_scaled};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed, TestRunner};

/// Relative tolerance against the naive DFT references: both sides
/// compute the same sums of the same products; they differ only by FFT
/// rounding, a few 1e-16 relative on bins of ordinary size. 1e-9 (the
/// SciPy fixtures' tolerance) leaves room for bins well below the peak.
const RTOL: f64 = 1e-9;

// ------------------------------------------------------ slow references

/// Deterministic test signal (an LCG, so no RNG crate is needed).
fn lcg_signal(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        })
        .collect()
}

fn direct_correlation(x: &[f64], y: &[f64]) -> Vec<f64> {
    let (nx, ny) = (x.len() as i64, y.len() as i64);
    (-(ny - 1)..nx)
        .map(|m| {
            (0..ny)
                .filter(|&n| n + m >= 0 && n + m < nx)
                .map(|n| x[(n + m) as usize] * y[n as usize])
                .sum()
        })
        .collect()
}

#[test]
fn fft_correlation_equals_direct_sum_for_many_lengths() {
    let mut c = Correlator::new(CorrelateSettings::default());
    for nx in 1..=40 {
        for ny in 1..=40 {
            let x = lcg_signal(nx, nx as u64);
            let y = lcg_signal(ny, 1000 + ny as u64);
            let got = c.correlate(&x, &y).unwrap();
            // Norm-wise 1e-13: FFT rounding is ~1e-16 of the peak here.
            assert_close_scaled(
                &format!("nx={nx} ny={ny}"),
                &got.values,
                &direct_correlation(&x, &y),
                1e-13,
            );
        }
    }
    for (nx, ny) in [
        (4000, 3999),
        (2503, 1),
        (1, 3001),
        (1000, 3000),
        (4096, 4096),
    ] {
        let x = lcg_signal(nx, 7);
        let y = lcg_signal(ny, 8);
        let got = c.correlate(&x, &y).unwrap();
        // Longer transforms: rounding grows like sqrt(log n); 1e-12 norm-wise.
        assert_close_scaled(
            &format!("nx={nx} ny={ny}"),
            &got.values,
            &direct_correlation(&x, &y),
            1e-12,
        );
        let auto = c.autocorrelate(&x).unwrap();
        assert_close_scaled(
            &format!("auto nx={nx}"),
            &auto.values,
            &direct_correlation(&x, &x),
            1e-12,
        );
    }
}

/// Naive DFT of a real sequence, bins `0 ..= nfft / 2`, with the phase
/// reduced exactly (`k n mod nfft`) so the reference itself is accurate.
fn naive_rdft(x: &[f64], nfft: usize) -> Vec<Complex64> {
    (0..=nfft / 2)
        .map(|k| {
            x.iter()
                .enumerate()
                .map(|(n, v)| {
                    let ph = -2.0 * std::f64::consts::PI * ((k * n) % nfft) as f64 / nfft as f64;
                    Complex64::new(v * ph.cos(), v * ph.sin())
                })
                .sum()
        })
        .collect()
}

/// Welch by the textbook, one-sided, mean-averaged, density-scaled.
fn naive_welch_csd(x: &[f64], y: &[f64], fs: f64, s: &WelchSettings) -> Vec<Complex64> {
    let nperseg = s.nperseg;
    let nov = s.noverlap.unwrap_or(nperseg / 2);
    let nfft = s.nfft.unwrap_or(nperseg);
    let w = s.window.values(nperseg).unwrap();
    let step = nperseg - nov;
    let nseg = (x.len() - nov) / step;
    let mut acc = vec![Complex64::new(0.0, 0.0); nfft / 2 + 1];
    for j in 0..nseg {
        let seg = |v: &[f64]| {
            let d = detrend(&v[j * step..j * step + nperseg], s.detrend).unwrap();
            let wd: Vec<f64> = d.iter().zip(&w).map(|(a, b)| a * b).collect();
            naive_rdft(&wd, nfft)
        };
        let (a, b) = (seg(x), seg(y));
        for k in 0..acc.len() {
            acc[k] += a[k].conj() * b[k];
        }
    }
    let scale = 1.0 / (fs * w.iter().map(|v| v * v).sum::<f64>()) / nseg as f64;
    let last = if nfft % 2 == 0 {
        acc.len() - 1
    } else {
        acc.len()
    };
    acc.iter()
        .enumerate()
        .map(|(k, v)| v * scale * if k > 0 && k < last { 2.0 } else { 1.0 })
        .collect()
}

#[test]
fn welch_and_csd_equal_naive_dft() {
    let x = lcg_signal(700, 1);
    let y: Vec<f64> = lcg_signal(700, 2)
        .iter()
        .zip(&x)
        .map(|(a, b)| a + 0.5 * b)
        .collect();
    let cases = [
        WelchSettings {
            nperseg: 64,
            ..Default::default()
        },
        WelchSettings {
            nperseg: 63,
            noverlap: Some(5),
            ..Default::default()
        },
        WelchSettings {
            nperseg: 50,
            nfft: Some(77),
            detrend: DetrendType::Linear,
            ..Default::default()
        },
        WelchSettings {
            nperseg: 100,
            noverlap: Some(0),
            window: Window::Hamming,
            detrend: DetrendType::None,
            ..Default::default()
        },
    ];
    for (i, s) in cases.iter().enumerate() {
        let want = naive_welch_csd(&x, &y, 250.0, s);
        let got = csd(&x, &y, 250.0, s).unwrap();
        // Naive DFT sums carry ~n eps rounding; 1e-9 elementwise as for SciPy.
        assert_close_complex(&format!("case {i} csd"), &got.pxy, &want, RTOL);
        let want_xx: Vec<f64> = naive_welch_csd(&x, &x, 250.0, s)
            .iter()
            .map(|v| v.re)
            .collect();
        let got_xx = welch(&x, 250.0, s).unwrap();
        assert_close(&format!("case {i} welch"), &got_xx.pxx, &want_xx, RTOL);
    }
    // Periodogram = one boxcar segment over everything.
    let s = WelchSettings {
        nperseg: 700,
        noverlap: Some(0),
        window: Window::Boxcar,
        ..Default::default()
    };
    let want: Vec<f64> = naive_welch_csd(&x, &x, 250.0, &s)
        .iter()
        .map(|v| v.re)
        .collect();
    let got = periodogram(&x, 250.0, &PeriodogramSettings::default()).unwrap();
    assert_close("periodogram", &got.pxx, &want, RTOL);
}

#[test]
fn delayed_copy_gives_documented_signs() {
    // y = x delayed by d: correlation peaks at lag -d; arg Pxy = -2 pi f d / fs.
    let x = lcg_signal(4000, 3);
    let d = 7usize;
    let y: Vec<f64> = (0..x.len())
        .map(|i| if i >= d { x[i - d] } else { 0.0 })
        .collect();
    let c = correlate(&x, &y, Normalization::Coeff).unwrap();
    let (imax, _) = c
        .values
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .unwrap();
    assert_eq!(c.lags[imax], -(d as i64));
    assert_eq!(c.lag_s(1000.0)[imax], -0.007);
    let fs = 1000.0;
    let p = csd(
        &x,
        &y,
        fs,
        &WelchSettings {
            nperseg: 256,
            ..Default::default()
        },
    )
    .unwrap();
    for k in [3usize, 10, 20] {
        let expect = -2.0 * std::f64::consts::PI * p.freq_hz[k] * d as f64 / fs;
        // White-noise estimate of a pure delay: phase within 0.05 rad at
        // these low bins (the delay is 7 of 256 samples, coherence ~0.95).
        let diff = (p.pxy[k] * Complex64::from_polar(1.0, -expect)).arg();
        assert!(diff.abs() < 0.05, "bin {k}: phase off by {diff} rad");
    }
}

// ------------------------------------------------------ property tests

fn runner(cases: u32) -> TestRunner {
    TestRunner::new(Config {
        cases,
        rng_seed: RngSeed::Fixed(0x5EC7_0A11),
        failure_persistence: None,
        ..Config::default()
    })
}

fn signal_strategy(max_len: usize) -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec(-1.0e3..1.0e3f64, 1..max_len)
}

#[test]
fn parseval_for_periodogram() {
    runner(64)
        .run(
            &(signal_strategy(300), 0.5..5.0e3f64, any::<bool>()),
            |(x, fs, pad)| {
                let nfft = if pad { Some(x.len() + 17) } else { None };
                let base = PeriodogramSettings {
                    detrend: DetrendType::None,
                    nfft,
                    ..Default::default()
                };
                let ms = x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64;
                // density: sum(Pxx) * df = mean square; spectrum (boxcar):
                // sum(Pxx) = mean square * nfft / N... only without padding:
                let p = periodogram(&x, fs, &base).unwrap();
                let df = fs / nfft.unwrap_or(x.len()) as f64;
                let integral = p.pxx.iter().sum::<f64>() * df;
                // Tolerance 1e-10 relative: a sum of a few hundred rounded terms.
                prop_assert!(
                    (integral - ms).abs() <= 1e-10 * ms.max(1e-300),
                    "{integral} vs {ms}"
                );
                if !pad {
                    let sp = periodogram(
                        &x,
                        fs,
                        &PeriodogramSettings {
                            scaling: Scaling::Spectrum,
                            ..base.clone()
                        },
                    )
                    .unwrap();
                    let total: f64 = sp.pxx.iter().sum();
                    prop_assert!(
                        (total - ms).abs() <= 1e-10 * ms.max(1e-300),
                        "{total} vs {ms}"
                    );
                }
                // Two-sided sums to the same power.
                let two = periodogram(
                    &x,
                    fs,
                    &PeriodogramSettings {
                        onesided: false,
                        ..base
                    },
                )
                .unwrap();
                let integral2 = two.pxx.iter().sum::<f64>() * df;
                prop_assert!((integral2 - ms).abs() <= 1e-10 * ms.max(1e-300));
                Ok(())
            },
        )
        .unwrap();
}

#[test]
fn cross_correlation_mirrors() {
    runner(64)
        .run(&(signal_strategy(200), signal_strategy(200)), |(x, y)| {
            let a = correlate(&x, &y, Normalization::None).unwrap();
            let b = correlate(&y, &x, Normalization::None).unwrap();
            let scale = a
                .values
                .iter()
                .fold(0.0f64, |m, v| m.max(v.abs()))
                .max(1e-300);
            // R_xy[m] = R_yx[-m]; norm-wise 1e-12 (FFT rounding, see above).
            for (m, v) in a.lags.iter().zip(&a.values) {
                let w = b.at_lag(-m).unwrap();
                prop_assert!((v - w).abs() <= 1e-12 * scale, "lag {m}: {v} vs {w}");
            }
            Ok(())
        })
        .unwrap();
}

#[test]
fn correlation_and_csd_are_linear() {
    let strat = (1usize..150, -5.0..5.0f64, -5.0..5.0f64, any::<u64>());
    runner(48)
        .run(&strat, |(n, a, b, seed)| {
            let x1 = lcg_signal(n, seed);
            let x2 = lcg_signal(n, seed ^ 0xABCD);
            let y = lcg_signal(n, seed.wrapping_add(99));
            let mix: Vec<f64> = x1.iter().zip(&x2).map(|(p, q)| a * p + b * q).collect();
            let r = correlate(&mix, &y, Normalization::None).unwrap();
            let r1 = correlate(&x1, &y, Normalization::None).unwrap();
            let r2 = correlate(&x2, &y, Normalization::None).unwrap();
            let want: Vec<f64> = r1
                .values
                .iter()
                .zip(&r2.values)
                .map(|(p, q)| a * p + b * q)
                .collect();
            let scale = want.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-12);
            for (g, w) in r.values.iter().zip(&want) {
                // 1e-12 norm-wise: three FFT correlations' rounding.
                prop_assert!((g - w).abs() <= 1e-12 * scale * (1.0 + a.abs() + b.abs()));
            }
            let s = WelchSettings {
                nperseg: 32.min(n),
                ..Default::default()
            };
            let p = csd(&mix, &y, 10.0, &s).unwrap();
            let p1 = csd(&x1, &y, 10.0, &s).unwrap();
            let p2 = csd(&x2, &y, 10.0, &s).unwrap();
            let sc = p.pxy.iter().fold(0.0f64, |m, v| m.max(v.norm())).max(1e-12);
            for k in 0..p.pxy.len() {
                let w = p1.pxy[k] * a + p2.pxy[k] * b;
                prop_assert!((p.pxy[k] - w).norm() <= 1e-12 * sc * (1.0 + a.abs() + b.abs()));
            }
            Ok(())
        })
        .unwrap();
}

#[test]
fn welch_is_reusable_across_threads() {
    let s = WelchSettings {
        nperseg: 128,
        ..Default::default()
    };
    let w = Welch::new(s.clone()).unwrap();
    let xs: Vec<Vec<f64>> = (0..4).map(|i| lcg_signal(2000, i)).collect();
    let results: Vec<_> = std::thread::scope(|sc| {
        let handles: Vec<_> = xs
            .iter()
            .map(|x| {
                let mut w = w.clone();
                sc.spawn(move || w.psd(x, 100.0).unwrap())
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for (x, r) in xs.iter().zip(results) {
        assert_eq!(r, welch(x, 100.0, &s).unwrap());
    }
}

/// `Welch::spectra` gives each signal's `psd` and each pair's `csd` (to
/// rounding: those pack segments into complex FFTs differently; bit for bit
/// with median averaging, which shares their code), for mean and median
/// averaging, one- and two-sided, every detrend, zero padding, and a signal
/// shorter than `nperseg`; bad inputs are errors.
#[test]
fn spectra_set_equals_psd_and_csd() {
    let sig = |seed: u64, n: usize| -> Vec<f64> {
        let mut s = seed;
        (0..n)
            .map(|i| {
                s = s
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                (s >> 11) as f64 / (1u64 << 53) as f64 + (0.01 * i as f64).sin()
            })
            .collect()
    };
    for n in [300, 1000, 5001] {
        let (a, b, c) = (sig(1, n), sig(2, n), sig(3, n));
        let signals = [&a[..], &b[..], &c[..]];
        let pairs = [(0, 1), (0, 2), (1, 2), (2, 0)];
        for (average, onesided, detrend, nfft) in [
            (Average::Mean, true, DetrendType::Constant, None),
            (Average::Mean, false, DetrendType::Linear, Some(700)),
            (Average::Mean, true, DetrendType::None, None),
            (Average::Median, true, DetrendType::Constant, None),
        ] {
            let settings = WelchSettings {
                nperseg: 512,
                noverlap: Some(200),
                nfft,
                detrend,
                average,
                onesided,
                ..WelchSettings::default()
            };
            let mut w = Welch::new(settings).unwrap();
            let set = w.spectra(&signals, &pairs, 1000.0).unwrap();
            // Mean: 1e-13 of the series' largest value (the FFT roundings
            // differ, ~1e-16 each); median: exact.
            let tol = if average == Average::Median {
                0.0
            } else {
                1e-13
            };
            let close = |a: &[Complex64], b: &[Complex64], what: String| {
                assert_eq!(a.len(), b.len(), "{what}");
                let big = b.iter().map(|z| z.norm()).fold(0.0, f64::max);
                let err = a
                    .iter()
                    .zip(b)
                    .map(|(x, y)| (x - y).norm())
                    .fold(0.0, f64::max);
                assert!(err <= tol * big, "{what}: {err:e} vs {big:e}");
            };
            let real = |v: &[f64]| {
                v.iter()
                    .map(|&x| Complex64::new(x, 0.0))
                    .collect::<Vec<_>>()
            };
            for (k, x) in signals.iter().enumerate() {
                let p = w.psd(x, 1000.0).unwrap();
                close(
                    &real(&set.auto[k]),
                    &real(&p.pxx),
                    format!("n {n} {average:?} auto {k}"),
                );
                assert_eq!(set.freq_hz, p.freq_hz);
                assert_eq!(set.n_segments, p.n_segments);
            }
            for (k, &(i, j)) in pairs.iter().enumerate() {
                let c = w.csd(signals[i], signals[j], 1000.0).unwrap();
                close(&set.cross[k], &c.pxy, format!("n {n} {average:?} pair {k}"));
            }
        }
    }
    let mut w = Welch::new(WelchSettings::default()).unwrap();
    let x = vec![1.0; 600];
    assert!(w.spectra(&[], &[], 1000.0).is_err());
    assert!(w.spectra(&[&x, &x[..599]], &[(0, 1)], 1000.0).is_err());
    assert!(w.spectra(&[&x], &[(0, 1)], 1000.0).is_err());
    let mut bad = x.clone();
    bad[7] = f64::NAN;
    assert!(w.spectra(&[&x, &bad], &[], 1000.0).is_err());
    assert!(w.spectra(&[&x], &[], 0.0).is_err());
}
