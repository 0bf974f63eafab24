//! The correlation lag window (`--max-lag`): the values in the window are
//! the full-range correlation's, the period and the phases found in it are
//! the same, and the outputs say which window was used.

use ballpass::analysis::{analyze, AnalyzeSettings, MaxLag, Signal};
use ballpass::bearing::lookup;
use ballpass::sim::{simulate, SimSettings};

#[test]
fn a_lag_window_holds_the_full_range_values_and_finds_the_same_period() {
    // 40 s at 20 mm/s: ~200 ball periods of 0.2 s; a 4 s window holds 20.
    let s = simulate(&SimSettings {
        velocity_mm_s: 20.0,
        duration_s: 40.0,
        seed: 11,
        ..Default::default()
    })
    .unwrap();
    let pred = lookup("sr25w").unwrap().geometry.predict(20.0, 5).unwrap();
    let recs = [s.recording];
    let full = analyze(
        &recs,
        &pred,
        &AnalyzeSettings {
            max_lag: MaxLag::Full,
            ..Default::default()
        },
    )
    .unwrap();
    let win = analyze(
        &recs,
        &pred,
        &AnalyzeSettings {
            max_lag: MaxLag::Seconds(4.0),
            ..Default::default()
        },
    )
    .unwrap();
    let n = full.samples_analysed;
    assert!(full.correlation_window.full_range);
    assert_eq!(full.correlation_window.max_lag_samples, n - 1);
    let w = &win.correlation_window;
    assert!(!w.full_range);
    assert_eq!(w.max_lag_samples, 4000);
    assert!((w.max_lag_s - 4.0).abs() < 1e-12);
    assert_eq!(win.correlations.lags.len(), 8001);
    assert_eq!(win.correlations.samples, n);
    // Coefficient-normalised, so values are O(1): both are FFT sums over
    // the record, rounding ~1e-15 each; 1e-12 leaves room.
    for ((k, r), (k2, r_full)) in win
        .correlations
        .series
        .iter()
        .zip(&full.correlations.series)
    {
        assert_eq!(k, k2);
        let off = full.correlations.zero_index() - win.correlations.zero_index();
        for (i, v) in r.iter().enumerate() {
            assert!(
                (v - r_full[off + i]).abs() < 1e-12,
                "{k:?} lag {}",
                i as i64 - 4000
            );
        }
    }
    // The period from the 20 peaks in the window against the ~100 of the
    // full range (up to half the record): within 0.5 % (the peaks' lags
    // scatter by a few ms with the spacing variation of the balls).
    let p_full = full.measured_period.period_s.unwrap();
    let p_win = win.measured_period.period_s.unwrap();
    assert!(
        (p_win - p_full).abs() < 5e-3 * p_full,
        "{p_win} vs {p_full}"
    );
    let opt = win
        .measured_period
        .per_signal
        .iter()
        .find(|p| p.signal == Signal::Optical)
        .unwrap();
    assert!(opt.windows <= 20, "{} windows in a 4 s window", opt.windows);
    assert!(win.method_notes.iter().any(|n| n.contains("±4.000 s")));
    let json = serde_json::to_value(&win).unwrap();
    assert_eq!(json["settings"]["max_lag"]["seconds"], 4.0);
    assert_eq!(json["correlation_window"]["full_range"], false);
}

#[test]
fn auto_keeps_every_lag_of_a_minute_and_a_window_under_two_periods_is_refused() {
    assert_eq!(MaxLag::Auto.samples(60_000, 1000.0, 0.9), 59_999);
    // 100 periods of 0.9 s = 90 s of a 2-hour record.
    assert_eq!(MaxLag::Auto.samples(7_200_000, 1000.0, 0.9), 90_000);
    // At 125 mm/s (tau_c 65 ms) the 60 s floor applies.
    assert_eq!(MaxLag::Auto.samples(7_200_000, 1000.0, 0.065), 60_000);
    assert_eq!(MaxLag::Seconds(1e9).samples(500, 1000.0, 0.9), 499);
    let s = simulate(&SimSettings {
        velocity_mm_s: 9.0,
        duration_s: 20.0,
        seed: 3,
        ..Default::default()
    })
    .unwrap();
    let pred = lookup("sr25w").unwrap().geometry.predict(9.0, 5).unwrap();
    let e = analyze(
        &[s.recording],
        &pred,
        &AnalyzeSettings {
            max_lag: MaxLag::Seconds(1.0),
            ..Default::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("max-lag") && e.contains("2 ball-pass periods"),
        "{e}"
    );
    assert!(AnalyzeSettings {
        max_lag: MaxLag::Seconds(-1.0),
        ..Default::default()
    }
    .validate()
    .is_err());
}
