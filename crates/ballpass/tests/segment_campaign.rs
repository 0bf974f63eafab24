//! A multi-speed run as a velocity sweep (issue 15): the simulated lab run
//! (42, 83 and 125 mm/s, each forward then backward, in one 25 s file)
//! segmented into its plateaus gives the sweep its three velocities with
//! two repeats each, and the same mean ball spacing, within the same
//! tolerance, as separate constant-speed records of the plateaus' length.

use std::path::{Path, PathBuf};

use ballpass::bearing::lookup;
use ballpass::campaign::manifest::{parse_manifest, Manifest};
use ballpass::campaign::record::RecordResult;
use ballpass::campaign::run::{process_entry, CampaignSettings};
use ballpass::campaign::segments::segment_manifest;
use ballpass::campaign::sweep::{sweep, Sweep};
use ballpass::recording::segment::Direction;
use ballpass::recording::{write_csv, LoadOptions};
use ballpass::sim::{simulate, SimSettings, SpeedProfile};

fn scratch(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("ballpass-segcamp-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Processes every entry of `m` (segmented first when `segment`) and builds
/// the sweep.
fn run(m: &Manifest, segment: bool) -> (Vec<RecordResult>, Sweep) {
    let g = lookup("sr25w").unwrap().geometry;
    let mut settings = CampaignSettings::default();
    let entries = if segment {
        settings.segment = Some(Default::default());
        let s = segment_manifest(m, &LoadOptions::default(), g, &settings);
        assert!(s.failed.is_empty(), "{:?}", s.failed);
        s.manifest.entries
    } else {
        m.entries.clone()
    };
    let recs: Vec<RecordResult> = entries
        .iter()
        .map(|e| process_entry(e, &LoadOptions::default(), g, &settings).unwrap())
        .collect();
    let refs: Vec<&RecordResult> = recs.iter().collect();
    let s = sweep(&refs, Some(g.d_avg_mm()));
    (recs, s)
}

fn manifest(dir: &Path, rows: &str) -> Manifest {
    let text = format!("path,bearing,velocity_mm_s,repeat\n{rows}");
    parse_manifest(&dir.join("manifest.csv"), &text).unwrap()
}

#[test]
fn a_lab_run_in_one_file_is_a_sweep_with_the_truths_ball_spacing() {
    let d = scratch("lab");
    let sim = simulate(&SimSettings {
        duration_s: 25.0,
        seed: 5,
        profile: Some(SpeedProfile::lab_run()),
        ..Default::default()
    })
    .unwrap();
    let truth_d = sim.truth.d_avg_mm;
    write_csv(&sim.recording, &d.join("run.csv")).unwrap();
    // The velocity left empty: measured from the plateaus.
    let (recs, seg) = run(&manifest(&d, "run.csv,sr25w,,1\n"), true);

    // Six plateaus, in time order, forward then backward at each speed.
    assert_eq!(recs.len(), 6);
    let truth = &sim.truth.plateaus;
    assert_eq!(truth.len(), 6);
    for (r, t) in recs.iter().zip(truth) {
        let p = r.plateau.as_ref().expect("a plateau record");
        assert_eq!(p.of, 6);
        assert_eq!(
            p.plateau.direction,
            if t.velocity_mm_s > 0.0 {
                Direction::Forward
            } else {
                Direction::Backward
            }
        );
        // The measured velocity within 1 % of the commanded one (the
        // segmentation's own bound, tests/segment_sim.rs), inside the
        // commanded interval.
        let rel = (p.plateau.velocity_mm_s - t.velocity_mm_s).abs() / t.velocity_mm_s.abs();
        assert!(rel < 0.01, "{p:?} vs {t:?}");
        assert!(p.plateau.start_s >= t.start_s - 1e-9 && p.plateau.end_s <= t.end_s + 0.3);
        assert!(r.f_c_passages_hz.is_some(), "{r:?}");
        let f = r.f_c_passages_hz.unwrap();
        eprintln!(
            "plateau {:?}: v {:.4} f_c {:.4} f_corr {:?} passages {:?} d {:.5} t {:.2}-{:.2}",
            p.plateau.direction,
            p.plateau.speed_mm_s,
            f,
            r.f_c_correlation_hz,
            r.passages,
            p.plateau.speed_mm_s / (2.0 * f),
            p.plateau.start_s,
            p.plateau.end_s
        );
    }
    // Three velocities, each the mean of its two plateaus, two repeats.
    assert_eq!(seg.velocities.len(), 3, "{:?}", seg.velocities);
    for (row, want) in seg.velocities.iter().zip([42.0, 83.0, 125.0]) {
        assert_eq!(row.records, 2);
        assert!((row.velocity_mm_s - want).abs() < 0.01 * want, "{row:?}");
        let at: Vec<&RecordResult> = recs
            .iter()
            .filter(|r| r.velocity_mm_s == row.velocity_mm_s)
            .collect();
        let mean = at
            .iter()
            .map(|r| r.plateau.as_ref().unwrap().plateau.speed_mm_s)
            .sum::<f64>()
            / 2.0;
        assert_eq!(row.velocity_mm_s, mean);
        let mut repeats: Vec<u32> = at.iter().map(|r| r.repeat).collect();
        repeats.sort_unstable();
        assert_eq!(repeats, [1, 2]);
    }

    // The same speeds as separate constant-speed records as long as the
    // plateaus found (two seeds each).
    let mut rows = String::new();
    for (i, r) in recs.iter().enumerate() {
        let p = &r.plateau.as_ref().unwrap().plateau;
        let v = truth[i].velocity_mm_s.abs();
        let s = simulate(&SimSettings {
            duration_s: p.end_s - p.start_s,
            velocity_mm_s: v,
            seed: 100 + i as u64,
            ..Default::default()
        })
        .unwrap();
        let name = format!("v{v}_{i}.csv");
        write_csv(&s.recording, &d.join(&name)).unwrap();
        rows.push_str(&format!("{name},sr25w,{v},{}\n", i % 2 + 1));
    }
    let (_, sep) = run(&manifest(&d, &rows), false);
    assert_eq!(sep.velocities.len(), 3);

    // Both d_avg against the simulated spacing. Tolerance: the larger of
    // the fit's 95 % interval and 0.5 % (the optical passages time the
    // balls to a sample, 1 ms in 10–30 ms periods over ~2 s plateaus: a
    // rate error well under 0.5 % per record, and the velocity measured on
    // the plateau carries the stage's ripple, < 0.1 %).
    for (name, s) in [("segmented", &seg), ("separate", &sep)] {
        let got = s.d_avg_fitted_mm.unwrap();
        let ci = s.d_avg_ci95_mm.unwrap();
        let tol = ci.max(0.005 * truth_d);
        eprintln!("{name}: d_avg {got:.5} ± {ci:.5} mm, truth {truth_d:.5} mm");
        assert!(
            (got - truth_d).abs() <= tol,
            "{name}: {got} vs {truth_d} (±{tol})"
        );
    }
    std::fs::remove_dir_all(&d).unwrap();
}
