//! End-to-end tests of `ballpass validate --from`: the bench taken from a
//! lab's recordings.

mod common;

use common::{run, scratch_path};

/// Two simulated records at 5 and 8 mm/s (1 kHz, 20 s): the domain written
/// must hold their rate, length and velocities and the catalogue bearing's
/// geometry, and the notes must say what was estimated.
#[test]
fn the_domain_is_taken_from_the_recordings() {
    let d = scratch_path("validate-from");
    std::fs::create_dir_all(&d).unwrap();
    let r1 = d.join("r1.csv");
    let r2 = d.join("r2.csv");
    for (v, seed, p) in [("5", "3", &r1), ("8", "4", &r2)] {
        let (ok, _, err) = run(&[
            "simulate",
            "-v",
            v,
            "--duration",
            "20",
            "--seed",
            seed,
            "-o",
            p.to_str().unwrap(),
        ]);
        assert!(ok, "{err}");
    }
    let dom = d.join("domain.json");
    let (ok, out, err) = run(&[
        "validate",
        "--from",
        r1.to_str().unwrap(),
        r2.to_str().unwrap(),
        "--fleets",
        "0",
        "--records",
        "0",
        "--durations",
        "10",
        "--write-domain",
        dom.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("bench estimated from 2 recording(s)"), "{out}");
    assert!(out.contains("load_cell_tau_s"), "{out}");
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&dom).unwrap()).unwrap();
    assert_eq!(j["fs_hz"], serde_json::json!([1000.0]));
    assert!((j["duration_s"]["lo"].as_f64().unwrap() - 20.0).abs() < 0.01);
    // Velocities measured from the encoder: within 0.1 % of the commanded.
    assert!((j["velocity_mm_s"]["lo"].as_f64().unwrap() - 5.0).abs() < 5e-3);
    assert!((j["velocity_mm_s"]["hi"].as_f64().unwrap() - 8.0).abs() < 8e-3);
    assert_eq!(j["ball_diameter_mm"]["lo"], j["ball_diameter_mm"]["hi"]);

    // A file that is not a recording: one line naming it.
    let bad = d.join("bad.csv");
    std::fs::write(&bad, "nothing here\n").unwrap();
    let (ok, _, err) = run(&["validate", "--from", bad.to_str().unwrap(), "--fleets", "0"]);
    assert!(!ok);
    assert!(err.contains("bad.csv"), "{err}");
}
