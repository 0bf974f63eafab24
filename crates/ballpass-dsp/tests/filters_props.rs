//! Laws of the filter kernels, checked with proptest on a fixed seed:
//! zero phase and linearity of `sosfiltfilt`, transient-free steps with
//! `sosfilt_zi`, and unit DC gain of Butterworth designs.

use ballpass_dsp::{butter, sosfilt_with_state, sosfilt_zi, sosfiltfilt, FilterBand, Sos};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

fn runner(seed: u8) -> TestRunner {
    let config = Config {
        cases: 64,
        failure_persistence: None,
        ..Config::default()
    };
    TestRunner::new_with_rng(
        config,
        TestRng::from_seed(RngAlgorithm::ChaCha, &[seed; 32]),
    )
}

fn band_strategy() -> impl Strategy<Value = (usize, FilterBand)> {
    let lp =
        (1usize..=8, 5.0f64..200.0).prop_map(|(n, f)| (n, FilterBand::LowPass { cutoff_hz: f }));
    let hp =
        (1usize..=8, 5.0f64..200.0).prop_map(|(n, f)| (n, FilterBand::HighPass { cutoff_hz: f }));
    let bp = (1usize..=4, 5.0f64..100.0, 1.2f64..4.0).prop_map(|(n, f, r)| {
        (
            n,
            FilterBand::BandPass {
                low_hz: f,
                high_hz: f * r,
            },
        )
    });
    let bs = (1usize..=4, 5.0f64..100.0, 1.2f64..4.0).prop_map(|(n, f, r)| {
        (
            n,
            FilterBand::BandStop {
                low_hz: f,
                high_hz: f * r,
            },
        )
    });
    prop_oneof![lp, hp, bp, bs]
}

const FS: f64 = 1000.0;

#[test]
fn sosfiltfilt_has_zero_phase_for_a_passband_sinusoid() {
    let sos = butter(5, FilterBand::LowPass { cutoff_hz: 20.0 }, FS).unwrap();
    runner(1)
        .run(
            &(0.5f64..12.0, -3.1f64..3.1, 0.1f64..10.0),
            |(f_hz, phi, amp)| {
                let n = 4000;
                let w = 2.0 * std::f64::consts::PI * f_hz / FS;
                let x: Vec<f64> = (0..n).map(|i| amp * (w * i as f64 + phi).sin()).collect();
                let y = sosfiltfilt(&sos, &x).unwrap();
                // Least-squares fit y = g sin + h cos over the interior, away
                // from the edge transients (the 20 Hz filter settles in ~100
                // samples).
                let (mut ss, mut sc, mut cc, mut ys, mut yc) = (0.0, 0.0, 0.0, 0.0, 0.0);
                for (i, yi) in y.iter().enumerate().take(3000).skip(1000) {
                    let (s, c) = (w * i as f64 + phi).sin_cos();
                    ss += s * s;
                    sc += s * c;
                    cc += c * c;
                    ys += yi * s;
                    yc += yi * c;
                }
                let det = ss * cc - sc * sc;
                let g = (ys * cc - yc * sc) / det;
                let h = (yc * ss - ys * sc) / det;
                let phase = h.atan2(g);
                // Zero phase to 1e-6 rad: the steady-state phase of a
                // forward-backward filter is exactly 0; what is left is the
                // decayed edge transient and rounding.
                prop_assert!(phase.abs() < 1e-6, "phase {phase} rad at {f_hz} Hz");
                // Gain |H|^2 > 0.99 this deep in the pass band.
                prop_assert!(g / amp > 0.99 && g / amp < 1.0 + 1e-9, "gain {}", g / amp);
                // No shift at all: the interior output is the input scaled by
                // |H|^2 = g / amp sample by sample (1e-9 of the amplitude: the
                // edge transient has decayed by e^-38 here, what is left is
                // rounding).
                for i in 1000..3000 {
                    prop_assert!((y[i] - g / amp * x[i]).abs() < 1e-9 * amp, "sample {i}");
                }
                Ok(())
            },
        )
        .unwrap();
}

#[test]
fn sosfiltfilt_is_linear() {
    runner(2)
        .run(
            &(
                band_strategy(),
                proptest::collection::vec(-10.0f64..10.0, 100..400),
                -5.0f64..5.0,
                -5.0f64..5.0,
            ),
            |((order, band), x, a, b)| {
                let sos = butter(order, band, FS).unwrap();
                prop_assume!(x.len() > sos.default_padlen());
                let y: Vec<f64> = x
                    .iter()
                    .enumerate()
                    .map(|(i, v)| v * (i as f64 * 0.1).cos())
                    .collect();
                let combo: Vec<f64> = x.iter().zip(&y).map(|(p, q)| a * p + b * q).collect();
                let lhs = sosfiltfilt(&sos, &combo).unwrap();
                let fx = sosfiltfilt(&sos, &x).unwrap();
                let fy = sosfiltfilt(&sos, &y).unwrap();
                let scale = 1.0 + combo.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                for (i, (l, (p, q))) in lhs.iter().zip(fx.iter().zip(&fy)).enumerate() {
                    let rhs = a * p + b * q;
                    // 1e-9 of the input scale: linear up to rounding, which
                    // the narrowest band filters amplify by up to ~1e4.
                    prop_assert!((l - rhs).abs() <= 1e-9 * scale, "sample {i}: {l} vs {rhs}");
                }
                Ok(())
            },
        )
        .unwrap();
}

fn dc_gain(sos: &Sos) -> f64 {
    sos.sections()
        .iter()
        .map(|s| (s[0] + s[1] + s[2]) / (s[3] + s[4] + s[5]))
        .product()
}

#[test]
fn sosfilt_zi_gives_a_step_response_without_transient() {
    runner(3)
        .run(
            &(band_strategy(), -100.0f64..100.0),
            |((order, band), level)| {
                let sos = butter(order, band, FS).unwrap();
                let zi: Vec<[f64; 2]> = sosfilt_zi(&sos)
                    .unwrap()
                    .iter()
                    .map(|r| [r[0] * level, r[1] * level])
                    .collect();
                let out = sosfilt_with_state(&sos, &vec![level; 300], &zi).unwrap();
                let expect = level * dc_gain(&sos);
                for (i, v) in out.y.iter().enumerate() {
                    // 1e-10 of the level: the state is the exact steady state,
                    // so every output sample is the DC response up to rounding
                    // (amplified by high-order, narrow designs).
                    prop_assert!(
                        (v - expect).abs() <= 1e-10 * (1.0 + level.abs()),
                        "sample {i}: {v} vs {expect}"
                    );
                }
                Ok(())
            },
        )
        .unwrap();
}

#[test]
fn butterworth_gain_is_minus_3db_at_the_cutoff() {
    runner(4)
        .run(&(1usize..=8, 1.0f64..450.0), |(order, fc)| {
            let sos = butter(order, FilterBand::LowPass { cutoff_hz: fc }, FS).unwrap();
            let h = ballpass_dsp::sosfreqz(&sos, &[0.0, fc], FS).unwrap().h;
            // 1e-9: exact by construction (pre-warped cutoff), up to rounding.
            prop_assert!((h[0].norm() - 1.0).abs() < 1e-9);
            prop_assert!(
                (h[1].norm() - 0.5f64.sqrt()).abs() < 1e-9,
                "|H(fc)| = {}",
                h[1].norm()
            );
            Ok(())
        })
        .unwrap();
}
