//! A fast subset of the randomized passage validation
//! (`ballpass::validate::passages`; the full run is the `validate_passages`
//! bench binary): 40 benches drawn from the default domain, seeds
//! 2_000_001..=2_000_040, a range used neither to design the rules (seeds
//! 1..) nor for the scored runs (1_000_001.., 8_000_001..). Each bench's record is scored
//! against the simulator's truth.
//!
//! The bars are the acceptance figures or looser, with room for
//! the binomial spread of 40 records (a bar at the measured rate would
//! fail on a fair draw): detection at least 98 % of the required passages
//! (the full run measures ~99.8 %), false passages at most 1 % of the
//! detections (0 in the full run), the median timing error at most
//! 0.01 τc (0.004), the median width error at SNR ≥ 10 at most 3 % (the
//! acceptance bar; ~1 % measured). Records under coherent-light
//! interference are scored by the condition verdicts, not here.

use ballpass::validate::passages::{score, summarize, PassageScore};
use ballpass::validate::{Bench, Domain};
use rayon::prelude::*;

#[test]
fn passages_hold_on_randomized_benches() {
    let domain = Domain::default();
    let scores: Vec<PassageScore> = (2_000_001u64..=2_000_040)
        .into_par_iter()
        .map(|seed| {
            score(&domain.draw(seed), seed).expect("the default domain draws valid benches")
        })
        .collect();
    let s = summarize(&scores);
    let h = &s.headline;
    let table = s.to_markdown();
    // Most records must be scorable, or the subset proves nothing.
    assert!(h.records >= 25, "{} records scored\n{table}", h.records);
    assert_eq!(h.failed.k, 0, "analyses failed\n{table}");
    assert!(h.detection.rate >= 0.98, "detection\n{table}");
    assert!(h.false_passages.rate <= 0.01, "false passages\n{table}");
    assert!(h.timing_tau_c.p50 <= 0.01, "timing\n{table}");
    assert!(h.width_error_snr10.p50 <= 0.03, "width\n{table}");
    // The matching never pairs a detection with two truths, nor the reverse.
    for r in &scores {
        assert!(r.matched <= r.detected && r.missed <= r.required, "{r:?}");
        assert_eq!(r.matched + r.spurious, r.detected, "{r:?}");
    }
}

/// Benches of the design set (seeds 1–300) on which the second revision of
/// the detector was built, kept as regressions: each failed before it.
fn design_bench(seed: u64) -> PassageScore {
    score(&Domain::default().draw(seed), seed).expect("the default domain draws valid benches")
}

/// A pulse whose centre lies inside the record but whose far half is cut
/// (0.53 and 0.63 FWHM from the end) is counted: the baseline past the last
/// pulse found used to bend and take it (one required passage missed on
/// each of these benches).
#[test]
fn pulses_cut_by_the_record_end_are_counted() {
    for seed in [242, 257] {
        let s = design_bench(seed);
        assert!(
            s.count_exact,
            "bench {seed}: missed {} spurious {}",
            s.missed, s.spurious
        );
    }
}

/// Skewed pulses (FWHM 0.41 τc) recorded AC coupled (T = 0.86 s): the
/// skewed pulse's long tail hides the dip the old rule looked for, so the
/// coupling went unseen and the widths read 8 % narrow. The step across the
/// pulse finds it; the widths then read 3.5 % narrow (the wide pulse's own
/// bias, docs/verdicts.md), within the 5 % asserted here.
#[test]
fn ac_coupling_is_found_under_skewed_pulses() {
    let s = design_bench(103);
    assert!(s.truth.ac_coupling);
    assert!(s.reported.ac_coupling, "{:?}", s.reported);
    let w = s.width_error.expect("widths measured");
    assert!(w.abs() <= 0.05, "width error {w}");
}

/// Wide pulses recorded DC coupled (FWHM 0.41 and 0.44 τc): their tails
/// leave the template's ends a few percent apart, which read as slow AC
/// couplings (T 10 s and 3.4 s) and were reported, and undoing them
/// ramped the reported baseline by 23 and 41 pulse heights (reported as a
/// drift). Integrating the record's DC level back is no light level a
/// photodetector saw, so neither is kept now.
#[test]
fn wide_dc_coupled_pulses_are_not_taken_for_an_ac_coupling() {
    for seed in [27, 226] {
        let s = design_bench(seed);
        assert!(!s.truth.ac_coupling && s.truth.drift_fraction == 0.0);
        assert!(!s.reported.ac_coupling, "bench {seed}: {:?}", s.reported);
        assert!(!s.reported.baseline_drift, "bench {seed}: {:?}", s.reported);
        assert!(s.count_exact, "bench {seed}");
    }
}

/// Design bench `seed` made clean (no noise to speak of, no AC coupling,
/// drift or interference), its pulses of `shape`, `width` τc wide.
fn clean_bench(seed: u64, shape: ballpass::sim::PulseShape, width: f64) -> Bench {
    let mut bench = Domain::default().draw(seed);
    let o = &mut bench.optical;
    o.noise_v = 1e-5 * o.pulse_amplitude_v;
    o.ac_coupling = false;
    o.baseline_drift_v = 0.0;
    o.interference_drift = false;
    o.pulse_shape = shape;
    o.width_ratio = width;
    bench
}

/// The scorer's second width truth is the FWHM of one pulse alone (the
/// simulated shape's own half-maximum points, through the recorded stage
/// position; `width_error_fwhm`).
/// The analysis reports the width at half prominence of the pulses as
/// recorded, which is the same where pulses do not overlap: clean records
/// of pulses that cannot overlap (raised cosine, zero past one FWHM from
/// its peak, here 0.2 τc) read within 1 % of it. Where the tails overlap
/// (Gaussian, 0.44 τc) the recorded width is narrower (see
/// `overlapping_pulses_read_the_width_at_half_prominence_of_their_sum`):
/// between 2 % and 6 % here, never wide. On the design benches this
/// measured +0.2 % at most for the raised cosine with enough passages,
/// −3.6 % to −4.2 % for the Gaussian.
#[test]
fn clean_widths_are_scored_against_the_isolated_pulse() {
    use ballpass::sim::PulseShape;
    let clean = |seed: u64, shape: PulseShape, width: f64| -> PassageScore {
        score(&clean_bench(seed, shape, width), seed)
            .expect("the default domain draws valid benches")
    };
    // Seeds of the design set with 20 passages or more.
    for seed in [3, 7, 19] {
        let s = clean(seed, PulseShape::RaisedCosine, 0.2);
        assert!(s.count_exact && s.required >= 20, "bench {seed}: {s:?}");
        let w = s.width_error_fwhm.expect("widths measured");
        assert!(
            w.abs() <= 0.01,
            "bench {seed}: raised cosine width error {w}"
        );
        let s = clean(seed, PulseShape::Gaussian, 0.44);
        assert!(s.count_exact, "bench {seed}: {s:?}");
        let w = s.width_error_fwhm.expect("widths measured");
        assert!(
            (-0.06..=-0.02).contains(&w),
            "bench {seed}: Gaussian width error {w}"
        );
    }
}

/// Which width the analysis reads where the tails of neighbouring pulses
/// overlap. The truth's FWHM is that of one pulse; the width at half
/// prominence (CONVENTIONS.md: "as `peak_widths`") of the pulses as
/// recorded is narrower, because the light never falls back to the dark
/// level between them. Independent reference: SciPy 1.17's `find_peaks` /
/// `peak_widths(rel_height = 0.5)` on an exact periodic train of unit
/// pulses 0.45 of the spacing wide reads 4.64 % narrow for the Gaussian,
/// 4.24 % for the skewed pulse and 0 for the raised cosine (which ends one
/// FWHM from its peak). The benches' spacings and amplitudes are not
/// exactly regular, hence ±0.5 % (measured on 12 Gaussian design benches:
/// −4.6 to −4.8 %). The analysis of the same clean records reads within
/// 1 % of the width at half prominence (measured: −0.1 to +0.5 %), not of
/// the FWHM. That width is the score's headline truth (`width_error`,
/// `width_truth: half_prominence`).
#[test]
fn overlapping_pulses_read_the_width_at_half_prominence_of_their_sum() {
    use ballpass::sim::PulseShape;
    use ballpass::validate::passages::{score_and_recorded_width, WidthTruth};
    let clean = |seed: u64, shape: PulseShape| -> (PassageScore, f64) {
        let (s, r) = score_and_recorded_width(&clean_bench(seed, shape, 0.45), seed)
            .expect("the default domain draws valid benches");
        (s, r.expect("three clean pulses or more"))
    };
    // Seeds of the design set with 20 passages or more.
    for seed in [3, 7] {
        let (_, r) = clean(seed, PulseShape::RaisedCosine);
        assert!((r - 1.0).abs() <= 0.002, "bench {seed}: raised cosine {r}");
        let (_, r) = clean(seed, PulseShape::Skewed);
        assert!((r - 0.9576).abs() <= 0.005, "bench {seed}: skewed {r}");
        let (s, r) = clean(seed, PulseShape::Gaussian);
        assert!((r - 0.9536).abs() <= 0.005, "bench {seed}: Gaussian {r}");
        let e = s.width_error_fwhm.expect("widths measured");
        assert!(
            ((1.0 + e) / r - 1.0).abs() <= 0.01,
            "bench {seed}: analysis {e} against half prominence {r}"
        );
        assert_eq!(s.width_truth, WidthTruth::HalfProminence);
        let h = s.width_error.expect("widths measured");
        assert!(
            (h - ((1.0 + e) / r - 1.0)).abs() <= 1e-12,
            "bench {seed}: headline {h}"
        );
    }
}

/// The drift's period is scored in ball-pass periods (what decides whether
/// the baseline can follow it), and only for a record that drifts.
#[test]
fn drift_period_is_scored_in_ball_pass_periods() {
    let domain = Domain::default();
    let mut bench = domain.draw(5);
    bench.optical.baseline_drift_v = 0.3 * bench.optical.pulse_amplitude_v;
    bench.optical.baseline_drift_period_s = 12.0;
    let s = score(&bench, 5).expect("the default domain draws valid benches");
    let want = 12.0 / s.bench.tau_c_s;
    let got = s.truth.drift_period_tau_c.expect("a drift period");
    assert!((got / want - 1.0).abs() < 1e-12, "{got} vs {want}");
    bench.optical.baseline_drift_v = 0.0;
    let s = score(&bench, 5).expect("the default domain draws valid benches");
    assert_eq!(s.truth.drift_period_tau_c, None);
}

/// A baseline drifting within a few ball-pass periods (design benches 405
/// and 490: a drift of 0.58 and 0.42 pulse heights whose slower period is
/// 2.9 and 3.5 τ_c) is followed between the pulses at their own scale: the
/// count is exact (3 and 4 passages were missed when the dark level was a
/// running quantile over a window as long as the drift's faster period), and
/// bench 405's width (SNR 20) reads within 3 % (it read 11.7 % wide).
#[test]
fn a_fast_drift_is_followed_between_the_pulses() {
    for seed in [405, 490] {
        let s = design_bench(seed);
        let p = s.truth.drift_period_tau_c.expect("the bench drifts");
        assert!(p < 4.0 && s.truth.drift_fraction > 0.4, "bench {seed}: {p}");
        assert!(s.count_exact, "bench {seed}: {s:?}");
        assert_eq!(s.spurious, 0, "bench {seed}: {s:?}");
        if seed == 405 {
            let e = s.width_error.expect("widths measured");
            assert!(e.abs() < 0.03, "bench {seed}: width error {e}");
        }
    }
}

/// A record between one and two ball-pass periods long can hold two whole
/// passages a period apart (design benches 14 000 246 and 15 000 481: 1.90
/// and 1.95 periods, SNR 32 and 24, two required passages each): both are
/// found and measured. The detector refused every record shorter than two
/// periods, so both passages counted as missed. Two pulses give
/// `peak_widths` no pulse with a neighbour on each side, so their width is
/// scored against one pulse's FWHM, and the score says so.
#[test]
fn two_passages_in_less_than_two_periods_are_found() {
    use ballpass::validate::passages::WidthTruth;
    for seed in [14_000_246, 15_000_481] {
        let s = design_bench(seed);
        let periods = s.bench.duration_s / s.bench.tau_c_s;
        assert!((1.0..2.0).contains(&periods), "bench {seed}: {periods}");
        assert_eq!(s.required, 2, "bench {seed}: {s:?}");
        assert!(s.count_exact, "bench {seed}: {s:?}");
        let e = s.width_error.expect("widths measured");
        assert!(e.abs() < 0.03, "bench {seed}: width error {e}");
        assert_eq!(s.width_truth, WidthTruth::OnePulseFwhm, "bench {seed}");
        assert_eq!(s.width_error, s.width_error_fwhm, "bench {seed}");
    }
}

/// Where the level under the pulses moves as fast as the pulses (design
/// benches 14 000 367 and 15 100 442: drifts of 0.43 and 0.87 pulse heights
/// whose faster component has a period of 0.43 and 1.3 τ_c), a width cannot
/// be told from the drift: the previous detector read them 13 % and 100 %
/// wide. The analysis now withholds them and says why
/// (`widths_withheld`); the scorer counts the record as withheld, not as
/// measured.
#[test]
fn widths_under_a_drift_as_fast_as_the_pulses_are_withheld() {
    for seed in [14_000_367, 15_100_442] {
        let s = design_bench(seed);
        assert!(s.truth.drift_fraction > 0.4, "bench {seed}");
        assert!(s.reported.widths_withheld, "bench {seed}: {:?}", s.reported);
        let bend = s.reported.baseline_bend.expect("a bend measured");
        assert!(bend > 0.15, "bench {seed}: bend {bend}");
        assert!(
            s.width_withheld && s.width_s.is_none(),
            "bench {seed}: {s:?}"
        );
        assert_eq!(s.widths_used, Some(0), "bench {seed}");
    }
}

/// A record whose widths are withheld says so in its report, in words:
/// no "NaN" for τp, τp/τc or σ, and no mean line drawn at NaN (bench
/// 14 000 367 above).
#[test]
fn a_report_of_withheld_widths_says_withheld_not_nan() {
    use ballpass::analysis::passage::{detect_passages, PassageSettings};
    use ballpass::report::passage::passages_report;
    use ballpass::report::render_html;
    use ballpass::sim::simulate;
    let seed = 14_000_367;
    let bench = Domain::default().draw(seed);
    let sim = simulate(&bench.settings(&bench.bearing(0, false), seed)).expect("simulated");
    let settings = PassageSettings {
        geometry: Some(bench.geometry),
        ..PassageSettings::default()
    };
    let a = detect_passages(&sim.recording, &settings).expect("passages found");
    assert!(a.tau_p_s.mean.is_nan(), "widths withheld: {:?}", a.tau_p_s);
    let report = passages_report(
        std::slice::from_ref(&sim.recording),
        std::slice::from_ref(&a),
        &[],
        &settings,
        "sr25w",
    )
    .expect("report built");
    let html = render_html(&report, false).expect("rendered").html;
    assert!(
        html.contains("withheld (see the conditions)"),
        "no 'withheld' in the report"
    );
    assert!(!html.contains("NaN"), "NaN in the report");
}

/// Design benches with a drift at the pulses' own scale that the baseline
/// does not follow, so does not bend with (`train` 248: 0.51 pulse heights,
/// slower period 3.5 τc, 3 pulses; `fresh8` 15 300 182: 0.99 at 3.9 τc):
/// session 15's rule printed their widths 7 % and 23 % wide. Their widths
/// disagree from pulse to pulse beyond noise, so the mean width's standard
/// error from that excess is over 2 %, and they are withheld. A bench
/// without drift whose widths also scatter a little beyond the fits'
/// standard errors (`train` 159, 1.5 %) keeps its width, within 3 %.
#[test]
fn widths_that_scatter_beyond_noise_are_withheld() {
    for seed in [248, 15_300_182] {
        let s = design_bench(seed);
        let se = s.reported.width_scatter_se;
        assert!(
            s.width_withheld && s.reported.widths_withheld && se.is_some_and(|v| v > 0.02),
            "bench {seed}: width {:?} standard error {se:?}",
            s.width_error
        );
    }
    let s = design_bench(159);
    let e = s.width_error.expect("a width");
    assert!(!s.width_withheld && e.abs() < 0.03, "bench 159: {e}");
}
