//! A fast subset of the validation suite (`ballpass validate`): a few
//! fleets and records from a seed range used for nothing else (never for
//! tuning), with the acceptance bars where a small sample can test
//! them. The full grid runs as `cargo bench -p ballpass --bench
//! validate_grid` or `ballpass validate --grid`, its figures in
//! docs/verdicts.md.

use ballpass::validate::{run, Domain, SuiteSettings};

#[test]
fn the_verdicts_hold_on_a_fresh_sample_of_random_benches() {
    let s = SuiteSettings {
        fleets: 6,
        records: 16,
        durations_s: vec![10.0, 30.0],
        seed: 4_000_000,
    };
    let r = run(&Domain::default(), &s, &|_, _, _| {});
    eprintln!("{}", r.text());
    let f = r.fleets.as_ref().expect("fleets scored");
    assert!(f.failed.is_empty(), "{:?}", f.failed);
    // No good bearing may be called bad; suspect at most 2 % in the full
    // grid, so at most one here (30 good bearings or fewer).
    assert_eq!(f.good_called_bad.k, 0, "{}", r.text());
    assert!(f.good_called_suspect.k <= 1, "{}", r.text());
    // Every decided sticking bearing is flagged (≥ 98 % in the full grid).
    assert_eq!(f.sticking_flagged.k, f.sticking_flagged.n, "{}", r.text());
    // Periodicity claims on ripple-free benches within the binomial margin
    // of the nominal 1 %.
    for p in &r.periodicity {
        assert!(p.failed.is_empty(), "{:?}", p.failed);
        assert!(p.within_margin, "{}", r.text());
    }
    // Phases at f_c where measurable (≥ 10 periods, coherent): within
    // 0.02 τc or their own 95 % interval, with at most two misses of the
    // interval (P(more than 2 of ≤ 16 outside a 95 % interval) < 5 %).
    let l = r.lags.as_ref().expect("lags scored");
    assert!(l.measured.k >= 4, "{}", r.text());
    assert!(
        l.within_interval.n - l.within_interval.k <= 2,
        "{}",
        r.text()
    );
    // An identified stage is within ±5 % / ±20 %.
    let st = r.stage.as_ref().expect("stage scored");
    assert_eq!(st.within_tolerance.k, st.within_tolerance.n, "{}", r.text());
    assert!(r.failed.is_empty(), "{:?}", r.failed);
}
