use super::super::sticking::PassageHeights;
use super::super::sweep::tests::record;
use super::*;

/// A record whose periods rise `typical` N with a small spread, plus
/// `spikes` periods `spike` N higher.
fn bearing_record(
    name: &str,
    repeat: u32,
    typical: f64,
    spikes: usize,
    spike: f64,
) -> RecordResult {
    let mut r = record(20.0, repeat);
    r.bearing = name.into();
    r.friction_psd_freq_hz = (0..200).map(|i| f64::from(i) * 0.25).collect();
    r.friction_psd = (0..200)
        .map(|i| 1.0 + 0.1 * f64::from((i * 7 + repeat as i32) % 5))
        .collect();
    let mut heights: Vec<f64> = (0..74)
        .map(|i| typical * (1.0 + 0.05 * (f64::from((i * 13 + repeat as i32) % 11) / 5.0 - 1.0)))
        .collect();
    for h in heights.iter_mut().take(spikes) {
        *h += spike;
    }
    r.sticking = Some(PassageHeights {
        period_s: 0.4,
        periods: heights.len(),
        times_s: (0..heights.len()).map(|i| i as f64 * 0.4).collect(),
        heights_n: heights,
        typical_n: typical,
        spread_n: 0.05 * typical,
        spikes,
        spike_times_s: vec![],
        spike_heights_n: vec![],
    });
    r
}

#[test]
fn the_sticking_bearing_and_only_it_is_bad() {
    let mut recs = Vec::new();
    for b in 1..=5 {
        for rep in 1..=10 {
            let bad = b == 4;
            recs.push(bearing_record(
                &format!("bearing{b}"),
                rep,
                0.1 * (1.0 + 0.05 * f64::from(b)),
                if bad { 7 } else { 0 },
                0.3,
            ));
        }
    }
    let refs: Vec<&RecordResult> = recs.iter().collect();
    let d = diagnose(&refs, &DiagnoseSettings::default());
    assert_eq!(d.bearings.len(), 5);
    assert_eq!(d.bearings[0].bearing, "bearing4");
    assert_eq!(d.bearings[0].verdict, Condition::Bad, "{:?}", d.bearings[0]);
    assert_eq!(d.bearings[0].rank, 1);
    assert!(
        d.bearings[1..].iter().all(|b| b.verdict == Condition::Good),
        "{:#?}",
        d.bearings
    );
}

/// The robust spread's degrees of freedom against a simulation: 4000
/// sets of 200 normal heights; the variance of `σ̂ / σ` must be
/// `1 / (2 ν)` with `ν = 0.268 · 200`. Tolerance 10 %: the Monte-Carlo
/// variance of a variance from 4000 draws is ±2.2 % (1σ), plus the
/// large-sample approximation's own error at n = 200.
#[test]
fn the_robust_spread_has_the_stated_degrees_of_freedom() {
    let k = spread_dof_per_period();
    assert!((k - 0.268).abs() < 0.001, "{k}");
    let mut rng = crate::sim::rng::Rng::new(17);
    let n = 200;
    let draws: Vec<f64> = (0..4000)
        .map(|_| {
            let v: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
            lower_spread(&v).1
        })
        .collect();
    let m = draws.iter().sum::<f64>() / draws.len() as f64;
    let var = draws.iter().map(|d| (d - m).powi(2)).sum::<f64>() / (draws.len() - 1) as f64;
    let expected = 1.0 / (2.0 * k * n as f64);
    assert!((var / expected - 1.0).abs() < 0.10, "{var} vs {expected}");
}

/// Three periods whose spread reads 3.44× the batch's (validation
/// fleet 6 000 027, a good bearing) are no evidence; 80 periods at 3×
/// are.
#[test]
fn a_spread_ratio_from_few_periods_is_not_significant() {
    assert!(spread_ratio_p(3.44, 3.0, 3.0) > 1e-2);
    assert!(spread_ratio_p(3.0, 80.0, 80.0) < 1e-4);
    assert_eq!(spread_ratio_p(f64::NAN, 80.0, 80.0), 1.0);
    assert_eq!(spread_ratio_p(3.0, 0.0, 80.0), 1.0);
}

/// A flat PSD of 2 unit²/Hz on a 0.25 Hz grid holds 2 · 25 = 50 units²
/// between 0 and 25 Hz (the DC bin excluded, the edge bin included).
#[test]
fn low_band_power_integrates_the_band() {
    let f: Vec<f64> = (0..200).map(|i| f64::from(i) * 0.25).collect();
    let p = vec![2.0; 200];
    assert_eq!(low_band_power(&f, &p, 25.0), 50.0);
    assert_eq!(low_band_power(&f[..1], &p[..1], 25.0), 0.0);
}

/// A bench whose good bearings all show a few exceedances (heavier
/// tails than the nominal rate): the others' median rate raises the
/// bar, so none of them is bad, while a sticking sibling still is.
#[test]
fn a_heavy_tailed_bench_raises_the_bar_for_all() {
    let recs: Vec<RecordResult> = (1..=5)
        .flat_map(|b| {
            (1..=2).map(move |rep| {
                // 2 exceedances per 74-period record on every good
                // bearing (4 per bearing: bad at the nominal rate);
                // b5 sticks on 20 per record.
                let (n, h) = if b == 5 { (20, 1.0) } else { (2, 1.0) };
                bearing_record(&format!("b{b}"), rep, 0.1, n, h)
            })
        })
        .collect();
    let refs: Vec<&RecordResult> = recs.iter().collect();
    // At the nominal rate alone, 4 spikes in 148 periods would be bad.
    assert!(binomial_critical(148, 5e-4, 1e-4, 3) <= 4);
    let d = diagnose(&refs, &DiagnoseSettings::default());
    for b in &d.bearings {
        if b.bearing == "b5" {
            assert_eq!(b.verdict, Condition::Bad, "{b:#?}");
        } else {
            // Not flagged; with the raised bar 148 periods may be too
            // few to rule out mild sticking, which it says.
            assert!(
                matches!(b.verdict, Condition::Good | Condition::Inconclusive),
                "{b:#?}"
            );
        }
    }
}

/// A strong but regular ripple is not sticking, whatever its size
/// against the others'; twice the batch's makes a bearing suspect.
#[test]
fn a_regular_ripple_is_never_bad() {
    let recs: Vec<RecordResult> = (1..=5)
        .flat_map(|b| {
            (1..=10).map(move |rep| {
                // b2: 0.3 N against the batch's median 0.14 N (2.1×),
                // its spread in proportion (2.1×, below the 3× of
                // sticking on most passages).
                let typical = if b == 2 {
                    0.3
                } else {
                    0.1 * (1.0 + 0.1 * f64::from(b))
                };
                bearing_record(&format!("b{b}"), rep, typical, 0, 0.0)
            })
        })
        .collect();
    let refs: Vec<&RecordResult> = recs.iter().collect();
    let d = diagnose(&refs, &DiagnoseSettings::default());
    for b in &d.bearings {
        let want = if b.bearing == "b2" {
            Condition::Suspect
        } else {
            Condition::Good
        };
        assert_eq!(b.verdict, want, "{b:#?}");
    }
}

/// Binomial tail against scipy.stats.binom.sf(c - 1, n, p) (printed to 12
/// digits); the critical count of 740 periods at 5e-4 and 1e-4.
#[test]
fn binomial_tail_and_critical_count() {
    let t = binomial_tail(4, 740, 5e-4);
    assert!((t - 5.780_790_808_640_791e-4).abs() < 1e-12, "{t}");
    assert_eq!(binomial_critical(740, 5e-4, 1e-4, 3), 5);
    assert_eq!(binomial_critical(10, 5e-4, 1e-4, 3), 3);
}

/// Too few periods to see mild sticking: inconclusive, not good.
#[test]
fn few_periods_are_inconclusive() {
    let mut r = bearing_record("a", 1, 0.1, 0, 0.0);
    if let Some(s) = r.sticking.as_mut() {
        s.heights_n.truncate(12);
    }
    let d = diagnose(&[&r], &DiagnoseSettings::default());
    assert_eq!(
        d.bearings[0].verdict,
        Condition::Inconclusive,
        "{:?}",
        d.bearings[0]
    );
}
