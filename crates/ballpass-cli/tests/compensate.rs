//! End-to-end tests of `ballpass compensate` on the analyze fixture
//! recording (8 s at 200 Hz, 18 mm/s).

mod common;

use common::{library_test_file, run, scratch};

#[test]
fn writes_the_table_and_states_the_stage_it_used() {
    let out = scratch("compensate");
    let rec = library_test_file("fixtures/analyze/input.csv");
    let (ok, stdout, stderr) = run(&[
        "compensate",
        rec.to_str().unwrap(),
        "--velocity",
        "18",
        "--mass",
        "240",
        "--kkp",
        "11000",
        "--kkd",
        "1200",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("bins per ball-pass period"), "{stdout}");
    assert!(stdout.contains("stage: "), "{stdout}");
    assert!(stdout.contains("predicted: f_c component"), "{stdout}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("compensation.json")).unwrap())
            .unwrap();
    assert_eq!(json["schema"], "ballpass.compensation/1");
    let csv = std::fs::read_to_string(out.join("compensation_phase.csv")).unwrap();
    assert!(csv.starts_with("phase,force_n,velocity_error_after_um_s\n"));
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn partial_gains_are_refused_in_one_line() {
    let out = scratch("compensate-bad");
    let rec = library_test_file("fixtures/analyze/input.csv");
    let (ok, _, stderr) = run(&[
        "compensate",
        rec.to_str().unwrap(),
        "--velocity",
        "18",
        "--mass",
        "240",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(
        stderr.contains("--kkp") || stderr.contains("kkp"),
        "{stderr}"
    );
    assert!(!out.join("compensation.json").exists());
    let _ = std::fs::remove_dir_all(&out);
}
