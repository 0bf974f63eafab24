//! `analyze` on bad or partial input: a clear error, or a clear warning and
//! the series left out; never a silent wrong number.

use ballpass::analysis::{analyze, AnalyzeSettings, Signal};
use ballpass::bearing::{lookup, Prediction};
use ballpass::recording::{Channels, Metadata, Recording};

const FS: f64 = 1000.0;

fn pred(v: f64) -> Prediction {
    lookup("sr25w").unwrap().geometry.predict(v, 5).unwrap()
}

/// Gaussian pulses at the ball-pass period of `v` in friction and optical
/// (optical 0.2 s later), a ramp position, fixed pseudo-random noise.
fn record(v: f64, seconds: f64, optical: bool, position: bool) -> Recording {
    let n = (seconds * FS) as usize;
    let tau = pred(v).tau_c_s;
    let mut s: u64 = 0x2545_F491_4F6C_DD1D;
    let mut noise = move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let pulse = |t: f64, d: f64| {
        let ph = (t - d).rem_euclid(tau);
        let x = ph.min(tau - ph) / (0.155 * tau / 2.3548);
        (-0.5 * x * x).exp()
    };
    let t = |i: usize| i as f64 / FS;
    let fr: Vec<f64> = (0..n)
        .map(|i| 3.0 + 0.3 * pulse(t(i), 0.1) + 0.05 * noise())
        .collect();
    let op: Vec<f64> = (0..n)
        .map(|i| 1.0 + 0.5 * pulse(t(i), 0.3) + 0.02 * noise())
        .collect();
    let pos: Vec<f64> = (0..n).map(|i| v * t(i) + 1e-4 * noise()).collect();
    Recording::new(
        FS,
        Channels {
            friction_n: Some(fr),
            position_mm: position.then_some(pos),
            optical_v: optical.then_some(op),
        },
        Metadata {
            test_id: Some("synthetic".into()),
            ..Default::default()
        },
    )
    .unwrap()
}

#[test]
fn a_record_shorter_than_two_periods_is_an_error() {
    // 9 mm/s: tau_c = 0.901 s; 1.5 s is 1.66 periods.
    let e = analyze(
        &[record(9.0, 1.5, true, true)],
        &pred(9.0),
        &AnalyzeSettings::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("synthetic") && e.contains("at least 2"), "{e}");
    // A trim can make a long enough record too short.
    let s = AnalyzeSettings {
        trim_start_s: 2.5,
        ..Default::default()
    };
    let e = analyze(&[record(9.0, 4.0, true, true)], &pred(9.0), &s)
        .unwrap_err()
        .to_string();
    assert!(e.contains("ball-pass periods"), "{e}");
}

#[test]
fn a_missing_optical_channel_is_left_out_and_said() {
    let a = analyze(
        &[record(9.0, 20.0, false, true)],
        &pred(9.0),
        &AnalyzeSettings::default(),
    )
    .unwrap();
    assert_eq!(
        a.series.signals,
        vec![Signal::Friction, Signal::VelocityError]
    );
    assert_eq!(
        a.series.present,
        vec!["friction", "velocity_error", "friction__velocity_error"]
    );
    let absent: Vec<&str> = a.series.absent.iter().map(|x| x.name.as_str()).collect();
    assert_eq!(
        absent,
        vec!["optical", "friction__optical", "velocity_error__optical"]
    );
    assert!(a
        .warnings
        .iter()
        .any(|w| w.contains("optical not analysed")));
    assert_eq!(a.correlations.names().len(), 3);
    assert!(a.spectra.auto_of(Signal::Optical).is_none());
    // The period then comes from friction, which shows f_c.
    assert_eq!(a.measured_period.from_signal, Some(Signal::Friction));
    let f = a.measured_period.f_c_hz.unwrap();
    // Synthetic pulses at exactly f_c: 0.1 % covers the peak interpolation.
    assert!((f - pred(9.0).f_c_hz).abs() < 1e-3 * f, "{f}");
}

#[test]
fn a_missing_position_channel_gives_no_velocity_error() {
    let a = analyze(
        &[record(9.0, 20.0, true, false)],
        &pred(9.0),
        &AnalyzeSettings::default(),
    )
    .unwrap();
    assert!(a.velocity_error.is_none());
    assert_eq!(a.series.signals, vec![Signal::Friction, Signal::Optical]);
    assert!(a.warnings.iter().any(|w| w.contains("position_mm missing")));
    // Optical lags friction by 0.2 s (Eq. 7.1: peak at -0.2 s).
    let ph = &a.phases[0];
    assert_eq!(ph.pair, "friction__optical");
    // 1 ms sampling with parabolic refinement: well within 2 ms; the phase
    // of a pure delay at f_c gives the same lag.
    assert!(
        (ph.correlation_lag_s + 0.2).abs() < 2e-3,
        "{}",
        ph.correlation_lag_s
    );
    let lag = ph.lag_s.expect("coherent at f_c");
    assert!((lag + 0.2).abs() < 2e-3, "{lag}");
    assert!(
        ph.words.starts_with("optical lags friction by 0.20"),
        "{}",
        ph.words
    );
}

#[test]
fn zero_velocity_cutoff_above_nyquist_and_unresolvable_settings_are_errors() {
    let rec = record(9.0, 20.0, true, true);
    let mut p = pred(9.0);
    p.velocity_mm_s = 0.0;
    let e = analyze(std::slice::from_ref(&rec), &p, &AnalyzeSettings::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("velocity"), "{e}");
    let s = AnalyzeSettings {
        lowpass_hz: Some(500.0),
        ..Default::default()
    };
    let e = analyze(std::slice::from_ref(&rec), &pred(9.0), &s)
        .unwrap_err()
        .to_string();
    assert!(e.contains("Nyquist"), "{e}");
    // 32-sample high-resolution segments at 50 Hz: 1.56 Hz bins > f_c / 2.
    let s = AnalyzeSettings {
        hires_nperseg: Some(32),
        ..Default::default()
    };
    let e = analyze(std::slice::from_ref(&rec), &pred(9.0), &s)
        .unwrap_err()
        .to_string();
    assert!(e.contains("cannot resolve f_c"), "{e}");
    // 128 samples: 0.39 Hz bins, between f_c/4 = 0.28 and f_c/2 = 0.55 Hz: a warning.
    let s = AnalyzeSettings {
        hires_nperseg: Some(128),
        ..Default::default()
    };
    let a = analyze(std::slice::from_ref(&rec), &pred(9.0), &s).unwrap();
    assert!(
        a.warnings.iter().any(|w| w.contains("coarser than f_c/4")),
        "{:?}",
        a.warnings
    );
}

#[test]
fn repeats_must_share_the_rate_and_are_truncated_to_the_shortest() {
    let a = record(9.0, 20.0, true, true);
    let b = record(9.0, 18.0, true, true);
    let r = analyze(&[a.clone(), b], &pred(9.0), &AnalyzeSettings::default()).unwrap();
    assert_eq!(r.samples_analysed, 18_000);
    assert!(r
        .warnings
        .iter()
        .any(|w| w.contains("truncated to the shortest")));
    let rep = r.repeats.as_ref().unwrap();
    assert_eq!(rep.count, 2);
    let f = rep
        .spread
        .iter()
        .find(|s| s.quantity == "f_c_measured_hz")
        .unwrap();
    assert_eq!(f.count, 2);
    assert!(f.std.is_some());
    assert_eq!(r.spectrum_hires.n_records, 2);
    let c = Recording::new(
        500.0,
        Channels {
            friction_n: Some(vec![0.0; 10_000]),
            ..Default::default()
        },
        Metadata::default(),
    )
    .unwrap();
    let e = analyze(&[a, c], &pred(9.0), &AnalyzeSettings::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("sampling rate"), "{e}");
}

#[test]
fn five_identical_repeats_average_to_the_single_record() {
    let a = record(9.0, 20.0, true, true);
    let one = analyze(
        std::slice::from_ref(&a),
        &pred(9.0),
        &AnalyzeSettings::default(),
    )
    .unwrap();
    let five = analyze(&vec![a; 5], &pred(9.0), &AnalyzeSettings::default()).unwrap();
    for ((_, x), (_, y)) in one
        .correlations
        .series
        .iter()
        .zip(&five.correlations.series)
    {
        // Mean of five equal values: rounding of a sum of five, ~1e-15.
        assert!(x
            .iter()
            .zip(y)
            .all(|(u, v)| (u - v).abs() <= 1e-12 * (1.0 + u.abs())));
    }
    // The period comes from the averaged correlations, so it carries their
    // rounding (a few ulp), not more.
    let (p1, p5) = (
        one.measured_period.period_s.unwrap(),
        five.measured_period.period_s.unwrap(),
    );
    assert!((p1 - p5).abs() <= 1e-12 * p1, "{p1} vs {p5}");
    let s = five.repeats.unwrap();
    let lag = s
        .spread
        .iter()
        .find(|s| s.quantity.starts_with("lag_s"))
        .unwrap();
    // Five equal values: their sample std is rounding (the mean of five
    // copies of x need not be x to the last bit).
    assert!(lag.std.unwrap() <= 1e-12 * lag.mean.abs(), "{lag:?}");
}
