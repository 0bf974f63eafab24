//! Recordings as labs have them (issue 15) through the real binary: time
//! windows, the velocity measured from the encoder, and multi-speed runs
//! split into their plateaus.

mod common;

use std::path::PathBuf;

use common::{library_test_file, run, run_ok, scratch};

fn fixture() -> PathBuf {
    library_test_file("fixtures/analyze/input.csv")
}

fn json(p: PathBuf) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

/// `--window` keeps the part asked for, on the record's time axis, and the
/// outputs name every record with it.
#[test]
fn the_window_is_applied_and_stated_in_the_outputs() {
    let d = scratch("window");
    let rec = fixture();
    let r = rec.to_str().unwrap();
    let out = d.join("a");
    run_ok(common::bin().args([
        "analyze",
        r,
        "--velocity",
        "18",
        "--window",
        "2:6",
        "--out",
        out.to_str().unwrap(),
    ]));
    let a = json(out.join("analysis.json"));
    // 4 s at 200 Hz.
    assert_eq!(a["inputs"][0]["samples"], 800);
    let src = a["inputs"][0]["source"].as_str().unwrap();
    assert!(src.ends_with("input.csv (t = 2.000–6.000 s)"), "{src}");
    assert!(a["method_notes"]
        .as_array()
        .unwrap()
        .iter()
        .any(|n| n.as_str().unwrap().starts_with("window 2–6 s")));
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    // The report keeps a number and its unit together with a no-break space.
    assert!(html.contains("Record operations") && html.contains("2–6&nbsp;s"));
    // inspect and passage take it too.
    let (ok, stdout, stderr) = run(&["inspect", r, "--window", "1:", "--json"]);
    assert!(ok, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["files"][0]["inspection"]["samples"], 1400);
    assert_eq!(v["window"]["start_s"], 1.0);
    let p = d.join("p");
    run_ok(common::bin().args(["passage", r, "--window", ":5", "--out", p.to_str().unwrap()]));
    let pj = json(p.join("passage.json"));
    assert_eq!(pj["window"]["end_s"], 5.0);
    assert!(pj["records"][0]["duration_s"].as_f64().unwrap() <= 5.0);
    let _ = std::fs::remove_dir_all(&d);
}

/// Without a velocity, `analyze` and `passage` use the encoder's and say
/// it was measured.
#[test]
fn the_velocity_is_measured_from_the_encoder_when_none_is_given() {
    let d = scratch("measured");
    let rec = fixture();
    let r = rec.to_str().unwrap();
    let out = d.join("a");
    let (ok, stdout, stderr) = run(&["analyze", r, "--out", out.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("mm/s (measured)"), "{stdout}");
    assert!(stderr.contains("measured from the encoder"), "{stderr}");
    let a = json(out.join("analysis.json"));
    // The fixture's stage runs at 18 mm/s; the slope of its noisy,
    // quantised position is within 0.01 % of it.
    let v = a["prediction"]["velocity_mm_s"].as_f64().unwrap();
    assert!((v - 18.0).abs() < 18.0 * 1e-4, "{v}");
    let p = d.join("p");
    run_ok(common::bin().args(["passage", r, "--out", p.to_str().unwrap()]));
    let pj = json(p.join("passage.json"));
    assert_eq!(
        pj["records"][0]["velocity_source"],
        "measured from the encoder"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// A multi-speed run (the simulator's benchmark run: 42, 83, 125 mm/s back
/// and forth) is split into its six plateaus; `analyze --segment` analyses
/// each speed's two plateaus as repeats at their measured speed, within
/// 1 % of the commanded (the simulator's truth).
#[test]
fn a_multi_speed_run_is_analysed_per_plateau_speed() {
    let d = scratch("segment");
    let rec = d.join("run.csv");
    run_ok(common::bin().args([
        "simulate",
        "--multi-speed",
        "--duration",
        "25",
        "-o",
        rec.to_str().unwrap(),
    ]));
    let truth = json(d.join("run.truth.json"));
    assert_eq!(truth["plateaus"].as_array().unwrap().len(), 6);
    let r = rec.to_str().unwrap();
    let (ok, stdout, stderr) = run(&["inspect", r, "--segment"]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("6 constant-velocity plateau(s)"),
        "{stdout}"
    );
    let out = d.join("a");
    let (ok, stdout, stderr) = run(&[
        "analyze",
        r,
        "--segment",
        "--no-report",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let seg = json(out.join("segments.json"));
    assert_eq!(seg["records"][0]["plateaus"].as_array().unwrap().len(), 6);
    let groups = seg["groups"].as_array().unwrap();
    assert_eq!(groups.len(), 3, "{stdout}");
    for (g, want) in groups.iter().zip([42.0, 83.0, 125.0]) {
        let folder = g["folder"].as_str().unwrap();
        let a = json(out.join(folder).join("analysis.json"));
        assert_eq!(a["inputs"].as_array().unwrap().len(), 2, "{folder}");
        let v = a["prediction"]["velocity_mm_s"].as_f64().unwrap();
        assert!((v - want).abs() < 0.01 * want, "{folder}: {v}");
    }
    // --velocity picks one speed's plateaus.
    let one = d.join("b");
    let (ok, _, stderr) = run(&[
        "analyze",
        r,
        "--segment",
        "--velocity",
        "83",
        "--no-report",
        "--out",
        one.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let seg = json(one.join("segments.json"));
    assert_eq!(seg["groups"].as_array().unwrap().len(), 1);
    // passage: one record per plateau, each at its measured speed.
    let p = d.join("p");
    let (ok, _, stderr) = run(&[
        "passage",
        r,
        "--segment",
        "--no-report",
        "--out",
        p.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let pj = json(p.join("passage.json"));
    assert_eq!(pj["records"].as_array().unwrap().len(), 6);
    let _ = std::fs::remove_dir_all(&d);
}
