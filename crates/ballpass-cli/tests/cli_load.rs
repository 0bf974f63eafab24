//! End-to-end: `ballpass inspect` on good and bad recordings, run as a new
//! user would, in a scratch folder. Every bad input must give one line on
//! stderr naming the file (and line/column where there is one) and a
//! non-zero exit code.

mod common;

use std::path::PathBuf;

use common::{library_test_file, run_in, scratch, Run};

fn fixture(name: &str) -> PathBuf {
    library_test_file("data").join(name)
}

/// A 30 s, 1 kHz file with the three channels (enough periods at 9 mm/s).
fn good_csv() -> String {
    let mut s = String::from("time_s,friction_N,position_mm,optical_V\n");
    for i in 0..30_000 {
        let t = i as f64 / 1000.0;
        s.push_str(&format!(
            "{t},{},{},{}\n",
            2.0 + 0.1 * (7.0 * t).sin(),
            9.0 * t,
            0.3 + 0.1 * (6.97 * t).cos()
        ));
    }
    s
}

/// A small valid file body: `n` rows at 1 kHz, with one row replaced.
fn rows(n: usize, replace: Option<(usize, &str)>) -> String {
    let mut s = String::from("time_s,friction_N,optical_V\n");
    for i in 0..n {
        match replace {
            Some((k, row)) if k == i => s.push_str(row),
            _ => s.push_str(&format!("{},1.5,0.25", i as f64 / 1000.0)),
        }
        s.push('\n');
    }
    s
}

fn assert_one_line_error(r: &Run, must: &[&str]) {
    assert_ne!(r.code, 0, "exit code; stderr: {}", r.stderr);
    let lines: Vec<&str> = r.stderr.lines().collect();
    assert_eq!(lines.len(), 1, "stderr must be one line: {:?}", r.stderr);
    assert!(lines[0].starts_with("error: "), "{}", lines[0]);
    for m in must {
        assert!(lines[0].contains(m), "missing '{m}' in: {}", lines[0]);
    }
}

#[test]
fn good_csv_is_inspected_in_text_and_json() {
    let dir = scratch("good");
    std::fs::write(dir.join("run9.csv"), good_csv()).unwrap();
    let r = run_in(&dir, &["inspect", "run9.csv", "--velocity", "9"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(
        r.stdout.contains("30000 samples at 1000 Hz = 30.000 s"),
        "{}",
        r.stdout
    );
    assert!(
        r.stdout.contains("tau_c = 0.9012 s, 33.3 periods"),
        "{}",
        r.stdout
    );
    let r = run_in(&dir, &["inspect", "run9.csv", "-v", "9", "--json"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let j: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    assert_eq!(j["schema"], "ballpass.inspect/1");
    let i = &j["files"][0]["inspection"];
    assert_eq!(i["fs_hz"], 1000.0);
    assert_eq!(i["samples"], 30000);
    assert_eq!(i["test_id"], "run9");
    assert_eq!(i["bearing"], "THK SR25W");
    // Slope of the exact 9 t ramp, to the rounding of printed times.
    assert!((i["position_velocity_mm_s"].as_f64().unwrap() - 9.0).abs() < 1e-9);
    assert_eq!(i["channels"].as_array().unwrap().len(), 3);
}

#[test]
fn profile_maps_a_controldesk_mat_file() {
    let dir = scratch("profile");
    std::fs::write(
        dir.join("bench.toml"),
        "name = \"thesis bench\"\nbearing = \"sr25w\"\nmin_periods = 0.1\n\
         [friction]\nname = \"Force\"\n[position]\nname = \"Counts\"\nscale = 1e-4\n\
         [optical]\nname = \"Voltage\"\n",
    )
    .unwrap();
    let mat = fixture("controldesk.mat");
    let r = run_in(
        &dir,
        &[
            "inspect",
            mat.to_str().unwrap(),
            "--profile",
            "bench.toml",
            "-v",
            "9",
            "--json",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let j: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    let i = &j["files"][0]["inspection"];
    assert_eq!(i["fs_hz"], 1000.0);
    assert_eq!(i["missing"].as_array().unwrap().len(), 0);
    // A profile key that does not exist is named with its line.
    std::fs::write(
        dir.join("typo.toml"),
        "fs_hz = 1000\nfriction_col = \"F\"\n",
    )
    .unwrap();
    let r = run_in(
        &dir,
        &["inspect", mat.to_str().unwrap(), "--profile", "typo.toml"],
    );
    assert_one_line_error(&r, &["typo.toml:2", "friction_col"]);
}

#[test]
fn missing_channel_is_listed_and_a_mapped_missing_column_is_an_error() {
    let dir = scratch("missing");
    std::fs::write(dir.join("a.csv"), rows(40, None)).unwrap();
    let r = run_in(&dir, &["inspect", "a.csv"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stdout.contains("missing: position_mm"), "{}", r.stdout);
    let r = run_in(&dir, &["inspect", "a.csv", "--position-col", "Encoder"]);
    assert_one_line_error(
        &r,
        &[
            "a.csv:1",
            "no column 'Encoder' for position_mm",
            "'time_s', 'friction_N', 'optical_V'",
        ],
    );
}

#[test]
fn every_bad_text_input_gets_a_one_line_error_with_file_and_line() {
    let dir = scratch("badtext");
    let cases: Vec<(&str, String, Vec<&str>)> = vec![
        (
            "empty.csv",
            String::new(),
            vec!["empty.csv", "file is empty"],
        ),
        (
            "header.csv",
            "time_s,friction_N\n".into(),
            vec!["header.csv", "no data rows"],
        ),
        (
            "text.csv",
            rows(40, Some((7, "0.007,abc,0.25"))),
            vec!["text.csv:9 column 'friction_N'", "'abc' is not a number"],
        ),
        (
            "ragged.csv",
            rows(40, Some((12, "0.012,1.5"))),
            vec!["ragged.csv:14", "2 field(s), but the header (line 1) has 3"],
        ),
        (
            "nonuniform.csv",
            rows(40, Some((20, "0.0204,1.5,0.25"))),
            vec!["nonuniform.csv:22 column 'time_s'", "not uniform"],
        ),
        (
            "decreasing.csv",
            rows(40, Some((30, "0.001,1.5,0.25"))),
            vec!["decreasing.csv:32 column 'time_s'", "backwards"],
        ),
        (
            "duplicate.csv",
            rows(40, Some((25, "0.024,1.5,0.25"))),
            vec!["duplicate.csv:27 column 'time_s'", "duplicate time stamp"],
        ),
    ];
    for (name, text, must) in &cases {
        std::fs::write(dir.join(name), text).unwrap();
        let r = run_in(&dir, &["inspect", name]);
        assert_one_line_error(&r, must);
    }
    // inspect reports a record too short to analyse; analyses refuse it.
    std::fs::write(dir.join("short.csv"), rows(5, None)).unwrap();
    let r = run_in(&dir, &["inspect", "short.csv"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stdout.contains("only 5 samples"), "{}", r.stdout);
    let r = run_in(&dir, &["analyze", "short.csv", "-v", "9", "--out", "o"]);
    assert_one_line_error(&r, &["short.csv", "only 5 samples"]);
}

#[test]
fn bad_mat_files_get_one_line_errors() {
    let dir = scratch("badmat");
    for (name, must) in [
        ("csv_renamed.mat", "looks like a CSV file"),
        ("truncated.mat", "truncated MAT-file"),
        ("truncated_v7.mat", "truncated MAT-file"),
        ("garbage.mat", "malformed MAT-file"),
        (
            "v73_header.mat",
            "v7.3 (HDF5) MAT-file: not a readable HDF5 file",
        ),
    ] {
        let p = fixture(name);
        let r = run_in(&dir, &["inspect", p.to_str().unwrap()]);
        assert_one_line_error(&r, &[name, must]);
    }
}

#[test]
fn bad_velocity_and_geometry_are_refused() {
    let dir = scratch("badsettings");
    std::fs::write(dir.join("a.csv"), rows(40, None)).unwrap();
    for (args, must) in [
        (vec!["-v", "0"], "invalid velocity"),
        (vec!["--velocity", "-3"], "invalid velocity"),
        (vec!["--ball-diameter", "0"], "invalid ball diameter"),
        (vec!["--free-space", "-1"], "invalid free space"),
        (vec!["--balls", "0"], "invalid balls in race"),
        (vec!["--fs", "-1000"], "invalid fs"),
        (vec!["--fs", "2000"], "disagrees with the time column"),
        (vec!["--bearing", "xyz"], "unknown bearing 'xyz'"),
    ] {
        let mut all = vec!["inspect", "a.csv"];
        all.extend(args);
        let r = run_in(&dir, &all);
        assert_one_line_error(&r, &[must]);
    }
    // Velocity and geometry are checked by predict too.
    let r = run_in(&dir, &["predict", "--velocity", "0"]);
    assert_one_line_error(&r, &["invalid velocity"]);
    let r = run_in(&dir, &["predict", "-v", "9", "--balls", "-2"]);
    assert_one_line_error(&r, &["invalid balls in race"]);
}

#[test]
fn several_files_report_each_error_and_fail_overall() {
    let dir = scratch("several");
    std::fs::write(dir.join("good.csv"), good_csv()).unwrap();
    std::fs::write(dir.join("bad.csv"), "time_s,friction_N\n").unwrap();
    let r = run_in(&dir, &["inspect", "good.csv", "bad.csv"]);
    assert_ne!(r.code, 0);
    assert!(r.stdout.contains("good.csv"), "{}", r.stdout);
    assert!(
        r.stderr
            .contains("bad.csv: header (line 1) but no data rows"),
        "{}",
        r.stderr
    );
    assert!(
        r.stderr.contains("1 of 2 files could not be loaded"),
        "{}",
        r.stderr
    );
}
