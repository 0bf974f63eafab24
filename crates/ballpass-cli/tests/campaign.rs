//! `ballpass sweep` and `ballpass diagnose` through the real binary, on a
//! small simulated campaign written to disk the way a lab would have it.

mod common;

use std::path::Path;

use ballpass::campaign::manifest::manifest_csv;
use ballpass::campaign::ManifestEntry;
use ballpass::recording::write_csv;
use ballpass::sim::{simulate, Condition, SimSettings};
use common::{run_in, scratch};

/// Writes one 20 s simulated record and returns its manifest entry.
fn record(
    dir: &Path,
    name: &str,
    bearing: &str,
    v: f64,
    repeat: u32,
    sticking: bool,
    seed: u64,
) -> ManifestEntry {
    let mut s = SimSettings::for_bearing("sr25w", v).unwrap();
    s.duration_s = 20.0;
    s.seed = seed;
    if sticking {
        s.condition = Condition::Sticking;
    }
    let sim = simulate(&s).unwrap();
    write_csv(&sim.recording, &dir.join(name)).unwrap();
    ManifestEntry {
        path: name.into(),
        bearing: bearing.into(),
        velocity_mm_s: v,
        repeat,
        condition: Some(if sticking { "sticking" } else { "good" }.into()),
        notes: None,
        plateau: None,
    }
}

#[test]
fn sweep_and_diagnose_run_a_campaign_and_report_a_broken_record() {
    let d = scratch("campaign");
    let mut entries = Vec::new();
    let mut seed = 1;
    for v in [4.0, 8.0, 12.0, 16.0, 20.0] {
        for r in 1..=2 {
            entries.push(record(
                &d,
                &format!("v{v}_r{r}.csv"),
                "sr25w",
                v,
                r,
                false,
                seed,
            ));
            seed += 1;
        }
    }
    for b in 1..=3 {
        for r in 1..=3 {
            entries.push(record(
                &d,
                &format!("b{b}_r{r}.csv"),
                &format!("bearing{b}"),
                20.0,
                r,
                b == 2,
                seed,
            ));
            seed += 1;
        }
    }
    std::fs::write(d.join("manifest.csv"), manifest_csv(&entries)).unwrap();

    // Sweep: the bearing with the most velocities, five velocities × 2.
    let r = run_in(&d, &["sweep", "manifest.csv", "--out", "sw"]);
    assert!(r.ok(), "{}", r.stderr);
    assert!(r.stdout.contains("10 records (0 failed)"), "{}", r.stdout);
    assert!(r.stdout.contains("d_avg ="), "{}", r.stdout);
    for f in ["records.csv", "sweep.csv", "sweep.json", "report.html"] {
        assert!(d.join("sw").join(f).is_file(), "{f}");
    }
    let sweep_csv = std::fs::read_to_string(d.join("sw/sweep.csv")).unwrap();
    assert_eq!(sweep_csv.lines().count(), 1 + 5, "{sweep_csv}");
    // Regression: the report's header said "ballpass sweep" without the
    // arguments; it carries the command line and names the source.
    let html = std::fs::read_to_string(d.join("sw/report.html")).unwrap();
    assert!(
        html.contains("<title>ballpass sweep: manifest.csv</title>"),
        "report title"
    );
    let code = html
        .split("<code>")
        .nth(1)
        .unwrap()
        .split("</code>")
        .next()
        .unwrap();
    assert!(code.contains("sweep manifest.csv --out sw"), "{code}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("sw/sweep.json")).unwrap()).unwrap();
    // tau_c ∝ 1/v on the simulator: the fitted exponent is −1 within 1 %.
    let slope = json["result"]["tau_c_fit"]["slope"].as_f64().unwrap();
    assert!((slope + 1.0).abs() < 0.01, "slope {slope}");

    // Diagnose: 20 mm/s has four bearings; sr25w (also at other speeds) is left out.
    let r = run_in(
        &d,
        &["diagnose", "manifest.csv", "--out", "dg", "--no-report"],
    );
    assert!(r.ok(), "{}", r.stderr);
    assert!(r.stdout.contains("left out sr25w"), "{}", r.stdout);
    let first = r.stdout.lines().find(|l| l.starts_with("#1 ")).unwrap();
    assert!(
        first.contains("bearing2") && first.contains("bad"),
        "{}",
        r.stdout
    );
    assert!(!d.join("dg/report.html").exists());
    let diag = std::fs::read_to_string(d.join("dg/diagnosis.csv")).unwrap();
    assert_eq!(
        diag.lines().filter(|l| l.contains(",bad,")).count(),
        1,
        "{diag}"
    );

    // A broken record: reported with its file and reason, the others finish,
    // the exit code says something failed.
    std::fs::write(d.join("b1_r2.csv"), "time_s,friction_N\n0,1\n0.001,oops\n").unwrap();
    let r = run_in(
        &d,
        &["diagnose", "manifest.csv", "--out", "dg2", "--no-report"],
    );
    assert_eq!(r.code, 1, "{}\n{}", r.stdout, r.stderr);
    assert!(r.stdout.contains("9 records (1 failed)"), "{}", r.stdout);
    assert!(
        r.stdout.contains("b1_r2.csv") && r.stdout.contains("oops"),
        "{}",
        r.stdout
    );
    assert!(r.stderr.contains("1 of 9 records failed"), "{}", r.stderr);
    let recs = std::fs::read_to_string(d.join("dg2/records.csv")).unwrap();
    assert_eq!(recs.lines().filter(|l| l.contains(",failed,")).count(), 1);
    assert_eq!(recs.lines().filter(|l| l.contains(",ok,")).count(), 8);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_folder_with_a_pattern_works_without_a_manifest_and_bad_sources_are_one_line_errors() {
    let d = scratch("pattern");
    for v in [6.0, 12.0, 18.0] {
        record(&d, &format!("v{v}_r1.csv"), "sr25w", v, 1, false, v as u64);
    }
    let r = run_in(
        &d,
        &[
            "sweep",
            ".",
            "--pattern",
            "v{velocity}_r{repeat}.csv",
            "--out",
            "out",
            "--no-report",
        ],
    );
    assert!(r.ok(), "{}", r.stderr);
    assert!(r.stdout.contains("3 records (0 failed)"), "{}", r.stdout);
    for (args, want) in [
        (vec!["sweep", ".", "--out", "o"], "give --pattern"),
        (vec!["sweep", "missing.csv", "--out", "o"], "missing.csv"),
        (
            vec!["sweep", ".", "--pattern", "{speed}.csv", "--out", "o"],
            "unknown field {speed}",
        ),
    ] {
        let r = run_in(&d, &args);
        assert_eq!(r.code, 1, "{args:?}");
        assert!(
            r.stderr.contains(want) && r.stderr.lines().count() == 1,
            "{args:?}: {}",
            r.stderr
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// Every file of a run folder with its bytes, sorted by path.
fn run_files(d: &Path) -> Vec<(String, Vec<u8>)> {
    let m = ballpass::outdir::RunManifest::read(d).expect("ballpass-run.json");
    let mut v: Vec<(String, Vec<u8>)> = m
        .files
        .iter()
        .map(|f| (f.path.clone(), std::fs::read(d.join(&f.path)).unwrap()))
        .collect();
    v.push((
        "ballpass-run.json".into(),
        std::fs::read(d.join("ballpass-run.json")).unwrap(),
    ));
    v.sort();
    v
}

/// Issue 18 item 13: two identical runs write the same bytes: no
/// `elapsed_s` (or other timing) in sweep.json or diagnosis.json.
#[test]
fn item13_identical_runs_write_identical_outputs() {
    let d = scratch("item13");
    let mut entries = Vec::new();
    for (k, v) in [6.0, 12.0].into_iter().enumerate() {
        entries.push(record(
            &d,
            &format!("v{v}.csv"),
            "sr25w",
            v,
            1,
            false,
            k as u64,
        ));
        entries.push(record(
            &d,
            &format!("b{v}.csv"),
            "b2",
            v,
            1,
            false,
            10 + k as u64,
        ));
    }
    std::fs::write(d.join("m.csv"), manifest_csv(&entries)).unwrap();
    for cmd in ["sweep", "diagnose"] {
        let mut runs = Vec::new();
        for out in ["a", "b"] {
            let r = run_in(&d, &[cmd, "m.csv", "--out", out, "--jobs", "2"]);
            assert!(r.ok(), "{}", r.stderr);
            runs.push(run_files(&d.join(out)));
        }
        assert_eq!(runs[0].len(), runs[1].len());
        for (a, b) in runs[0].iter().zip(&runs[1]) {
            assert_eq!(a.0, b.0);
            // The report quotes its command line, which names its own
            // output folder: that one difference is expected.
            let a_bytes = String::from_utf8_lossy(&a.1).replace("--out a ", "--out b ");
            let b_bytes = String::from_utf8_lossy(&b.1).into_owned();
            assert!(
                a_bytes == b_bytes,
                "{cmd}: {} differs between identical runs",
                a.0
            );
        }
        let json = if cmd == "sweep" {
            "sweep.json"
        } else {
            "diagnosis.json"
        };
        let text = std::fs::read_to_string(d.join("a").join(json)).unwrap();
        assert!(!text.contains("elapsed"), "{json}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// Issue 18 item 9: in folder mode a linked recording and a file whose
/// name is not UTF-8 are records like the others, and what was left out
/// is said with the reason.
#[cfg(unix)]
#[test]
fn item9_folder_mode_reads_links_and_odd_names_and_says_what_it_skipped() {
    use std::os::unix::ffi::OsStrExt;
    let d = scratch("item9");
    let elsewhere = d.join("store");
    std::fs::create_dir_all(&elsewhere).unwrap();
    let src = d.join("recs");
    std::fs::create_dir_all(&src).unwrap();
    record(&src, "v6_r1.csv", "sr25w", 6.0, 1, false, 1);
    record(&elsewhere, "kept.csv", "sr25w", 6.0, 2, false, 2);
    std::os::unix::fs::symlink(elsewhere.join("kept.csv"), src.join("v6_r2.csv")).unwrap();
    record(&elsewhere, "odd.csv", "sr25w", 6.0, 3, false, 3);
    std::fs::rename(
        elsewhere.join("odd.csv"),
        src.join(std::ffi::OsStr::from_bytes(b"v6_r3\xe9.csv")),
    )
    .unwrap();
    std::os::unix::fs::symlink(src.join("gone.csv"), src.join("v6_r4.csv")).unwrap();
    let r = run_in(
        &src,
        &[
            "sweep",
            ".",
            "--pattern",
            "v{velocity}_r{repeat}*.csv",
            "--out",
            "../out",
            "--no-report",
        ],
    );
    assert!(r.ok(), "{} {}", r.stdout, r.stderr);
    assert!(r.stdout.contains("3 records (0 failed)"), "{}", r.stdout);
    assert!(
        r.stdout.contains("skipped v6_r4.csv: a broken link"),
        "{}",
        r.stdout
    );
    let json = std::fs::read_to_string(d.join("out/sweep.json")).unwrap();
    assert!(
        json.contains("skipped v6_r4.csv: a broken link"),
        "selection notes"
    );
    let _ = std::fs::remove_dir_all(&d);
}
