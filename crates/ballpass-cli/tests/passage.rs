//! End-to-end tests of `ballpass passage`: the real binary on CSV files
//! written in a temp directory.

mod common;

use std::fmt::Write as _;
use std::path::Path;

use common::{run, scratch};

/// 20 s at 1 kHz of Gaussian pulses (FWHM = 0.155 τ_c) every τ_c at 10 mm/s
/// on SR25W, plus a deterministic pseudo-noise of ±0.005 V.
fn write_pulses(path: &Path, with_optical: bool) -> usize {
    let tau_c = 2.0 * (4.0 + 2.0 / 36.0) / 10.0;
    let sigma = 0.155 * tau_c / 2.354_820_045;
    let centres: Vec<f64> = (0..)
        .map(|k| 0.3 + k as f64 * tau_c)
        .take_while(|t| *t < 19.7)
        .collect();
    let mut s = String::from(if with_optical {
        "time_s,optical_V\n"
    } else {
        "time_s,friction_N\n"
    });
    let mut state = 12345u64;
    for i in 0..20_000 {
        let t = i as f64 / 1000.0;
        let mut v = 1.0;
        for c in &centres {
            let u = (t - c) / sigma;
            if u.abs() < 10.0 {
                v += 0.5 * (-0.5 * u * u).exp();
            }
        }
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        v += 0.01 * ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5);
        writeln!(s, "{t:.3},{v:.6}").unwrap();
    }
    std::fs::write(path, s).unwrap();
    centres.len()
}

#[test]
fn passage_writes_csv_json_and_summary() {
    let d = scratch("ok");
    let rec = d.join("run.csv");
    let n = write_pulses(&rec, true);
    let out = d.join("out");
    let (ok, stdout, err) = run(&[
        "passage",
        rec.to_str().unwrap(),
        "--velocity",
        "10",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(stdout.contains(&format!("{n} passages")), "{stdout}");
    assert!(stdout.contains("no artefacts found"), "{stdout}");
    let csv = std::fs::read_to_string(out.join("passages.csv")).unwrap();
    assert_eq!(csv.lines().count(), n + 1, "header + one row per passage");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("passage.json")).unwrap()).unwrap();
    assert_eq!(json["schema"], "ballpass.passage/1");
    let r = &json["records"][0];
    // τ_c = 0.81111 s exactly in the file (times rounded to 1 ms): 0.5 % target.
    let tau_c = r["tau_c_s"]["mean"].as_f64().unwrap();
    assert!((tau_c / 0.811111 - 1.0).abs() < 0.005, "{tau_c}");
    let ratio = r["tau_p_over_tau_c"]["mean"].as_f64().unwrap();
    assert!((ratio / 0.155 - 1.0).abs() < 0.03, "{ratio}");
    assert_eq!(r["fits"]["better"], "gaussian");
    // The whole record's train was fitted, with its goodness of fit.
    assert_eq!(r["fits"]["pulses"].as_u64().unwrap() as usize, n);
    assert!(
        r["fits"]["gaussian"]["quality"]["r_squared"]
            .as_f64()
            .unwrap()
            > 0.99
    );
    // The report, on by default.
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(html.contains("Prediction vs measurement") && html.contains("no artefacts found"));
    for f in ["optical_1", "pulses_1", "widths_1"] {
        assert!(out.join(format!("figures/{f}.svg")).exists(), "{f}");
    }
}

#[test]
fn passage_takes_the_shared_load_flags() {
    // A headerless-time file with a renamed optical column, read through the
    // shared --fs / --optical-col flags as `inspect` does.
    let d = scratch("load");
    let rec = d.join("run.csv");
    write_pulses(&rec, true);
    let text = std::fs::read_to_string(&rec).unwrap();
    let renamed: String = std::iter::once("pd_volts".to_string())
        .chain(
            text.lines()
                .skip(1)
                .map(|l| l.split(',').nth(1).unwrap().to_string()),
        )
        .collect::<Vec<_>>()
        .join("\n");
    let rec2 = d.join("renamed.csv");
    std::fs::write(&rec2, renamed + "\n").unwrap();
    let out = d.join("out");
    let (ok, stdout, err) = run(&[
        "passage",
        rec2.to_str().unwrap(),
        "--fs",
        "1000",
        "--optical-col",
        "pd_volts",
        "-v",
        "10",
        "--no-report",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(stdout.contains("v = 10 mm/s (settings)"), "{stdout}");
    assert!(out.join("passage.json").exists() && !out.join("report.html").exists());
}

#[test]
fn record_without_optical_channel_or_pulses_is_a_clear_error() {
    let d = scratch("bad");
    let rec = d.join("friction_only.csv");
    write_pulses(&rec, false);
    let out = d.join("out");
    let (ok, _, err) = run(&[
        "passage",
        rec.to_str().unwrap(),
        "--velocity",
        "10",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(err.contains("optical_V is missing"), "{err}");
    assert!(!out.join("passages.csv").exists(), "no empty table written");

    let flat = d.join("flat.csv");
    let mut s = String::from("time_s,optical_V\n");
    for i in 0..20_000 {
        writeln!(
            s,
            "{:.3},{}",
            i as f64 / 1000.0,
            if i % 2 == 0 { 1.0 } else { 1.001 }
        )
        .unwrap();
    }
    std::fs::write(&flat, s).unwrap();
    let (ok, _, err) = run(&[
        "passage",
        flat.to_str().unwrap(),
        "--velocity",
        "10",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(err.contains("no ball passages found"), "{err}");
    assert!(!out.join("passages.csv").exists());
}
