//! Tests of the passage detection on synthetic records.

use super::signal::{
    gaussian_kernel, gaussian_smooth, noise_sigma, percentile, running_percentile, FFT_TAPS,
};
use super::*;
use crate::bearing::lookup;
use crate::recording::{Channels, Metadata};

/// The blocked Gaussian smoothing equals the plain per-sample sum (the
/// previous implementation, kept here as the reference) bit for bit, for
/// signals shorter than, as long as and much longer than the kernel;
/// long kernels (by FFT) equal it to rounding.
#[test]
fn gaussian_smooth_equals_the_plain_sum() {
    fn plain(x: &[f64], sigma: f64) -> Vec<f64> {
        let n = x.len();
        let (half, k) = gaussian_kernel(sigma, n);
        let at = |i: isize| -> f64 {
            let n = n as isize;
            let j = if i < 0 {
                -i
            } else if i >= n {
                2 * (n - 1) - i
            } else {
                i
            };
            x[j.clamp(0, n - 1) as usize]
        };
        (0..n)
            .map(|i| {
                k.iter()
                    .enumerate()
                    .map(|(j, w)| w * at(i as isize + j as isize - half as isize))
                    .sum()
            })
            .collect()
    }
    let mut rng = Rng(5);
    for (n, sigma) in [
        (1_usize, 2.0),
        (5, 2.0),
        (17, 2.0),
        (18, 2.0),
        (40, 7.5),
        (3001, 2.0),
        (3001, 7.5),
        (3001, 23.7),
        (30_000, 40.5),
    ] {
        let x: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
        let got = gaussian_smooth(&x, sigma);
        let want = plain(&x, sigma);
        let taps = gaussian_kernel(sigma, n).1.len();
        if taps > FFT_TAPS && n > taps {
            // By FFT: the same sums, rounded differently. The outputs are
            // O(0.1) for unit noise; 1e-13 absolute is ~1000 ulp of them.
            let err = got
                .iter()
                .zip(&want)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(err < 1e-13, "n {n}, sigma {sigma}: {err:e}");
        } else {
            let bits = |v: &[f64]| v.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&got), bits(&want), "n {n}, sigma {sigma}");
        }
    }
}

/// A small deterministic generator (SplitMix64 + Box–Muller) so the tests
/// need no dependency and are reproducible.
struct Rng(u64);
impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn normal(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

struct Synth {
    fs: f64,
    velocity: f64,
    duration_s: f64,
    /// FWHM / τ_c of the pulses.
    fwhm_ratio: f64,
    amplitude: f64,
    noise: f64,
    /// Relative spacing jitter (uniform ±).
    jitter: f64,
    drift_amp: f64,
    drift_period_s: f64,
    /// High-pass time constant, s (0: DC coupled).
    ac_tau_s: f64,
    /// Interference: pulses multiplied by cos(2π t / period) (0: none).
    interference_period_s: f64,
    seed: u64,
}

impl Default for Synth {
    fn default() -> Self {
        Self {
            fs: 1000.0,
            velocity: 10.0,
            duration_s: 30.0,
            fwhm_ratio: 0.155,
            amplitude: 0.5,
            noise: 0.01,
            jitter: 0.0,
            drift_amp: 0.0,
            drift_period_s: 20.0,
            ac_tau_s: 0.0,
            interference_period_s: 0.0,
            seed: 7,
        }
    }
}

/// Returns the recording and the true passage times.
fn synth(s: &Synth) -> (Recording, Vec<f64>) {
    let g = lookup("sr25w").unwrap().geometry;
    let tau_c = 2.0 * g.d_avg_mm() / s.velocity;
    let mut rng = Rng(s.seed);
    let mut times = Vec::new();
    let mut t = 0.37 * tau_c;
    while t < s.duration_s - 0.3 * tau_c {
        times.push(t);
        t += tau_c * (1.0 + s.jitter * (2.0 * rng.uniform() - 1.0));
    }
    let n = (s.duration_s * s.fs) as usize;
    let sigma = s.fwhm_ratio * tau_c / FWHM_PER_SIGMA;
    let mut x: Vec<f64> = (0..n)
        .map(|i| {
            let ti = i as f64 / s.fs;
            let mut v = 1.0;
            let mut pulses = 0.0;
            for &c in &times {
                let u = (ti - c) / sigma;
                if u.abs() < 10.0 {
                    pulses += (-0.5 * u * u).exp();
                }
            }
            let gain = if s.interference_period_s > 0.0 {
                (2.0 * std::f64::consts::PI * ti / s.interference_period_s).cos()
            } else {
                1.0
            };
            v += s.amplitude * gain * pulses;
            v += s.drift_amp * (2.0 * std::f64::consts::PI * ti / s.drift_period_s).sin();
            if s.interference_period_s > 0.0 {
                v += 0.3 * (2.0 * std::f64::consts::PI * ti / s.interference_period_s).cos();
            }
            v + s.noise * rng.normal()
        })
        .collect();
    if s.ac_tau_s > 0.0 {
        // First-order RC high-pass, exact for the sampled input held
        // between samples: y[n] = α (y[n−1] + x[n] − x[n−1]).
        let a = s.ac_tau_s / (s.ac_tau_s + 1.0 / s.fs);
        let mut prev_x = x[0];
        let mut prev_y = 0.0;
        for v in x.iter_mut() {
            let yv = a * (prev_y + *v - prev_x);
            prev_x = *v;
            prev_y = yv;
            *v = yv;
        }
    }
    let rec = Recording::new(
        s.fs,
        Channels {
            optical_v: Some(x),
            ..Default::default()
        },
        Metadata {
            velocity_mm_s: Some(s.velocity),
            test_id: Some("synthetic".into()),
            ..Default::default()
        },
    )
    .unwrap();
    (rec, times)
}

fn settings() -> PassageSettings {
    PassageSettings {
        geometry: Some(lookup("sr25w").unwrap().geometry),
        ..Default::default()
    }
}

fn kinds(a: &PassageAnalysis) -> Vec<ConditionKind> {
    a.conditions.iter().map(|c| c.kind).collect()
}

/// Every true passage matched by exactly one detection within a tenth of a period.
fn assert_all_found(a: &PassageAnalysis, truth: &[f64], tau_c: f64) {
    assert_eq!(
        a.count,
        truth.len(),
        "count: {:?} detected {:?} truth {:?}",
        kinds(a),
        a.passages
            .iter()
            .map(|p| (p.time_s, p.amplitude_v, p.edge))
            .collect::<Vec<_>>(),
        truth
    );
    for (p, t) in a.passages.iter().zip(truth) {
        assert!(
            (p.time_s - t).abs() < 0.1 * tau_c,
            "passage at {} vs {t}",
            p.time_s
        );
    }
}

#[test]
fn clean_records_at_1_to_20_mm_s_are_measured_within_spec() {
    let g = lookup("sr25w").unwrap().geometry;
    for v in [1.0, 2.0, 5.0, 9.0, 14.0, 20.0] {
        let tau_c = 2.0 * g.d_avg_mm() / v;
        let s = Synth {
            velocity: v,
            duration_s: (12.0 * tau_c).max(20.0),
            seed: v as u64,
            ..Default::default()
        };
        let (rec, truth) = synth(&s);
        let a = detect_passages(&rec, &settings()).unwrap();
        assert_all_found(&a, &truth, tau_c);
        // Issue targets: τ_c within 0.5 %, τ_p/τ_c within 3 %.
        assert!(
            (a.tau_c_s.mean / tau_c - 1.0).abs() < 0.005,
            "v = {v}: {}",
            a.tau_c_s.mean
        );
        assert!(
            (a.tau_p_over_tau_c.mean / 0.155 - 1.0).abs() < 0.03,
            "v = {v}: {}",
            a.tau_p_over_tau_c.mean
        );
        assert!(a.conditions.is_empty(), "v = {v}: {:?}", a.conditions);
        assert_eq!(a.velocity_source, "metadata");
        // d_avg implied matches the catalog to the τ_c accuracy.
        assert!((a.d_avg_implied_mm.unwrap() / g.d_avg_mm() - 1.0).abs() < 0.005);
    }
}

#[test]
fn noisy_jittered_record_finds_every_passage_and_spacing_limits() {
    let s = Synth {
        noise: 0.05,
        jitter: 0.2,
        seed: 11,
        ..Default::default()
    };
    let (rec, truth) = synth(&s);
    let tau_c = 2.0 * 4.05556 / 10.0;
    let a = detect_passages(&rec, &settings()).unwrap();
    assert_all_found(&a, &truth, tau_c);
    let sp = a.spacing.unwrap();
    // Jitter ±20 % of 4.056 mm spans 3.24–4.87 mm: some below d = 4 mm.
    assert!(sp.min_mm < 4.0 && sp.outside_limits > 0);
    assert_eq!((sp.limit_min_mm, sp.limit_max_mm), (4.0, 6.0));
    // Artefacts that were not simulated are not reported.
    for k in [
        ConditionKind::BaselineDrift,
        ConditionKind::AcCoupling,
        ConditionKind::InvertedPulses,
    ] {
        assert!(!kinds(&a).contains(&k), "{:?}", a.conditions);
    }
}

#[test]
fn drift_is_reported_and_does_not_break_detection() {
    let s = Synth {
        drift_amp: 0.4,
        drift_period_s: 25.0,
        ..Default::default()
    };
    let (rec, truth) = synth(&s);
    let a = detect_passages(&rec, &settings()).unwrap();
    assert_all_found(&a, &truth, 0.811);
    assert!(
        kinds(&a).contains(&ConditionKind::BaselineDrift),
        "{:?}",
        a.conditions
    );
    assert!(!kinds(&a).contains(&ConditionKind::AcCoupling));
    assert!((a.tau_c_s.mean / 0.811111 - 1.0).abs() < 0.005);
}

#[test]
fn ac_coupling_dips_are_reported() {
    // Thesis Fig. 38: slow pulses (0.5–1 mm/s) through an AC coupling.
    let s = Synth {
        velocity: 1.0,
        duration_s: 100.0,
        ac_tau_s: 5.0,
        ..Default::default()
    };
    let (rec, truth) = synth(&s);
    let a = detect_passages(&rec, &settings()).unwrap();
    assert_all_found(&a, &truth, 8.111);
    assert!(
        kinds(&a).contains(&ConditionKind::AcCoupling),
        "{:?}",
        a.conditions
    );
    assert!(!kinds(&a).contains(&ConditionKind::InvertedPulses));
    let c = a
        .conditions
        .iter()
        .find(|c| c.kind == ConditionKind::AcCoupling)
        .unwrap();
    assert!(c.advice.contains("DC coupled"));
}

#[test]
fn inverted_pulses_are_reported_as_interference() {
    // Thesis Fig. 32: pulses inverted on the crests of a 5 s interference fringe.
    let s = Synth {
        velocity: 20.0,
        duration_s: 20.0,
        interference_period_s: 5.0,
        ..Default::default()
    };
    let (rec, _) = synth(&s);
    let a = detect_passages(&rec, &settings()).unwrap();
    assert!(
        kinds(&a).contains(&ConditionKind::InvertedPulses),
        "{:?}",
        a.conditions
    );
    assert!(a.count_inverted > 5);
    let c = a
        .conditions
        .iter()
        .find(|c| c.kind == ConditionKind::InvertedPulses)
        .unwrap();
    assert!(c.advice.contains("incoherent"));
}

#[test]
fn velocity_free_mode_finds_the_period_from_the_pulses() {
    let (mut rec, truth) = synth(&Synth::default());
    rec.meta.velocity_mm_s = None;
    let a = detect_passages(&rec, &PassageSettings::default()).unwrap();
    assert_eq!(a.tau_c_guide_source, "pulses");
    assert_all_found(&a, &truth, 0.811);
    assert!(a.f_c_predicted_hz.is_none() && a.spacing.is_none() && a.d_avg_implied_mm.is_none());
}

#[test]
fn gaussian_fit_beats_rectangular_on_gaussian_pulses() {
    let (rec, _) = synth(&Synth::default());
    let a = detect_passages(&rec, &settings()).unwrap();
    let f = a.fits.unwrap();
    // The default fits the whole record's train (37 pulses here).
    assert_eq!(f.pulses, a.count);
    assert!(f.notes.is_empty(), "{:?}", f.notes);
    let g = f.gaussian.unwrap();
    let r = f.rectangular.unwrap();
    assert_eq!(f.better.as_deref(), Some("gaussian"));
    // Noise 0.01 on pulses of 0.5: a correct model leaves ~2 % of the amplitude.
    assert!(g.quality.rms_over_amplitude < 0.03, "{:?}", g.quality);
    assert!(r.quality.rms_over_amplitude > g.quality.rms_over_amplitude);
    assert!((g.tau_c_s / 0.811111 - 1.0).abs() < 0.005);
    assert!((g.tau_p_s / (0.155 * 0.811111) - 1.0).abs() < 0.03);
    assert!(g.amplitudes_v.iter().all(|p| (p - 0.5).abs() < 0.05));
}

#[test]
fn no_optical_channel_or_no_pulses_is_a_clear_error() {
    let rec = Recording::new(
        1000.0,
        Channels {
            friction_n: Some(vec![0.0; 5000]),
            ..Default::default()
        },
        Metadata::default(),
    )
    .unwrap();
    let e = detect_passages(&rec, &settings()).unwrap_err().to_string();
    assert!(e.contains("optical_V is missing"), "{e}");
    let mut rng = Rng(3);
    let noise: Vec<f64> = (0..20000).map(|_| 0.01 * rng.normal()).collect();
    let rec = Recording::new(
        1000.0,
        Channels {
            optical_v: Some(noise),
            ..Default::default()
        },
        Metadata {
            velocity_mm_s: Some(10.0),
            ..Default::default()
        },
    )
    .unwrap();
    let e = detect_passages(&rec, &settings()).unwrap_err();
    assert!(matches!(e, Error::NoPassages { .. }), "{e}");
    assert!(e.to_string().contains("no ball passages"), "{e}");
}

#[test]
fn helpers_are_right() {
    let v = vec![3.0, 1.0, 2.0, 4.0];
    // numpy.percentile([1,2,3,4], 25) = 1.75
    assert!((percentile(&v, 25.0) - 1.75).abs() < 1e-15);
    let mut rng = Rng(5);
    let x: Vec<f64> = (0..100_000).map(|_| 2.0 * rng.normal()).collect();
    // MAD estimate of σ = 2 from 1e5 samples: standard error ≈ 1.1 %.
    assert!((noise_sigma(&x, 1) / 2.0 - 1.0).abs() < 0.03);
    let b = running_percentile(&[5.0; 100], 20, 10.0);
    assert!(b.iter().all(|v| *v == 5.0));
}
