//! End-to-end tests of `ballpass simulate` and `ballpass simulate-campaign`,
//! running the real binary in temporary folders.

mod common;

use std::path::Path;

use ballpass::recording::{load, Channel, LoadOptions};
use ballpass::sim::{simulate, SimSettings, Truth};
use common::{bin, run_ok, scratch};

fn read_truth(p: &Path) -> Truth {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

#[test]
fn simulate_writes_the_recording_and_its_truth_reproducibly() {
    let d = scratch("simulate");
    let a = d.join("rec.csv");
    let b = d.join("again.csv");
    let args = [
        "simulate",
        "--velocity",
        "9",
        "--duration",
        "3",
        "--seed",
        "5",
    ];
    let out = run_ok(bin().args(args).arg("-o").arg(&a));
    assert!(out.contains("rec.truth.json"), "{out}");
    run_ok(bin().args(args).arg("-o").arg(&b));
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    let truth = read_truth(&d.join("rec.truth.json"));
    assert_eq!(truth.settings.seed, 5);
    assert_eq!(truth.n_samples, 3000);
    // The file holds exactly the library's samples (CSV keeps every bit).
    let lib = simulate(&truth.settings).unwrap();
    let rec = load(&a, &LoadOptions::default()).unwrap();
    for c in Channel::ALL {
        assert_eq!(
            rec.channel(c).unwrap(),
            lib.recording.channel(c).unwrap(),
            "{c}"
        );
    }
    // A truth file is a settings file: same bytes again.
    let c = d.join("from_truth.csv");
    run_ok(
        bin()
            .args(["simulate", "--settings"])
            .arg(d.join("rec.truth.json"))
            .arg("-o")
            .arg(&c),
    );
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&c).unwrap());
    // A different seed differs.
    let e = d.join("other.csv");
    run_ok(
        bin()
            .args([
                "simulate",
                "--velocity",
                "9",
                "--duration",
                "3",
                "--seed",
                "6",
                "-o",
            ])
            .arg(&e),
    );
    assert_ne!(std::fs::read(&a).unwrap(), std::fs::read(&e).unwrap());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn simulate_rejects_bad_input_with_one_line() {
    let d = scratch("simulate-bad");
    for (args, word) in [
        (vec!["--velocity", "0"], "velocity"),
        (vec!["--velocity", "9", "--fs", "0"], "fs"),
        (vec!["--velocity", "-2"], "velocity"),
        (
            vec!["--velocity", "9", "--bearing", "xx99"],
            "unknown bearing",
        ),
    ] {
        let out = bin()
            .arg("simulate")
            .args(&args)
            .arg("-o")
            .arg(d.join("x.csv"))
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(word) && err.lines().count() == 1, "{err}");
    }
    let out = bin()
        .args(["simulate", "--velocity", "9", "-o"])
        .arg(d.join("x.txt"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("expected a .csv or .mat"));
    assert!(!d.join("x.txt").exists());
    let _ = std::fs::remove_dir_all(&d);
}

/// `-o rec.mat` writes a MAT file that the loader reads back to the same
/// samples as the CSV of the same seed (bit for bit: both store f64).
#[test]
fn mat_output_holds_the_same_samples_as_csv() {
    let d = scratch("mat");
    for name in ["r.csv", "r.mat"] {
        let out = bin()
            .args([
                "simulate",
                "--velocity",
                "9",
                "--duration",
                "5",
                "--seed",
                "3",
                "-o",
            ])
            .arg(d.join(name))
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let opts = ballpass::recording::LoadOptions::default();
    let csv = ballpass::recording::load(&d.join("r.csv"), &opts).unwrap();
    let mat = ballpass::recording::load(&d.join("r.mat"), &opts).unwrap();
    assert_eq!(csv.fs_hz(), mat.fs_hz());
    for c in ballpass::recording::Channel::ALL {
        assert_eq!(csv.channel(c), mat.channel(c), "{c}");
    }
    assert!(d.join("r.truth.json").exists());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn campaign_writes_the_thesis_campaign_and_manifest() {
    let d = scratch("campaign");
    // Short records keep the test fast; the plan is the full campaign.
    run_ok(
        bin()
            .args([
                "simulate-campaign",
                "--duration",
                "0.5",
                "--fs",
                "200",
                "--oversample",
                "4",
                "--seed",
                "3",
                "--out",
            ])
            .arg(&d),
    );
    let manifest = std::fs::read_to_string(d.join("manifest.csv")).unwrap();
    let lines: Vec<&str> = manifest.lines().collect();
    assert_eq!(lines[0], "path,bearing,velocity_mm_s,repeat,condition");
    assert_eq!(lines.len(), 1 + 100 + 50);
    assert_eq!(lines[1], "sweep/v01_r1.csv,sr25w,1,1,good");
    assert_eq!(
        lines.iter().filter(|l| l.ends_with(",sticking")).count(),
        10
    );
    assert!(lines.contains(&"diagnosis/bearing4_r10.csv,bearing4,20,10,sticking"));
    for l in &lines[1..] {
        let rel = l.split(',').next().unwrap();
        let p = d.join(rel);
        assert!(p.exists(), "{rel}");
        assert!(d.join(rel.replace(".csv", ".truth.json")).exists(), "{rel}");
    }
    // Each record can be regenerated alone from its truth's settings.
    let t = read_truth(&d.join("diagnosis/bearing4_r03.truth.json"));
    assert_eq!(t.condition, ballpass::sim::Condition::Sticking);
    let lib = simulate(&t.settings).unwrap();
    let rec = load(
        &d.join("diagnosis/bearing4_r03.csv"),
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(
        rec.channel(Channel::Friction).unwrap(),
        lib.recording.channel(Channel::Friction).unwrap()
    );
    assert_ne!(t.settings.seed, SimSettings::default().seed);
    let _ = std::fs::remove_dir_all(&d);
}
