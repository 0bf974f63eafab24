//! A long record is analysed in stages, one after the other, to hold few
//! record-length buffers at once ([`run_staged_above`]); a short one runs
//! the same stages side by side. Both must give the same analysis, number
//! for number: forced here on records short enough for a debug test.

use super::{run, run_staged_above};
use crate::analysis::{AnalyzeSettings, MaxLag};
use crate::bearing::lookup;
use crate::recording::Recording;

fn record(seed: u64, duration_s: f64) -> Recording {
    crate::sim::test_record(seed, duration_s)
}

/// Every output of the two schedules, compared exactly: `analysis.json`
/// as serialised, and the tables it leaves out.
fn assert_same(recs: &[Recording], settings: &AnalyzeSettings) {
    let pred = lookup("sr25w")
        .expect("catalog")
        .geometry
        .predict(9.0, settings.harmonics)
        .expect("predicts");
    let side = run(recs, &pred, settings, true, None).expect("side by side");
    let staged = run_staged_above(recs, &pred, settings, true, None, 0).expect("staged");
    // The staged run did restore an owned friction (the simulated load
    // cell discharges) and took it over: the path under test.
    assert!(
        side.load_cell.iter().all(|d| d.applied),
        "{:?}",
        side.load_cell
    );
    assert!(side.position.is_some() && side.sync.is_some());
    assert!(side.passages.iter().all(|p| p.count.is_some()));
    let json = |a: &crate::analysis::Analysis| serde_json::to_string(a).expect("serialises");
    assert_eq!(json(&side), json(&staged));
    assert_eq!(side.correlations, staged.correlations);
    assert_eq!(side.spectra, staged.spectra);
    assert_eq!(side.spectra_hires, staged.spectra_hires);
    assert_eq!(side.spectra_unfiltered, staged.spectra_unfiltered);
    assert_eq!(side.position, staged.position);
    assert_eq!(side.stage_spectra, staged.stage_spectra);
}

#[test]
fn a_staged_analysis_equals_the_side_by_side_one() {
    assert_same(&[record(3, 60.0)], &AnalyzeSettings::default());
}

#[test]
fn a_staged_analysis_of_trimmed_repeats_equals_the_side_by_side_one() {
    // Two records of different lengths, a trim and a lag window: the
    // owned friction is cut in place to the common range.
    let settings = AnalyzeSettings {
        trim_start_s: 2.5,
        max_lag: MaxLag::Seconds(10.0),
        ..Default::default()
    };
    assert_same(&[record(5, 45.0), record(6, 40.0)], &settings);
}
