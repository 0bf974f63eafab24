//! Spectral and correlation kernels against SciPy fixtures
//! (`tools/scipy_fixtures/spectral.py`). The slow references and laws are
//! in `spectral_references.rs`.

mod common;

use std::collections::HashMap;

use ballpass_dsp::{
    coherence, correlate, csd, detrend, periodogram, polyphase_average_csd, polyphase_average_psd,
    welch, Average, Complex64, DetrendType, Normalization, PeriodogramSettings, Scaling, Welch,
    WelchSettings, Window,
};
use common::{
    assert_close, assert_close_complex, assert_close_scaled, f64s, fixture, fixture_names,
};
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
