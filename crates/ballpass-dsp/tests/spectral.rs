//! Spectral and correlation kernels against SciPy fixtures
//! (`tools/scipy_fixtures/spectral.py`), against slow obviously-correct
//! references (direct-sum correlation, naive DFT Welch), and against laws
//! (Parseval, `R_xy[m] = R_yx[-m]`, linearity) with proptest.

mod common;

use std::collections::HashMap;

use ballpass_dsp::{
    coherence, correlate, csd, detrend, periodogram, polyphase_average_csd, polyphase_average_psd,
    welch, Average, Complex64, CorrelateSettings, Correlator, DetrendType, Normalization,
    PeriodogramSettings, Scaling, Welch, WelchSettings, Window,
};
use common::{assert_close, assert_close_scaled, f64s, fixture, fixture_names};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed, TestRunner};
use serde_json::Value;

const AREA: &str = "spectral";

/// Relative tolerance against SciPy for the spectral estimates. Both sides
/// compute the same sums of the same products in nearly the same order;
/// they differ only by FFT rounding (pocketfft vs RustFFT) and where the
/// scale factor is applied, a few 1e-16 relative on bins of ordinary size.
/// 1e-9 leaves room for bins well below the spectrum's peak.
const RTOL: f64 = 1e-9;

fn signals() -> HashMap<String, Vec<f64>> {
    let v = fixture(AREA, "signals");
    v.as_object()
        .unwrap()
        .iter()
        .map(|(k, v)| (k.clone(), f64s(v)))
        .collect()
}

fn names_of(kind: &str) -> Vec<String> {
    let names: Vec<String> = fixture_names(AREA)
        .into_iter()
        .filter(|n| n.starts_with(&format!("{kind}_")))
        .collect();
    assert!(!names.is_empty(), "no {kind} fixtures");
    names
}

fn window_of(v: &Value) -> Window {
    match v {
        Value::String(s) => match s.as_str() {
            "hann" => Window::Hann,
            "hamming" => Window::Hamming,
            "boxcar" => Window::Boxcar,
            other => panic!("unknown window {other}"),
        },
        Value::Array(_) => Window::Custom(f64s(v)),
        other => panic!("bad window {other}"),
    }
}

fn detrend_of(v: &Value) -> DetrendType {
    match v.as_str().unwrap() {
        "none" => DetrendType::None,
        "constant" => DetrendType::Constant,
        "linear" => DetrendType::Linear,
        other => panic!("unknown detrend {other}"),
    }
}

fn scaling_of(v: &Value) -> Scaling {
    match v.as_str().unwrap() {
        "density" => Scaling::Density,
        "spectrum" => Scaling::Spectrum,
        other => panic!("unknown scaling {other}"),
    }
}

fn opt_usize(v: &Value) -> Option<usize> {
    v.as_u64().map(|n| n as usize)
}

fn welch_settings(s: &Value) -> WelchSettings {
    let d = WelchSettings::default();
    WelchSettings {
        window: window_of(&s["window"]),
        nperseg: opt_usize(&s["nperseg"]).unwrap_or(d.nperseg),
        noverlap: opt_usize(&s["noverlap"]),
        nfft: opt_usize(&s["nfft"]),
        detrend: detrend_of(&s["detrend"]),
        scaling: scaling_of(&s["scaling"]),
        onesided: s["onesided"].as_bool().unwrap(),
        average: match s["average"].as_str().unwrap() {
            "mean" => Average::Mean,
            "median" => Average::Median,
            other => panic!("unknown average {other}"),
        },
    }
}

fn complex_of(v: &Value, key: &str) -> Vec<Complex64> {
    let re = f64s(&v[format!("{key}_re")]);
    let im = f64s(&v[format!("{key}_im")]);
    re.into_iter()
        .zip(im)
        .map(|(r, i)| Complex64::new(r, i))
        .collect()
}

/// Elementwise `|a - b| / max(|b|, 1e-12 max|b|) <= rtol` for complex
/// values (the modulus, so that a bin whose imaginary part alone is tiny is
/// judged against its size).
#[track_caller]
fn assert_close_complex(what: &str, a: &[Complex64], b: &[Complex64], rtol: f64) {
    assert_eq!(a.len(), b.len(), "{what}: length");
    let scale = b.iter().fold(0.0f64, |m, z| m.max(z.norm()));
    let floor = (1e-12 * scale).max(f64::MIN_POSITIVE);
    let err = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).norm() / y.norm().max(floor))
        .fold(0.0, f64::max);
    assert!(err <= rtol, "{what}: max relative error {err:e} > {rtol:e}");
}

// ---------------------------------------------------------------- fixtures

#[test]
fn windows_match_get_window() {
    for name in names_of("window") {
        let f = fixture(AREA, &name);
        let w = window_of(&f["window"])
            .values(opt_usize(&f["n"]).unwrap())
            .unwrap();
        // Same formula, same operation order as SciPy's general_cosine:
        // agreement to a couple of ulps.
        assert_close(&name, &w, &f64s(&f["values"]), 1e-15);
    }
}

#[test]
fn detrend_matches_scipy() {
    let sig = signals();
    for name in names_of("detrend") {
        let f = fixture(AREA, &name);
        let x = &sig[f["x"].as_str().unwrap()];
        let kind = match f["type"].as_str().unwrap() {
            "linear" => DetrendType::Linear,
            _ => DetrendType::Constant,
        };
        let y = detrend(x, kind).unwrap();
        let want = f64s(&f["out"]);
        if want.iter().all(|v| v.abs() < 1e-12) {
            // One-sample signals: SciPy's lstsq leaves rounding residue
            // around 0; ours is exactly 0.
            assert!(y.iter().all(|v| v.abs() < 1e-12), "{name}");
            continue;
        }
        // Closed-form least squares vs SciPy's lstsq: same line, different
        // rounding (~1e-15 relative to the data's scale).
        assert_close(&name, &y, &want, RTOL);
    }
}

#[test]
fn correlate_matches_numpy_full() {
    let sig = signals();
    for name in names_of("correlate") {
        let f = fixture(AREA, &name);
        let x = &sig[f["x"].as_str().unwrap()];
        let y = &sig[f["y"].as_str().unwrap()];
        let lags: Vec<i64> = f["lags"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_i64().unwrap())
            .collect();
        let mut forms = vec![(Normalization::None, "direct")];
        if f.get("coeff").is_some() {
            forms.push((Normalization::Coeff, "coeff"));
        }
        if f.get("biased").is_some() {
            forms.push((Normalization::Biased, "biased"));
            forms.push((Normalization::Unbiased, "unbiased"));
        }
        for (norm, key) in forms {
            let c = correlate(x, y, norm).unwrap();
            assert_eq!(c.lags, lags, "{name}");
            let want = f64s(&f[key]);
            // FFT correlation: error ~ eps * sqrt(log n) * ||x|| ||y|| at
            // every lag, so compare norm-wise. 1e-12 of the peak is ~1e3
            // times the expected rounding; a wrong lag or scale is O(1).
            if norm == Normalization::Unbiased {
                // 1/(N-|m|) magnifies the absolute error at the far lags by
                // up to N; compare the unscaled form instead.
                let n = x.len() as f64;
                let back: Vec<f64> = c
                    .values
                    .iter()
                    .zip(&lags)
                    .map(|(v, m)| v * (n - m.abs() as f64))
                    .collect();
                let raw = f64s(&f["direct"]);
                assert_close_scaled(&format!("{name} unbiased"), &back, &raw, 1e-12);
                // and near lag 0 the values themselves agree closely
                let mid = y.len() - 1;
                assert_close(
                    &format!("{name} unbiased lag 0"),
                    &c.values[mid..=mid],
                    &want[mid..=mid],
                    1e-12,
                );
            } else {
                assert_close_scaled(&format!("{name} {key}"), &c.values, &want, 1e-12);
            }
        }
    }
}

#[test]
fn welch_matches_scipy() {
    let sig = signals();
    for name in names_of("welch") {
        let f = fixture(AREA, &name);
        let x = &sig[f["x"].as_str().unwrap()];
        let s = welch_settings(&f["settings"]);
        let fs = f["fs"].as_f64().unwrap();
        let p = welch(x, fs, &s).unwrap();
        // Frequencies use numpy's fftfreq arithmetic: identical to rounding.
        assert_close(
            &format!("{name} freq"),
            &p.freq_hz,
            &f64s(&f["freq"]),
            1e-15,
        );
        assert_close(&format!("{name} pxx"), &p.pxx, &f64s(&f["pxx"]), RTOL);
        assert_eq!(
            p.n_segments as u64,
            f["n_segments"].as_u64().unwrap(),
            "{name}"
        );
        // The reusable estimator gives bit-identical results, twice.
        let mut w = Welch::new(s).unwrap();
        assert_eq!(w.psd(x, fs).unwrap(), p, "{name} Welch::psd");
        assert_eq!(w.psd(x, fs).unwrap(), p, "{name} Welch::psd reused");
    }
}

#[test]
fn csd_matches_scipy() {
    let sig = signals();
    for name in names_of("csd") {
        let f = fixture(AREA, &name);
        let x = &sig[f["x"].as_str().unwrap()];
        let y = &sig[f["y"].as_str().unwrap()];
        let s = welch_settings(&f["settings"]);
        let fs = f["fs"].as_f64().unwrap();
        let p = csd(x, y, fs, &s).unwrap();
        assert_close(
            &format!("{name} freq"),
            &p.freq_hz,
            &f64s(&f["freq"]),
            1e-15,
        );
        assert_close_complex(&format!("{name} pxy"), &p.pxy, &complex_of(&f, "pxy"), RTOL);
        assert_eq!(
            p.n_segments as u64,
            f["n_segments"].as_u64().unwrap(),
            "{name}"
        );
        let mut w = Welch::new(s).unwrap();
        assert_eq!(w.csd(x, y, fs).unwrap(), p, "{name} Welch::csd");
    }
}

#[test]
fn coherence_matches_scipy() {
    let sig = signals();
    for name in names_of("coherence") {
        let f = fixture(AREA, &name);
        let x = &sig[f["x"].as_str().unwrap()];
        let y = &sig[f["y"].as_str().unwrap()];
        let s = welch_settings(&f["settings"]);
        let fs = f["fs"].as_f64().unwrap();
        let c = coherence(x, y, fs, &s).unwrap();
        assert_close(
            &format!("{name} freq"),
            &c.freq_hz,
            &f64s(&f["freq"]),
            1e-15,
        );
        // Bins where Pxx or Pyy is rounding residue (the DC bin of a
        // mean-removed boxcar segment) hold 0/0 noise in SciPy and here
        // alike; compare only bins with power above 1e-20 of the peak.
        let pxx = welch(x, fs, &s).unwrap().pxx;
        let pyy = welch(y, fs, &s).unwrap().pxx;
        let live = |p: &[f64], k: usize| p[k] > 1e-20 * p.iter().fold(0.0f64, |m, v| m.max(*v));
        let keep: Vec<usize> = (0..pxx.len())
            .filter(|&k| live(&pxx, k) && live(&pyy, k))
            .collect();
        assert!(
            keep.len() + 1 >= pxx.len(),
            "{name}: more than the DC bin is degenerate"
        );
        let want = f64s(&f["cxy"]);
        let got: Vec<f64> = keep.iter().map(|&k| c.cxy[k]).collect();
        let want: Vec<f64> = keep.iter().map(|&k| want[k]).collect();
        assert_close(&format!("{name} cxy"), &got, &want, RTOL);
        assert!(
            c.cxy.iter().all(|&v| (0.0..=1.0 + 1e-12).contains(&v)),
            "{name}"
        );
    }
}

#[test]
fn periodogram_matches_scipy() {
    let sig = signals();
    for name in names_of("periodogram") {
        let f = fixture(AREA, &name);
        let x = &sig[f["x"].as_str().unwrap()];
        let st = &f["settings"];
        let s = PeriodogramSettings {
            window: window_of(&st["window"]),
            nfft: opt_usize(&st["nfft"]),
            detrend: detrend_of(&st["detrend"]),
            scaling: scaling_of(&st["scaling"]),
            onesided: st["onesided"].as_bool().unwrap(),
        };
        let p = periodogram(x, f["fs"].as_f64().unwrap(), &s).unwrap();
        assert_close(
            &format!("{name} freq"),
            &p.freq_hz,
            &f64s(&f["freq"]),
            1e-15,
        );
        assert_close(&format!("{name} pxx"), &p.pxx, &f64s(&f["pxx"]), RTOL);
        assert_eq!(p.n_segments, 1);
    }
}

#[test]
fn polyphase_average_matches_numpy_steps() {
    let sig = signals();
    for name in names_of("zoom") {
        let f = fixture(AREA, &name);
        let x = &sig[f["x"].as_str().unwrap()];
        let y = &sig[f["y"].as_str().unwrap()];
        let s = welch_settings(&f["settings"]);
        let fs = f["fs"].as_f64().unwrap();
        let m = opt_usize(&f["decimation"]).unwrap();
        let p = polyphase_average_psd(x, fs, m, &s).unwrap();
        assert_close(
            &format!("{name} freq"),
            &p.freq_hz,
            &f64s(&f["freq"]),
            1e-15,
        );
        assert_close(&format!("{name} pxx"), &p.pxx, &f64s(&f["pxx"]), RTOL);
        assert_eq!(
            p.n_segments as u64,
            f["n_segments"].as_u64().unwrap(),
            "{name}"
        );
        let c = polyphase_average_csd(x, y, fs, m, &s).unwrap();
        assert_close_complex(&format!("{name} pxy"), &c.pxy, &complex_of(&f, "pxy"), RTOL);
    }
}

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
