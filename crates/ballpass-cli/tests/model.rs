//! End-to-end tests of `ballpass model`: the real binary in a temp directory.

mod common;

use std::path::PathBuf;

use common::{run, scratch_path};

/// Column `name` of a CSV file as numbers.
fn column(path: &PathBuf, name: &str) -> Vec<f64> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let i = header
        .iter()
        .position(|h| *h == name)
        .unwrap_or_else(|| panic!("{name} in {header:?}"));
    lines
        .map(|l| l.split(',').nth(i).unwrap().parse().unwrap())
        .collect()
}

#[test]
fn pulses_writes_errata_coefficients() {
    let d = scratch_path("pulses");
    let (ok, out, err) = run(&[
        "model",
        "pulses",
        "--ratio",
        "0.155",
        "--out",
        d.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("10.05%"), "{out}");
    let c = column(&d.join("gaussian_coefficients.csv"), "c_over_p");
    // docs/methods.md §6 values, 5 significant digits printed.
    for (got, want) in c.iter().zip([0.38853, 0.24180, 0.058290, 0.0054426]) {
        assert!((got - want).abs() / want < 5e-5, "{got} vs {want}");
    }
    let a = column(&d.join("rectangular_coefficients.csv"), "a_n");
    // docs/methods.md §5 a0 = 0.310, a1 = 0.26326 (truncated digits).
    assert!((a[0] - 0.310).abs() < 5e-4 && (a[1] - 0.26326).abs() < 1e-5);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("pulses.json")).unwrap()).unwrap();
    assert_eq!(json["schema"], "ballpass.model.pulses/1");
    // No temp files left behind by the atomic writes.
    assert!(std::fs::read_dir(&d).unwrap().all(|e| !e
        .unwrap()
        .file_name()
        .to_string_lossy()
        .starts_with('.')));
}

#[test]
fn stage_writes_bode_and_velocity_response() {
    let d = scratch_path("stage");
    let (ok, out, err) = run(&[
        "model",
        "stage",
        "--mass",
        "3",
        "--natural-frequency",
        "16.6",
        "--damping",
        "0.05",
        "--velocity",
        "9",
        "--out",
        d.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("natural frequency 16.6000 Hz"), "{out}");
    for f in [
        "bode.csv",
        "difference.csv",
        "harmonics.csv",
        "velocity_response.csv",
        "stage.json",
        "report.html",
        "figures/bode_g_xr.svg",
        "figures/bode_g_xf.svg",
        "figures/bode_g_vf.svg",
        "figures/difference.svg",
        "figures/velocity_response.svg",
    ] {
        assert!(d.join(f).exists(), "{f}");
    }
    // (the report keeps a number and its unit together with a no-break space)
    let html = std::fs::read_to_string(d.join("report.html"))
        .unwrap()
        .replace("&nbsp;", " ");
    // f_c = 1.1096 Hz, f_n = 16.6 Hz: the natural frequency is marked.
    assert!(
        html.contains("Natural frequency f_n = 16.60 Hz"),
        "natural frequency in the captions"
    );
    assert!(
        html.contains(env!("CARGO_PKG_VERSION")),
        "version in the report"
    );
    let v = column(&d.join("velocity_response.csv"), "velocity_mm_s");
    assert_eq!(v.len(), 1000);
    // The velocity deviation has zero mean (D_0 = 0): rounding only.
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    let pp = v.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        - v.iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(mean.abs() < 1e-12 * pp.max(1.0), "{mean}");
}

#[test]
fn stage_without_loop_parameters_is_a_clear_error() {
    let d = scratch_path("bad");
    let (ok, _, err) = run(&[
        "model",
        "stage",
        "--mass",
        "3",
        "--out",
        d.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(
        err.contains("--kp") && err.contains("--natural-frequency"),
        "{err}"
    );
    let (ok, _, err) = run(&["model", "signals", "--out", d.to_str().unwrap()]);
    assert!(!ok && err.contains("--velocity"), "{err}");
    let (ok, _, err) = run(&[
        "model",
        "pulses",
        "--ratio",
        "1.5",
        "--out",
        d.to_str().unwrap(),
    ]);
    assert!(!ok && err.contains("ratio"), "{err}");
}

#[test]
fn signals_reports_phase_in_words() {
    let d = scratch_path("signals");
    let (ok, out, err) = run(&[
        "model",
        "signals",
        "--f-c",
        "1",
        "--out",
        d.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("ve leads F by 0.25000 s"), "{out}");
    let r = column(&d.join("correlations.csv"), "r_fve_n_mm_s");
    let tau = column(&d.join("correlations.csv"), "tau_s");
    // Eq. 7.1 default: R_Fve(τ) = +(a_f a_v/2) sin ω_c τ; rounding only.
    for (t, r) in tau.iter().zip(&r) {
        assert!((r - 0.5 * (2.0 * std::f64::consts::PI * t).sin()).abs() < 1e-12);
    }
}

#[test]
fn pulses_report_has_the_coefficients_on_a_log_axis_and_no_report_writes_none() {
    let d = scratch_path("pulses-report");
    let (ok, _, err) = run(&["model", "pulses", "--out", d.to_str().unwrap(), "--png"]);
    assert!(ok, "{err}");
    for f in [
        "report.html",
        "figures/gaussian_coefficients.svg",
        "figures/gaussian_coefficients.png",
        "figures/trains.svg",
    ] {
        assert!(d.join(f).exists(), "{f}");
    }
    let svg = std::fs::read_to_string(d.join("figures/gaussian_coefficients.svg")).unwrap();
    assert!(svg.contains("|C_n| / P"), "log-axis title");
    let d2 = scratch_path("pulses-noreport");
    let (ok, _, err) = run(&[
        "model",
        "pulses",
        "--out",
        d2.to_str().unwrap(),
        "--no-report",
    ]);
    assert!(ok, "{err}");
    assert!(d2.join("pulses.json").exists());
    assert!(!d2.join("report.html").exists() && !d2.join("figures").exists());
}
