//! Helpers shared by the fixture tests: loading SciPy fixtures and comparing
//! arrays with a stated relative tolerance.
#![allow(dead_code)] // each test binary uses its own subset

use std::path::PathBuf;

/// Parses `tests/fixtures/<area>/<name>.json`.
pub fn fixture(area: &str, name: &str) -> serde_json::Value {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(area)
        .join(format!("{name}.json"));
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("fixture {}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("fixture {}: {e}", path.display()))
}

/// Names of all fixtures of an area (file stems), sorted.
pub fn fixture_names(area: &str) -> Vec<String> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(area);
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("fixtures {}: {e}", dir.display()))
        .filter_map(|e| {
            let p = e.ok()?.path();
            if p.extension()? != "json" {
                return None;
            }
            Some(p.file_stem()?.to_string_lossy().into_owned())
        })
        .collect();
    names.sort();
    names
}

/// A JSON array of numbers as `Vec<f64>`.
pub fn f64s(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .unwrap_or_else(|| panic!("expected an array, got {v}"))
        .iter()
        .map(|x| {
            x.as_f64()
                .unwrap_or_else(|| panic!("expected a number, got {x}"))
        })
        .collect()
}

/// Largest relative error `|a - b| / max(|b|, floor)` over two arrays.
///
/// `floor` keeps the ratio meaningful where the reference passes through zero;
/// callers pass a floor tied to the array's scale (e.g. `1e-12 * max|b|`).
pub fn max_rel_err(a: &[f64], b: &[f64], floor: f64) -> f64 {
    assert_eq!(a.len(), b.len(), "length differs");
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs() / y.abs().max(floor))
        .fold(0.0, f64::max)
}

/// Asserts `a ≈ b` elementwise with relative tolerance `rtol`, relative to
/// the largest |b| for elements far below it (floor = 1e-12 · max|b|).
#[track_caller]
pub fn assert_close(what: &str, a: &[f64], b: &[f64], rtol: f64) {
    assert_eq!(
        a.len(),
        b.len(),
        "{what}: length {} vs reference {}",
        a.len(),
        b.len()
    );
    let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let floor = (scale * 1e-12).max(f64::MIN_POSITIVE);
    let err = max_rel_err(a, b, floor);
    assert!(err <= rtol, "{what}: max relative error {err:e} > {rtol:e}");
}

/// Asserts `max|a - b| <= rtol * max|b|`: a norm-wise comparison for results
/// whose rounding error scales with the largest value rather than with each
/// element (FFT correlation: every lag carries an absolute error of order
/// `eps * sqrt(sum x^2 sum y^2)`, so small lags far from the peak cannot be
/// held to an elementwise relative bound).
#[track_caller]
pub fn assert_close_scaled(what: &str, a: &[f64], b: &[f64], rtol: f64) {
    assert_eq!(
        a.len(),
        b.len(),
        "{what}: length {} vs reference {}",
        a.len(),
        b.len()
    );
    let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let err = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(
        err <= rtol * scale,
        "{what}: max error {err:e} > {rtol:e} * max|ref| ({scale:e})"
    );
}

/// Elementwise `|a - b| / max(|b|, 1e-12 max|b|) <= rtol` for complex
/// values (the modulus, so that a bin whose imaginary part alone is tiny is
/// judged against its size).
#[track_caller]
pub fn assert_close_complex(
    what: &str,
    a: &[ballpass_dsp::Complex64],
    b: &[ballpass_dsp::Complex64],
    rtol: f64,
) {
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
