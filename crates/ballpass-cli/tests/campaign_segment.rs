//! `ballpass sweep --segment` and `ballpass diagnose --segment` through the
//! real binary: multi-speed runs (the lab run of issue 15: 42, 83 and
//! 125 mm/s forward and back in one 25 s file) as campaigns.

mod common;

use std::path::Path;

use ballpass::recording::write_csv;
use ballpass::sim::{simulate, Condition, SimSettings, SpeedProfile};
use common::{run_in, scratch};

/// Writes the simulated lab run of one bearing to `dir/name`.
fn lab_run(dir: &Path, name: &str, condition: Condition, seed: u64) {
    let sim = simulate(&SimSettings {
        duration_s: 25.0,
        seed,
        condition,
        profile: Some(SpeedProfile::lab_run()),
        ..Default::default()
    })
    .unwrap();
    write_csv(&sim.recording, &dir.join(name)).unwrap();
}

fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let mut rd = ::csv::Reader::from_path(path).unwrap();
    let header = rd.headers().unwrap().iter().map(str::to_string).collect();
    let rows = rd
        .records()
        .map(|r| r.unwrap().iter().map(str::to_string).collect())
        .collect();
    (header, rows)
}

#[test]
fn a_multi_speed_run_is_a_sweep_and_its_plateaus_are_a_bearings_repeats() {
    let d = scratch("segment");
    lab_run(&d, "b1.csv", Condition::Good, 1);
    lab_run(&d, "b2.csv", Condition::Good, 2);
    lab_run(&d, "b3.csv", Condition::Sticking, 3);
    // Velocities left empty: measured from the plateaus.
    std::fs::write(
        d.join("manifest.csv"),
        "path,bearing,velocity_mm_s,repeat\nb1.csv,b1,,1\nb2.csv,b2,,1\nb3.csv,b3,,1\n",
    )
    .unwrap();

    // Without --segment an empty velocity is a failed record that says how.
    let r = run_in(&d, &["sweep", "manifest.csv", "-o", "plain", "--no-report"]);
    assert_eq!(r.code, 1, "{}\n{}", r.stdout, r.stderr);
    assert!(r.stdout.contains("--segment"), "{}", r.stdout);

    // The sweep of b1: its six plateaus, three velocities of two repeats.
    let r = run_in(
        &d,
        &[
            "sweep",
            "manifest.csv",
            "--segment",
            "--only-bearing",
            "b1",
            "-o",
            "sw",
            "--no-report",
        ],
    );
    assert!(r.ok(), "{}\n{}", r.stdout, r.stderr);
    assert!(r.stdout.contains("6 records (0 failed)"), "{}", r.stdout);
    assert!(
        r.stdout.contains("into 18 constant-velocity plateaus"),
        "{}",
        r.stdout
    );
    let (h, rows) = read_csv(&d.join("sw/records.csv"));
    // The plateau columns come last; the earlier ones keep their places.
    assert_eq!(h[0], "path");
    assert_eq!(h[13], "tau_c_s");
    assert_eq!(
        &h[h.len() - 6..],
        [
            "plateau",
            "plateaus_in_file",
            "plateau_start_s",
            "plateau_end_s",
            "plateau_velocity_mm_s",
            "direction"
        ]
    );
    assert_eq!(rows.len(), 6);
    let n = h.len();
    for (i, row) in rows.iter().enumerate() {
        assert_eq!(row[n - 6], (i + 1).to_string());
        assert_eq!(row[n - 5], "6");
        let v: f64 = row[n - 2].parse().unwrap();
        let dir = if i % 2 == 0 { "forward" } else { "backward" };
        assert_eq!(row[n - 1], dir, "{row:?}");
        assert_eq!(v > 0.0, i % 2 == 0);
        // The pooled velocity within 1 % of this plateau's speed.
        let pooled: f64 = row[2].parse().unwrap();
        assert!((pooled - v.abs()).abs() < 0.01 * pooled, "{row:?}");
    }
    let (_, sweep) = read_csv(&d.join("sw/sweep.csv"));
    assert_eq!(sweep.len(), 3);
    assert!(sweep.iter().all(|r| r[1] == "2"), "{sweep:?}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("sw/sweep.json")).unwrap()).unwrap();
    let p = &json["record_results"][1]["plateau"];
    assert_eq!(p["direction"], "backward", "{p}");
    assert!(p["file"].as_str().unwrap().ends_with("b1.csv"));
    assert_eq!(json["settings"]["segment"]["tolerance"], 0.02);

    // --only-velocity matches a plateau's measured mean within 5 %.
    let r = run_in(
        &d,
        &[
            "sweep",
            "manifest.csv",
            "--segment",
            "--only-bearing",
            "b1",
            "--only-velocity",
            "83",
            "-o",
            "sw83",
            "--no-report",
        ],
    );
    assert!(r.ok(), "{}\n{}", r.stdout, r.stderr);
    assert!(r.stdout.contains("2 records (0 failed)"), "{}", r.stdout);

    // Diagnose: one velocity, each bearing's two plateaus there its repeats.
    let r = run_in(&d, &["diagnose", "manifest.csv", "--segment", "-o", "dg"]);
    assert!(r.ok(), "{}\n{}", r.stdout, r.stderr);
    assert!(r.stdout.contains("6 records (0 failed)"), "{}", r.stdout);
    let (h, diag) = read_csv(&d.join("dg/diagnosis.csv"));
    let records = h.iter().position(|c| c == "records").unwrap();
    assert_eq!(diag.len(), 3);
    assert!(diag.iter().all(|r| r[records] == "2"), "{diag:?}");
    assert!(d.join("dg/report.html").is_file());
    std::fs::remove_dir_all(&d).unwrap();
}

/// A file without a plateau (a stage at rest) is a failed record that says
/// so; the others still make the sweep.
#[test]
fn a_file_without_plateaus_fails_alone() {
    let d = scratch("segment-rest");
    lab_run(&d, "run.csv", Condition::Good, 4);
    std::fs::write(
        d.join("rest.csv"),
        (0..5000)
            .map(|i| format!("{},{},0\n", i as f64 / 1000.0, 1.0 + (i as f64).sin()))
            .fold("time_s,friction_n,position_mm\n".to_string(), |s, l| s + &l),
    )
    .unwrap();
    std::fs::write(
        d.join("m.csv"),
        "path,bearing,velocity_mm_s,repeat\nrun.csv,b1,,1\nrest.csv,b1,,2\n",
    )
    .unwrap();
    let r = run_in(
        &d,
        &["sweep", "m.csv", "--segment", "-o", "sw", "--no-report"],
    );
    assert_eq!(r.code, 1, "{}\n{}", r.stdout, r.stderr);
    assert!(r.stdout.contains("7 records (1 failed)"), "{}", r.stdout);
    assert!(
        r.stdout.contains("rest.csv") && r.stdout.contains("no constant-velocity plateau"),
        "{}",
        r.stdout
    );
    std::fs::remove_dir_all(&d).unwrap();
}
